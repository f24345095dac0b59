//! Land cover derived from the terrain (pure): the CPU twin of `landcover_weights` in
//! `shaders/landcover.glsl`, and the classes' colours. The shader takes its inputs — height,
//! unit normal, a jitter in [−1, 1] from world-anchored noise — from the vertex stage today; a
//! land-cover raster or a normal map can feed the same function later (the raster replacing
//! the weights, the normal map the normal).
//!
//! The rules, applied as layers in this order (each layer takes its coverage c ∈ [0, 1] from
//! everything below it, so the weights always sum to 1 and borders blend over the smoothstep
//! widths); h is the height above sea level, s the slope (degrees), n_y the normal's north
//! component (> 0 on north-facing slopes, 0 on the flat), h' = h + 60 m·jitter and
//! s' = s + 3°·jitter the jittered values that break borders into natural shapes:
//!
//! | layer | class | coverage |
//! |---|---|---|
//! | 1 | grass | everywhere (the base) |
//! | 2 | crops | valley floors: h' below 900…1100 m, s' below 3…6°, above the beach (h 4…8 m) |
//! | 3 | forest | slopes s' above 6…10° below the tree line t = 2000 m − 250 m·n_y (±60 m), above the beach |
//! | 4 | sand/bare | beaches (h below 4…8 m, s below 6…10°) and scree above t + 450 m (±100 m) |
//! | 5 | rock | s' above r ± 4°, r falling from 42° (below 1200 m) to 30° (above 2800 m) |
//! | 6 | snow | h' above the snow line 2900 m − 600 m·n_y (±80 m), s below 50…58° |
//! | 7 | water | h below 0.5…1.5 m (at or under sea level) and s below 1…2.5° (no jitter) |
//! | – | urban | never derived: left for the land-cover raster |
//!
//! Aspect moves both lines: north faces (in the northern hemisphere, the shaded side) hold
//! snow 600 m lower at 90° and lose the forest 250 m lower than south faces.

/// Classes, in the order of the shader's weight array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(usize)]
pub enum Class {
    Water = 0,
    Sand = 1,
    Grass = 2,
    Crops = 3,
    Forest = 4,
    Rock = 5,
    Snow = 6,
    Urban = 7,
}

pub const CLASS_COUNT: usize = 8;

/// The classes' base colours (sRGB), the same table as `CLASS_ALBEDO` in the shader: the
/// colours of the class view (`--look classes`) and the mean of each class's procedural detail.
pub const CLASS_ALBEDO_SRGB: [[f32; 3]; CLASS_COUNT] = [
    [0.07, 0.16, 0.22], // water
    [0.62, 0.57, 0.46], // sand / bare
    [0.31, 0.41, 0.18], // grass
    [0.52, 0.50, 0.28], // crops
    [0.16, 0.25, 0.12], // forest
    [0.44, 0.42, 0.40], // rock
    [0.93, 0.95, 0.98], // snow
    [0.50, 0.47, 0.45], // urban
];

/// Jitter amplitudes: heights by up to 60 m, slopes by up to 3°.
pub const JITTER_M: f32 = 60.0;
pub const JITTER_DEG: f32 = 3.0;

/// What the rules look at in one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoverInputs {
    /// Height above sea level, metres.
    pub height_m: f32,
    /// Unit surface normal, ENU (z up).
    pub normal: [f32; 3],
    /// World-anchored noise in [−1, 1] that shifts the thresholds.
    pub jitter: f32,
}

/// GLSL's smoothstep (edge0 < edge1).
fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Slope of a unit normal, degrees.
pub fn slope_deg(normal: [f32; 3]) -> f32 {
    normal[2].clamp(-1.0, 1.0).acos().to_degrees()
}

