//! Numerical stress tests (issue 5): assertions, no timings.
//!
//! - World origin offsets 0, 1e5, 1e6, 1e7 m: the screen position of fixed terrain features,
//!   computed the way the vertex shader does (f32 node origin relative to the eye, f32 vertex
//!   offsets, f32 matrix), moves < 1/8 px between offsets and stays within 1/8 px of the f64
//!   reference.
//! - Extreme cameras (0.5 m above ground to 50 km, pitch ±90°, roll 180°, heading wrap
//!   359.99° → 0.01°): finite matrices, selections whose nodes cover the visible ground exactly
//!   once, validation-clean GPU renders with terrain where it must be.
//! - A 100,000-frame CPU-only flight (clipmap placement and caches, selection, refined-tile
//!   pools): patches snapped, nested and centred, caches holding their patch, pools within
//!   capacity, no growth of the per-frame buffers after warm-up.
//! - τ 0.1 px and 100 px, viewports 1×1 and 16384² (selection) / 1×1 and 16384×1 (GPU; a
//!   16385-pixel target is refused naming the limit), FOV 1° and 170°.
//! - Depth: surfaces 0.5 m apart at 50 km stay ordered (reversed-Z), in the shader's f32 math
//!   and on the GPU.

use std::sync::{Arc, OnceLock};

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::render::frame::TerrainRenderer;
use aerie::terrain::bake::{bake, BakeParams, ErrorBake};
use aerie::terrain::clipmap::{place_levels, update_cache, CacheRegion, ClipmapDesc};
use aerie::terrain::dataset::Dataset;
use aerie::terrain::gen::{generate, DemKind, GenParams, FLAT_HEIGHT};
use aerie::terrain::pool::{RefinedTilePool, Request, TileKey};
use aerie::terrain::select::{select_tiles, LodMode, SelectParams, Selection, EARTH_RADIUS_M};
use aerie::terrain::Heightfield;
use aerie::tools::image_error::TrueSurface;
use aerie_tests::*;
use glam::{DVec2, DVec3, Mat4, Vec2, Vec3};

const M: u32 = 17;
const Q: u32 = M - 1;
const W: u32 = 320;
const H: u32 = 180;
/// Generated scene: 513² samples at 25 m (12.8 km): south-west ridged, south-east cliffs,
/// north-west spikes, north-east flat.
const N: usize = 513;
const SPACING: f64 = 25.0;

struct Scene {
    ds: Arc<Dataset>,
    bake: Arc<ErrorBake>,
    clip: ClipmapDesc,
}

fn scene() -> &'static Scene {
    static SCENE: OnceLock<Scene> = OnceLock::new();
    SCENE.get_or_init(|| {
        let hf = generate(&GenParams {
            size: N,
            spacing: SPACING,
            kind: DemKind::Mixed,
            seed: 5,
        });
        let ds = Dataset::from_heightfield(hf, "mixed".into());
        let b = bake(
            &ds,
            BakeParams {
                tile_size: M,
                levels: 0,
            },
            &|_, _| {},
        );
        let clip = ClipmapDesc {
            tile_quads: Q,
            patch_tiles: 8,
            margin_tiles: 2,
            width: ds.hf.width as u32,
            height: ds.hf.height as u32,
        };
        Scene {
            ds: Arc::new(ds),
            bake: Arc::new(b),
            clip,
        }
    })
}

fn camera(pos: DVec3, hpr: [f64; 3], fov_deg: f64, w: u32, h: u32) -> Camera {
    Camera::new(
        pos,
        Attitude::from_degrees(hpr[0], hpr[1], hpr[2]),
        Frustum::symmetric(fov_deg.to_radians(), w, h),
    )
}

/// The drawn full-resolution surface (what `full` draws) under (x, y), curvature on.
fn ground(s: &Scene, eye: DVec3, x: f64, y: f64) -> f64 {
    TrueSurface::new(&s.ds, eye, true)
        .height_at(x, y)
        .expect("inside the dataset")
}

fn select(
    s: &Scene,
    cam: &Camera,
    viewport: (u32, u32),
    params: &SelectParams,
    sel: &mut Selection,
) {
    let hf = &s.ds.hf;
    let viewer = [cam.position.x / hf.spacing_x, cam.position.y / hf.spacing_y];
    let placements = place_levels(&s.clip, viewer);
    select_tiles(&s.bake, &s.clip, &placements, cam, viewport, params, sel);
}

fn drop(eye: DVec3, x: f64, y: f64) -> f64 {
    (DVec2::new(x, y) - eye.truncate()).length_squared() / (2.0 * EARTH_RADIUS_M)
}

