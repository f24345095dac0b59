//! A selection carried across frames (`SelectParams::carry`, `terrain/src/select/carry.rs`),
//! checked by brute force on flights over the flat plane: in every frame the drawn nodes cover
//! the visible ground exactly once and each, carried or walked, lies within τ of the true
//! surface and within the bound it reports (`flat_oracle`); the flights carry most nodes, and
//! carrying draws about the nodes a fresh walk does. The same on the WGS84 ellipsoid
//! (geographic grids at 47° N and 70° N, `geo_oracle`: every sample at its exact position).

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::terrain::clipmap::place_levels;
use aerie::terrain::gen::{generate, DemKind, GenParams};
use aerie::terrain::geodesy::Geodetic;
use aerie::terrain::select::DrawItem;
use aerie::terrain::select::{select_tiles, SelectParams, Selection};
use aerie_tests::flat_oracle::{self, alpine, scene, Scene};
use aerie_tests::geo_oracle::{alpine_47n, cliffs_70n, geo_tile_error_px, GeoScene};
use glam::{DVec2, DVec3};

const W: u32 = 320;
const H: u32 = 180;
const M: u32 = 17;

/// splitmix64, so failures reproduce.
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

/// One flight: a straight line at a steady speed, turning steadily or not at all.
fn flight(rng: &mut Rng, s: &Scene, frames: usize) -> Vec<Camera> {
    let hf = &s.ds.hf;
    let (ex, ey) = hf.extent_m();
    let (x, y) = (rng.range(0.3, 0.7) * ex, rng.range(0.3, 0.7) * ey);
    let z = hf.height_at_m(x, y) + rng.range(100.0, 2000.0);
    let heading = rng.range(0.0, 360.0);
    let pitch = rng.range(-45.0, -3.0);
    let speed = rng.range(30.0, 250.0) / 30.0;
    // Half the flights turn (up to 0.3° a frame in heading, 0.1° in pitch).
    let turns = rng.next() < 0.5;
    let (yaw_rate, pitch_rate) = if turns {
        (rng.range(-0.3, 0.3), rng.range(-0.1, 0.1))
    } else {
        (0.0, 0.0)
    };
    let climb = rng.range(-0.1, 0.1);
    let frustum = Frustum::symmetric(rng.range(50.0, 100.0).to_radians(), W, H);
    let dir = heading.to_radians();
    (0..frames)
        .map(|k| {
            let t = k as f64;
            let p = DVec3::new(x, y, z) + DVec3::new(dir.sin(), dir.cos(), climb) * speed * t;
            let att = Attitude::from_degrees(heading + yaw_rate * t, pitch + pitch_rate * t, 0.0);
            Camera::new(p, att, frustum)
        })
        .collect()
}

fn select(s: &Scene, cam: &Camera, carry: bool, sel: &mut Selection) {
    select_at(s, cam, (W, H), carry, sel);
}

fn select_at(s: &Scene, cam: &Camera, viewport: (u32, u32), carry: bool, sel: &mut Selection) {
    let hf = &s.ds.hf;
    let viewer = [cam.position.x / hf.spacing_x, cam.position.y / hf.spacing_y];
    let placements = place_levels(&s.clip, viewer);
    let params = SelectParams {
        tau_px: 1.0,
        max_refinement: 6,
        carry,
        ..SelectParams::default()
    };
    select_tiles(&s.bake, &s.clip, &placements, cam, viewport, &params, sel);
}

/// Records made in one frame fall due together ages later; at most
/// `AGED_WALKS_PER_FRAME` are walked afresh a frame and the others drawn again, certified,
/// for up to `AGE_GRACE` frames more (`carry.rs`). On a long straight flight, where most
/// records hold, some are drawn past their age — every node of those frames checked against
/// τ and its bound by brute force — and no frame walks more than the budget for age.
#[test]
fn records_drawn_past_their_age_stay_within_tau() {
    use aerie::terrain::select::AGED_WALKS_PER_FRAME;
    let s = scene("alpine", alpine(), M);
    let hf = &s.ds.hf;
    let (ex, ey) = hf.extent_m();
    let (x, y) = (0.35 * ex, 0.4 * ey);
    let z = hf.height_at_m(x, y) + 600.0;
    let viewport = (960, 540);
    let frustum = Frustum::symmetric(90f64.to_radians(), viewport.0, viewport.1);
    let mut sel = Selection::default();
    let (mut deferred, mut checked) = (0u32, 0u32);
    for k in 0..100 {
        let p = DVec3::new(x + 3.0 * k as f64, y + 2.0 * k as f64, z);
        let cam = Camera::new(p, Attitude::from_degrees(56.0, -15.0, 0.0), frustum);
        select_at(&s, &cam, viewport, true, &mut sel);
        let stats = sel.carry.stats;
        assert!(
            stats.aged_tiles <= AGED_WALKS_PER_FRAME,
            "frame {k}: {} ring tiles walked for their age",
            stats.aged_tiles
        );
        if stats.deferred_tiles == 0 {
            continue;
        }
        deferred += stats.deferred_tiles;
        for item in &sel.items {
            let up = item.morph.levels_up();
            let (l, tx, ty) = (item.node_level, item.node_tx, item.node_ty);
            let err = flat_oracle::tile_error_px(hf, &cam, viewport, M, l, tx, ty, l + up);
            assert!(
                err <= 1.0 + 1e-6 && err <= item.rho_px as f64 + 1e-6,
                "frame {k}: node L{l} ({tx}, {ty}) +{up} projects {err:.4} px (bound {:.4})",
                item.rho_px
            );
            checked += 1;
        }
    }
    eprintln!("{deferred} records drawn past their age; {checked} nodes of their frames checked");
    assert!(
        deferred >= 5,
        "only {deferred} records drawn past their age"
    );
}

