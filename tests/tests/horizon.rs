//! Horizon culling checked by brute force (issue 15 item 3): for random eyes — low in valleys,
//! high above ridges — over generated rough terrain and the embedded Inn valley (on the flat
//! plane with the curvature drop, and on the WGS84 ellipsoid), every node box the horizon
//! hides has every level-0 sample inside it hidden by an f64 ray cast against the
//! full-resolution heights: the segment from the eye to the sample passes strictly below the
//! lowest corner of some level-0 cell it crosses (below every triangle drawn over that cell).
//! The drawn triangles' corners are level-0 samples of the node, so they are hidden too. The
//! sweep also asserts the horizon hides something (the check is not vacuous), and that the
//! selection with culling on draws a subset of the nodes it draws with culling off.

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::terrain::bake::{bake, BakeParams, ErrorBake};
use aerie::terrain::clipmap::{place_levels, ClipmapDesc};
use aerie::terrain::dataset::Dataset;
use aerie::terrain::gen::{generate, DemKind, GenParams};
use aerie::terrain::geodesy::{GeoGrid, Geodetic};
use aerie::terrain::load::geographic_spacing_m;
use aerie::terrain::load_dem;
use aerie::terrain::select::{
    select_tiles, tile_aabb, HorizonSet, SelectParams, Selection, EARTH_RADIUS_M,
};
use aerie::terrain::tiles::Aabb;
use aerie::terrain::{GeoReference, Heightfield};
use aerie_tests::demo_dem;
use glam::{DVec2, DVec3};

const M: u32 = 17;

/// splitmix64: deterministic, so failures reproduce.
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
    ds: Dataset,
    bake: ErrorBake,
    grid: Option<GeoGrid>,
}

fn scene(hf: Heightfield) -> Scene {
    let grid = GeoGrid::of(hf.geo.as_ref(), hf.spacing_x, hf.spacing_y);
    let ds = Dataset::from_heightfield(hf, "horizon".into());
    assert_eq!(
        (ds.valid_width, ds.valid_height),
        (ds.hf.width, ds.hf.height)
    );
    let bake = bake(
        &ds,
        BakeParams {
            tile_size: M,
            levels: 0,
        },
        &|_, _| {},
    );
    Scene { ds, bake, grid }
}

