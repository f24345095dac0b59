//! The fast selection (cached node values kept across frames, reused vectors, the fused corner
//! pass, the children a parent's upgrade formed taken instead of formed again) selects exactly what the reference evaluation does, on random cameras over flat and
//! geographic data, one and two channels, with one `Selection` kept across all of them (so the
//! cache also meets dataset changes).

use glam::DVec3;

use super::walk::reference::{with_every_hybrid, with_reference};
use super::*;
use crate::bake::{bake, BakeParams, ErrorBake};
use crate::camera::{Attitude, Camera, Frustum};
use crate::clipmap::{place_levels, ClipmapDesc};
use crate::dataset::Dataset;
use crate::gen::{generate, DemKind, GenParams};
use crate::geodesy::{GeoGrid, Geodetic};
use crate::GeoReference;

const N: usize = 513;
const W: u32 = 256;
const H: u32 = 144;

/// splitmix64, so failures reproduce (the selection's unit tests share it).
pub(super) struct Rng(pub(super) u64);
impl Rng {
    pub(super) fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    pub(super) fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

struct Scene {
    ds: Dataset,
    bake: ErrorBake,
    clip: ClipmapDesc,
    earth: Option<GeoGrid>,
}

/// A ridged terrain on the plane, or its samples on a 3″ grid at 60°N (nodes up to 0.4° wide,
/// so the coarse ones take the lattice boxes).
fn scene(geographic: bool) -> Scene {
    let mut hf = generate(&GenParams {
        size: N,
        spacing: 30.0,
        kind: DemKind::Ridged,
        seed: 15,
    });
    let mut earth = None;
    if geographic {
        let d = 3.0 / 3600.0;
        let (sx, sy) = crate::load::geographic_spacing_m(60.2, d, d);
        let geo = GeoReference::Geographic {
            south_lat_deg: 60.0,
            west_lon_deg: 10.0,
            dlat_deg: d,
            dlon_deg: d,
        };
        earth = GeoGrid::of(Some(&geo), sx, sy);
        (hf.spacing_x, hf.spacing_y, hf.geo) = (sx, sy, Some(geo));
    }
    let ds = Dataset::from_heightfield(hf, "equivalence".into());
    let bake = bake(
        &ds,
        BakeParams {
            tile_size: 17,
            levels: 0,
        },
        &|_, _| {},
    );
    let clip = ClipmapDesc {
        tile_quads: 16,
        patch_tiles: 8,
        margin_tiles: 2,
        width: N as u32,
        height: N as u32,
    };
    Scene {
        ds,
        bake,
        clip,
        earth,
    }
}

fn random_camera(rng: &mut Rng, s: &Scene) -> Camera {
    let hf = &s.ds.hf;
    let (ex, ey) = hf.extent_m();
    let (x, y) = (
        rng.range(-0.2 * ex, 1.2 * ex),
        rng.range(-0.2 * ey, 1.2 * ey),
    );
    let agl = if rng.next() < 0.4 {
        rng.range(2.0, 300.0)
    } else {
        rng.range(300.0, 9000.0)
    };
    let alt = hf.height_at_m(x, y) + agl;
    let attitude = Attitude::from_degrees(
        rng.range(0.0, 360.0),
        rng.range(-89.0, 20.0),
        rng.range(-60.0, 60.0),
    );
    let frustum = Frustum::symmetric(rng.range(30.0, 120.0).to_radians(), W, H);
    match &s.earth {
        Some(g) => {
            let (lat, lon) = g.lat_lon_of_grid(glam::DVec2::new(x, y));
            Camera::new(
                g.world_of_geodetic(Geodetic::new(lat, lon, alt)),
                attitude.in_frame(g.local_enu_axes(lat, lon)),
                frustum,
            )
        }
        None => Camera::new(DVec3::new(x, y, alt), attitude, frustum),
    }
}

fn select(s: &Scene, cams: &[Camera], params: &SelectParams, out: &mut Selection) {
    let eye = match &s.earth {
        Some(g) => g.grid_of_world(cams[0].position),
        None => cams[0].position,
    };
    let viewer = [eye.x / s.ds.hf.spacing_x, eye.y / s.ds.hf.spacing_y];
    let placements = place_levels(&s.clip, viewer);
    let views: Vec<View> = cams
        .iter()
        .map(|camera| View {
            camera,
            viewport: (W, H),
            tau_px: params.tau_px,
        })
        .collect();
    select_tiles_multi(&s.bake, &s.clip, &placements, &views, params, out);
}

fn assert_same(fast: &Selection, reference: &Selection, what: &str) {
    assert_eq!(fast.items, reference.items, "{what}: draw items");
    assert_eq!(fast.levels, reference.levels, "{what}: level statistics");
    assert_eq!(fast.unbounded, reference.unbounded, "{what}: unbounded");
    assert_eq!(fast.finest_level, reference.finest_level, "{what}: finest");
    assert_eq!(fast.stream_late, reference.stream_late, "{what}: late");
    assert_eq!(fast.wants, reference.wants, "{what}: wants");
}

#[test]
fn the_fast_selection_equals_the_reference_on_random_cameras_flat_and_geographic() {
    let scenes = [scene(false), scene(true)];
    let modes = [
        ("bounded", true, LodMode::Bounded),
        ("bounded rings", false, LodMode::Bounded),
        ("clipmap", false, LodMode::Clipmap),
    ];
    let mut rng = Rng(0x15_04);
    // One selection for everything: its cache must follow the dataset it is given.
    let mut fast = Selection::default();
    let mut drawn = 0;
    for k in 0..240 {
        let s = &scenes[k % 2];
        let (name, coarsen, mode) = modes[(k / 2) % modes.len()];
        let params = SelectParams {
            mode,
            coarsen,
            tau_px: [0.5, 1.0, 3.0][k % 3],
            max_refinement: 5,
            earth: s.earth,
            ..SelectParams::default()
        };
        let channels = 1 + (k / 6) % 2;
        let cams: Vec<Camera> = (0..channels).map(|_| random_camera(&mut rng, s)).collect();
        select(s, &cams, &params, &mut fast);
        let mut reference = Selection::default();
        with_reference(|| select(s, &cams, &params, &mut reference));
        let what = format!(
            "camera {k} ({name}, geographic {}, {channels} views)",
            k % 2
        );
        assert_same(&fast, &reference, &what);
        assert!(
            reference.node_cache.is_empty(),
            "{what}: reference used the cache"
        );
        drawn += fast.items.len();
    }
    assert!(drawn > 1000, "the cameras saw too little: {drawn} items");
    assert!(!fast.node_cache.is_empty());
}

/// Skipping the exact evaluations of children within reach that could change nothing
/// (`Frame::gain_floor`, one view on the plane) draws the same nodes in the same parts, each
/// with a bound no tighter than the exact one.
#[test]
fn skipping_exact_evaluations_that_change_nothing_draws_the_same() {
    let s = scene(false);
    let mut rng = Rng(0x15_06);
    let (mut fast, mut every) = (Selection::default(), Selection::default());
    let (mut looser, mut drawn) = (0, 0);
    for k in 0..160 {
        let params = SelectParams {
            coarsen: k % 4 != 3,
            tau_px: [0.5, 1.0, 3.0][k % 3],
            max_refinement: 5,
            ..SelectParams::default()
        };
        let cams = [random_camera(&mut rng, &s)];
        select(&s, &cams, &params, &mut fast);
        with_every_hybrid(|| select(&s, &cams, &params, &mut every));
        let what = format!("camera {k}");
        assert_eq!(fast.items.len(), every.items.len(), "{what}: items");
        for (a, b) in fast.items.iter().zip(&every.items) {
            let bare = |i: &DrawItem| DrawItem { rho_px: 0.0, ..*i };
            assert_eq!(bare(a), bare(b), "{what}: item");
            assert!(a.rho_px >= b.rho_px, "{what}: {} < {}", a.rho_px, b.rho_px);
            looser += (a.rho_px > b.rho_px) as usize;
        }
        assert_eq!(fast.levels, every.levels, "{what}: level statistics");
        assert_eq!(fast.unbounded, every.unbounded, "{what}: unbounded");
        drawn += fast.items.len();
    }
    // The skip happened (some bounds stayed looser) on cameras that saw enough.
    assert!(drawn > 1000, "the cameras saw too little: {drawn} items");
    assert!(looser > 0, "no evaluation was skipped");
}

/// Copying a selection copies what was selected, never the node cache: a clone starts with
/// none and `clone_from` keeps the target's own.
#[test]
fn a_copied_selection_keeps_its_own_node_cache() {
    // On the ellipsoid: the plane's nodes are not cached (two table reads are cheaper).
    let s = scene(true);
    let mut rng = Rng(7);
    let params = SelectParams {
        earth: s.earth,
        ..SelectParams::default()
    };
    let mut warm = Selection::default();
    let mut target = Selection::default();
    for _ in 0..4 {
        select(&s, &[random_camera(&mut rng, &s)], &params, &mut warm);
        select(&s, &[random_camera(&mut rng, &s)], &params, &mut target);
    }
    assert!(!warm.node_cache.is_empty() && !target.node_cache.is_empty());
    let kept = target.node_cache.len();
    let copy = warm.clone();
    assert_same(&copy, &warm, "clone");
    assert!(copy.node_cache.is_empty());
    target.clone_from(&warm);
    assert_same(&target, &warm, "clone_from");
    assert_eq!(target.node_cache.len(), kept);
}

/// A split node whose children holding terrain all meet τ as quadrants at its resolution is
/// drawn whole (fewer triangles, one instance), so a selection draws all four children of a
/// node as quadrants only where one of them missed τ as a quadrant by its own box and met it
/// split — on the ellipsoid, where that is decided when the child is walked, after its
/// siblings (rare: under 2 % of the nodes drawn in parts); quadrants are drawn where only some
/// of them meet τ so, and sixteenths are drawn.
#[test]
fn a_node_whose_every_quadrant_meets_tau_is_drawn_whole() {
    let scenes = [scene(false), scene(true)];
    let mut rng = Rng(0x15_05);
    let mut sel = Selection::default();
    let (mut quadrants, mut sixteenths, mut parents, mut apart) = (0, 0, 0, 0);
    for k in 0..120 {
        let s = &scenes[k % 2];
        let params = SelectParams {
            coarsen: k % 4 < 2,
            tau_px: [0.5, 1.0, 3.0][k % 3],
            max_refinement: 5,
            earth: s.earth,
            ..SelectParams::default()
        };
        select(s, &[random_camera(&mut rng, s)], &params, &mut sel);
        let mut siblings = std::collections::HashMap::new();
        for i in sel.items.iter().filter(|i| i.morph.quadrant) {
            let parent = (i.node_level + 1, i.node_tx / 2, i.node_ty / 2);
            if i.morph.sixteenth {
                sixteenths += 1;
            } else {
                *siblings.entry(parent).or_insert(0) += 1;
                quadrants += 1;
            }
        }
        parents += siblings.len();
        apart += siblings.values().filter(|&&n| n == 4).count();
    }
    assert!(quadrants > 100, "too few quadrants to tell: {quadrants}");
    assert!(sixteenths > 20, "too few sixteenths to tell: {sixteenths}");
    assert!(
        apart * 50 <= parents,
        "of {parents} nodes with quadrants drawn, {apart} had all four drawn apart"
    );
}

/// Ring tiles are carried across frames only where the certificate holds (`carry.rs`): one
/// view, on the plane or the ellipsoid, no horizon culling, `carry` asked for. A short
/// straight flight carries there; with two views, with horizon culling or with `carry` off
/// nothing is carried and no record is kept (the ground a carried tile draws is checked by
/// `tests/tests/carried_selection.rs`).
#[test]
fn ring_tiles_are_carried_only_where_the_certificate_holds() {
    let (flat, geo) = (scene(false), scene(true));
    // A camera over the scene's middle, then the same camera moved 2 m a frame.
    let flight = |s: &Scene| -> Vec<Camera> {
        let mut rng = Rng(0x15_0d);
        let start = loop {
            let c = random_camera(&mut rng, s);
            let (ex, ey) = s.ds.hf.extent_m();
            let g = match &s.earth {
                Some(e) => e.grid_of_world(c.position),
                None => c.position,
            };
            if (0.3 * ex..0.7 * ex).contains(&g.x) && (0.3 * ey..0.7 * ey).contains(&g.y) {
                break c;
            }
        };
        let pitched = Camera::new(
            start.position,
            Attitude::from_degrees(40.0, -20.0, 0.0),
            start.frustum,
        );
        (0..12)
            .map(|k| Camera {
                position: pitched.position + DVec3::new(2.0 * k as f64, 0.0, 0.0),
                ..pitched
            })
            .collect()
    };
    let carried = |s: &Scene, params: &SelectParams, views: usize| {
        let mut sel = Selection::default();
        let mut carried = 0;
        for cam in flight(s) {
            let cams = vec![cam; views];
            select(s, &cams, params, &mut sel);
            carried += sel.carry.stats.carried_tiles;
        }
        (carried, sel.carry.len())
    };
    let plane = SelectParams::default();
    let (n, kept) = carried(&flat, &plane, 1);
    assert!(
        n > 0 && kept > 0,
        "a straight flight on the plane carried {n}"
    );
    let off = SelectParams {
        carry: false,
        ..plane
    };
    assert_eq!(carried(&flat, &off, 1), (0, 0), "carry off");
    assert_eq!(carried(&flat, &plane, 2), (0, 0), "two views");
    let horizon = SelectParams {
        horizon_cull: true,
        ..plane
    };
    assert_eq!(carried(&flat, &horizon, 1), (0, 0), "horizon culling");
    let ellipsoid = SelectParams {
        earth: geo.earth,
        ..plane
    };
    let (n, kept) = carried(&geo, &ellipsoid, 1);
    assert!(
        n > 0 && kept > 0,
        "a straight flight on the ellipsoid carried {n}"
    );
    assert_eq!(
        carried(&geo, &ellipsoid, 2),
        (0, 0),
        "two views on the ellipsoid"
    );
}

/// A node that meets τ but crosses a frustum plane or holds padding is drawn as its seen
/// parts (`seen_quadrants.rs`) only where that is all that changes: every other item is the
/// same; each node left out is drawn whole without, and what its parts leave out of it holds
/// no terrain or (on the plane, checked here from the bake's bounds) lies wholly outside the
/// frustum; each part is a quadrant or a sixteenth of the node at the node's resolution, from
/// the node's texture (no refinement), meets τ with ε within the node's, no two overlap, and
/// together they are fewer triangles than the node.
#[test]
fn a_node_is_drawn_in_its_seen_parts_only_where_the_rest_cannot_show() {
    use super::bound::{outside_of, tile_aabb};
    use super::cdlod_morph::Morph;
    use super::walk::{has_terrain, Grid};
    let scenes = [scene(false), scene(true)];
    let mut rng = Rng(0x15_07);
    let (mut on, mut off) = (Selection::default(), Selection::default());
    let (mut replaced, mut quadrants, mut sixteenths, mut culled) = (0, 0, 0, 0);
    for k in 0..120 {
        let s = &scenes[k % 2];
        let tau = [1.0, 3.0, 10.0][k % 3];
        let params = |seen_quadrants| SelectParams {
            tau_px: tau,
            earth: s.earth,
            seen_quadrants,
            ..SelectParams::default()
        };
        let cam = random_camera(&mut rng, s);
        select(s, &[cam], &params(true), &mut on);
        select(s, &[cam], &params(false), &mut off);
        let what = format!("camera {k}, geographic {}", k % 2);
        let is_part = |i: &DrawItem| i.refinement == 0 && i.node_level < i.level;
        for i in on.items.iter().filter(|i| !is_part(i)) {
            assert!(off.items.contains(i), "{what}: {i:?} only with parts");
        }
        assert!(off.items.iter().all(|i| !is_part(i)), "{what}");
        let costs = super::parts::MeshCosts::of(s.bake.params.tile_size - 1);
        let grid = Grid::of(&s.bake);
        let to_view = cam.world_to_view();
        let outside = |l: u32, x: u32, y: u32, drawn: u32| {
            let (lo, hi) = grid.rect(l, x, y);
            let (min_h, max_h) = s.bake.bounds(l, x, y);
            let diagonal = grid.cell_diagonal(drawn);
            let aabb = tile_aabb(lo, hi, min_h, max_h, cam.position, true, diagonal);
            let corners = aabb.corners().map(|c| to_view.transform_point3(c));
            outside_of(&corners, &cam.frustum, cam.near)
        };
        for node in off.items.iter().filter(|i| !on.items.contains(i)) {
            let level = node.level;
            assert_eq!((node.refinement, node.node_level), (0, level), "{what}");
            let kids: Vec<&DrawItem> = on
                .items
                .iter()
                .filter(|i| is_part(i) && (i.level, i.tx, i.ty) == (level, node.tx, node.ty))
                .collect();
            let mut triangles = 0;
            for kid in &kids {
                let up = level - kid.node_level;
                let (mesh, morph) = match up {
                    1 => (costs.quadrant, Morph::QUADRANT),
                    2 => (costs.sixteenth, Morph::SIXTEENTH),
                    _ => panic!("{what}: {kid:?}"),
                };
                assert_eq!(kid.morph, morph, "{what}");
                assert_eq!((kid.node_tx >> up, kid.node_ty >> up), (node.tx, node.ty));
                assert!(kid.rho_px as f64 <= tau * (1.0 + 1e-9), "{what}: {kid:?}");
                assert!(kid.eps_m <= node.eps_m, "{what}: {kid:?} over {node:?}");
                triangles += mesh;
                quadrants += (up == 1) as usize;
                sixteenths += (up == 2) as usize;
            }
            assert!(triangles < costs.whole, "{what}: {kids:?} for {node:?}");
            replaced += 1;
            // Each sixteenth of the node (quadrant of a level-1 node): drawn (itself or in
            // its quadrant), or no terrain, or outside the frustum by its box or its
            // quadrant's; never drawn twice.
            let base = level.saturating_sub(2);
            let side = 1u32 << (level - base);
            for j in 0..side * side {
                let (gx, gy) = (side * node.tx + j % side, side * node.ty + j / side);
                let covering = kids
                    .iter()
                    .filter(|i| {
                        let up = i.node_level - base;
                        (i.node_tx, i.node_ty) == (gx >> up, gy >> up)
                    })
                    .count();
                assert!(covering <= 1, "{what}: overlapping parts");
                let up = level - 1 - base;
                let (qx, qy) = (gx >> up, gy >> up);
                if covering == 1 || !has_terrain(&s.bake, base, gx, gy) {
                    continue;
                }
                culled += 1;
                if s.earth.is_some() {
                    continue;
                }
                let gone = outside(level - 1, qx, qy, level) || outside(base, gx, gy, level);
                assert!(
                    gone,
                    "{what}: part ({base}, {gx}, {gy}) of {node:?} left out but in the frustum; parts {kids:?}"
                );
            }
        }
    }
    eprintln!(
        "{replaced} nodes drawn as {quadrants} quadrants and {sixteenths} sixteenths; {culled} sixteenths left out"
    );
    assert!(
        replaced > 20 && culled > 20 && sixteenths > 20,
        "{replaced} {culled} {sixteenths}"
    );
}