/// Selection validity: nodes inside their ring tile, finite ε, ρ above τ exactly for the
/// unbounded count, no level-0 cell drawn twice, every cell whose ground projects inside the
/// viewport drawn.
fn check_selection(
    s: &Scene,
    cam: &Camera,
    viewport: (u32, u32),
    params: &SelectParams,
    sel: &Selection,
    what: &str,
) {
    let hf = &s.ds.hf;
    for it in &sel.items {
        // Within its ring tile's refinement, or (`SelectParams::seen_quadrants`) a quadrant or
        // sixteenth of an unrefined ring tile drawn at the tile's resolution.
        let up = it.morph.levels_up();
        let seen_quadrant = it.refinement == 0 && up >= 1 && it.node_level + up == it.level;
        assert!(
            it.node_level <= it.level
                && (it.level - it.node_level <= it.refinement || seen_quadrant),
            "{what}: {it:?}"
        );
        let up = it.level - it.node_level;
        assert_eq!(
            (it.node_tx >> up, it.node_ty >> up),
            (it.tx, it.ty),
            "{what}: node outside its tile {it:?}"
        );
        assert!(it.eps_m.is_finite() && it.eps_m >= 0.0, "{what}: {it:?}");
        assert!(!it.rho_px.is_nan(), "{what}: {it:?}");
    }
    if params.mode == LodMode::Bounded {
        // ρ is stored as f32: compare with τ up to its rounding.
        let above = |k: f64| {
            sel.items
                .iter()
                .filter(|i| i.rho_px as f64 > params.tau_px * k)
                .count() as u32
        };
        assert!(
            above(1.0 + 1e-6) <= sel.unbounded && sel.unbounded <= above(1.0 - 1e-6),
            "{what}: {} nodes above τ, {} unbounded",
            above(1.0),
            sel.unbounded
        );
    }
    let cells_x = hf.width - 1;
    let mut count = vec![0u8; cells_x * (hf.height - 1)];
    for it in &sel.items {
        let side = (Q as usize) << it.node_level;
        let (c0, r0) = (it.node_tx as usize * side, it.node_ty as usize * side);
        for row in r0..(r0 + side).min(hf.height - 1) {
            for c in c0..(c0 + side).min(cells_x) {
                count[row * cells_x + c] += 1;
            }
        }
    }
    assert!(count.iter().all(|&n| n <= 1), "{what}: overlapping nodes");
    let (w, h) = viewport;
    for row in 0..hf.height - 1 {
        for c in 0..cells_x {
            let (x, y) = ((c as f64 + 0.5) * SPACING, (row as f64 + 0.5) * SPACING);
            let z = hf.height_at_m(x, y) - drop(cam.position, x, y);
            let Some((p, _)) = cam.project_px(DVec3::new(x, y, z), w, h) else {
                continue;
            };
            if p.x >= 0.0 && p.x <= w as f64 && p.y >= 0.0 && p.y <= h as f64 {
                assert_eq!(
                    count[row * cells_x + c],
                    1,
                    "{what}: visible cell ({c}, {row}) is not drawn"
                );
            }
        }
    }
}

fn assert_finite_matrices(cam: &Camera, what: &str) {
    let v = cam.world_to_view();
    let p = cam.view_to_clip();
    let m = cam.relative_world_to_clip_f32();
    assert!(
        v.to_cols_array().iter().all(|x| x.is_finite()),
        "{what}: {v:?}"
    );
    assert!(
        p.to_cols_array().iter().all(|x| x.is_finite()),
        "{what}: {p:?}"
    );
    assert!(
        m.to_cols_array().iter().all(|x| x.is_finite()),
        "{what}: {m:?}"
    );
    let r = cam.world_to_view_rotation();
    let i = r * r.transpose();
    let err = (i - glam::DMat3::IDENTITY)
        .to_cols_array()
        .iter()
        .fold(0.0f64, |a, &b| a.max(b.abs()));
    assert!(err < 1e-12, "{what}: rotation not orthonormal ({err})");
}

/// The vertex shader's position (shaders/terrain.vert): `origin_rel` = f32(node origin − eye)
/// computed in f64, `xy = origin_rel + ij·step·spacing` and `z = h − f32(eye z) − c·|xy|²` in
/// f32, then the f32 camera-relative matrix, the divide and the viewport. Pixel (x, y), depth.
#[allow(clippy::too_many_arguments)]
fn shader_px(
    cam: &Camera,
    m: &Mat4,
    node_origin: DVec2,
    ij: (u32, u32),
    step: u32,
    h: f32,
    curvature: bool,
    (w, hgt): (u32, u32),
) -> (DVec2, f32) {
    let origin_rel = Vec2::new(
        (node_origin.x - cam.position.x) as f32,
        (node_origin.y - cam.position.y) as f32,
    );
    let xy = origin_rel + Vec2::new(ij.0 as f32, ij.1 as f32) * step as f32 * SPACING as f32;
    let c = if curvature {
        (1.0 / (2.0 * EARTH_RADIUS_M)) as f32
    } else {
        0.0
    };
    let z = h - cam.position.z as f32 - c * xy.dot(xy);
    let clip = *m * Vec3::new(xy.x, xy.y, z).extend(1.0);
    let ndc = clip.truncate() / clip.w;
    let px = (ndc.x + 1.0) * 0.5 * w as f32;
    let py = (ndc.y + 1.0) * 0.5 * hgt as f32;
    (DVec2::new(px as f64, py as f64), ndc.z)
}