#[test]
fn carried_nodes_cover_the_ground_once_and_stay_within_tau() {
    let scenes = [
        scene("alpine", alpine(), M),
        scene(
            "cliffs",
            generate(&GenParams {
                size: 1025,
                spacing: 30.0,
                kind: DemKind::Cliffs,
                seed: 7,
            }),
            M,
        ),
    ];
    let mut rng = Rng(0x15_0c);
    let mut tally = Tally::default();
    for f in 0..8 {
        let s = &scenes[f % scenes.len()];
        let hf = &s.ds.hf;
        let (mut sel, mut fresh) = (Selection::default(), Selection::default());
        for (k, cam) in flight(&mut rng, s, 30).iter().enumerate() {
            let what = format!("{} flight {f} frame {k}", s.name);
            select(s, cam, true, &mut sel);
            select(s, cam, false, &mut fresh);
            // Every third frame, and every frame that repaired a record (one node walked
            // afresh beside the others drawn again): the ground covered exactly once.
            if k % 3 == 2 || sel.carry.stats.repaired_tiles > 0 {
                flat_oracle::assert_covered_once(hf, cam, (W, H), M, &sel.items, &what);
            }
            tally.frame(&sel, &fresh, &mut rng, &what, |l, x, y, drawn| {
                flat_oracle::tile_error_px(hf, cam, (W, H), M, l, x, y, drawn)
            });
        }
    }
    tally.finish("carried selection", 2);
    assert!(
        tally.repaired > 5,
        "{} records repaired: too few to tell",
        tally.repaired
    );
}

/// A carried flight's counts: nodes carried and drawn, nodes fresh walks drew, nodes checked,
/// and the tightest measured error over its bound.
#[derive(Default)]
struct Tally {
    carried: u64,
    drawn: u64,
    fresh_drawn: u64,
    checked: u64,
    worst_ratio: f64,
    /// Records drawn past their age (`CarryStats::deferred_tiles`), over the frames.
    deferred: u64,
    /// Records repaired (`CarryStats::repaired_tiles`), over the frames.
    repaired: u64,
}

impl Tally {
    /// One frame, `sel` carried and `fresh` walked afresh: where nodes were carried, the nodes
    /// nearest τ and three at random are checked with `error_px(level, tx, ty, drawn level)`
    /// against τ and their bound.
    fn frame(
        &mut self,
        sel: &Selection,
        fresh: &Selection,
        rng: &mut Rng,
        what: &str,
        error_px: impl Fn(u32, u32, u32, u32) -> f64,
    ) {
        assert_eq!(sel.unbounded, 0, "{what}: unbounded nodes");
        self.deferred += sel.carry.stats.deferred_tiles as u64;
        self.repaired += sel.carry.stats.repaired_tiles as u64;
        self.carried += sel.carry.stats.carried_nodes as u64;
        self.drawn += sel.items.len() as u64;
        self.fresh_drawn += fresh.items.len() as u64;
        if sel.carry.stats.carried_nodes == 0 || sel.items.is_empty() {
            return;
        }
        // A frame that drew records past their age (waiting for a frame with room to walk
        // them) or repaired one has more of its nodes checked: they are certified like any
        // other.
        let random = if sel.carry.stats.deferred_tiles + sel.carry.stats.repaired_tiles > 0 {
            12
        } else {
            3
        };
        for item in picked(sel, rng, random) {
            let up = item.morph.levels_up();
            let (l, x, y) = (item.node_level, item.node_tx, item.node_ty);
            let err = error_px(l, x, y, l + up);
            assert!(
                err <= 1.0 + 1e-6 && err <= item.rho_px as f64 + 1e-6,
                "{what}: node L{l} ({x}, {y}) +{up} projects {err:.4} px (bound {:.4})",
                item.rho_px
            );
            if item.rho_px > 0.0 {
                self.worst_ratio = self.worst_ratio.max(err / item.rho_px as f64);
            }
            self.checked += 1;
        }
    }

