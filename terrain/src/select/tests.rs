use glam::{DVec2, DVec3};

use super::bound::{frustum_gain_floor, outside_of, view_corners, CornerPass};
use super::*;
use crate::camera::{Attitude, Camera, Frustum};
use crate::clipmap::ClipmapDesc;
use crate::tiles::Aabb;

#[test]
fn projected_error_is_monotonic_and_infinite_inside_the_error() {
    let f = 960.0;
    let c = 1.5;
    let a = projected_error_px(1.0, 1000.0, f, c);
    assert!((a - 1.0 * 960.0 * 1.5 / 999.0).abs() < 1e-12);
    assert!(projected_error_px(1.0, 2000.0, f, c) < a);
    assert!(projected_error_px(2.0, 1000.0, f, c) > a);
    assert_eq!(projected_error_px(5.0, 5.0, f, c), f64::INFINITY);
    assert_eq!(projected_error_px(0.0, 0.5, f, c), 0.0);
}

/// Distance LOD keeps its previous decision inside the ±10 % band: the same camera position
/// selects different nodes when approached from near than from far.
#[test]
fn distance_mode_has_hysteresis() {
    use crate::bake::{bake, BakeParams};
    use crate::clipmap::place_levels;
    use crate::dataset::Dataset;
    use crate::Heightfield;
    let n = 257;
    let hf = Heightfield {
        width: n,
        height: n,
        spacing_x: 10.0,
        spacing_y: 10.0,
        heights: (0..n * n)
            .map(|k| ((k % n) as f32 * 0.3).sin() * 20.0)
            .collect(),
        geo: None,
        voids_filled: 0,
        spacing_note: String::new(),
    };
    let ds = Dataset::from_heightfield(hf, "t".into());
    let b = bake(
        &ds,
        BakeParams {
            tile_size: 17,
            levels: 0,
        },
        &|_, _| {},
    );
    let desc = ClipmapDesc {
        tile_quads: 16,
        patch_tiles: 8,
        margin_tiles: 2,
        width: n as u32,
        height: n as u32,
    };
    let params = SelectParams {
        mode: LodMode::Distance,
        coarsen: false,
        ..SelectParams::default()
    };
    let run = |heights: &[f64]| {
        let mut sel = Selection::default();
        for &z in heights {
            let cam = Camera::new(
                DVec3::new(1280.0, 1280.0, z),
                Attitude::from_degrees(0.0, -89.0, 0.0),
                Frustum::symmetric(170f64.to_radians(), 64, 64),
            );
            let placements = place_levels(&desc, [128.0, 128.0]);
            select_tiles(&b, &desc, &placements, &cam, (64, 64), &params, &mut sel);
        }
        sel.items.len()
    };
    // Level-1 ring tiles are 320 m wide: split below 3 × 320 = 960 m (± 10 %). The nearest
    // ones are 640 m away horizontally, so at 716 m up the eye is 960 m from them.
    let from_near = run(&[100.0, 700.0, 716.0]);
    let from_far = run(&[5000.0, 800.0, 716.0]);
    assert!(from_near > from_far, "near {from_near} vs far {from_far}");
    // Far outside the band, history does not matter.
    assert_eq!(run(&[100.0, 30_000.0]), run(&[30_000.0]));
}