/// The weights of the eight classes (sum 1) by the table above.
pub fn class_weights(i: &CoverInputs) -> [f32; CLASS_COUNT] {
    let h = i.height_m;
    let s = slope_deg(i.normal);
    let ny = i.normal[1];
    let hj = h + JITTER_M * i.jitter;
    let sj = s + JITTER_DEG * i.jitter;
    let mut w = [0.0f32; CLASS_COUNT];
    w[Class::Grass as usize] = 1.0;
    let mut layer = |class: Class, c: f32| {
        for v in w.iter_mut() {
            *v *= 1.0 - c;
        }
        w[class as usize] += c;
    };
    let above_beach = smoothstep(4.0, 8.0, h);
    let crops = (1.0 - smoothstep(900.0, 1100.0, hj)) * (1.0 - smoothstep(3.0, 6.0, sj));
    layer(Class::Crops, crops * above_beach);
    let tree_line = 2000.0 - 250.0 * ny;
    let forest =
        smoothstep(6.0, 10.0, sj) * (1.0 - smoothstep(tree_line - 60.0, tree_line + 60.0, hj));
    layer(Class::Forest, forest * above_beach);
    let beach = (1.0 - smoothstep(4.0, 8.0, h)) * (1.0 - smoothstep(6.0, 10.0, s));
    let bare_line = tree_line + 450.0;
    let scree = smoothstep(bare_line - 100.0, bare_line + 100.0, hj);
    layer(Class::Sand, beach.max(scree));
    let r = 42.0 - 12.0 * smoothstep(1200.0, 2800.0, h);
    layer(Class::Rock, smoothstep(r - 4.0, r + 4.0, sj));
    let snow_line = 2900.0 - 600.0 * ny;
    let snow =
        smoothstep(snow_line - 80.0, snow_line + 80.0, hj) * (1.0 - smoothstep(50.0, 58.0, s));
    layer(Class::Snow, snow);
    let water = (1.0 - smoothstep(0.5, 1.5, h)) * (1.0 - smoothstep(1.0, 2.5, s));
    layer(Class::Water, water);
    w
}

/// The class texture's "no class" value (`DRAPE_NO_CLASS` in `shaders/drape.glsl`).
pub const NO_CLASS: u8 = 255;

/// The four class texels around grid position `g` (level-0 samples) of a `size` class
/// texture draped over a `grid` of samples, with their bilinear weights: `drape_uv` and the
/// corner loop of `landcover_raster` in the shaders. Texels outside are [`NO_CLASS`].
pub fn class_corners(
    classes: &[u8],
    size: (usize, usize),
    grid: (u32, u32),
    g: (f32, f32),
) -> [(u8, f32); 4] {
    let t = (
        (g.0 + 0.5) / grid.0 as f32 * size.0 as f32 - 0.5,
        (g.1 + 0.5) / grid.1 as f32 * size.1 as f32 - 0.5,
    );
    let (i, j) = (t.0.floor(), t.1.floor());
    let (fx, fy) = (t.0 - i, t.1 - j);
    let at = |dx: i64, dy: i64| {
        let (x, y) = (i as i64 + dx, j as i64 + dy);
        if x < 0 || y < 0 || x >= size.0 as i64 || y >= size.1 as i64 {
            NO_CLASS
        } else {
            classes[y as usize * size.0 + x as usize]
        }
    };
    [
        (at(0, 0), (1.0 - fx) * (1.0 - fy)),
        (at(1, 0), fx * (1.0 - fy)),
        (at(0, 1), (1.0 - fx) * fy),
        (at(1, 1), fx * fy),
    ]
}

/// The land-cover raster over the derived weights (`landcover_raster` in
/// `shaders/landcover.glsl`): the corners' classes by their weights replace the derived
/// weights as far as they cover the point (texels without a class leave the derived ones), and
/// the derived rock stays on steep faces whatever the raster says (rasters of 10–100 m do not
/// resolve cliffs).
pub fn raster_weights(
    derived: &[f32; CLASS_COUNT],
    corners: &[(u8, f32); 4],
) -> [f32; CLASS_COUNT] {
    let mut r = [0.0f32; CLASS_COUNT];
    let mut covered = 0.0f32;
    for &(class, wt) in corners {
        if (class as usize) < CLASS_COUNT && wt > 0.0 {
            r[class as usize] += wt;
            covered += wt;
        }
    }
    if covered <= 0.0 {
        return *derived;
    }
    let rock = derived[Class::Rock as usize];
    let mut w = *derived;
    for k in 0..CLASS_COUNT {
        let keep = if k == Class::Rock as usize { rock } else { 0.0 };
        let raster = r[k] / covered * (1.0 - rock) + keep;
        w[k] += (raster - w[k]) * covered;
    }
    w
}