#[test]
fn origin_offsets_move_features_less_than_an_eighth_of_a_pixel() {
    let size = (1920u32, 1080u32);
    // Not dyadic: the f64 eye of each offset rounds differently.
    let local_eye = DVec3::new(1234.567, 987.123, 1500.3);
    let att = [211.0, -4.0, 9.0];
    // Features: (distance m, a, b) in the view's tan space, heights from a smooth function.
    let mut features = Vec::new();
    for dist in [2.0, 10.0, 150.0, 1_000.0, 8_000.0, 30_000.0, 50_000.0] {
        for (ta, tb) in [(0.5, 0.5), (0.02, 0.97), (0.97, 0.05), (0.3, 0.8)] {
            features.push((dist, ta, tb));
        }
    }
    let mut worst_ref: f64 = 0.0;
    let mut worst_move: f64 = 0.0;
    let mut naive_worst: f64 = 0.0;
    let mut checked = 0;
    // px of every feature at offset 0.
    let mut base: Vec<Option<DVec2>> = Vec::new();
    for (k, offset) in [0.0, 1.0e5, 1.0e6, 1.0e7].into_iter().enumerate() {
        let shift = DVec3::new(offset, offset, 0.0);
        let cam = camera(local_eye + shift, att, 90.0, size.0, size.1);
        assert_finite_matrices(&cam, &format!("offset {offset}"));
        let m = cam.relative_world_to_clip_f32();
        let f = cam.frustum;
        for (j, &(dist, ta, tb)) in features.iter().enumerate() {
            // The feature's local position: along the view direction (a, b), then snapped to
            // the sample grid so it is a vertex.
            let a = f.tan_left + ta * (f.tan_right - f.tan_left);
            let b = -f.tan_up + tb * (f.tan_up - f.tan_down);
            let dir = cam.world_to_view_rotation().transpose() * DVec3::new(a, b, 1.0);
            let p = local_eye + dir * dist;
            let (col, row) = (
                (p.x / SPACING).round() as i64,
                (p.y / SPACING).round() as i64,
            );
            // Node of the level the clipmap would use at this distance.
            let level = ((dist / 2_000.0).max(1.0).log2().floor() as u32).min(6);
            let node = (Q as i64) << level;
            let step = 1i64 << level;
            let (col, row) = (col.div_euclid(step) * step, row.div_euclid(step) * step);
            let (n0x, n0y) = (col.div_euclid(node) * node, row.div_euclid(node) * node);
            let ij = (((col - n0x) / step) as u32, ((row - n0y) / step) as u32);
            let hgt = (p.z + 37.0 * ((col as f64) * 0.01).sin()) as f32;
            // World positions with the origin shift (offsets are multiples of the spacing).
            let node_origin =
                DVec2::new(n0x as f64 * SPACING + offset, n0y as f64 * SPACING + offset);
            let world = DVec3::new(
                col as f64 * SPACING + offset,
                row as f64 * SPACING + offset,
                hgt as f64,
            );
            let world = world - DVec3::Z * drop(cam.position, world.x, world.y);
            let reference = cam.project_px(world, size.0, size.1);
            let (got, depth) = shader_px(&cam, &m, node_origin, ij, step as u32, hgt, true, size);
            let Some((want, want_depth)) = reference else {
                if k == 0 {
                    base.push(None);
                }
                continue;
            };
            assert!(depth.is_finite() && depth > 0.0);
            assert!(
                ((depth as f64) - want_depth).abs() <= 1e-5 * want_depth,
                "offset {offset} feature {j}: depth {depth} vs {want_depth}"
            );
            let err = (got - want).length();
            worst_ref = worst_ref.max(err);
            // What a world-space f32 path would do (f32 world position and eye): the test can tell.
            let naive_rel = world.as_vec3() - cam.position.as_vec3();
            let clip = m * naive_rel.extend(1.0);
            if clip.w > 0.0 {
                let ndc = clip.truncate() / clip.w;
                let naive = DVec2::new(
                    ((ndc.x + 1.0) * 0.5 * size.0 as f32) as f64,
                    ((ndc.y + 1.0) * 0.5 * size.1 as f32) as f64,
                );
                if offset == 1.0e7 {
                    naive_worst = naive_worst.max((naive - want).length());
                }
            }
            assert!(
                err < 0.125,
                "offset {offset}: feature {j} at {dist} m is {err} px from the f64 reference"
            );
            if k == 0 {
                base.push(Some(got));
            } else if let Some(b0) = base[j] {
                let moved = (got - b0).length();
                worst_move = worst_move.max(moved);
                assert!(
                    moved < 0.125,
                    "offset {offset}: feature {j} at {dist} m moved {moved} px"
                );
                checked += 1;
            }
        }
    }
    assert!(checked >= 3 * 20, "{checked} features compared");
    assert!(
        naive_worst > 1.0,
        "a world-space f32 path at 1e7 m is off by only {naive_worst} px"
    );
    eprintln!(
        "origin offsets: worst {worst_ref:.2e} px from f64, worst move {worst_move:.2e} px (world-space f32 at 1e7 m: {naive_worst:.1} px)"
    );
}

