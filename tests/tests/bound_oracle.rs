//! The screen-space error bound, checked by brute force (CPU, DESIGN.md "What within τ means
//! when tested"): for random cameras over a real alpine DEM and over `cliffs` / `spikes`
//! terrains, every drawn tile's true full-resolution samples and the surface actually drawn
//! (level L−r, the GPU's diagonal, per-vertex curvature drop interpolated linearly) project
//! within τ pixels of each other. Also: the drawn tiles cover the visible ground exactly once.

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::terrain::bake::{bake, BakeParams, ErrorBake};
use aerie::terrain::clipmap::{place_levels, ClipmapDesc};
use aerie::terrain::dataset::Dataset;
use aerie::terrain::gen::{generate, DemKind, GenParams};
use aerie::terrain::load_dem;
use aerie::terrain::select::{select_tiles, SelectParams, Selection, EARTH_RADIUS_M};
use aerie::terrain::Heightfield;
use aerie_tests::demo_dem;
use glam::{DVec2, DVec3};

const W: u32 = 320;
const H: u32 = 180;
const M: u32 = 17;

/// splitmix64: a small deterministic generator, so failures reproduce.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

struct Scene {
    name: &'static str,
    ds: Dataset,
    bake: ErrorBake,
    clip: ClipmapDesc,
}

fn scene(name: &'static str, hf: Heightfield) -> Scene {
    let ds = Dataset::from_heightfield(hf, name.into());
    assert_eq!(
        (ds.valid_width, ds.valid_height),
        (ds.hf.width, ds.hf.height),
        "oracle scenes are 2^K+1: no padding"
    );
    let bake = bake(
        &ds,
        BakeParams {
            tile_size: M,
            levels: 0,
        },
        &|_, _| {},
    );
    let clip = ClipmapDesc {
        tile_quads: M - 1,
        patch_tiles: 8,
        margin_tiles: 2,
        width: ds.hf.width as u32,
        height: ds.hf.height as u32,
    };
    Scene {
        name,
        ds,
        bake,
        clip,
    }
}

/// A 1025² crop of the Inn valley tile (Karwendel, Nordkette, Innsbruck).
fn alpine() -> Heightfield {
    let full = load_dem(&demo_dem()).expect("demo DEM");
    let (n, c0, r0) = (1025usize, 88usize, 88usize);
    let mut heights = Vec::with_capacity(n * n);
    for r in 0..n {
        heights.extend_from_slice(&full.heights[(r0 + r) * full.width + c0..][..n]);
    }
    Heightfield {
        width: n,
        height: n,
        heights,
        ..full
    }
}

fn generated(kind: DemKind, seed: u64) -> Heightfield {
    generate(&GenParams {
        size: 1025,
        spacing: 30.0,
        kind,
        seed,
    })
}

fn random_camera(rng: &mut Rng, s: &Scene) -> Camera {
    let hf = &s.ds.hf;
    let (ex, ey) = hf.extent_m();
    let x = rng.range(0.0, ex);
    let y = rng.range(0.0, ey);
    let ground = hf.height_at_m(x, y);
    // Low and high: 2 m above the ground up to 3 km.
    let agl = if rng.next() < 0.3 {
        rng.range(2.0, 50.0)
    } else {
        rng.range(50.0, 3000.0)
    };
    let attitude = Attitude::from_degrees(
        rng.range(0.0, 360.0),
        rng.range(-70.0, 10.0),
        rng.range(-30.0, 30.0),
    );
    let fov = rng.range(40.0, 110.0);
    Camera::new(
        DVec3::new(x, y, ground + agl),
        attitude,
        Frustum::symmetric(fov.to_radians(), W, H),
    )
}

fn select(s: &Scene, cam: &Camera, tau: f64) -> Selection {
    let hf = &s.ds.hf;
    let viewer = [cam.position.x / hf.spacing_x, cam.position.y / hf.spacing_y];
    let placements = place_levels(&s.clip, viewer);
    let params = SelectParams {
        tau_px: tau,
        max_refinement: 6,
        ..SelectParams::default()
    };
    let mut sel = Selection::default();
    select_tiles(
        &s.bake,
        &s.clip,
        &placements,
        cam,
        (W, H),
        &params,
        &mut sel,
    );
    sel
}

/// Curvature drop of a point at horizontal offset `d` from the eye.
fn drop(eye: DVec3, x: f64, y: f64) -> f64 {
    (DVec2::new(x, y) - eye.truncate()).length_squared() / (2.0 * EARTH_RADIUS_M)
}

