//! Headless renders on lavapipe with the validation layer on: golden image of a real DEM,
//! the rendered depth against an f64 ray-cast oracle (camera math + reversed-Z), depth ordering,
//! and uploads split across submissions by the staging budget.

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::render::frame::{Look, RendererDesc, TerrainRenderer, SKY_LINEAR};
use aerie::terrain::load_dem;
use aerie::terrain::select::{LodMode, SelectParams};
use aerie_tests::*;
use glam::DVec3;

const W: u32 = 320;
const H: u32 = 180;

fn camera(pos: [f64; 3], hpr_deg: [f64; 3], fov_deg: f64) -> Camera {
    Camera::new(
        DVec3::from_array(pos),
        Attitude::from_degrees(hpr_deg[0], hpr_deg[1], hpr_deg[2]),
        Frustum::symmetric(fov_deg.to_radians(), W, H),
    )
}

fn linear_to_srgb8(c: f32) -> u8 {
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// South of Innsbruck above the Wipptal, looking north across the Inn valley at the
/// Nordkette (Karwendel); the valley floor is 1800 m below the range.
fn inn_camera() -> Camera {
    camera([30500.0, 12000.0, 4500.0], [0.0, -15.0, 0.0], 90.0)
}

fn desc_with(mode: LodMode, tau: f64) -> RendererDesc {
    let mut d = test_desc(W, H);
    d.select = SelectParams {
        mode,
        tau_px: tau,
        ..SelectParams::default()
    };
    if mode == LodMode::Full {
        d.pool_capacity = [1024, 512, 256, 128, 48, 16];
        d.select.max_refinement = 6;
    }
    d
}

#[test]
fn inn_valley_matches_golden_image() {
    let hf = load_dem(&demo_dem()).expect("demo DEM loads");
    let frames = render_frames(&desc_with(LodMode::Bounded, 1.0), &hf, &[inn_camera()]);
    let f = &frames[0];
    let s = f.stats;
    assert!(s.tiles_culled > 0 && s.tiles_drawn > 0, "{s:?}");
    assert_eq!(s.tiles_drawn + s.tiles_culled, s.tiles_considered);
    assert_eq!(s.tiles_by_refinement.iter().sum::<u32>(), s.tiles_drawn);
    assert!(
        s.tiles_by_refinement[0] < s.tiles_drawn,
        "τ = 1 px refines some tiles"
    );
    assert_eq!((s.draw_calls, s.tiles_late, s.tiles_unbounded), (1, 0, 0));
    // Terrain fills the lower part of the view, sky the top row.
    let sky = f.depth[..W as usize].iter().filter(|&&d| d == 0.0).count();
    let ground = f.depth[((H - 1) * W) as usize..]
        .iter()
        .filter(|&&d| d > 0.0)
        .count();
    assert_eq!(sky, W as usize, "top row should be sky");
    assert_eq!(ground, W as usize, "bottom row should be terrain");
    check_golden("inn_valley_320x180", f, GOLDEN_TOLERANCE);
}

#[test]
fn debug_tiles_view_matches_golden_image() {
    let hf = load_dem(&demo_dem()).expect("demo DEM loads");
    let mut desc = desc_with(LodMode::Bounded, 1.0);
    desc.debug_tiles = true;
    let frames = render_frames(&desc, &hf, &[inn_camera()]);
    check_golden(
        "inn_valley_debug_tiles_320x180",
        &frames[0],
        GOLDEN_TOLERANCE,
    );
}

/// At τ = 0.5 px the error-bounded clipmap and brute force (every tile at full resolution)
/// draw the same picture, with far fewer triangles.
#[test]
fn bounded_at_half_pixel_looks_like_brute_force() {
    let hf = load_dem(&demo_dem()).expect("demo DEM loads");
    let cam = inn_camera();
    let full = render_frames(&desc_with(LodMode::Full, 0.5), &hf, &[cam]);
    let bounded = render_frames(&desc_with(LodMode::Bounded, 0.5), &hf, &[cam]);
    let plain = render_frames(&desc_with(LodMode::Clipmap, 0.5), &hf, &[cam]);
    let (f, b, p) = (&full[0], &bounded[0], &plain[0]);
    assert!(
        b.stats.triangles < f.stats.triangles,
        "{} vs {}",
        b.stats.triangles,
        f.stats.triangles
    );
    let d_bounded = diff_images(&b.rgba, &f.rgba, 16);
    let d_plain = diff_images(&p.rgba, &f.rgba, 16);
    let out = test_output_dir();
    for (name, img) in [("full", f), ("bounded", b), ("clipmap", p)] {
        aerie::tools::output::write_png(&out.join(format!("tau_half_{name}.png")), W, H, &img.rgba)
            .unwrap();
    }
    assert!(
        d_bounded.fraction_over <= 0.01 && d_bounded.mean <= 1.0,
        "bounded vs brute force: {d_bounded:?}"
    );
    // The comparison can tell: plain clipmaps (no refinement) differ visibly.
    assert!(
        d_plain.mean > d_bounded.mean,
        "plain {d_plain:?} vs bounded {d_bounded:?}"
    );
}

/// A pool packed several slots to a layer (`render/pool_atlas.rs`: more slots than the
/// device's layers) draws exactly what one slot a layer draws: every refined node reads its
/// own slot's samples, its normals' neighbours clamped into the slot's cell. Brute force
/// refines every tile (pools r = 1..6), bounded at τ = 0.5 px some; 48 layers pack the four
/// biggest pools (1024 slots: 5 × 5 to a layer).
#[test]
fn pools_packed_several_slots_to_a_layer_draw_the_same_image() {
    let hf = load_dem(&demo_dem()).expect("demo DEM loads");
    let cam = inn_camera();
    for mode in [LodMode::Full, LodMode::Bounded] {
        let one = desc_with(mode, 0.5);
        let mut packed = one.clone();
        packed.pool_layers = Some(48);
        let a = &render_frames(&one, &hf, &[cam])[0];
        let b = &render_frames(&packed, &hf, &[cam])[0];
        assert!(
            a.stats.tiles_by_refinement[1..].iter().sum::<u32>() > 0,
            "{mode:?} refines tiles: {:?}",
            a.stats.tiles_by_refinement
        );
        assert_eq!(a.stats.tiles_late, 0);
        assert_eq!(
            (a.stats.triangles, a.stats.tiles_by_refinement),
            (b.stats.triangles, b.stats.tiles_by_refinement)
        );
        let differ = a.rgba.iter().zip(&b.rgba).filter(|(x, y)| x != y).count();
        assert_eq!(differ, 0, "{mode:?}: {differ} bytes differ");
        assert!(a.depth == b.depth, "{mode:?}: the depth differs");
    }
}

/// Every pixel of a flat plane: the GPU's depth equals the f64 oracle's (ray through the pixel
/// centre, intersected with the plane, projected with the reversed-Z infinite projection).
#[test]
fn flat_plane_depth_matches_f64_ray_cast() {
    let plane_h = 250.0f32;
    let hf = synthetic(257, 257, 20.0, plane_h, &[]);
    let cams = [
        camera([2571.0, 300.0, 400.0], [10.0, -20.0, 0.0], 90.0),
        camera([1000.0, 4000.0, 1250.0], [135.0, -35.0, 25.0], 60.0),
    ];
    let mut desc = test_desc(W, H);
    desc.select.curvature = false;
    // The plain look clears the sky to one colour (the full look's sky: tests/look.rs).
    desc.look = Look::Plain;
    let frames = render_frames(&desc, &hf, &cams);
    for (cam, f) in cams.iter().zip(&frames) {
        let (ex, ey) = hf.extent_m();
        let mut checked = 0;
        let mut sky = 0;
        for py in 0..H {
            for px in 0..W {
                let gpu = f.depth[(py * W + px) as usize];
                let dir = cam.pixel_ray(px as f64 + 0.5, py as f64 + 0.5, W, H);
                let t = (plane_h as f64 - cam.position.z) / dir.z;
                if dir.z >= 0.0 {
                    assert_eq!(gpu, 0.0, "pixel {px},{py} looks up but has depth");
                    sky += 1;
                    continue;
                }
                let p = cam.position + dir * t;
                // Skip pixels within a metre of the plane's edge (partial coverage).
                if p.x < 1.0 || p.y < 1.0 || p.x > ex - 1.0 || p.y > ey - 1.0 {
                    continue;
                }
                let (_, depth) = cam.project_px(p, W, H).expect("in front");
                let rel = (gpu as f64 - depth).abs() / depth;
                assert!(
                    rel < 2e-3,
                    "pixel {px},{py}: GPU depth {gpu} vs oracle {depth} (rel {rel:.2e})"
                );
                checked += 1;
            }
        }
        assert!(
            checked > (W * H / 4) as usize,
            "only {checked} pixels checked"
        );
        assert!(sky > 0 || cam.attitude.pitch < -0.5);
    }
    // The sky is cleared to the documented colour.
    let f = &frames[0];
    let px = &f.rgba[..4];
    let want = SKY_LINEAR.map(linear_to_srgb8);
    for c in 0..3 {
        assert!(px[c].abs_diff(want[c]) <= 1, "sky {px:?} vs {want:?}");
    }
}

/// Reversed-Z: a tower in front of the ground hides it (GREATER keeps the nearer surface), and
/// the stored depth is the tower's, not the ground's behind it.
#[test]
fn nearer_surface_wins_with_reversed_z() {
    // Flat ground at 0 with a 200 m block over samples 60..=68 in both directions (10 m spacing).
    let hf = synthetic(129, 129, 10.0, 0.0, &[(60, 60, 68, 68, 200.0)]);
    let cam = camera([640.0, 100.0, 150.0], [0.0, -5.0, 0.0], 60.0);
    let mut desc = test_desc(W, H);
    desc.select.curvature = false;
    let frames = render_frames(&desc, &hf, &[cam]);
    let f = &frames[0];
    // A point on the tower's south face (sloped from y=590 at z=0 to y=600 at z=200).
    let face = DVec3::new(640.0, 595.0, 100.0);
    let (pix, face_depth) = cam.project_px(face, W, H).unwrap();
    let (px, py) = (pix.x as u32, pix.y as u32);
    let gpu = f.depth[(py * W + px) as usize] as f64;
    // The ground behind the face along the same ray.
    let dir = cam.pixel_ray(px as f64 + 0.5, py as f64 + 0.5, W, H);
    let ground = cam.position + dir * (-cam.position.z / dir.z);
    let (_, ground_depth) = cam.project_px(ground, W, H).unwrap();
    assert!(ground_depth < face_depth, "ground must be farther");
    assert!(
        (gpu - face_depth).abs() / face_depth < 0.05,
        "depth at the tower face {gpu} vs oracle {face_depth} (ground {ground_depth})"
    );
    // Far less than the ground: the occluded surface did not overwrite the nearer one.
    assert!(gpu > ground_depth * 1.2);
}

/// With curvature on, a flat plane drops by d²/2R: every pixel's depth matches an f64 ray cast
/// against the curved surface (the horizon sinks: pixels just below it see sky without curvature
/// checks would fail by hundreds of metres at 50 km).
#[test]
fn curvature_drop_matches_f64_ray_cast() {
    let hf = synthetic(1025, 1025, 100.0, 0.0, &[]);
    let cam = camera([51200.0, 2000.0, 300.0], [0.0, -1.0, 0.0], 60.0);
    let frames = render_frames(&test_desc(W, H), &hf, &[cam]);
    let f = &frames[0];
    let r = aerie::terrain::select::EARTH_RADIUS_M;
    let (mut checked, mut sky) = (0, 0);
    for py in 0..H {
        for px in 0..W {
            let gpu = f.depth[(py * W + px) as usize] as f64;
            let dir = cam.pixel_ray(px as f64 + 0.5, py as f64 + 0.5, W, H);
            // eye.z + t·dz = −(t·|dxy|)²/2R  →  a t² + dz t + eye.z = 0
            let a = dir.truncate().length_squared() / (2.0 * r);
            let disc = dir.z * dir.z - 4.0 * a * cam.position.z;
            if disc < 0.0 {
                sky += 1;
                assert_eq!(
                    gpu, 0.0,
                    "pixel {px},{py} misses the curved plane but has depth"
                );
                continue;
            }
            let t = (-dir.z - disc.sqrt()) / (2.0 * a);
            let p = cam.position + dir * t;
            if p.x < 200.0 || p.y < 200.0 || p.x > 102_200.0 || p.y > 102_200.0 {
                continue;
            }
            let (_, depth) = cam.project_px(p, W, H).expect("in front");
            let rel = (gpu - depth).abs() / depth;
            assert!(
                rel < 0.02,
                "pixel {px},{py}: GPU depth {gpu} vs oracle {depth} at {p:?}"
            );
            checked += 1;
        }
    }
    assert!(
        sky > 0 && checked > (W * H / 4) as usize,
        "{sky} sky, {checked} checked"
    );
}

/// A dataset whose first fill is larger than the per-frame staging budget is uploaded over
/// several submissions and renders exactly like a single-submission upload.
#[test]
fn upload_split_by_staging_budget_renders_identically() {
    let mut hf = synthetic(256, 256, 15.0, 0.0, &[]);
    for r in 0..256 {
        for c in 0..256 {
            hf.heights[r * 256 + c] =
                300.0 + 120.0 * ((c as f32 * 0.07).sin() + (r as f32 * 0.05).cos());
        }
    }
    let cam = camera([1900.0, -300.0, 900.0], [20.0, -25.0, 0.0], 80.0);
    let mut images = Vec::new();
    let mut submissions = Vec::new();
    for budget in [8u64 << 20, 64 << 10] {
        let mut desc = desc_with(LodMode::Clipmap, 1.0);
        desc.staging_budget = budget;
        let (ds, b) = prepare(&desc, &hf);
        let mut r = TerrainRenderer::new(&desc).unwrap();
        let up = r.load_terrain(ds, b, cam.position).unwrap();
        submissions.push(up.submissions);
        let stats = r.render(&cam).unwrap();
        assert!(stats.bytes_uploaded > 0 && stats.bytes_uploaded <= budget);
        images.push(r.colour_rgba());
        let counters = r.validation_counters();
        r.destroy();
        assert_validation_clean(&counters);
    }
    assert_eq!(submissions[0], 1);
    assert!(submissions[1] > 1, "{submissions:?}");
    assert!(
        images[0].chunks(4).any(|p| p[0] != images[0][0]),
        "image is blank"
    );
    assert_eq!(images[0], images[1], "chunked upload changed the image");
}

#[test]
fn misuse_is_an_error_not_a_crash() {
    let desc = test_desc(64, 32);
    let mut r = TerrainRenderer::new(&desc).unwrap();
    let cam = camera([0.0, 0.0, 100.0], [0.0, 0.0, 0.0], 90.0);
    let err = r.render(&cam).unwrap_err().to_string();
    assert!(err.contains("before load_terrain"), "{err}");
    // A bake made for another tile size is refused with the fix.
    let hf = synthetic(65, 65, 10.0, 0.0, &[]);
    let (ds, _) = prepare(&desc, &hf);
    let other = aerie::terrain::bake::bake(
        &ds,
        aerie::terrain::bake::BakeParams {
            tile_size: 9,
            levels: 0,
        },
        &|_, _| {},
    );
    let err = r
        .load_terrain(ds, std::sync::Arc::new(other), cam.position)
        .unwrap_err()
        .to_string();
    assert!(err.contains("re-bake"), "{err}");
    let c = r.validation_counters();
    r.destroy();
    assert_validation_clean(&c);
    // Zero-sized target refused.
    let err = TerrainRenderer::new(&test_desc(0, 10))
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("0x10"), "{err}");
}