/// Cameras at the edges of what a flight can do, over the generated scene.
fn extreme_cameras(s: &Scene) -> Vec<(String, Camera)> {
    let mut out = Vec::new();
    // Flat quadrant (north-east) for the lowest eye; ridged (south-west) otherwise.
    let flat = DVec2::new(9_600.0, 9_600.0);
    let ridged = DVec2::new(3_300.0, 3_100.0);
    let at = |p: DVec2, agl: f64| {
        let eye = DVec3::new(p.x, p.y, 0.0);
        DVec3::new(p.x, p.y, ground(s, eye, p.x, p.y) + agl)
    };
    for agl in [0.5, 2.0, 30.0, 1_000.0, 10_000.0, 50_000.0] {
        let p = if agl < 10.0 { flat } else { ridged };
        let pitch = if agl >= 10_000.0 { -90.0 } else { -20.0 };
        out.push((
            format!("{agl} m AGL"),
            camera(at(p, agl), [40.0, pitch, 0.0], 90.0, W, H),
        ));
    }
    out.push((
        "0.5 m AGL looking down".into(),
        camera(at(flat, 0.5), [0.0, -90.0, 0.0], 90.0, W, H),
    ));
    for pitch in [-90.0, -89.999, -45.0, 0.0, 45.0, 89.999, 90.0] {
        out.push((
            format!("pitch {pitch}"),
            camera(at(ridged, 300.0), [123.0, pitch, 0.0], 90.0, W, H),
        ));
    }
    for roll in [180.0, -180.0, 90.0] {
        out.push((
            format!("roll {roll}"),
            camera(at(ridged, 300.0), [300.0, -10.0, roll], 90.0, W, H),
        ));
    }
    for heading in [359.99, 0.01, 360.0, 720.0, -0.01] {
        out.push((
            format!("heading {heading}"),
            camera(at(ridged, 500.0), [heading, -15.0, 0.0], 90.0, W, H),
        ));
    }
    out
}

#[test]
fn extreme_cameras_keep_matrices_finite_and_selection_covering() {
    let s = scene();
    let params = SelectParams::default();
    let mut sel = Selection::default();
    for (what, cam) in extreme_cameras(s) {
        assert_finite_matrices(&cam, &what);
        select(s, &cam, (W, H), &params, &mut sel);
        check_selection(s, &cam, (W, H), &params, &sel, &what);
        if what.starts_with("0.5 m") {
            assert!(!sel.items.is_empty(), "{what}: nothing drawn");
        }
    }
    // Heading wrap: 359.99° and 0.01° are 0.02° apart, 360° and 720° are 0°.
    let cams = extreme_cameras(s);
    let get = |name: &str| cams.iter().find(|(w, _)| w == name).unwrap().1;
    let r = |c: Camera| c.world_to_view_rotation();
    let d = |a: Camera, b: Camera| {
        (r(a) - r(b))
            .to_cols_array()
            .iter()
            .fold(0.0f64, |m, &v| m.max(v.abs()))
    };
    assert!(d(get("heading 359.99"), get("heading 0.01")) < 4e-4);
    assert!(d(get("heading 359.99"), get("heading -0.01")) < 1e-12);
    assert!(d(get("heading 360"), get("heading 720")) < 1e-12);
}