/// An n² crop of the Inn valley tile from (c0, r0).
fn inn(n: usize, c0: usize, r0: usize) -> Heightfield {
    let full = load_dem(&demo_dem()).expect("demo DEM");
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

/// The same crop on the ellipsoid: 3" cells at 47°N (as the tile is).
fn inn_geo(n: usize) -> Heightfield {
    let mut hf = inn(n, 300, 300);
    let d = 1.0 / 1200.0;
    let lat = 47.0 + 300.0 * d;
    let (sx, sy) = geographic_spacing_m(lat + d * n as f64 / 2.0, d, d);
    hf.spacing_x = sx;
    hf.spacing_y = sy;
    hf.geo = Some(GeoReference::Geographic {
        south_lat_deg: lat,
        west_lon_deg: 11.0 + 300.0 * d,
        dlat_deg: d,
        dlon_deg: d,
    });
    hf
}

/// An eye: 30 % low (2–60 m above the ground, in valleys or on slopes), the rest 60–2500 m.
fn random_eye(rng: &mut Rng, s: &Scene) -> DVec3 {
    let hf = &s.ds.hf;
    let (ex, ey) = hf.extent_m();
    let (x, y) = (rng.range(0.0, ex), rng.range(0.0, ey));
    let ground = hf.height_at_m(x, y);
    let agl = if rng.next() < 0.6 {
        rng.range(2.0, 60.0)
    } else {
        rng.range(60.0, 2500.0)
    };
    match &s.grid {
        Some(g) => {
            let (lat, lon) = g.lat_lon_of_grid(DVec2::new(x, y));
            g.world_of_geodetic(Geodetic::new(lat, lon, ground + agl))
        }
        None => DVec3::new(x, y, ground + agl),
    }
}

/// Every tile of every bake level: (level, tx, ty, box as the selection makes it).
fn node_boxes(s: &Scene, eye: DVec3) -> Vec<(u32, u32, u32, Aabb)> {
    let b = &s.bake;
    let q = (M - 1) as u64;
    let sp = DVec2::new(b.spacing_x, b.spacing_y);
    let vmax = DVec2::new(
        (b.valid_width - 1) as f64 * b.spacing_x,
        (b.valid_height - 1) as f64 * b.spacing_y,
    );
    let mut out = Vec::new();
    for (l, t) in b.levels.iter().enumerate() {
        let side = q << l;
        for ty in 0..t.tiles_y {
            for tx in 0..t.tiles_x {
                let lo = (DVec2::new((tx as u64 * side) as f64, (ty as u64 * side) as f64) * sp)
                    .min(vmax);
                let hi = (lo + DVec2::splat(side as f64) * sp).min(vmax);
                let (min_h, max_h) = b.bounds(l as u32, tx, ty);
                let aabb = match &s.grid {
                    Some(g) => g.node_geometry(lo, hi, min_h, max_h).aabb,
                    None => {
                        let cell = (sp * (1u64 << l) as f64).length();
                        tile_aabb(lo, hi, min_h, max_h, eye, true, cell)
                    }
                };
                out.push((l as u32, tx, ty, aabb));
            }
        }
    }
    out
}

/// Height of sample (c, r) as drawn from `eye` on the flat plane (curvature drop applied).
fn flat_height(hf: &Heightfield, eye: DVec3, c: usize, r: usize) -> f64 {
    let p = DVec2::new(c as f64 * hf.spacing_x, r as f64 * hf.spacing_y);
    hf.at(c, r) as f64 - (p - eye.truncate()).length_squared() / (2.0 * EARTH_RADIUS_M)
}

/// Flat plane: whether the segment eye → sample (c, r) passes strictly below the lowest
/// (dropped) corner of a level-0 cell it crosses. Exact: the segment is cut at every grid
/// line; on each piece it is linear, so its lowest point is an end.
fn flat_blocked(hf: &Heightfield, eye: DVec3, c: usize, r: usize) -> bool {
    let a = DVec2::new(eye.x / hf.spacing_x, eye.y / hf.spacing_y);
    let b = DVec2::new(c as f64, r as f64);
    let pz = flat_height(hf, eye, c, r);
    let mut ts = vec![0.0, 1.0];
    for axis in 0..2 {
        let (a0, b0) = (a[axis], b[axis]);
        if (b0 - a0).abs() < 1e-12 {
            continue;
        }
        let (lo, hi) = (a0.min(b0), a0.max(b0));
        let mut k = lo.floor() + 1.0;
        while k < hi {
            ts.push((k - a0) / (b0 - a0));
            k += 1.0;
        }
    }
    ts.sort_by(f64::total_cmp);
    let (w, h) = (hf.width as i64, hf.height as i64);
    for pair in ts.windows(2) {
        let (t0, t1) = (pair[0], pair[1]);
        if t1 - t0 < 1e-12 {
            continue;
        }
        let mid = a + (b - a) * (0.5 * (t0 + t1));
        let (ci, ri) = (mid.x.floor() as i64, mid.y.floor() as i64);
        if ci < 0 || ri < 0 || ci + 1 >= w || ri + 1 >= h {
            continue;
        }
        let (ci, ri) = (ci as usize, ri as usize);
        let floor = [(0, 0), (1, 0), (0, 1), (1, 1)]
            .iter()
            .map(|&(dx, dy)| flat_height(hf, eye, ci + dx, ri + dy))
            .fold(f64::INFINITY, f64::min);
        let z = |t: f64| eye.z + (pz - eye.z) * t;
        if z(t0).min(z(t1)) < floor - 1e-6 {
            return true;
        }
    }
    false
}

/// Ellipsoid: whether the segment eye → sample (c, r) (exact positions) has a point whose
/// height above the ellipsoid is below the lowest corner of the level-0 cell under it (less
/// 1 cm for the chord of a 90 m cell, < 1 mm). Sampled every quarter of a cell.
fn geo_blocked(hf: &Heightfield, g: &GeoGrid, eye: DVec3, c: usize, r: usize) -> bool {
    let gp = DVec2::new(c as f64 * hf.spacing_x, r as f64 * hf.spacing_y);
    let p = g.world_of_grid(gp, hf.at(c, r) as f64);
    let len = (p - eye).length();
    let step = 0.25 * hf.spacing_x.min(hf.spacing_y);
    let n = (len / step).ceil() as usize;
    for i in 1..n {
        let q = eye + (p - eye) * (i as f64 / n as f64);
        let gq = g.grid_of_world(q);
        let (fc, fr) = (gq.x / hf.spacing_x, gq.y / hf.spacing_y);
        let (ci, ri) = (fc.floor() as i64, fr.floor() as i64);
        if ci < 0 || ri < 0 || ci + 1 >= hf.width as i64 || ri + 1 >= hf.height as i64 {
            continue;
        }
        let (ci, ri) = (ci as usize, ri as usize);
        let floor = [(0, 0), (1, 0), (0, 1), (1, 1)]
            .iter()
            .map(|&(dx, dy)| hf.at(ci + dx, ri + dy) as f64)
            .fold(f64::INFINITY, f64::min);
        if gq.z < floor - 0.01 {
            return true;
        }
    }
    false
}

/// Runs `eyes` random eyes over `s`: every sample of every hidden node must be blocked.
/// At most `budget` samples are cast per eye (a deterministic stride over the marked ones);
/// returns (nodes hidden, nodes considered, samples cast).
fn sweep(s: &Scene, seed: u64, eyes: usize, budget: usize) -> (usize, usize, usize) {
    let hf = &s.ds.hf;
    let mut rng = Rng(seed);
    let (mut hidden_nodes, mut nodes, mut cast) = (0, 0, 0);
    for e in 0..eyes {
        let eye = random_eye(&mut rng, s);
        let mut set = HorizonSet::default();
        set.build(&s.bake, s.grid.as_ref(), true, &[eye]);
        let mut marked = vec![false; hf.width * hf.height];
        for (l, tx, ty, aabb) in node_boxes(s, eye) {
            nodes += 1;
            if !set.hides(0, &aabb) {
                continue;
            }
            hidden_nodes += 1;
            let side = ((M - 1) as usize) << l;
            let (c0, r0) = (tx as usize * side, ty as usize * side);
            for r in r0..=(r0 + side).min(hf.height - 1) {
                for c in c0..=(c0 + side).min(hf.width - 1) {
                    marked[r * hf.width + c] = true;
                }
            }
        }
        let samples: Vec<usize> = (0..marked.len()).filter(|&i| marked[i]).collect();
        let stride = samples.len().div_ceil(budget.max(1)).max(1);
        for &i in samples.iter().step_by(stride) {
            let (c, r) = (i % hf.width, i / hf.width);
            let blocked = match &s.grid {
                Some(g) => geo_blocked(hf, g, eye, c, r),
                None => flat_blocked(hf, eye, c, r),
            };
            assert!(
                blocked,
                "eye {e} at {eye:?}: sample ({c}, {r}) (height {}) is in a hidden node but \
                 the ray cast reaches it",
                hf.at(c, r)
            );
            cast += 1;
        }
    }
    (hidden_nodes, nodes, cast)
}

#[test]
fn hidden_nodes_are_hidden_on_rough_generated_terrain() {
    for (kind, seed) in [
        (DemKind::Ridged, 3),
        (DemKind::Cliffs, 5),
        (DemKind::Mixed, 8),
    ] {
        let s = scene(generate(&GenParams {
            size: 257,
            spacing: 30.0,
            kind,
            seed,
        }));
        let (hidden, nodes, cast) = sweep(&s, 100 + seed, 12, 40_000);
        eprintln!("{kind:?}: {hidden} of {nodes} nodes hidden, {cast} samples cast");
        assert!(hidden > 0, "{kind:?}: the horizon hid nothing");
    }
}

#[test]
fn hidden_nodes_are_hidden_in_the_inn_valley() {
    let s = scene(inn(513, 200, 200));
    let (hidden, nodes, cast) = sweep(&s, 7, 10, 30_000);
    eprintln!("Inn valley (flat): {hidden} of {nodes} nodes hidden, {cast} samples cast");
    assert!(hidden > 0, "the horizon hid nothing in the Inn valley");
}

#[test]
fn hidden_nodes_are_hidden_in_the_inn_valley_on_the_ellipsoid() {
    let s = scene(inn_geo(257));
    let (hidden, nodes, cast) = sweep(&s, 11, 8, 1_500);
    eprintln!("Inn valley (ellipsoid): {hidden} of {nodes} nodes hidden, {cast} samples cast");
    assert!(hidden > 0, "the horizon hid nothing on the ellipsoid");
}

/// The hook: with culling on, the selection draws what it draws with culling off less what the
/// horizon hides (a node whose hidden child no longer costs triangles may be drawn in other
/// parts over the same ground, never in more triangles), and every node dropped with its
/// ground is one the horizon hides.
#[test]
fn the_selection_drops_only_hidden_nodes() {
    let s = scene(inn(513, 200, 200));
    let hf = &s.ds.hf;
    let clip = ClipmapDesc {
        tile_quads: M - 1,
        patch_tiles: 8,
        margin_tiles: 2,
        width: hf.width as u32,
        height: hf.height as u32,
    };
    let mut rng = Rng(21);
    let mut dropped_total = 0;
    for _ in 0..12 {
        let eye = random_eye(&mut rng, &s);
        let cam = Camera::new(
            eye,
            Attitude::from_degrees(rng.range(0.0, 360.0), rng.range(-20.0, 5.0), 0.0),
            Frustum::symmetric(90f64.to_radians(), 256, 144),
        );
        let placements = place_levels(&clip, [eye.x / hf.spacing_x, eye.y / hf.spacing_y]);
        let run = |cull: bool| {
            let params = SelectParams {
                horizon_cull: cull,
                coarsen: false,
                ..SelectParams::default()
            };
            let mut sel = Selection::default();
            select_tiles(
                &s.bake,
                &clip,
                &placements,
                &cam,
                (256, 144),
                &params,
                &mut sel,
            );
            sel
        };
        let (off, on) = (run(false), run(true));
        assert_eq!(off.hidden, 0);
        let key = |d: &aerie::terrain::select::DrawItem| (d.node_level, d.node_tx, d.node_ty);
        let drawn_off: std::collections::HashSet<_> = off.items.iter().map(key).collect();
        let drawn_on: std::collections::HashSet<_> = on.items.iter().map(key).collect();
        // A node whose hidden child no longer costs triangles may be drawn in other parts
        // (`choose_parts`): over the same ground, never in more triangles.
        let related = |(l, tx, ty): (u32, u32, u32), set: &std::collections::HashSet<_>| {
            set.iter().any(|&(a, ax, ay): &(u32, u32, u32)| {
                (a > l && (tx >> (a - l), ty >> (a - l)) == (ax, ay))
                    || (a < l && (ax >> (l - a), ay >> (l - a)) == (tx, ty))
            })
        };
        for &n in drawn_on.difference(&drawn_off) {
            assert!(
                related(n, &drawn_off),
                "culling drew node {n:?} over ground it would not draw"
            );
        }
        let triangles = |sel: &Selection| -> u64 {
            let tris = |k: u64| aerie::render::terrain_draws::skirted_tile_triangles(k as u32);
            let q = (M - 1) as u64;
            sel.items
                .iter()
                .map(|i| tris(q >> i.morph.levels_up()))
                .sum()
        };
        assert!(
            triangles(&on) <= triangles(&off),
            "culling drew more triangles: {} > {}",
            triangles(&on),
            triangles(&off)
        );
        let mut set = HorizonSet::default();
        set.build(&s.bake, None, true, &[eye]);
        for &(l, tx, ty) in drawn_off.difference(&drawn_on) {
            if related((l, tx, ty), &drawn_on) {
                continue;
            }
            // A dropped node or an ancestor of it was hidden, or — a node drawn whole because
            // each of its quadrants met τ at its resolution — each of its quadrants holding
            // terrain was.
            let hidden_box = |a: u32, ax: u32, ay: u32| {
                node_boxes_one(&s, eye, a, ax, ay).is_some_and(|b| set.hides(0, &b))
            };
            let hidden = (l..s.bake.levels.len() as u32)
                .any(|a| hidden_box(a, tx >> (a - l), ty >> (a - l)))
                || (l > 0
                    && [(0, 0), (1, 0), (0, 1), (1, 1)].iter().all(|&(dx, dy)| {
                        let (cx, cy) = (2 * tx + dx, 2 * ty + dy);
                        let t = &s.bake.levels[l as usize - 1];
                        let terrain =
                            cx < t.tiles_x && cy < t.tiles_y && s.bake.is_terrain(l - 1, cx, cy);
                        !terrain || hidden_box(l - 1, cx, cy)
                    }));
            assert!(hidden, "node ({l}, {tx}, {ty}) dropped but not hidden");
            dropped_total += 1;
        }
        assert!(on.hidden as usize >= (off.items.len() > on.items.len()) as usize);
    }
    assert!(dropped_total > 0, "culling dropped nothing over 12 eyes");
}

fn node_boxes_one(s: &Scene, eye: DVec3, l: u32, tx: u32, ty: u32) -> Option<Aabb> {
    let t = &s.bake.levels[l as usize];
    if tx >= t.tiles_x || ty >= t.tiles_y {
        return None;
    }
    let b = &s.bake;
    let side = ((M - 1) as u64) << l;
    let sp = DVec2::new(b.spacing_x, b.spacing_y);
    let lo = DVec2::new((tx as u64 * side) as f64, (ty as u64 * side) as f64) * sp;
    let hi = lo + DVec2::splat(side as f64) * sp;
    let (min_h, max_h) = b.bounds(l, tx, ty);
    let cell = (sp * (1u64 << l) as f64).length();
    Some(tile_aabb(lo, hi, min_h, max_h, eye, true, cell))
}

/// On the GPU (lavapipe, validation on): a frame low in the Inn valley rendered with and
/// without culling. Culling hides tiles and draws fewer triangles, and the image-space error
/// of the culled frame against the full-resolution reference stays within τ + 0.5 px.
#[test]
fn culling_keeps_the_image_within_the_bound_on_the_gpu() {
    use aerie::render::frame::RendererDesc;
    use aerie::terrain::select::LodMode;
    use aerie::tools::image_error::{measure, MeasureParams};
    use aerie_tests::{prepare, render_dataset, test_desc};

    let (w, h) = (256u32, 144u32);
    let hf = load_dem(&demo_dem()).expect("demo DEM");
    let grid = GeoGrid::of(hf.geo.as_ref(), hf.spacing_x, hf.spacing_y).expect("geographic");
    let tau = 1.0;
    let desc = |mode: LodMode, cull: bool| -> RendererDesc {
        let mut d = test_desc(w, h);
        d.select = SelectParams {
            mode,
            tau_px: tau,
            horizon_cull: cull,
            ..SelectParams::default()
        };
        if mode == LodMode::Full {
            d.pool_capacity = [1024, 512, 256, 128, 48, 16];
            d.select.max_refinement = 6;
        }
        d
    };
    let (ds, bake) = prepare(&desc(LodMode::Full, false), &hf);
    // Over the Inn at Innsbruck, 120 m above the valley floor, looking up the valley.
    let (lat, lon) = (47.268, 11.40);
    let g = grid.grid_of_lat_lon(lat, lon);
    let ground = hf.height_at_m(g.x, g.y);
    let eye = grid.world_of_geodetic(Geodetic::new(lat, lon, ground + 120.0));
    let attitude = Attitude::from_degrees(75.0, -4.0, 0.0).in_frame(grid.local_enu_axes(lat, lon));
    let cam = Camera::new(eye, attitude, Frustum::symmetric(90f64.to_radians(), w, h));
    let render =
        |mode, cull| render_dataset(&desc(mode, cull), ds.clone(), bake.clone(), &[cam]).remove(0);
    let full = render(LodMode::Full, false);
    let off = render(LodMode::Bounded, false);
    let on = render(LodMode::Bounded, true);
    let params = MeasureParams {
        tau_px: tau,
        ..MeasureParams::default()
    };
    let m = |depth: &[f32]| measure(&ds, &cam, (w, h), depth, Some(&full.depth), &params, None);
    let (e_off, e_on) = (m(&off.depth), m(&on.depth));
    eprintln!(
        "culling off: {} triangles, max {:.3} px; on: {} triangles ({} hidden), max {:.3} px",
        off.stats.triangles,
        e_off.max_px(),
        on.stats.triangles,
        on.stats.tiles_hidden,
        e_on.max_px()
    );
    assert_eq!(off.stats.tiles_hidden, 0);
    assert!(
        on.stats.tiles_hidden > 0,
        "nothing hidden low in the valley"
    );
    assert!(on.stats.triangles < off.stats.triangles);
    assert!(e_on.max_px() <= tau + 0.5, "culled frame: {e_on:?}");
}
