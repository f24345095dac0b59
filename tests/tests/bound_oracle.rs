//! The screen-space error bound, checked by brute force (CPU, DESIGN.md "What within τ means
//! when tested"): for random cameras over a real alpine DEM and over `cliffs` / `spikes`
//! terrains, every drawn tile's true full-resolution samples and the surface actually drawn
//! (level L−r, the GPU's diagonal, per-vertex curvature drop interpolated linearly) project
//! within τ pixels of each other. Also: the drawn tiles cover the visible ground exactly once.
//! The same on geographic data drawn on the WGS84 ellipsoid (issue 14): true samples at their
//! exact positions, the drawn surface the linear interpolation of the vertices' exact positions,
//! at 47°N, 70°N and over a 10° region at 60°N.

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::terrain::clipmap::place_levels;
use aerie::terrain::gen::{generate, DemKind, GenParams};
use aerie::terrain::geodesy::Geodetic;
use aerie::terrain::select::{select_tiles, DrawItem, SelectParams, Selection};
use aerie::terrain::Heightfield;
use aerie_tests::flat_oracle::{self, alpine, Scene};
use aerie_tests::geo_oracle::{
    alpine_47n, cliffs_70n, geo_scene, geo_tile_error_px, utm_geo_scene, GeoScene,
};
use glam::{DVec2, DVec3};

const W: u32 = 320;
const H: u32 = 180;
const M: u32 = 17;

/// splitmix64: a small deterministic generator, so failures reproduce.
/// `any` drawn items of `sel` at random, and `parts` each of its quadrants drawn at their
/// parent's resolution and of its sixteenths drawn at their grandparent's (fewer where fewer).
fn sample_items(sel: &Selection, rng: &mut Rng, any: usize, parts: usize) -> Vec<DrawItem> {
    let pick = |rng: &mut Rng, items: &[&DrawItem]| {
        *items[(rng.next() * items.len() as f64) as usize % items.len()]
    };
    let all: Vec<&DrawItem> = sel.items.iter().collect();
    let mut sample: Vec<DrawItem> = (0..all.len().min(any)).map(|_| pick(rng, &all)).collect();
    for up in [1, 2] {
        let kind: Vec<&DrawItem> = all
            .iter()
            .copied()
            .filter(|i| i.morph.levels_up() == up)
            .collect();
        for _ in 0..kind.len().min(parts) {
            sample.push(pick(rng, &kind));
        }
    }
    sample
}

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