#[test]
fn extreme_cameras_render_validation_clean_with_terrain_where_expected() {
    let s = scene();
    let (w, h) = (96u32, 54u32);
    let all = extreme_cameras(s);
    let wanted = [
        "0.5 m AGL looking down",
        "50000 m AGL",
        "pitch 90",
        "pitch -89.999",
        "roll 180",
        "heading 359.99",
        "heading 0.01",
    ];
    let mut cams: Vec<(String, Camera)> = all
        .into_iter()
        .filter(|(name, _)| wanted.contains(&name.as_str()))
        .map(|(name, c)| {
            (
                name,
                Camera::new(
                    c.position,
                    c.attitude,
                    Frustum::symmetric(90f64.to_radians(), w, h),
                ),
            )
        })
        .collect();
    // FOV extremes on the same renderer.
    let base = cams.iter().find(|(n, _)| n == "heading 0.01").unwrap().1;
    for fov in [1.0, 170.0] {
        cams.push((
            format!("fov {fov}"),
            Camera::new(
                base.position,
                base.attitude,
                Frustum::symmetric(f64::to_radians(fov), w, h),
            ),
        ));
    }
    let frames = render_dataset(
        &test_desc(w, h),
        s.ds.clone(),
        s.bake.clone(),
        &cams.iter().map(|c| c.1).collect::<Vec<_>>(),
    );
    let terrain = |f: &Rendered| f.depth.iter().filter(|&&d| d > 0.0).count();
    let n = (w * h) as usize;
    for ((name, _), f) in cams.iter().zip(&frames) {
        assert!(
            f.depth
                .iter()
                .all(|d| d.is_finite() && *d >= 0.0 && *d <= 1.0),
            "{name}"
        );
        let t = terrain(f);
        match name.as_str() {
            "0.5 m AGL looking down" | "pitch -89.999" => {
                assert_eq!(t, n, "{name}: {t}/{n} terrain")
            }
            "pitch 90" => assert_eq!(t, 0, "{name}: {t} terrain pixels looking up"),
            "50000 m AGL" => {
                // Looking straight down at a 12.8 km square from 50 km: terrain in the middle
                // (≈ 14 % of the width), sky in the corners.
                assert!(
                    f.depth[(h / 2 * w + w / 2) as usize] > 0.0,
                    "{name}: centre"
                );
                assert_eq!(f.depth[0], 0.0, "{name}: corner");
                assert!(t > 20 && t < n / 4, "{name}: {t} terrain pixels");
            }
            "roll 180" => {
                // Upside down, pitched 10° down: the ground is at the top of the picture.
                let half = n / 2;
                let top = f.depth[..half].iter().filter(|&&d| d > 0.0).count();
                let bottom = f.depth[half..].iter().filter(|&&d| d > 0.0).count();
                let first_row = f.depth[..w as usize].iter().all(|&d| d > 0.0);
                assert!(
                    first_row && top > 2 * bottom,
                    "{name}: top {top}, bottom {bottom}"
                );
            }
            _ => assert!(t > n / 4, "{name}: {t} terrain pixels"),
        }
    }
    let img = |name: &str| &frames[cams.iter().position(|(n, _)| n == name).unwrap()];
    let d = diff_images(&img("heading 359.99").rgba, &img("heading 0.01").rgba, 16);
    assert!(
        d.fraction_over < 0.02 && d.mean < 2.0,
        "heading wrap: {d:?}"
    );
}

/// An integrated flight: position += velocity·dt, so rounding accumulates as in a simulator.
struct Flight {
    pos: DVec3,
    frame: u64,
}

impl Flight {
    const PERIOD: u64 = 4_000;
    const DT: f64 = 1.0 / 60.0;

    /// Heading, pitch and speed of the loop at frame f (a rounded figure eight over the scene,
    /// climbing and descending between ~40 m and ~3 km above the terrain).
    fn step(&mut self, s: &Scene) -> Camera {
        let phase = (self.frame % Self::PERIOD) as f64 / Self::PERIOD as f64;
        let a = std::f64::consts::TAU * phase;
        // Velocity of x = c + A sin a, y = c + B sin 2a: the loop is closed.
        let (ax, by) = (4_500.0, 3_000.0);
        let da = std::f64::consts::TAU / Self::PERIOD as f64 / Self::DT;
        let v = DVec2::new(ax * a.cos() * da, 2.0 * by * (2.0 * a).cos() * da);
        self.pos.x += v.x * Self::DT;
        self.pos.y += v.y * Self::DT;
        let agl = 1_500.0 - 1_460.0 * (3.0 * a).cos();
        let g = s.ds.hf.height_at_m(self.pos.x, self.pos.y);
        self.pos.z = g + agl;
        self.frame += 1;
        let heading = v.x.atan2(v.y).to_degrees();
        let pitch = -25.0 + 20.0 * (5.0 * a).sin();
        camera(
            self.pos,
            [heading, pitch, 15.0 * (2.0 * a).sin()],
            90.0,
            160,
            90,
        )
    }
}