    /// The summary line; more than one node in `share` carried, enough checked, and carried
    /// nodes — an earlier frame's walk's — never far more than a fresh walk's.
    fn finish(&self, name: &str, share: u64) {
        let Self {
            carried,
            drawn,
            fresh_drawn,
            checked,
            worst_ratio,
            deferred,
            repaired,
        } = *self;
        eprintln!(
            "{name}: {carried} of {drawn} nodes carried; {fresh_drawn} drawn by fresh walks; {checked} nodes checked, tightest measured/bound {worst_ratio:.3}; {deferred} records drawn past their age; {repaired} repaired"
        );
        assert!(
            carried * share > drawn,
            "too little carried to tell: {carried} of {drawn}"
        );
        assert!(checked > 200, "{checked} nodes checked");
        assert!(
            drawn * 100 <= fresh_drawn * 110,
            "carrying drew {drawn} nodes, fresh walks {fresh_drawn}"
        );
    }
}

/// The nodes nearest τ in `sel` and `random` more at random.
fn picked(sel: &Selection, rng: &mut Rng, random: usize) -> Vec<DrawItem> {
    let mut order: Vec<usize> = (0..sel.items.len()).collect();
    order.sort_by(|&a, &b| sel.items[b].rho_px.total_cmp(&sel.items[a].rho_px));
    let mut pick: Vec<usize> = order.iter().take(3).copied().collect();
    for _ in 0..random {
        pick.push((rng.next() * sel.items.len() as f64) as usize % sel.items.len());
    }
    pick.into_iter().map(|i| sel.items[i]).collect()
}

/// A flight on the ellipsoid: straight and level in the world frame of the grid (the ENU
/// frame at its south-west sample) at a steady speed, the attitude in the local frame where
/// it starts, turning steadily or not at all.
fn geo_flight(rng: &mut Rng, g: &GeoScene, frames: usize) -> Vec<Camera> {
    let hf = &g.s.ds.hf;
    let (ex, ey) = hf.extent_m();
    let (x, y) = (rng.range(0.3, 0.7) * ex, rng.range(0.3, 0.7) * ey);
    let (lat, lon) = g.grid.lat_lon_of_grid(DVec2::new(x, y));
    let h = hf.height_at_m(x, y) + rng.range(100.0, 2000.0);
    let start = g.grid.world_of_geodetic(Geodetic::new(lat, lon, h));
    let axes = g.grid.local_enu_axes(lat, lon);
    let heading = rng.range(0.0, 360.0);
    let pitch = rng.range(-45.0, -3.0);
    let speed = rng.range(30.0, 250.0) / 30.0;
    let turns = rng.next() < 0.5;
    let (yaw_rate, pitch_rate) = if turns {
        (rng.range(-0.3, 0.3), rng.range(-0.1, 0.1))
    } else {
        (0.0, 0.0)
    };
    let frustum = Frustum::symmetric(rng.range(50.0, 100.0).to_radians(), W, H);
    let dir = heading.to_radians();
    let east = axes.x_axis;
    let north = axes.y_axis;
    (0..frames)
        .map(|k| {
            let t = k as f64;
            let p = start + (east * dir.sin() + north * dir.cos()) * speed * t;
            let att = Attitude::from_degrees(heading + yaw_rate * t, pitch + pitch_rate * t, 0.0)
                .in_frame(axes);
            Camera::new(p, att, frustum)
        })
        .collect()
}

fn select_geo(g: &GeoScene, cam: &Camera, carry: bool, sel: &mut Selection) {
    let hf = &g.s.ds.hf;
    let eye = g.grid.grid_of_world(cam.position);
    let placements = place_levels(&g.s.clip, [eye.x / hf.spacing_x, eye.y / hf.spacing_y]);
    let params = SelectParams {
        tau_px: 1.0,
        max_refinement: 6,
        earth: Some(g.grid),
        carry,
        ..SelectParams::default()
    };
    select_tiles(&g.s.bake, &g.s.clip, &placements, cam, (W, H), &params, sel);
}

#[test]
fn carried_nodes_on_the_ellipsoid_stay_within_tau() {
    let scenes = [alpine_47n(M), cliffs_70n(M)];
    let mut rng = Rng(0x15_0e);
    let mut tally = Tally::default();
    for f in 0..8 {
        let g = &scenes[f % scenes.len()];
        let (mut sel, mut fresh) = (Selection::default(), Selection::default());
        for (k, cam) in geo_flight(&mut rng, g, 30).iter().enumerate() {
            let what = format!("{} flight {f} frame {k}", g.s.name);
            select_geo(g, cam, true, &mut sel);
            select_geo(g, cam, false, &mut fresh);
            tally.frame(&sel, &fresh, &mut rng, &what, |l, x, y, drawn| {
                geo_tile_error_px(g, cam, (W, H), M, l, x, y, drawn)
            });
        }
    }
    // A third, not half as on the plane: these grids are 3× as wide (far ring tiles reach
    // 40 km), and a turn moves a far box by k·D — the turning flights' records hold fewer
    // frames.
    tally.finish("carried selection on the ellipsoid", 3);
}
