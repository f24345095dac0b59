//! CDLOD's geomorph (Strugar 2009 §2.3; reference `CDLODQuadTree::LODSelect` and
//! `CDLODTerrain.vsh`), pure: the morph zone of each level, and what the vertex shader does with
//! it — [`morph_vertex`] is `shaders/terrain.vert`'s `morph_vertex` written again on the CPU, for
//! the tests (keep the two in step).
//!
//! A node of level ℓ is drawn within range(ℓ) of the eye. Its vertices slide onto the grid of
//! level ℓ + 1 as their distance to the eye d goes from the zone's start to its end:
//! k = clamp((d − start) / (end − start), 0, 1); end(ℓ) = range(ℓ) and
//! start(ℓ) = start(ℓ − 1) + (end(ℓ) − start(ℓ − 1)) · [`MORPH_START_RATIO`], start(−1) = 0 (the
//! reference's recurrence and its default ratio). A vertex with odd grid coordinates moves
//! towards its lower-left neighbour on the coarser grid — along the row, the column, or the
//! south-west → north-east diagonal every drawn quad is cut by (`mesh::TILE_DIAGONAL`) — so at
//! k = 1 the node's mesh is the coarser level's, and at a range's end it meets a coarser
//! neighbour without a crack.
//!
//! Departure, named: the reference samples its full-resolution heightmap bilinearly at the
//! morphed position; the renderer holds each level's samples, so a morphed vertex's height is
//! interpolated along the node's own mesh edge it slides on. Both agree at k = 0 and k = 1.
//!
//! A quadrant of a node that its parent covers (`cdlod.rs`) is drawn as the child node fully
//! morphed (k = 1: the parent's quarter mesh exactly) and then morphed by the parent's own zone
//! towards the grandparent's grid, as the parent would be.

/// The reference's default `MorphStartRatio`: a level's vertices start to morph two thirds of
/// the way from the previous level's morph start to the end of their own range.
pub const MORPH_START_RATIO: f64 = 0.667;

/// How one drawn node morphs (all zero: not at all — every mode but CDLOD).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Morph {
    /// Its level's zone (start, end), metres from the eye; end 0: no morph.
    pub zone: [f32; 2],
    /// A quadrant its parent covers: drawn fully morphed onto the parent's grid, then morphed by
    /// `parent_zone` (end 0: the parent does not morph — the coarsest level).
    pub quadrant: bool,
    pub parent_zone: [f32; 2],
    /// With `quadrant` (bounded only): a sixteenth of its grandparent drawn at the grandparent's
    /// resolution — the tile's every fourth vertex (`mesh::skirted_sixteenth_tile_indices`),
    /// which the full morph onto the parent's grid leaves where they are.
    pub sixteenth: bool,
}

impl Morph {
    pub const NONE: Morph = Morph {
        zone: [0.0, 0.0],
        quadrant: false,
        parent_zone: [0.0, 0.0],
        sixteenth: false,
    };

    /// A quadrant drawn at its parent's resolution (no morph zone).
    pub const QUADRANT: Morph = Morph {
        quadrant: true,
        ..Morph::NONE
    };

    /// A sixteenth drawn at its grandparent's resolution.
    pub const SIXTEENTH: Morph = Morph {
        quadrant: true,
        sixteenth: true,
        ..Morph::NONE
    };

    /// How many levels coarser than its own the node is drawn: 0, 1 (a quadrant) or 2 (a
    /// sixteenth).
    pub fn levels_up(&self) -> u32 {
        self.quadrant as u32 + self.sixteenth as u32
    }

    /// What the shader reads (`TileInstance.morph`): xy the node's zone, zw the parent's; a
    /// quadrant says so with x = −1, y = 0.
    pub fn to_gpu(&self) -> [f32; 4] {
        if self.quadrant {
            [-1.0, 0.0, self.parent_zone[0], self.parent_zone[1]]
        } else {
            [self.zone[0], self.zone[1], 0.0, 0.0]
        }
    }
}

/// The morph zones (start, end) of levels 0..=`level`, metres, for ranges `range(ℓ)`.
pub fn morph_zones(range: impl Fn(u32) -> f64, level: u32) -> Vec<[f64; 2]> {
    let mut out = Vec::with_capacity(level as usize + 1);
    let mut prev_start = 0.0;
    for l in 0..=level {
        let end = range(l);
        let start = prev_start + (end - prev_start) * MORPH_START_RATIO;
        out.push([start, end]);
        prev_start = start;
    }
    out
}

/// The morph factor of a vertex `dist` metres from the eye in `zone` (0 when the zone is empty).
pub fn morph_k(zone: [f32; 2], dist: f32) -> f32 {
    if zone[1] <= 0.0 {
        return 0.0;
    }
    ((dist - zone[0]) / (zone[1] - zone[0]).max(1e-3)).clamp(0.0, 1.0)
}