#[test]
#[allow(clippy::needless_range_loop)]
fn hundred_thousand_frame_cpu_flight_stays_snapped_bounded_and_flat() {
    let s = scene();
    let clip = &s.clip;
    let side = clip.texture_side() as i64;
    let q = clip.tile_quads as i64;
    let params = SelectParams {
        tau_px: 2.0,
        ..SelectParams::default()
    };
    let capacities = [24u32, 12, 6, 3, 0, 0];
    let mut pools: Vec<RefinedTilePool> = capacities
        .iter()
        .map(|&c| RefinedTilePool::new(c))
        .collect();
    let mut caches: Vec<Option<CacheRegion>> = vec![None; clip.level_count() as usize];
    let mut sel = Selection::default();
    let c = (N as f64 - 1.0) * SPACING / 2.0;
    let mut flight = Flight {
        pos: DVec3::new(c, c, 0.0),
        frame: 0,
    };
    let (mut requests, mut late, mut uploads, mut strip_frames) = (0u64, 0u64, 0u64, 0u64);
    let mut watermark = None;
    const FRAMES: u64 = 100_000;
    for frame in 0..FRAMES {
        let cam = flight.step(s);
        let viewer = [cam.position.x / SPACING, cam.position.y / SPACING];
        let placements = place_levels(clip, viewer);
        for (i, p) in placements.iter().enumerate() {
            let t = (q << p.level) as f64;
            if !p.is_coarsest {
                assert!(
                    p.patch_origin.iter().all(|o| o % 2 == 0),
                    "frame {frame}: level {} origin {:?} not snapped",
                    p.level,
                    p.patch_origin
                );
                // The patch centre is within one level tile of the viewer.
                for a in 0..2 {
                    let centre = (p.patch_origin[a] as f64 + p.patch_tiles as f64 / 2.0) * t;
                    assert!(
                        (centre - viewer[a]).abs() <= t,
                        "frame {frame}: level {} centre {centre} vs viewer {}",
                        p.level,
                        viewer[a]
                    );
                }
                // Nested: at least one whole coarser tile between this patch and the next.
                let coarser = &placements[i + 1];
                if !coarser.is_coarsest {
                    for a in 0..2 {
                        let lo = p.patch_origin[a].div_euclid(2);
                        let hi = (p.patch_origin[a] + p.patch_tiles as i64).div_euclid(2);
                        assert!(
                            lo > coarser.patch_origin[a]
                                && hi < coarser.patch_origin[a] + coarser.patch_tiles as i64,
                            "frame {frame}: level {} not nested in {}",
                            p.level,
                            coarser.level
                        );
                    }
                }
            }
            let (region, rects) = update_cache(clip, caches[i].as_ref(), p);
            if !p.is_coarsest {
                for a in 0..2 {
                    let lo = p.patch_origin[a] * q;
                    let hi = lo + p.patch_tiles as i64 * q;
                    assert!(
                        lo >= region.origin[a] && hi < region.origin[a] + side,
                        "frame {frame}: level {} cache {region:?} misses its patch",
                        p.level
                    );
                }
            }
            if caches[i].is_some() {
                assert!(rects.len() <= 2, "frame {frame}: {rects:?}");
                strip_frames += !rects.is_empty() as u64;
                for r in &rects {
                    assert!(r.size[0] as i64 <= side && r.size[1] as i64 <= side);
                    // A smooth flight never re-uploads a whole level.
                    assert!(
                        (r.size[0] as u64) * (r.size[1] as u64) < (side * side) as u64,
                        "frame {frame}: whole level {} re-uploaded",
                        p.level
                    );
                }
            }
            caches[i] = Some(region);
        }
        select_tiles(
            &s.bake,
            clip,
            &placements,
            &cam,
            (160, 90),
            &params,
            &mut sel,
        );
        assert!(sel
            .items
            .iter()
            .all(|i| i.rho_px >= 0.0 && i.eps_m.is_finite()));
        for p in &mut pools {
            p.begin_frame(frame);
        }
        let mut budget = 6u32;
        let mut last = None;
        for it in &sel.items {
            if it.refinement == 0 || last == Some((it.level, it.tx, it.ty)) {
                continue;
            }
            last = Some((it.level, it.tx, it.ty));
            let key = TileKey {
                level: it.level,
                tx: it.tx,
                ty: it.ty,
                refinement: it.refinement,
            };
            let pool = &mut pools[it.refinement as usize - 1];
            requests += 1;
            let mut can = || {
                if budget > 0 {
                    budget -= 1;
                    true
                } else {
                    false
                }
            };
            match pool.request(key, &mut can) {
                Request::Hit { slot } => assert!(slot < pool.capacity()),
                Request::Miss { slot, .. } => {
                    assert!(slot < pool.capacity());
                    uploads += 1;
                }
                Request::Unavailable => late += 1,
            }
        }
        for (p, &cap) in pools.iter().zip(&capacities) {
            assert!(p.occupancy() <= cap, "frame {frame}: pool over capacity");
        }
        // Memory: the per-frame buffers stop growing once every phase of the loop was flown.
        let caps = (
            sel.items.capacity(),
            sel.levels.capacity(),
            sel.split.capacity(),
        );
        if frame == 5 * Flight::PERIOD {
            watermark = Some(caps);
        } else if let Some(w) = watermark {
            assert_eq!(caps, w, "frame {frame}: selection buffers grew");
        }
    }
    let counted: u64 = pools
        .iter()
        .map(|p| {
            let c = p.counters();
            c.hits + c.misses + c.late
        })
        .sum();
    assert_eq!(counted, requests);
    assert!(
        requests > 10_000 && uploads > 100 && late > 0,
        "{requests} {uploads} {late}"
    );
    assert!(
        strip_frames > 1_000,
        "{strip_frames} frames uploaded strips"
    );
    eprintln!(
        "100k frames: {requests} refined-tile requests, {uploads} uploads, {late} late, {strip_frames} level moves"
    );
}