/// The tightened factor is never above the direction-free obliquity, and the bound it gives
/// holds by brute force: random cameras and boxes, random visible points in the box moved
/// vertically by up to ε, the exact screen displacement never exceeds ε·f·g/(z_min − ε).
#[test]
fn vertical_gain_bounds_vertical_errors_on_screen() {
    let mut rnd = crate::test_rng::unit(0x2545_f491_4f6c_dd1du64);
    let (w, h) = (320u32, 180u32);
    let mut checked = 0;
    let mut tightest: f64 = 0.0;
    for _ in 0..400 {
        let cam = Camera::new(
            DVec3::new(0.0, 0.0, 1000.0),
            Attitude::from_degrees(rnd() * 360.0, rnd() * 180.0 - 90.0, rnd() * 360.0 - 180.0),
            Frustum::symmetric((20.0 + rnd() * 140.0).to_radians(), w, h),
        );
        let lo = DVec3::new(
            rnd() * 8000.0 - 4000.0,
            rnd() * 8000.0 - 4000.0,
            rnd() * 900.0,
        );
        let size = DVec3::new(50.0 + rnd() * 2000.0, 50.0 + rnd() * 2000.0, rnd() * 300.0);
        let aabb = Aabb {
            min: lo,
            max: lo + size,
        };
        let g = box_vertical_gain(&cam, &aabb);
        // The per-frame fast path agrees with the public functions.
        let corners = aabb
            .corners()
            .map(|c| cam.world_to_view().transform_point3(c));
        assert_eq!(
            outside_of(&corners, &cam.frustum, cam.near),
            crate::tiles::outside_frustum(&cam, &aabb)
        );
        let fused = view_corners(&cam.world_to_view(), &aabb);
        assert_eq!(
            CornerPass::cull_and_depth(&fused, &cam.frustum, cam.near).outside,
            outside_of(&corners, &cam.frustum, cam.near)
        );
        // No box's gain is below the frustum's least.
        let up = cam.world_to_view_rotation() * DVec3::Z;
        let floor = frustum_gain_floor(&cam.frustum, up);
        assert!(floor <= g, "floor {floor} above gain {g}");
        // And it is the least: a grid over the frustum comes within its spacing of it.
        let f = &cam.frustum;
        let n = 40;
        let (sa, sb) = (
            (f.tan_right - f.tan_left) / n as f64,
            (f.tan_up - f.tan_down) / n as f64,
        );
        let least = (0..=n)
            .flat_map(|i| (0..=n).map(move |j| (i, j)))
            .map(|(i, j)| {
                let (a, b) = (f.tan_left + sa * i as f64, -f.tan_up + sb * j as f64);
                ((up.x - a * up.z).powi(2) + (up.y - b * up.z).powi(2)).sqrt()
            })
            .fold(f64::INFINITY, f64::min);
        assert!(
            floor <= least + 1e-12,
            "floor {floor} above the grid's {least}"
        );
        assert!(
            least - floor <= (sa + sb) * up.z.abs() + 1e-12,
            "floor {floor} far below the grid's {least}"
        );
        assert!(g <= box_obliquity_reference(&cam, &aabb) + 1e-12);
        let (fx, fy) = cam.frustum.focal_px(w, h);
        let eps = 1.0 + rnd() * 20.0;
        let z_min = min_view_depth(&cam, &aabb);
        let bound = projected_error_px(eps, z_min, fx.max(fy), g);
        for _ in 0..50 {
            let p = aabb.min + (aabb.max - aabb.min) * DVec3::new(rnd(), rnd(), rnd());
            let Some((s0, _)) = cam.project_px(p, w, h) else {
                continue;
            };
            if !(0.0..=w as f64).contains(&s0.x) || !(0.0..=h as f64).contains(&s0.y) {
                continue;
            }
            let e = eps * (2.0 * rnd() - 1.0);
            let q = p + DVec3::new(0.0, 0.0, e);
            let Some((s1, _)) = cam.project_px(q, w, h) else {
                continue;
            };
            let moved = (s1 - s0).length();
            assert!(
                moved <= bound * (1.0 + 1e-9),
                "moved {moved} px > bound {bound} px"
            );
            tightest = tightest.max(moved / bound);
            checked += 1;
        }
    }
    assert!(checked > 1000, "only {checked} visible samples");
    // Not vacuous: some samples come close to the bound.
    assert!(tightest > 0.5, "tightest {tightest}");
}

/// The direction-free factor sqrt(1 + a² + b²) over the box's clamped (a, b) ranges.
fn box_obliquity_reference(camera: &Camera, aabb: &Aabb) -> f64 {
    let f = camera.frustum;
    let m = camera.world_to_view();
    let (mut a, mut b) = (0.0f64, 0.0f64);
    for c in aabb.corners() {
        let v = m.transform_point3(c);
        if v.z <= 1e-9 {
            return f.max_obliquity();
        }
        a = a.max((v.x / v.z).clamp(f.tan_left, f.tan_right).abs());
        b = b.max((v.y / v.z).clamp(-f.tan_up, -f.tan_down).abs());
    }
    (1.0 + a * a + b * b).sqrt()
}

