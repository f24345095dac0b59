//! The full look on lavapipe with the validation layer on: the land-cover classes the shader
//! draws against their CPU twin on a generated DEM (flat sea, plain, steep wall, high plateau,
//! forested slope, high pasture), the sky the shader draws against the CPU sky model pixel by
//! pixel, aerial perspective that takes distant terrain to exactly the sky's colour, and
//! goldens of the sky (sun up, sun low, night).

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::render::frame::{Lighting, Look, RendererDesc};
use aerie::render::landcover::{class_colour_srgb, class_weights, dominant, Class, CoverInputs};
use aerie::terrain::Heightfield;
use aerie_tests::*;
use glam::DVec3;

const W: u32 = 256;
const H: u32 = 144;

fn camera(pos: [f64; 3], hpr_deg: [f64; 3], fov_deg: f64) -> Camera {
    Camera::new(
        DVec3::from_array(pos),
        Attitude::from_degrees(hpr_deg[0], hpr_deg[1], hpr_deg[2]),
        Frustum::symmetric(fov_deg.to_radians(), W, H),
    )
}

fn srgb8_from_linear(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// Renders each (camera, light) of `hf` with one renderer; validation must stay clean.
fn render_hf(desc: &RendererDesc, hf: &Heightfield, shots: &[(Camera, Lighting)]) -> Vec<Rendered> {
    let (ds, b) = prepare(desc, hf);
    render_lit(desc, &ds, &b, shots)
}

fn sun(az_deg: f64, el_deg: f64) -> Lighting {
    let (az, el) = (az_deg.to_radians(), el_deg.to_radians());
    Lighting::from_host(
        Some([el.cos() * az.sin(), el.cos() * az.cos(), el.sin()]),
        None,
    )
}

const SPACING: f64 = 30.0;
const N: usize = 256;

/// The test landscape, 256 × 256 samples 30 m apart. South half (rows < 128), west to east:
/// sea at 0 m, a plain at 400 m, a 60° wall up to a plateau at 3500 m. North half: a slope of
/// 20° rising east from 600 m to 1800 m, then a flat pasture at 1800 m.
fn landscape_height(col: usize, row: usize) -> f32 {
    if row < 128 {
        match col {
            0..40 => 0.0,
            40..90 => 400.0,
            90..150 => 400.0 + 3100.0 * (col - 90) as f32 / 60.0,
            _ => 3500.0,
        }
    } else {
        let rise = (SPACING * 20f64.to_radians().tan()) as f32;
        (600.0 + rise * col as f32).min(1800.0)
    }
}

fn landscape() -> Heightfield {
    let mut hf = synthetic(N, N, SPACING, 0.0, &[]);
    for row in 0..N {
        for col in 0..N {
            hf.heights[row * N + col] = landscape_height(col, row);
        }
    }
    hf
}

/// The analytic normal of the landscape at an interior sample.
fn landscape_normal(col: usize, row: usize) -> [f32; 3] {
    let dhdx =
        (landscape_height(col + 1, row) - landscape_height(col - 1, row)) / (2.0 * SPACING as f32);
    let len = (dhdx * dhdx + 1.0).sqrt();
    [-dhdx / len, 0.0, 1.0 / len]
}

/// Every region's interior shows the colour of the class the CPU rules give there, in the class
/// view; the rules are jitter-proof at these points, so the shader's noise cannot decide them.
#[test]
fn drawn_classes_match_the_cpu_rules() {
    let mut desc = test_desc(W, H);
    desc.select.curvature = false;
    desc.look = Look::Classes;
    // Straight down from 14 km: the whole landscape in view.
    let cam = camera([3840.0, 3840.0, 14_000.0], [0.0, -90.0, 0.0], 70.0);
    let frames = render_hf(&desc, &landscape(), &[(cam, Lighting::default())]);
    let f = &frames[0];
    write_png_for_review("look_classes", f);
    let points = [
        (20, 64, Class::Water),
        (65, 64, Class::Crops),
        (120, 40, Class::Rock),
        (200, 64, Class::Snow),
        (50, 190, Class::Forest),
        (200, 190, Class::Grass),
    ];
    for (col, row, want) in points {
        let h = landscape_height(col, row);
        let n = landscape_normal(col, row);
        let at = |jitter| {
            class_weights(&CoverInputs {
                height_m: h,
                normal: n,
                jitter,
            })
        };
        let w = at(0.0);
        assert_eq!(dominant(&w), want, "rules at ({col}, {row})");
        assert_eq!(at(-1.0), w, "jitter changes the class at ({col}, {row})");
        assert_eq!(at(1.0), w, "jitter changes the class at ({col}, {row})");
        let expected = class_colour_srgb(&w).map(|c| (c * 255.0).round() as u8);
        let p = DVec3::new(col as f64 * SPACING, row as f64 * SPACING, h as f64);
        let (px, _) = cam.project_px(p, W, H).expect("in front of the camera");
        let (x, y) = (px.x as u32, px.y as u32);
        assert!(x < W && y < H, "({col}, {row}) projects off screen: {px}");
        assert!(f.depth[(y * W + x) as usize] > 0.0, "no terrain at {x},{y}");
        let got = &f.rgba[((y * W + x) * 4) as usize..][..3];
        for c in 0..3 {
            assert!(
                got[c].abs_diff(expected[c]) <= 2,
                "{want:?} at ({col}, {row}) → pixel {x},{y}: {got:?}, rules say {expected:?}"
            );
        }
    }
    // Borders blend: along the sea-to-plateau row some pixels lie between two class colours.
    let row_y = cam
        .project_px(DVec3::new(3000.0, 64.0 * SPACING, 2000.0), W, H)
        .unwrap()
        .0
        .y as u32;
    let palette: Vec<[u8; 3]> = aerie::render::landcover::CLASS_ALBEDO_SRGB
        .iter()
        .map(|c| c.map(|v| (v * 255.0).round() as u8))
        .collect();
    let blended = (0..W)
        .filter(|&x| f.depth[(row_y * W + x) as usize] > 0.0)
        .filter(|&x| {
            let p = &f.rgba[((row_y * W + x) * 4) as usize..][..3];
            palette
                .iter()
                .all(|c| (0..3).any(|k| c[k].abs_diff(p[k]) > 3))
        })
        .count();
    assert!(blended > 0, "no blended pixel along row {row_y}");
}

/// The landscape in the full look from the south-west, sun in the south: sea with the sky's
/// reflection, fields, forest, cliffs, snow (a golden; `target/test-output` for review).
#[test]
fn landscape_in_the_full_look_matches_golden_image() {
    let mut desc = test_desc(W, H);
    desc.select.curvature = false;
    let cam = camera([-1500.0, 1900.0, 900.0], [80.0, 2.0, 0.0], 80.0);
    let frames = render_hf(&desc, &landscape(), &[(cam, sun(230.0, 25.0))]);
    let f = &frames[0];
    write_png_for_review("look_landscape", f);
    let sky = f.depth.iter().filter(|&&d| d == 0.0).count();
    assert!(sky > 0 && sky < f.depth.len() / 2, "{sky} sky pixels");
    check_golden("look_landscape_256x144", f, GOLDEN_TOLERANCE);
}

fn write_png_for_review(name: &str, f: &Rendered) {
    let path = test_output_dir().join(format!("{name}.png"));
    aerie::tools::output::write_png(&path, f.width, f.height, &f.rgba).unwrap();
}

/// Every sky pixel is the CPU model's colour for that pixel's view ray (away from the sun's
/// disc), with the sun up, low and below the horizon; the terrain pass left the terrain alone.
#[test]
fn drawn_sky_matches_the_cpu_model() {
    let mut desc = test_desc(W, H);
    desc.select.curvature = false;
    let hf = synthetic(129, 129, 30.0, 200.0, &[(40, 40, 60, 60, 900.0)]);
    let cams = [
        camera([1920.0, -2000.0, 600.0], [10.0, 15.0, 0.0], 90.0),
        camera([1920.0, -2000.0, 600.0], [260.0, 5.0, 5.0], 90.0),
        camera([1920.0, -2000.0, 600.0], [0.0, 30.0, 0.0], 60.0),
    ];
    let shots = [
        (cams[0], sun(200.0, 35.0)),
        (cams[1], sun(250.0, 3.0)),
        (cams[2], sun(90.0, -20.0)),
    ];
    let frames = render_hf(&desc, &hf, &shots);
    for ((cam, light), f) in shots.iter().zip(&frames) {
        let atmos = light.atmosphere();
        let s = light.sun_enu.map(f64::from);
        let sun_dir = DVec3::new(s[0], s[1], s[2]);
        let (mut checked, mut worst) = (0, 0u8);
        for y in 0..H {
            for x in 0..W {
                let i = (y * W + x) as usize;
                if f.depth[i] != 0.0 {
                    continue;
                }
                let dir = cam.pixel_ray(x as f64 + 0.5, y as f64 + 0.5, W, H);
                if dir.dot(sun_dir) > 1.0f64.to_radians().cos() {
                    continue; // the disc
                }
                let want = atmos
                    .sky_radiance([dir.x as f32, dir.y as f32, dir.z as f32])
                    .map(srgb8_from_linear);
                let got = &f.rgba[i * 4..][..3];
                for c in 0..3 {
                    worst = worst.max(got[c].abs_diff(want[c]));
                }
                checked += 1;
            }
        }
        assert!(checked > (W * H / 3) as usize, "only {checked} sky pixels");
        assert!(worst <= 3, "sky differs from the CPU model by {worst}/255");
    }
    // The low sun's disc shows where the sun is, brighter than the sky model there.
    let (cam, light) = &shots[1];
    let s = light.sun_enu.map(f64::from);
    let toward = cam.position + DVec3::new(s[0], s[1], s[2]) * 1e4;
    let (p, _) = cam.project_px(toward, W, H).expect("the sun is ahead");
    let (x, y) = (p.x as u32, p.y as u32);
    assert!(x < W && y < H, "the sun is off screen at {p}");
    let i = (y * W + x) as usize;
    let disc = &frames[1].rgba[i * 4..][..3];
    let dir = cam.pixel_ray(x as f64 + 0.5, y as f64 + 0.5, W, H);
    let around = light
        .atmosphere()
        .sky_radiance([dir.x as f32, dir.y as f32, dir.z as f32])
        .map(srgb8_from_linear);
    let sum = |c: &[u8]| c.iter().map(|&v| u32::from(v)).sum::<u32>();
    assert!(
        disc[0] >= 250 && sum(disc) > sum(&around) + 30,
        "sun disc {disc:?}, sky there {around:?}"
    );
    let night = &frames[2];
    let sky_mean = mean_where(night, |d| d == 0.0);
    assert!(sky_mean < 12.0, "the night sky is dark: {sky_mean}");
    check_golden("look_sky_day_256x144", &frames[0], GOLDEN_TOLERANCE);
    check_golden("look_sky_low_sun_256x144", &frames[1], GOLDEN_TOLERANCE);
    check_golden("look_sky_night_256x144", &frames[2], GOLDEN_TOLERANCE);
}

fn mean_where(f: &Rendered, keep: impl Fn(f32) -> bool) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for (i, &d) in f.depth.iter().enumerate() {
        if keep(d) {
            sum += f.rgba[i * 4..][..3].iter().map(|&v| v as f64).sum::<f64>() / 3.0;
            n += 1;
        }
    }
    sum / n.max(1) as f64
}