/// Largest on-screen distance (px) between true samples and the drawn surface of one tile,
/// computed independently of the bake: own barycentric interpolation over the SW–NE diagonal
/// at level L−r, vertices dropped by curvature and interpolated linearly as on the GPU.
fn tile_error_px(hf: &Heightfield, cam: &Camera, level: u32, tx: u32, ty: u32, r: u32) -> f64 {
    let q = (M - 1) as usize;
    let side = q << level;
    let step = 1usize << (level - r);
    let (c0, r0) = (tx as usize * side, ty as usize * side);
    let eye = cam.position;
    let vertex = |c: usize, row: usize| {
        let (x, y) = (c as f64 * hf.spacing_x, row as f64 * hf.spacing_y);
        hf.at(c, row) as f64 - drop(eye, x, y)
    };
    let on_screen = |p: DVec2| p.x >= 0.0 && p.x <= W as f64 && p.y >= 0.0 && p.y <= H as f64;
    let mut worst: f64 = 0.0;
    for row in r0..=r0 + side {
        for c in c0..=c0 + side {
            let (x, y) = (c as f64 * hf.spacing_x, row as f64 * hf.spacing_y);
            let truth = hf.at(c, row) as f64 - drop(eye, x, y);
            // The drawn cell and the position inside it.
            let (ci, ri) = (
                ((c - c0) / step).min(side / step - 1),
                ((row - r0) / step).min(side / step - 1),
            );
            let (vc, vr) = (c0 + ci * step, r0 + ri * step);
            let u = (c - vc) as f64 / step as f64;
            let v = (row - vr) as f64 / step as f64;
            let sw = vertex(vc, vr);
            let se = vertex(vc + step, vr);
            let nw = vertex(vc, vr + step);
            let ne = vertex(vc + step, vr + step);
            let drawn = if u >= v {
                sw * (1.0 - u) + se * (u - v) + ne * v
            } else {
                sw * (1.0 - v) + nw * (v - u) + ne * u
            };
            let a = cam.project_px(DVec3::new(x, y, truth), W, H);
            let b = cam.project_px(DVec3::new(x, y, drawn), W, H);
            if let (Some((pa, _)), Some((pb, _))) = (a, b) {
                if on_screen(pa) || on_screen(pb) {
                    worst = worst.max((pa - pb).length());
                }
            }
        }
    }
    worst
}

#[test]
fn every_drawn_tile_is_within_tau_for_a_thousand_random_cameras() {
    let scenes = [
        scene("alpine", alpine()),
        scene("cliffs", generated(DemKind::Cliffs, 7)),
        scene("spikes", generated(DemKind::Spikes, 11)),
    ];
    let tau = 1.0;
    let mut rng = Rng(2026);
    let (mut tiles_checked, mut refined_checked) = (0u64, 0u64);
    let mut worst_ratio: f64 = 0.0;
    for k in 0..1002 {
        let s = &scenes[k % scenes.len()];
        let cam = random_camera(&mut rng, s);
        let sel = select(s, &cam, tau);
        assert_eq!(
            sel.unbounded, 0,
            "{}: camera {k} has unbounded tiles",
            s.name
        );
        // A sample of the drawn tiles per camera (all of them would take minutes in debug).
        let n = sel.items.len();
        for j in 0..n.min(6) {
            let item = sel.items[(rng.next() * n as f64) as usize % n];
            let _ = j;
            // The node is drawn as the level-`node_level` surface over its own tile.
            let err = tile_error_px(
                &s.ds.hf,
                &cam,
                item.node_level,
                item.node_tx,
                item.node_ty,
                0,
            );
            assert!(
                err <= tau + 1e-6,
                "{}: camera {k} {:?}: node L{} ({}, {}) of tile L{} r{} projects {err:.4} px > τ (bound said {:.4})",
                s.name,
                cam.position,
                item.node_level,
                item.node_tx,
                item.node_ty,
                item.level,
                item.refinement,
                item.rho_px
            );
            // The bound is an upper bound of the true error.
            assert!(
                err <= item.rho_px as f64 + 1e-6,
                "measured {err} > bound {}",
                item.rho_px
            );
            if item.rho_px > 0.0 {
                worst_ratio = worst_ratio.max(err / item.rho_px as f64);
            }
            tiles_checked += 1;
            refined_checked += (item.refinement > 0) as u64;
        }
    }
    eprintln!(
        "bound oracle: {tiles_checked} tiles ({refined_checked} refined) within τ; tightest measured/bound = {worst_ratio:.3}"
    );
    assert!(
        tiles_checked > 3000 && refined_checked > 300,
        "{tiles_checked} / {refined_checked}"
    );
}

/// Rasterises the drawn tiles' footprints onto level-0 cells: no cell is drawn twice, and every
/// cell whose ground is visible on screen is drawn (culling and level boundaries leave no hole).
#[test]
fn drawn_tiles_cover_the_visible_ground_exactly_once() {
    let s = scene("alpine", alpine());
    let hf = &s.ds.hf;
    let cells = (hf.width - 1) * (hf.height - 1);
    let q = (M - 1) as usize;
    let mut rng = Rng(7);
    for k in 0..24 {
        let cam = random_camera(&mut rng, &s);
        let sel = select(&s, &cam, 1.0);
        let mut count = vec![0u8; cells];
        for item in &sel.items {
            let side = q << item.node_level;
            let (c0, r0) = (item.node_tx as usize * side, item.node_ty as usize * side);
            for row in r0..(r0 + side).min(hf.height - 1) {
                for c in c0..(c0 + side).min(hf.width - 1) {
                    count[row * (hf.width - 1) + c] += 1;
                }
            }
        }
        assert!(
            count.iter().all(|&n| n <= 1),
            "camera {k}: overlapping tiles"
        );
        let mut visible = 0;
        for row in 0..hf.height - 1 {
            for c in 0..hf.width - 1 {
                let (x, y) = (
                    (c as f64 + 0.5) * hf.spacing_x,
                    (row as f64 + 0.5) * hf.spacing_y,
                );
                let z = hf.height_at_m(x, y) - drop(cam.position, x, y);
                let Some((p, _)) = cam.project_px(DVec3::new(x, y, z), W, H) else {
                    continue;
                };
                if p.x >= 0.0 && p.x <= W as f64 && p.y >= 0.0 && p.y <= H as f64 {
                    visible += 1;
                    assert_eq!(
                        count[row * (hf.width - 1) + c],
                        1,
                        "camera {k}: visible cell ({c}, {row}) is not drawn"
                    );
                }
            }
        }
        assert!(visible > 0 || k > 0);
    }
}