#[test]
fn skirts_reach_the_roughest_neighbour() {
    // Level 1 node (0, 0) covers level-0 (0..2, 0..2); two level-0 nodes east of it at
    // (2, 0) and (2, 1), and a level-0 node (3, 0) east of those; one far away.
    let nodes = [
        (1, 0, 0, 8.0),
        (0, 2, 0, 1.0),
        (0, 2, 1, 0.5),
        (0, 3, 0, 2.0),
        (0, 9, 9, 0.25),
    ];
    let m = neighbour_eps(&nodes);
    assert_eq!(m[0], 8.0, "the coarse node is the roughest itself");
    assert_eq!(m[1], 8.0, "fine next to coarse: T-junction");
    assert_eq!(m[2], 8.0);
    assert_eq!(m[3], 2.0, "same-level neighbour (2, 0) has less");
    assert_eq!(m[4], 0.25, "no neighbours");
    // A fine node rougher than its coarse neighbour raises the coarse one.
    let m = neighbour_eps(&[(1, 0, 0, 1.0), (0, 2, 1, 5.0)]);
    assert_eq!(m, vec![5.0, 5.0]);
    // Overlapping nodes (a drawn node inside another, which no selection makes): (0, 2, 0)
    // lies in (2, 0, 0), so (1, 1, 0) is split, yet the walk west from (0, 4, 0) goes on
    // through it to (2, 0, 0).
    let m = neighbour_eps(&[(2, 0, 0, 9.0), (0, 2, 0, 1.0), (0, 4, 0, 0.5)]);
    assert_eq!(m[2], 9.0, "the coarse neighbour past a split node");
}

#[test]
fn curvature_lowers_the_box_by_the_far_drop() {
    let eye = DVec3::new(0.0, 0.0, 1000.0);
    let lo = DVec2::new(10_000.0, -500.0);
    let hi = DVec2::new(20_000.0, 500.0);
    let flat = tile_aabb(lo, hi, 100.0, 200.0, eye, false, 10.0);
    let curved = tile_aabb(lo, hi, 100.0, 200.0, eye, true, 10.0);
    assert_eq!(flat.min.z, 100.0);
    let far = (20_000f64.powi(2) + 500f64.powi(2)) / (2.0 * EARTH_RADIUS_M);
    let near = 10_000f64.powi(2) / (2.0 * EARTH_RADIUS_M);
    assert!((curved.min.z - (100.0 - far - 100.0 / (8.0 * EARTH_RADIUS_M))).abs() < 1e-9);
    assert!((curved.max.z - (200.0 - near)).abs() < 1e-9);
    // Eye above the tile: nearest distance is 0, the top does not move.
    let above = tile_aabb(
        lo,
        hi,
        100.0,
        200.0,
        DVec3::new(15_000.0, 0.0, 900.0),
        true,
        10.0,
    );
    assert_eq!(above.max.z, 200.0);
}

/// The shared-product corner transform is `transform_point3` bit for bit, on cameras at every
/// attitude and boxes from a metre to the Earth's radius away.
#[test]
fn view_corners_are_transform_point3_bit_for_bit() {
    let mut next = crate::test_rng::unit(0x2545_f491_4f6c_dd1d);
    for _ in 0..2000 {
        let scale = 10f64.powf(6.8 * next());
        let eye = DVec3::new(next() - 0.5, next() - 0.5, next()) * scale;
        let att = Attitude::from_degrees(360.0 * next(), 180.0 * next() - 90.0, 360.0 * next());
        let cam = Camera::new(eye, att, Frustum::symmetric(90f64.to_radians(), 1280, 720));
        let lo = DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * scale;
        let aabb = Aabb {
            min: lo,
            max: lo + DVec3::new(next(), next(), next()) * scale * 0.1,
        };
        let m = cam.world_to_view();
        let want = aabb.corners().map(|c| m.transform_point3(c));
        let got = super::bound::view_corners(&m, &aabb);
        for (i, w) in want.iter().enumerate() {
            let g = [got.x[i], got.y[i], got.z[i]];
            assert_eq!(g.map(f64::to_bits), w.to_array().map(f64::to_bits));
        }
    }
}