/// A selection whose instance records would crowd the staging region out (many small nodes:
/// tiles of 9 at τ = 0.25 px, a region of 512 KiB) grows the region once instead of leaving
/// every refined tile late: after the start-up frames nothing is late and the image is the
/// one an ample region draws.
#[test]
fn instance_records_that_crowd_the_staging_region_grow_it() {
    let hf = load_dem(&demo_dem()).expect("demo DEM loads");
    let cam = inn_camera();
    let mut results = Vec::new();
    for budget in [64u64 << 20, 512 << 10] {
        let mut desc = desc_with(LodMode::Bounded, 0.25);
        desc.tile_size = 9;
        desc.staging_budget = budget;
        let (ds, b) = prepare(&desc, &hf);
        let mut r = TerrainRenderer::new(&desc).unwrap();
        r.load_terrain(ds, b, cam.position).unwrap();
        let mut stats = Vec::new();
        for _ in 0..6 {
            stats.push(r.render(&cam).unwrap());
        }
        results.push((stats, r.staging_region(), r.colour_rgba()));
        let counters = r.validation_counters();
        r.destroy();
        assert_validation_clean(&counters);
    }
    let (ample, small) = (&results[0], &results[1]);
    let last = &small.0[5];
    // The selection's records alone take more than half of 512 KiB: without growing, no pool
    // upload fits and the frame draws coarse ancestors (90 tiles late every frame).
    let records = ample.0[5].instances as u64
        * std::mem::size_of::<aerie::render::gpu::TileInstance>() as u64;
    assert!(records > 256 << 10, "{records} bytes of records");
    assert_eq!(ample.1, (64 << 20, 0), "an ample region never grows");
    assert!(small.1 .0 > 512 << 10 && small.1 .1 >= 1, "{:?}", small.1);
    assert_eq!(
        last.tiles_late,
        0,
        "{:?}",
        small.0.iter().map(|s| s.tiles_late).collect::<Vec<_>>()
    );
    assert_eq!(last.triangles, ample.0[5].triangles);
    assert!(
        small.2 == ample.2,
        "the grown region draws the ample region's image"
    );
}