/// The class with the largest weight.
pub fn dominant(w: &[f32; CLASS_COUNT]) -> Class {
    const ALL: [Class; CLASS_COUNT] = [
        Class::Water,
        Class::Sand,
        Class::Grass,
        Class::Crops,
        Class::Forest,
        Class::Rock,
        Class::Snow,
        Class::Urban,
    ];
    let mut best = 0;
    for k in 1..CLASS_COUNT {
        if w[k] > w[best] {
            best = k;
        }
    }
    ALL[best]
}

/// The class view's colour (sRGB): the weights' blend of the base colours.
pub fn class_colour_srgb(w: &[f32; CLASS_COUNT]) -> [f32; 3] {
    let mut c = [0.0f32; 3];
    for (k, wk) in w.iter().enumerate() {
        for (ch, out) in c.iter_mut().enumerate() {
            *out += wk * CLASS_ALBEDO_SRGB[k][ch];
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_raster_replaces_the_derived_classes_but_keeps_rock_on_cliffs() {
        let flat = class_weights(&CoverInputs {
            height_m: 400.0,
            normal: [0.0, 0.0, 1.0],
            jitter: 0.0,
        });
        assert_eq!(dominant(&flat), Class::Crops);
        let forest = [
            (Class::Forest as u8, 1.0),
            (NO_CLASS, 0.0),
            (NO_CLASS, 0.0),
            (NO_CLASS, 0.0),
        ];
        let w = raster_weights(&flat, &forest);
        assert!((w[Class::Forest as usize] - 1.0).abs() < 1e-6, "{w:?}");
        // Half covered (a border with no class): half raster, half derived.
        let half = [
            (Class::Urban as u8, 0.5),
            (NO_CLASS, 0.5),
            (NO_CLASS, 0.0),
            (NO_CLASS, 0.0),
        ];
        let w = raster_weights(&flat, &half);
        assert!((w[Class::Urban as usize] - 0.5).abs() < 1e-6);
        assert!((w[Class::Crops as usize] - 0.5 * flat[Class::Crops as usize]).abs() < 1e-6);
        // Grass on a 60° cliff stays rock.
        let cliff = class_weights(&CoverInputs {
            height_m: 1500.0,
            normal: normal(60.0, 90.0),
            jitter: 0.0,
        });
        let grass = [
            (Class::Grass as u8, 1.0),
            (NO_CLASS, 0.0),
            (NO_CLASS, 0.0),
            (NO_CLASS, 0.0),
        ];
        assert_eq!(dominant(&raster_weights(&cliff, &grass)), Class::Rock);
        assert_eq!(raster_weights(&flat, &[(NO_CLASS, 0.25); 4]), flat);
        // Corners: a 2×2 texture over a 2×2 grid, at sample (0, 0) exactly texel (0, 0).
        let c = class_corners(&[1, 2, 3, 4], (2, 2), (2, 2), (0.0, 0.0));
        assert_eq!(c[0], (1, 1.0));
        let c = class_corners(&[1, 2, 3, 4], (2, 2), (2, 2), (0.5, 0.0));
        assert_eq!((c[0], c[1]), ((1, 0.5), (2, 0.5)));
        assert_eq!(
            class_corners(&[1, 2, 3, 4], (2, 2), (2, 2), (1.0, 1.0))[3].0,
            NO_CLASS
        );
    }

    /// A unit normal of slope `s` degrees facing `aspect` degrees (clockwise from north).
    fn normal(s: f32, aspect: f32) -> [f32; 3] {
        let (s, a) = (s.to_radians(), aspect.to_radians());
        [s.sin() * a.sin(), s.sin() * a.cos(), s.cos()]
    }

    fn class_at(h: f32, s: f32, aspect: f32, jitter: f32) -> Class {
        dominant(&class_weights(&CoverInputs {
            height_m: h,
            normal: normal(s, aspect),
            jitter,
        }))
    }

    #[test]
    fn weights_are_a_partition_of_one() {
        for h in [
            -50.0, 0.0, 1.0, 5.0, 300.0, 1000.0, 2000.0, 2500.0, 2900.0, 4000.0,
        ] {
            for s in [0.0, 2.0, 5.0, 8.0, 20.0, 35.0, 45.0, 60.0, 85.0] {
                for j in [-1.0, 0.0, 1.0] {
                    let w = class_weights(&CoverInputs {
                        height_m: h,
                        normal: normal(s, 30.0),
                        jitter: j,
                    });
                    let sum: f32 = w.iter().sum();
                    assert!((sum - 1.0).abs() < 1e-5, "h {h} s {s}: {w:?}");
                    assert!(w.iter().all(|&v| (0.0..=1.0).contains(&v)), "{w:?}");
                    assert_eq!(w[Class::Urban as usize], 0.0);
                }
            }
        }
    }

    #[test]
    fn the_documented_rules() {
        // Water: at or under sea level and flat, whatever the jitter; not on a steep shore.
        for j in [-1.0, 0.0, 1.0] {
            assert_eq!(class_at(0.0, 0.0, 0.0, j), Class::Water);
            assert_eq!(class_at(-20.0, 0.5, 0.0, j), Class::Water);
        }
        assert_ne!(class_at(-20.0, 20.0, 0.0, 0.0), Class::Water);
        // A flat beach just above the sea; a flat valley floor is farmland.
        assert_eq!(class_at(3.0, 2.0, 0.0, 0.0), Class::Sand);
        assert_eq!(class_at(550.0, 1.0, 0.0, 0.0), Class::Crops);
        // Flat high pasture is grass; slopes below the tree line are forest.
        assert_eq!(class_at(1500.0, 2.0, 0.0, 0.0), Class::Grass);
        assert_eq!(class_at(1200.0, 20.0, 180.0, 0.0), Class::Forest);
        // Above the tree line: meadows, then scree.
        assert_eq!(class_at(2200.0, 15.0, 180.0, 0.0), Class::Grass);
        assert_eq!(class_at(2700.0, 15.0, 180.0, 0.0), Class::Sand);
        // Cliffs are rock at any height, and high slopes get rocky sooner.
        assert_eq!(class_at(600.0, 55.0, 90.0, 0.0), Class::Rock);
        assert_eq!(class_at(2500.0, 36.0, 180.0, 0.0), Class::Rock);
        assert_eq!(class_at(800.0, 36.0, 180.0, 0.0), Class::Forest);
        // Snow on a high plateau, not on a vertical wall.
        assert_eq!(class_at(3500.0, 0.0, 0.0, 0.0), Class::Snow);
        assert_eq!(class_at(3500.0, 70.0, 0.0, 0.0), Class::Rock);
    }

    #[test]
    fn the_snow_line_is_lower_on_north_faces() {
        // At 2750 m on a 30° slope: snow facing north, bare facing south.
        assert_eq!(class_at(2750.0, 30.0, 0.0, 0.0), Class::Snow);
        assert_ne!(class_at(2750.0, 30.0, 180.0, 0.0), Class::Snow);
        // And the snow line itself moves by 600 m·n_y.
        let line = |aspect: f32| {
            (2000..4000)
                .find(|&h| class_at(h as f32, 30.0, aspect, 0.0) == Class::Snow)
                .unwrap() as f32
        };
        let (north, south) = (line(0.0), line(180.0));
        assert!((south - north - 600.0).abs() < 10.0, "{north} {south}");
    }

    #[test]
    fn jitter_moves_borders_but_not_far() {
        // Near the tree line the jitter decides; far from it, it does not.
        let w = |j| class_at(2000.0, 20.0, 90.0, j);
        assert_eq!(w(-1.0), Class::Forest);
        assert_ne!(w(1.0), Class::Forest);
        for j in [-1.0, 1.0] {
            assert_eq!(class_at(1500.0, 20.0, 90.0, j), Class::Forest);
        }
    }

    #[test]
    fn class_colours_blend_by_weight() {
        let mut w = [0.0; CLASS_COUNT];
        w[Class::Snow as usize] = 1.0;
        assert_eq!(
            class_colour_srgb(&w),
            CLASS_ALBEDO_SRGB[Class::Snow as usize]
        );
        w[Class::Snow as usize] = 0.5;
        w[Class::Rock as usize] = 0.5;
        let c = class_colour_srgb(&w);
        for ch in 0..3 {
            let m = 0.5 * (CLASS_ALBEDO_SRGB[5][ch] + CLASS_ALBEDO_SRGB[6][ch]);
            assert!((c[ch] - m).abs() < 1e-6);
        }
    }
}