/// The shared flat scene at this file's tile size.
fn scene(name: &'static str, hf: Heightfield) -> Scene {
    flat_oracle::scene(name, hf, M)
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

/// [`flat_oracle::tile_error_px`] at this file's viewport and tile size.
fn tile_error_px(hf: &Heightfield, cam: &Camera, level: u32, tx: u32, ty: u32, drawn: u32) -> f64 {
    flat_oracle::tile_error_px(hf, cam, (W, H), M, level, tx, ty, drawn)
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
    let mut quadrants_checked = 0u64;
    let mut sixteenths_checked = 0u64;
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
        // A sample of the drawn tiles per camera (all of them would take minutes in debug), and
        // as many of the quadrants drawn at their parent's resolution and of the sixteenths
        // drawn at their grandparent's.
        let sample = sample_items(&sel, &mut rng, 6, 6);
        for item in sample {
            // The node is drawn as the level-`node_level` surface over its own tile, a quadrant
            // as its parent's, a sixteenth as its grandparent's.
            let drawn = item.node_level + item.morph.levels_up();
            quadrants_checked += (item.morph.levels_up() == 1) as u64;
            sixteenths_checked += (item.morph.levels_up() == 2) as u64;
            let err = tile_error_px(
                &s.ds.hf,
                &cam,
                item.node_level,
                item.node_tx,
                item.node_ty,
                drawn,
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
        "bound oracle: {tiles_checked} tiles ({refined_checked} refined, {quadrants_checked} quadrants at their parent's resolution, {sixteenths_checked} sixteenths at their grandparent's) within τ; tightest measured/bound = {worst_ratio:.3}"
    );
    assert!(
        tiles_checked > 3000
            && refined_checked > 300
            && quadrants_checked > 300
            && sixteenths_checked > 100,
        "{tiles_checked} / {refined_checked} / {quadrants_checked} / {sixteenths_checked}"
    );
}

/// Rasterises the drawn tiles' footprints onto level-0 cells: no cell is drawn twice, and every
/// cell whose ground is visible on screen is drawn (culling and level boundaries leave no hole).
#[test]
fn drawn_tiles_cover_the_visible_ground_exactly_once() {
    let s = scene("alpine", alpine());
    let hf = &s.ds.hf;
    let mut rng = Rng(7);
    for k in 0..24 {
        let cam = random_camera(&mut rng, &s);
        let sel = select(&s, &cam, 1.0);
        let visible = flat_oracle::assert_covered_once(
            hf,
            &cam,
            (W, H),
            M,
            &sel.items,
            &format!("camera {k}"),
        );
        assert!(visible > 0 || k > 0);
    }
}

/// Roots of the coarsest clipmap level drawn coarser, checked one by one: each measured error
/// within τ and within the root's bound; how many, how many as sixteenths, the tightest.
#[derive(Default)]
struct CoarserRoots {
    checked: u64,
    sixteenths: u64,
    worst_ratio: f64,
}

impl CoarserRoots {
    /// `item`, a root drawn `levels_up` coarser, measured `err` px; `what` names the frame.
    fn check(&mut self, item: &DrawItem, err: f64, tau: f64, what: &str) {
        assert!(
            err <= tau + 1e-6 && err <= item.rho_px as f64 + 1e-6,
            "{what}, τ {tau}: root ({}, {}) drawn {} level(s) up projects {err:.4} px (bound {:.4})",
            item.node_tx,
            item.node_ty,
            item.morph.levels_up(),
            item.rho_px
        );
        if item.rho_px > 0.0 {
            self.worst_ratio = self.worst_ratio.max(err / item.rho_px as f64);
        }
        self.checked += 1;
        self.sixteenths += (item.morph.levels_up() == 2) as u64;
    }

    fn report(&self, what: &str, at_least: u64) {
        let Self {
            checked,
            sixteenths,
            worst_ratio,
        } = self;
        eprintln!(
            "{what}: {checked} checked ({sixteenths} at their grandparent's resolution); tightest measured/bound = {worst_ratio:.3}"
        );
        assert!(
            *checked > at_least && *sixteenths > 10,
            "{checked} / {sixteenths}"
        );
    }
}

/// A root of the coarsest clipmap level drawn at its parent's or its grandparent's resolution
/// (`SelectParams::coarser_roots`: levels the bake holds above the textures, drawn with the
/// root's stride-2 and stride-4 meshes) at coarse τ: each such root's true error within τ and
/// within its bound by brute force, and the ground still covered exactly once.
#[test]
fn roots_drawn_coarser_are_within_tau() {
    let scenes = [
        scene("alpine", alpine()),
        scene("cliffs", generated(DemKind::Cliffs, 7)),
    ];
    let mut rng = Rng(15);
    let mut roots = CoarserRoots::default();
    for k in 0..48 {
        let s = &scenes[k % scenes.len()];
        let cam = random_camera(&mut rng, s);
        let tau = [3.0, 8.0, 30.0][k % 3];
        let sel = select(s, &cam, tau);
        let top = s.clip.level_count() - 1;
        assert!(
            (top as usize) + 2 < s.bake.levels.len(),
            "two bake levels above"
        );
        let coarser = sel
            .items
            .iter()
            .filter(|i| i.node_level == top && i.morph.levels_up() > 0);
        for item in coarser.take(8) {
            assert_eq!((item.level, item.refinement), (top, 0), "{item:?}");
            let drawn = top + item.morph.levels_up();
            let err = tile_error_px(&s.ds.hf, &cam, top, item.node_tx, item.node_ty, drawn);
            roots.check(item, err, tau, &format!("{}: camera {k}", s.name));
        }
        if k % 4 == 0 {
            flat_oracle::assert_covered_once(
                &s.ds.hf,
                &cam,
                (W, H),
                M,
                &sel.items,
                &format!("{} camera {k}, τ {tau}", s.name),
            );
        }
    }
    roots.report("coarser roots", 40);
}

fn random_geo_camera(rng: &mut Rng, g: &GeoScene) -> Camera {
    let hf = &g.s.ds.hf;
    let (ex, ey) = hf.extent_m();
    let (x, y) = (rng.range(0.0, ex), rng.range(0.0, ey));
    let ground = hf.height_at_m(x, y);
    let agl = if rng.next() < 0.3 {
        rng.range(2.0, 50.0)
    } else {
        rng.range(50.0, 8000.0)
    };
    let (lat, lon) = g.grid.lat_lon_of_grid(DVec2::new(x, y));
    let attitude = Attitude::from_degrees(
        rng.range(0.0, 360.0),
        rng.range(-70.0, 10.0),
        rng.range(-30.0, 30.0),
    )
    .in_frame(g.grid.local_enu_axes(lat, lon));
    let fov = rng.range(40.0, 110.0);
    Camera::new(
        g.grid
            .world_of_geodetic(Geodetic::new(lat, lon, ground + agl)),
        attitude,
        Frustum::symmetric(fov.to_radians(), W, H),
    )
}

fn select_geo(g: &GeoScene, cam: &Camera, tau: f64) -> Selection {
    let hf = &g.s.ds.hf;
    let eye = g.grid.grid_of_world(cam.position);
    let placements = place_levels(&g.s.clip, [eye.x / hf.spacing_x, eye.y / hf.spacing_y]);
    let params = SelectParams {
        tau_px: tau,
        max_refinement: 6,
        earth: Some(g.grid),
        ..SelectParams::default()
    };
    let mut sel = Selection::default();
    select_tiles(
        &g.s.bake,
        &g.s.clip,
        &placements,
        cam,
        (W, H),
        &params,
        &mut sel,
    );
    sel
}

/// The oracle over `cameras` random cameras on `scenes`: returns (tiles, refined) checked.
fn geodetic_oracle(scenes: &[GeoScene], cameras: usize, seed: u64, what: &str) -> (u64, u64) {
    let tau = 1.0;
    let mut rng = Rng(seed);
    let (mut tiles_checked, mut refined_checked) = (0u64, 0u64);
    let mut quadrants_checked = 0u64;
    let mut sixteenths_checked = 0u64;
    let mut worst_ratio: f64 = 0.0;
    for k in 0..cameras {
        let g = &scenes[k % scenes.len()];
        let cam = random_geo_camera(&mut rng, g);
        let sel = select_geo(g, &cam, tau);
        assert_eq!(
            sel.unbounded, 0,
            "{}: camera {k} has unbounded tiles",
            g.s.name
        );
        let sample = sample_items(&sel, &mut rng, 6, 3);
        for item in sample {
            // A quadrant is drawn as its parent's surface, a sixteenth as its grandparent's.
            let drawn = item.node_level + item.morph.levels_up();
            quadrants_checked += (item.morph.levels_up() == 1) as u64;
            sixteenths_checked += (item.morph.levels_up() == 2) as u64;
            let err = geo_tile_error_px(
                g,
                &cam,
                (W, H),
                M,
                item.node_level,
                item.node_tx,
                item.node_ty,
                drawn,
            );
            assert!(
                err <= tau + 1e-6,
                "{}: camera {k} {:?}: node L{} ({}, {}) of tile L{} r{} projects {err:.4} px > τ (bound said {:.4})",
                g.s.name,
                cam.position,
                item.node_level,
                item.node_tx,
                item.node_ty,
                item.level,
                item.refinement,
                item.rho_px
            );
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
        "{what} bound oracle: {tiles_checked} tiles ({refined_checked} refined, {quadrants_checked} quadrants at their parent's resolution, {sixteenths_checked} sixteenths at their grandparent's) within τ; tightest measured/bound = {worst_ratio:.3}"
    );
    assert!(quadrants_checked > 0, "{what}: no quadrant checked");
    assert!(sixteenths_checked > 0, "{what}: no sixteenth checked");
    (tiles_checked, refined_checked)
}

/// [`roots_drawn_coarser_are_within_tau`] on the ellipsoid: at coarse τ, each root of the
/// coarsest clipmap level drawn at its parent's or grandparent's resolution is within τ and
/// its bound, its true samples at their exact positions against the drawn surface.
#[test]
fn geodetic_roots_drawn_coarser_are_within_tau() {
    let scenes = [
        alpine_47n(M),
        geo_scene(
            "ridged 10° 60°N",
            generated(DemKind::Ridged, 3),
            55.0,
            10.0,
            0.01,
            M,
        ),
    ];
    let mut rng = Rng(16);
    let mut roots = CoarserRoots::default();
    for k in 0..48 {
        let g = &scenes[k % scenes.len()];
        let cam = random_geo_camera(&mut rng, g);
        let tau = [3.0, 8.0, 30.0][k % 3];
        let sel = select_geo(g, &cam, tau);
        let top = g.s.clip.level_count() - 1;
        for item in sel
            .items
            .iter()
            .filter(|i| i.node_level == top && i.morph.levels_up() > 0)
            .take(6)
        {
            let drawn = top + item.morph.levels_up();
            let err = geo_tile_error_px(g, &cam, (W, H), M, top, item.node_tx, item.node_ty, drawn);
            roots.check(item, err, tau, &format!("{}: camera {k}", g.s.name));
        }
    }
    roots.report("geodetic coarser roots", 30);
}

#[test]
fn every_drawn_geodetic_tile_is_within_tau_for_a_thousand_random_cameras() {
    let scenes = [
        // The Inn valley crop where SRTM has it (its south-west sample 88 rows and columns in).
        alpine_47n(M),
        // High latitude: a longitude step is a third of a latitude step.
        cliffs_70n(M),
        // A 10° region across the seam at 60°S: nodes of degrees, the normal turning 10°.
        geo_scene(
            "ridged 10° 60°S seam",
            generated(DemKind::Ridged, 3),
            -65.0,
            175.0,
            0.01,
            M,
        ),
    ];
    let (tiles, refined) = geodetic_oracle(&scenes, 1002, 1414, "geodetic");
    assert!(tiles > 3000 && refined > 300, "{tiles} / {refined}");
}

/// The same on UTM grids: one straddling zone 32's western edge at 46.5° N (30 m), one of
/// 123 km at 120 m near 70° N, one in a southern zone.
#[test]
fn every_drawn_utm_tile_is_within_tau_for_random_cameras() {
    let mut wide = generated(DemKind::Ridged, 3);
    wide.spacing_x = 120.0;
    wide.spacing_y = 120.0;
    let scenes = [
        utm_geo_scene(
            "alpine UTM 32N zone edge",
            alpine_utm(),
            "EPSG:32632",
            255_000.0,
            5_150_000.0,
            M,
        ),
        utm_geo_scene(
            "ridged UTM 33N 70°N",
            wide,
            "EPSG:32633",
            420_000.0,
            7_760_000.0,
            M,
        ),
        utm_geo_scene(
            "cliffs UTM 19S",
            generated(DemKind::Cliffs, 7),
            "EPSG:32719",
            600_000.0,
            6_200_000.0,
            M,
        ),
    ];
    let (tiles, refined) = geodetic_oracle(&scenes, 501, 3232, "UTM");
    assert!(tiles > 1500 && refined > 150, "{tiles} / {refined}");
}

/// The alpine crop on a 30 m grid (a UTM GeoTIFF's spacing).
fn alpine_utm() -> Heightfield {
    let mut hf = alpine();
    hf.spacing_x = 30.0;
    hf.spacing_y = 30.0;
    hf
}

/// The drawn tiles of a geographic selection cover the visible ground exactly once, also on a
/// 10° region where the ground bends away by kilometres.
#[test]
fn geodetic_tiles_cover_the_visible_ground_exactly_once() {
    let g = geo_scene(
        "ridged 10° 60°N",
        generated(DemKind::Ridged, 3),
        55.0,
        10.0,
        0.01,
        M,
    );
    let hf = &g.s.ds.hf;
    let q = (M - 1) as usize;
    let mut rng = Rng(9);
    let mut visible_total = 0;
    for k in 0..12 {
        let cam = random_geo_camera(&mut rng, &g);
        let sel = select_geo(&g, &cam, 1.0);
        let mut count = vec![0u8; (hf.width - 1) * (hf.height - 1)];
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
        for row in 0..hf.height - 1 {
            for c in 0..hf.width - 1 {
                let p = g.world(c, row, hf.at(c, row) as f64);
                let Some((px, _)) = cam.project_px(p, W, H) else {
                    continue;
                };
                if px.x >= 0.0 && px.x <= W as f64 && px.y >= 0.0 && px.y <= H as f64 {
                    visible_total += 1;
                    assert_eq!(
                        count[row * (hf.width - 1) + c],
                        1,
                        "camera {k}: visible cell ({c}, {row}) is not drawn"
                    );
                }
            }
        }
    }
    assert!(visible_total > 1000, "{visible_total}");
}