/// Aerial perspective: every terrain pixel lies between its own colour and the sky's in its
/// direction by the CPU transmittance (|pixel − sky| ≤ 255·T), so in a 2 km visibility the
/// terrain kilometres away has the sky's colour (the horizon blends), while terrain near the
/// eye keeps its own.
#[test]
fn distant_terrain_fades_into_the_sky() {
    let mut desc = test_desc(W, H);
    desc.select.curvature = false;
    // 15 km of flat pasture at 1000 m.
    let hf = synthetic(257, 257, 60.0, 1000.0, &[]);
    let horizon = camera([7680.0, 100.0, 1030.0], [0.0, 0.0, 0.0], 20.0);
    let ground = camera([7680.0, 100.0, 1030.0], [0.0, -30.0, 0.0], 60.0);
    let light = Lighting::from_host(None, Some(2_000.0));
    let frames = render_hf(&desc, &hf, &[(horizon, light), (ground, light)]);
    let atmos = light.atmosphere();
    let (mut far, mut near) = (0, 0);
    for (cam, f) in [horizon, ground].iter().zip(&frames) {
        for y in 0..H {
            for x in 0..W {
                let i = (y * W + x) as usize;
                if f.depth[i] == 0.0 {
                    continue;
                }
                let dir = cam.pixel_ray(x as f64 + 0.5, y as f64 + 0.5, W, H);
                let dist = ((1000.0 - cam.position.z) / dir.z * dir.length()) as f32;
                let tr = atmos.transmittance(1030.0, 1000.0, dist);
                let sky = atmos
                    .sky_radiance([dir.x as f32, dir.y as f32, dir.z as f32])
                    .map(srgb8_from_linear);
                let got = &f.rgba[i * 4..][..3];
                let diff = (0..3).map(|c| got[c].abs_diff(sky[c])).max().unwrap();
                let allowed = 3.0 + 255.0 * tr;
                assert!(
                    f32::from(diff) <= allowed,
                    "pixel {x},{y} at {dist:.0} m (T = {tr:.3}): {got:?} vs sky {sky:?}"
                );
                if tr < 0.01 {
                    far += 1;
                } else if tr > 0.9 {
                    assert!(diff > 20, "pixel {x},{y} at {dist:.0} m looks like the sky");
                    near += 1;
                }
            }
        }
    }
    assert!(far > 200 && near > 200, "far {far}, near {near}");
}