#[test]
fn tau_viewport_and_fov_extremes_keep_selection_valid() {
    let s = scene();
    let eye = DVec2::new(3_300.0, 3_100.0);
    let pos = DVec3::new(eye.x, eye.y, ground(s, DVec3::ZERO, eye.x, eye.y) + 400.0);
    let mut sel = Selection::default();
    let mut nodes = std::collections::HashMap::new();
    for (w, h) in [(1u32, 1u32), (320, 180), (16384, 16384)] {
        for fov in [1.0, 90.0, 170.0] {
            for tau in [0.1, 100.0] {
                let cam = camera(pos, [40.0, -20.0, 0.0], fov, w, h);
                let params = SelectParams {
                    tau_px: tau,
                    ..SelectParams::default()
                };
                select(s, &cam, (w, h), &params, &mut sel);
                let what = format!("{w}x{h} fov {fov} τ {tau}");
                check_selection(s, &cam, (w, h), &params, &sel, &what);
                // Triangles drawn (a node drawn at a coarser level's resolution draws fewer:
                // a coarse τ may draw more, smaller parts than a fine one draws nodes).
                let tris = |k: u64| aerie::render::terrain_draws::skirted_tile_triangles(k as u32);
                let q = s.bake.params.tile_size as u64 - 1;
                let triangles: u64 = sel
                    .items
                    .iter()
                    .map(|i| tris(q >> i.morph.levels_up()))
                    .sum();
                nodes.insert((w, fov as u32, tau.to_bits()), triangles);
            }
        }
    }
    for (w, _) in [(1u32, 1u32), (320, 180), (16384, 16384)] {
        for fov in [1u32, 90, 170] {
            let fine = nodes[&(w, fov, 0.1f64.to_bits())];
            let coarse = nodes[&(w, fov, 100.0f64.to_bits())];
            assert!(
                fine >= coarse,
                "{w} px fov {fov}: τ 0.1 draws {fine} triangles < τ 100 {coarse}"
            );
        }
    }
    // A bigger viewport at the same τ never needs fewer triangles.
    assert!(nodes[&(16384, 90, 0.1f64.to_bits())] > nodes[&(1, 90, 0.1f64.to_bits())]);
}

#[test]
fn one_pixel_and_max_width_targets_render_and_over_limit_is_refused() {
    let s = scene();
    let eye = DVec2::new(3_300.0, 3_100.0);
    let pos = DVec3::new(eye.x, eye.y, ground(s, DVec3::ZERO, eye.x, eye.y) + 400.0);
    for (w, h) in [(1u32, 1u32), (16384, 1)] {
        let cam = camera(pos, [40.0, -30.0, 0.0], 90.0, w, h);
        let frames = render_dataset(&test_desc(w, h), s.ds.clone(), s.bake.clone(), &[cam]);
        let f = &frames[0];
        assert_eq!(f.depth.len(), (w * h) as usize);
        let t = f.depth.iter().filter(|&&d| d > 0.0).count();
        assert!(
            t as u32 >= (w * 9 / 10).max(1),
            "{w}x{h}: {t} terrain pixels"
        );
    }
    let err = TerrainRenderer::new(&test_desc(16385, 1))
        .err()
        .expect("a 16385-pixel target must be refused")
        .to_string();
    assert!(err.contains("16385") && err.contains("16384"), "{err}");
    assert!(!err.contains('\n'), "{err}");
}

