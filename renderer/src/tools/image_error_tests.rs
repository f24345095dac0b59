use super::*;
use aerie_terrain::camera::{Attitude, Frustum};
use aerie_terrain::Heightfield;

fn plane(n: usize, spacing: f64, h: f32) -> Dataset {
    Dataset::from_heightfield(
        Heightfield {
            width: n,
            height: n,
            spacing_x: spacing,
            spacing_y: spacing,
            heights: vec![h; n * n],
            geo: None,
            voids_filled: 0,
            spacing_note: String::new(),
        },
        "plane".into(),
    )
}

#[test]
fn histogram_quantiles_within_a_bin() {
    let mut hist = ErrorHistogram::new();
    for k in 0..1000 {
        hist.add(k as f64 / 100.0); // 0 .. 9.99
    }
    hist.add(500.0);
    assert_eq!(hist.count(), 1001);
    assert_eq!(hist.max(), 500.0);
    let p50 = hist.quantile(0.5);
    assert!((p50 - 5.0).abs() <= 1.0 / 256.0 + 1e-12, "{p50}");
    assert_eq!(hist.quantile(1.0), 500.0);
    let p99 = hist.quantile(0.99);
    assert!((p99 - 9.9).abs() <= 1.0 / 256.0 + 0.01, "{p99}");
    let mut other = ErrorHistogram::new();
    other.add(f64::NAN);
    hist.merge(&other);
    assert_eq!(hist.max(), f64::INFINITY);
    // Logarithmic bins: 1 % resolution.
    let mut big = ErrorHistogram::new();
    big.add(100.0);
    big.add(1000.0);
    let q = big.quantile(0.5);
    assert!((100.0..=101.0).contains(&q), "{q}");
    assert_eq!(ErrorHistogram::new().quantile(0.99), 0.0);
}

#[test]
fn true_surface_follows_the_diagonal_and_curvature() {
    let mut ds = plane(5, 10.0, 0.0);
    // One raised north-east corner of the first quad: the SW–NE diagonal gives 5 at its centre.
    let w = ds.hf.width;
    ds.hf.heights[w + 1] = 10.0;
    let s = TrueSurface::new(&ds, DVec3::new(0.0, 0.0, 100.0), false);
    assert!((s.height_at(5.0, 5.0).unwrap() - 5.0).abs() < 1e-12);
    assert!((s.height_at(7.5, 2.5).unwrap() - 2.5).abs() < 1e-12);
    assert!(s.height_at(-1.0, 5.0).is_none());
    assert!(s.height_at(40.0, 40.0).is_some());
    assert!(s.height_at(40.1, 40.0).is_none());
    let curved = TrueSurface::new(&ds, DVec3::new(0.0, 0.0, 100.0), true);
    let drop = (40.0f64 * 40.0) / (2.0 * EARTH_RADIUS_M);
    assert!((curved.height_at(40.0, 0.0).unwrap() + drop).abs() < 1e-12);
}