/// On random quadtree covers (every part a node, split at random down to level 0, tiles far
/// from the origin; in half the cases with a fifth of the parts culled), each node's reach is the largest ε
/// among itself and every node sharing a stretch of edge with it, found by brute force.
#[test]
fn neighbour_eps_is_the_brute_force_edge_maximum() {
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    // Level-0 coordinates up to 2^25 and up to 2^31.
    for case in 0..40 {
        let top = 5u32;
        let base = if case % 2 == 0 {
            1u32 << 20
        } else {
            1u32 << 26
        };
        let mut nodes = Vec::new();
        let mut stack = vec![(top, base + case, base + 2 * case)];
        while let Some((l, x, y)) = stack.pop() {
            if l > 0 && next() % 3 != 0 {
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    stack.push((l - 1, 2 * x + dx, 2 * y + dy));
                }
            } else if case % 4 < 2 || next() % 5 != 0 {
                nodes.push((l, x, y, (next() % 1000) as f32 / 10.0));
            }
            // Else (cases 2, 3 mod 4) culled: a hole in the cover, as a selection leaves.
        }
        // Squares in level-0 units: [x·2^l, (x+1)·2^l) on each axis.
        let span = |l: u32, v: u32| ((v as u64) << l, ((v as u64) + 1) << l);
        let touch = |a: (u32, u32, u32, f32), b: (u32, u32, u32, f32)| {
            let ((ax0, ax1), (ay0, ay1)) = (span(a.0, a.1), span(a.0, a.2));
            let ((bx0, bx1), (by0, by1)) = (span(b.0, b.1), span(b.0, b.2));
            let overlap = |p0: u64, p1: u64, q0: u64, q1: u64| p0.max(q0) < p1.min(q1);
            ((ax1 == bx0 || bx1 == ax0) && overlap(ay0, ay1, by0, by1))
                || ((ay1 == by0 || by1 == ay0) && overlap(ax0, ax1, bx0, bx1))
        };
        let got = neighbour_eps(&nodes);
        for (i, &a) in nodes.iter().enumerate() {
            let want = nodes
                .iter()
                .filter(|&&b| touch(a, b))
                .map(|b| b.3)
                .fold(a.3, f32::max);
            assert_eq!(got[i], want, "case {case}, node {a:?} of {}", nodes.len());
        }
    }
}