#[test]
fn half_metre_at_fifty_km_stays_ordered_in_the_shaders_f32_math() {
    let size = (1920u32, 1080u32);
    let mut checked = 0;
    for offset in [0.0, 1.0e5, 1.0e6, 1.0e7] {
        for hpr in [[0.0, 0.0, 0.0], [77.0, -3.0, 10.0], [250.0, 5.0, -170.0]] {
            let eye = DVec3::new(offset + 12.5, offset - 37.5, 2_000.0);
            let cam = camera(eye, hpr, 90.0, size.0, size.1);
            let m = cam.relative_world_to_clip_f32();
            let f = cam.frustum;
            let rot_t = cam.world_to_view_rotation().transpose();
            for k in 0..64 {
                let ta = (k % 8) as f64 / 7.0;
                let tb = (k / 8) as f64 / 7.0;
                let a = f.tan_left + ta * (f.tan_right - f.tan_left);
                let b = -f.tan_up + tb * (f.tan_up - f.tan_down);
                let dir = (rot_t * DVec3::new(a, b, 1.0)).normalize();
                // Two surface points on one ray, 0.5 m apart, 50 km away; each is a vertex
                // whose node origin is itself (the shader's origin_rel path, no curvature).
                let depth_of = |d: f64| {
                    let p = eye + dir * d;
                    shader_px(&cam, &m, p.truncate(), (0, 0), 1, p.z as f32, false, size).1
                };
                let near = depth_of(50_000.0);
                let far = depth_of(50_000.5);
                assert!(
                    near > far && far > 0.0,
                    "offset {offset} {hpr:?} ray {k}: {near} vs {far}"
                );
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 4 * 3 * 64);
}

/// Two ridges across the view 50 km away, the second ~0.4–0.5 m behind the first along every
/// ray that meets both: the GPU keeps the nearer surface (reversed-Z D32), i.e. the depth
/// read back where the first ridge is hit is the first ridge's, to well under the gap.
#[test]
fn half_metre_at_fifty_km_stays_ordered_on_the_gpu() {
    let (w, h) = (128u32, 128u32);
    // Row-invariant profile along x, 0.25 m spacing: ridge 1 (10 m) peaks at col 21, ridge 2
    // (20 m) at col 23; between them the ground is back at 0.
    let (cols, rows, sp) = (65usize, 129usize, 0.25f64);
    let profile = |c: usize| match c {
        21 => 10.0f32,
        23 => 20.0,
        _ => 0.0,
    };
    let mut heights = Vec::with_capacity(cols * rows);
    for _ in 0..rows {
        heights.extend((0..cols).map(profile));
    }
    let hf = Heightfield {
        width: cols,
        height: rows,
        spacing_x: sp,
        spacing_y: sp,
        heights,
        geo: None,
        voids_filled: 0,
        spacing_note: "ridges".into(),
    };
    let x20 = 20.0 * sp;
    let cam = Camera::new(
        DVec3::new(x20 - 50_000.0, (rows - 1) as f64 * sp / 2.0, 5.0),
        Attitude::from_degrees(90.0, 0.0, 0.0),
        Frustum::symmetric(0.1f64.to_radians(), w, h),
    );
    let mut desc = test_desc(w, h);
    desc.select.curvature = false;
    let frames = render_frames(&desc, &hf, &[cam]);
    let f = &frames[0];
    let fwd = cam.world_to_view_rotation().transpose() * DVec3::Z;
    // First hits of a ray with the profile's faces, in f64 (view z of each face hit in order).
    let hits = |dir: DVec3| -> Vec<(usize, f64)> {
        let mut out = Vec::new();
        for c in 0..cols - 1 {
            let (x0, x1) = (c as f64 * sp, (c + 1) as f64 * sp);
            let (h0, h1) = (profile(c) as f64, profile(c + 1) as f64);
            // eye + t dir on the segment: z(t) = h0 + (x(t) − x0)(h1 − h0)/sp.
            let s = (h1 - h0) / sp;
            let denom = dir.z - s * dir.x;
            if denom.abs() < 1e-15 {
                continue;
            }
            let t = (h0 + s * (cam.position.x - x0) - cam.position.z) / denom;
            let x = cam.position.x + t * dir.x;
            if t > 0.0 && x >= x0 && x <= x1 && (h0 != 0.0 || h1 != 0.0) {
                out.push((c, t * dir.dot(fwd)));
            }
        }
        out
    };
    let (mut occluding, mut correct) = (0, 0);
    for py in 0..h {
        for px in 0..w {
            let dir = cam.pixel_ray(px as f64 + 0.5, py as f64 + 0.5, w, h);
            let y = cam.position.y + dir.y / dir.x * (50_000.0);
            if !(2.0..(rows - 1) as f64 * sp - 2.0).contains(&y) {
                continue;
            }
            let hs = hits(dir);
            // Rays through ridge 1's front face (cols 20..21) that would go on to ridge 2's
            // front face (cols 22..23).
            let (Some(first), Some(second)) = (
                hs.iter().find(|(c, _)| *c == 20),
                hs.iter().find(|(c, _)| *c == 22),
            ) else {
                continue;
            };
            let gap = second.1 - first.1;
            assert!(gap > 0.35 && gap <= 0.5 + 1e-9, "gap {gap}");
            occluding += 1;
            let d = f.depth[(py * w + px) as usize] as f64;
            assert!(d > 0.0, "pixel {px},{py} is sky");
            let z = cam.near / d;
            if (z - first.1).abs() < 0.1 {
                correct += 1;
            }
        }
    }
    eprintln!("ridges at 50 km: {correct}/{occluding} pixels show the nearer ridge");
    assert!(occluding > 100, "only {occluding} pixels see both ridges");
    assert!(
        correct as f64 >= 0.98 * occluding as f64,
        "{correct}/{occluding} pixels show the nearer ridge"
    );
}

/// The flat quadrant really is flat (the lowest cameras rely on it).
#[test]
fn scene_flat_quadrant_is_flat() {
    let s = scene();
    let eye = DVec3::new(9_600.0, 9_600.0, 200.0);
    let g = ground(s, eye, 9_600.0, 9_600.0) + drop(eye, 9_600.0, 9_600.0);
    assert!((g - FLAT_HEIGHT as f64).abs() < 1e-6, "{g}");
}