/// A depth buffer made analytically for a plane drawn 1 m above the true one: the measured
/// error of each pixel is the projected length of that metre, computed here independently.
#[test]
fn measure_finds_a_known_vertical_offset() {
    let ds = plane(257, 10.0, 100.0);
    let (w, h) = (64u32, 36u32);
    let cam = Camera::new(
        DVec3::new(1280.0, 300.0, 400.0),
        Attitude::from_degrees(0.0, -30.0, 0.0),
        Frustum::symmetric(90f64.to_radians(), w, h),
    );
    let drawn_h = 101.0;
    let mut depth = vec![0f32; (w * h) as usize];
    let mut want = vec![f64::NAN; (w * h) as usize];
    for py in 0..h {
        for px in 0..w {
            let ray = cam.pixel_ray(px as f64 + 0.5, py as f64 + 0.5, w, h);
            if ray.z >= 0.0 {
                continue;
            }
            let t = (drawn_h - cam.position.z) / ray.z;
            let p = cam.position + ray * t;
            if p.x < 0.0 || p.y < 0.0 || p.x > 2560.0 || p.y > 2560.0 {
                continue;
            }
            let (a, d) = cam.project_px(p, w, h).unwrap();
            let (b, _) = cam.project_px(DVec3::new(p.x, p.y, 100.0), w, h).unwrap();
            depth[(py * w + px) as usize] = d as f32;
            want[(py * w + px) as usize] = (a - b).length();
        }
    }
    let mut heat = vec![0f32; (w * h) as usize];
    let params = MeasureParams {
        tau_px: 1.0,
        curvature: false,
        hole_search_px: 8,
    };
    let e = measure(&ds, &cam, (w, h), &depth, None, &params, Some(&mut heat));
    let terrain = want.iter().filter(|v| !v.is_nan()).count() as u64;
    assert!(terrain > 500);
    assert_eq!(e.terrain_px, terrain);
    let mut worst = 0.0f64;
    for (got, want) in heat.iter().zip(&want) {
        if want.is_nan() {
            assert!(got.is_nan());
        } else {
            worst = worst.max((*got as f64 - want).abs() / want);
        }
    }
    assert!(worst < 1e-3, "relative error {worst}");
    let max_want = want
        .iter()
        .copied()
        .filter(|v| !v.is_nan())
        .fold(0.0, f64::max);
    assert!((e.max_px() - max_want).abs() < 1e-3 * max_want);
    // A smooth error field: every pixel is confirmed by a neighbour within a few per cent.
    assert_eq!(e.confirmed.count(), e.hist.count());
    assert!(e.confirmed_max_px() > 0.95 * e.max_px() && e.confirmed_max_px() <= e.max_px());
    // A lone spike is capped at its neighbours' level; a pair confirms itself.
    let mut spiky = heat.clone();
    let i = spiky.iter().position(|v| !v.is_nan()).unwrap() + 3 * w as usize;
    spiky[i] = 50.0;
    let mut lone = ImageError::default();
    confirm(&spiky, w, h, 1.0, &mut lone);
    assert!(lone.confirmed_max_px() < 1.0, "{}", lone.confirmed_max_px());
    spiky[i + 1] = 40.0;
    let mut pair = ImageError::default();
    confirm(&spiky, w, h, 1.0, &mut pair);
    assert_eq!(pair.confirmed_max_px(), 40.0);
    // Holes: a reference that has terrain where the frame has sky.
    let reference = vec![0.5f32; (w * h) as usize];
    let e = measure(&ds, &cam, (w, h), &depth, Some(&reference), &params, None);
    assert_eq!(e.holes_px, (w * h) as u64 - terrain);
    assert!(
        e.hole_max_px >= 1.0 && e.hole_max_px <= 8.0,
        "{}",
        e.hole_max_px
    );
    assert_eq!(e.hist.count(), terrain);
}

#[test]
fn heatmap_colours() {
    let img = heatmap_rgba(&[f32::NAN, 0.0, 1.0, 3.0, -1.0], 2.0);
    assert_eq!(&img[0..4], &[0, 0, 0, 255]);
    assert_eq!(&img[4..8], &[20, 30, 120, 255]);
    assert_eq!(&img[12..16], &[255, 0, 255, 255]);
    assert_eq!(&img[16..20], &[0, 255, 255, 255]);
}

/// A node drawn at a coarser level's resolution is measured on that level's surface: one
/// raised odd sample is exact on the level-0 node's own mesh, and the quadrant drawn at its
/// parent's resolution (or the sixteenth at its grandparent's) misses it by the projected
/// height of the bump.
#[test]
fn node_error_is_measured_at_the_resolution_drawn() {
    let mut ds = plane(65, 10.0, 0.0);
    let w = ds.hf.width;
    // Sample (5, 5): odd, so no vertex of the level-1 or level-2 grid.
    ds.hf.heights[5 * w + 5] = 4.0;
    let (vw, vh) = (320u32, 180u32);
    let cam = Camera::new(
        DVec3::new(50.0, -200.0, 150.0),
        Attitude::from_degrees(0.0, -30.0, 0.0),
        Frustum::symmetric(90f64.to_radians(), vw, vh),
    );
    let node = (0, 0, 0);
    let own = node_error_px(&ds, &cam, (vw, vh), 8, node, 0, false, 1);
    let quadrant = node_error_px(&ds, &cam, (vw, vh), 8, node, 1, false, 1);
    let sixteenth = node_error_px(&ds, &cam, (vw, vh), 8, node, 2, false, 1);
    assert_eq!(own, 0.0);
    // The bump's 4 m on screen, independently: its top and its foot projected.
    let top = cam
        .project_px(DVec3::new(50.0, 50.0, 4.0), vw, vh)
        .unwrap()
        .0;
    let foot = cam
        .project_px(DVec3::new(50.0, 50.0, 0.0), vw, vh)
        .unwrap()
        .0;
    let bump = (top - foot).length();
    assert!(bump > 1.0, "{bump}");
    assert!((quadrant - bump).abs() < 1e-9, "{quadrant} vs {bump}");
    assert!((sixteenth - bump).abs() < 1e-9, "{sixteenth} vs {bump}");
}