/// How a node with evaluated children is drawn: the fewest triangles meeting τ, an instance
/// weighed as 64 — whole, as a quadrant of its parent when every seen child meets τ as a
/// sixteenth, or child by child — ties to fewer instances; children walked when one needs
/// more than the node's resolution and the node misses τ.
#[test]
fn choose_parts_draws_the_fewest_triangles_that_meet_tau() {
    use super::parts::{choose_parts, MeshCosts, NodeEval, Parts, Quadrant};
    let eval = |rho_px: f64| NodeEval::new(1.0, rho_px, rho_px, 0.0, 0.0, false);
    // ρ as a sixteenth (None: not measured), as a quadrant; own never read.
    let seen = |sub: Option<f64>, q: f64| Quadrant::Seen {
        q: eval(q),
        own: eval(q / 4.0),
        sub: sub.map(eval),
    };
    let (none, unseen) = (Quadrant::NoTerrain, Quadrant::Unseen);
    let cost = MeshCosts::of(16);
    assert_eq!(
        cost,
        MeshCosts {
            whole: 512 + 2 * 24,
            quadrant: 128 + 2 * 12,
            sixteenth: 32 + 2 * 6,
            instance: 64,
        }
    );
    let fine = seen(Some(0.9), 0.5);
    let coarse_only = seen(Some(1.5), 0.8);
    let deeper = seen(Some(3.0), 1.2);
    // Every child a sixteenth: the node as its parent's quadrant, ρ the largest sixteenth's.
    assert_eq!(
        choose_parts(&[fine, fine, fine, seen(Some(0.7), 0.2)], false, cost),
        Parts::AsQuadrant {
            rho_px: 0.9,
            rho_norm: 0.9
        }
    );
    // Three sixteenths and an unseen child: still one quadrant (240 < 3 × 120).
    assert_eq!(
        choose_parts(&[fine, unseen, fine, fine], true, cost),
        Parts::AsQuadrant {
            rho_px: 0.9,
            rho_norm: 0.9
        }
    );
    // Three sixteenths, one quadrant: 600 < 672, child by child.
    let three = [fine, coarse_only, fine, fine];
    assert_eq!(choose_parts(&three, true, cost), Parts::Children);
    assert_eq!(choose_parts(&three, false, cost), Parts::Children);
    // Two sixteenths, two quadrants: 720 ≥ 672, drawn whole (its own ρ when it meets τ
    // itself, else the largest child's at its resolution).
    let two = [fine, coarse_only, fine, coarse_only];
    assert_eq!(choose_parts(&two, true, cost), Parts::Whole(None));
    assert_eq!(choose_parts(&two, false, cost), Parts::Whole(Some(0.8)));
    // Without sixteenths: three quadrants (720) whole, two and no terrain (480) apart.
    let q = seen(None, 0.8);
    assert_eq!(
        choose_parts(&[q, q, none, q], false, cost),
        Parts::Whole(Some(0.8))
    );
    assert_eq!(
        choose_parts(&[q, none, none, q], false, cost),
        Parts::Children
    );
    // An unseen child is not drawn, and does not keep the node from being drawn whole: what
    // is seen of the node meets τ.
    assert_eq!(
        choose_parts(&[q, q, unseen, q], false, cost),
        Parts::Whole(Some(0.8))
    );
    assert_eq!(
        choose_parts(&[q, unseen, unseen, q], true, cost),
        Parts::Children
    );
    // A child needing more than the node's resolution: whole if the node meets τ, else walk.
    assert_eq!(
        choose_parts(&[fine, deeper, fine, fine], true, cost),
        Parts::Whole(None)
    );
    assert_eq!(
        choose_parts(&[fine, deeper, fine, fine], false, cost),
        Parts::Children
    );
    // A child meeting τ as a sixteenth but not at the node's resolution (the coarser surface
    // closer there): the node is not drawn whole on its children's word.
    let odd = seen(Some(0.9), 1.1);
    assert_eq!(choose_parts(&[odd, q, q, q], false, cost), Parts::Children);
    assert_eq!(
        choose_parts(&[odd, q, q, q], true, cost),
        Parts::Whole(None)
    );
    // Nothing seen: nothing to draw.
    assert_eq!(
        choose_parts(&[unseen, none, unseen, none], false, cost),
        Parts::Children
    );
}

/// `NodeEval` keeps the gain slack and the crossing flag in one word: each reads back as
/// given, for every combination (a slack of zero with the flag set included), and the record
/// stays five words — the three an evaluation returns are copied inline, not through `memcpy`.
#[test]
fn node_eval_keeps_gain_slack_and_straddles_apart_in_five_words() {
    use super::parts::NodeEval;
    assert_eq!(std::mem::size_of::<NodeEval>(), 5 * 8);
    for slack in [0.0, 1e-300, 0.25, 3.5, f64::MAX] {
        for straddles in [false, true] {
            let e = NodeEval::new(1.5, 2.0, 0.5, 7.0, slack, straddles);
            assert_eq!(
                e.gain_slack().to_bits(),
                slack.to_bits(),
                "{slack} {straddles}"
            );
            assert_eq!(e.straddles(), straddles, "{slack}");
            assert_eq!((e.eps, e.rho_px, e.rho_norm, e.gain), (1.5, 2.0, 0.5, 7.0));
        }
    }
}