/// A node's vertex `ij` (quads from its south-west vertex) morphed by `k1` onto the next
/// coarser grid and then, for a quadrant (`k1` = 1), by `k2` onto the one after: its fractional
/// grid coordinates and height, `height(ij)` the node's samples. f32, operation for operation
/// as the shader.
pub fn morph_vertex(
    ij: [i32; 2],
    k1: f32,
    k2: f32,
    height: impl Fn([i32; 2]) -> f32,
) -> ([f32; 2], f32) {
    let mut h = height(ij);
    let odd = [ij[0] & 1, ij[1] & 1];
    let mut f = [ij[0] as f32, ij[1] as f32];
    if k1 > 0.0 && odd != [0, 0] {
        let hb = height([ij[0] - odd[0], ij[1] - odd[1]]);
        h = mix(h, hb, k1);
        f = [f[0] - odd[0] as f32 * k1, f[1] - odd[1] as f32 * k1];
    }
    if k2 > 0.0 {
        let p = [ij[0] - odd[0], ij[1] - odd[1]];
        let odd2 = [(p[0] >> 1) & 1, (p[1] >> 1) & 1];
        if odd2 != [0, 0] {
            let hb = height([p[0] - 2 * odd2[0], p[1] - 2 * odd2[1]]);
            h = mix(h, hb, k2);
            f = [
                f[0] - 2.0 * odd2[0] as f32 * k2,
                f[1] - 2.0 * odd2[1] as f32 * k2,
            ];
        }
    }
    (f, h)
}

/// GLSL's `mix`.
fn mix(a: f32, b: f32, t: f32) -> f32 {
    a * (1.0 - t) + b * t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::tile_indices;

    #[test]
    fn zones_follow_the_reference_recurrence() {
        let z = morph_zones(|l| 100.0 * (1u64 << l) as f64, 3);
        let r = MORPH_START_RATIO;
        assert_eq!(z[0], [100.0 * r, 100.0]);
        let s1 = z[0][0] + (200.0 - z[0][0]) * r;
        assert!((z[1][0] - s1).abs() < 1e-9 && z[1][1] == 200.0);
        // Each zone starts past the previous one's start and ends at its range.
        for w in z.windows(2) {
            assert!(w[1][0] > w[0][0] && w[1][0] < w[1][1]);
        }
        assert_eq!(morph_k([60.0, 100.0], 50.0), 0.0);
        assert_eq!(morph_k([60.0, 100.0], 80.0), 0.5);
        assert_eq!(morph_k([60.0, 100.0], 150.0), 1.0);
        assert_eq!(morph_k([0.0, 0.0], 150.0), 0.0);
    }

    /// A plane's heights are kept (a morphed vertex stays on it), and at k = 1 every fine
    /// triangle becomes a coarse one or collapses: the node's mesh is the coarser level's.
    #[test]
    fn at_one_the_mesh_is_the_coarser_mesh() {
        let n = 16i32;
        let plane = |ij: [i32; 2]| 3.0 * ij[0] as f32 - 2.0 * ij[1] as f32 + 7.0;
        let idx = tile_indices((n + 1) as u32);
        let m = n / 2 + 1;
        let at = |i: u16| [2 * (i as i32 % m), 2 * (i as i32 / m)];
        let coarse: Vec<[[i32; 2]; 3]> = tile_indices(m as u32)
            .chunks(3)
            .map(|t| [at(t[0]), at(t[1]), at(t[2])])
            .collect();
        for k2 in [0.0, 1.0] {
            let morphed = |i: u16| {
                let ij = [i as i32 % (n + 1), i as i32 / (n + 1)];
                let (f, h) = morph_vertex(ij, 1.0, k2, plane);
                assert!(
                    (h - plane([f[0] as i32, f[1] as i32])).abs() < 1e-4,
                    "{ij:?}"
                );
                [f[0] as i32, f[1] as i32]
            };
            let mut kept = 0;
            for t in idx.chunks(3) {
                let v = [morphed(t[0]), morphed(t[1]), morphed(t[2])];
                let area = (v[1][0] - v[0][0]) * (v[2][1] - v[0][1])
                    - (v[2][0] - v[0][0]) * (v[1][1] - v[0][1]);
                if area == 0 {
                    continue;
                }
                kept += 1;
                if k2 == 0.0 {
                    // A coarse triangle, same winding, as some rotation of its corners.
                    let found = coarse
                        .iter()
                        .any(|c| (0..3).any(|r| [c[r], c[(r + 1) % 3], c[(r + 2) % 3]] == v));
                    assert!(found, "{v:?} is no coarse triangle");
                }
            }
            if k2 == 0.0 {
                assert_eq!(kept, coarse.len());
            } else {
                // Two levels coarser: a quarter of those.
                assert_eq!(kept, coarse.len() / 4);
            }
        }
        // Halfway, an odd vertex sits halfway to its lower-left neighbour, on the edge.
        let (f, h) = morph_vertex([3, 5], 0.5, 0.0, plane);
        assert_eq!(f, [2.5, 4.5]);
        assert!((h - (3.0 * 2.5 - 2.0 * 4.5 + 7.0)).abs() < 1e-5);
        assert_eq!(Morph::NONE.to_gpu(), [0.0; 4]);
    }
}
