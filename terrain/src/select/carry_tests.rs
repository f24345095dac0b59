//! `carry.rs`' tests: the certificates against the gains, depths and culls they bound.
use super::*;

fn corners_of(b: &Aabb) -> ViewCorners {
    let c = b.corners();
    ViewCorners {
        x: c.map(|p| p.x),
        y: c.map(|p| p.y),
        z: c.map(|p| p.z),
    }
}

/// A box wholly right of the right plane is outside it by its nearest corner's distance;
/// one straddling the plane is not outside.
#[test]
fn outside_margin_is_the_nearest_corners_distance_past_a_plane() {
    let f = crate::camera::Frustum {
        tan_left: -1.0,
        tan_right: 1.0,
        tan_down: -0.5,
        tan_up: 0.5,
    };
    let planes = FrustumPlanes::of(&f, 1.0);
    // x − z > 0 at every corner; the nearest to the plane x = z is (20, ·, 10): 10/√2.
    let b = Aabb {
        min: DVec3::new(20.0, -1.0, 5.0),
        max: DVec3::new(30.0, 1.0, 10.0),
    };
    let m = planes.outside_margin(&corners_of(&b));
    assert!((m - 10.0 / 2f64.sqrt()).abs() < 1e-12, "{m}");
    let straddling = Aabb {
        min: DVec3::new(0.0, -1.0, 5.0),
        max: DVec3::new(30.0, 1.0, 10.0),
    };
    assert!(planes.outside_margin(&corners_of(&straddling)) <= 0.0);
    // Behind the near plane: its distance past it.
    let behind = Aabb {
        min: DVec3::new(-1.0, -1.0, -5.0),
        max: DVec3::new(1.0, 1.0, 0.5),
    };
    assert!((planes.outside_margin(&corners_of(&behind)) - 0.5).abs() < 1e-12);
}

use super::super::equivalence_tests::Rng;

/// A random unit vector.
fn unit(rng: &mut Rng) -> DVec3 {
    loop {
        let v = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        if (0.1..1.0).contains(&v.length()) {
            return v.normalize();
        }
    }
}

/// The growth bound of the module's doc, by brute force: a node's gain over a box within
/// its ring tile's box, formed afresh after the eye moved by m and turned by k, is never
/// more than its gain when the record was made times `Growth::gain` — on the plane (the
/// world vertical, no slack) and on the ellipsoid (the node's normal within the tile's
/// spread of the tile's, a slack part).
#[test]
fn a_gain_grows_at_most_by_the_records_factor() {
    use super::super::bound::{spread_gain_of, vertical_gain_of};
    let mut rng = Rng(0x15_0f);
    let (mut checked, mut tight) = (0u32, 0f64);
    for case in 0..20_000 {
        let ellipsoid = case % 2 == 1;
        let f = crate::camera::Frustum::symmetric(rng.range(40f64, 110.0).to_radians(), 16, 9);
        // World → view at the record: looking along a random direction, below the horizon
        // mostly; the world vertical is +Z.
        let r0 = DMat3::from_euler(
            glam::EulerRot::ZXY,
            rng.range(0.0, 6.3),
            rng.range(-1.6, 1.6),
            rng.range(-0.6, 0.6),
        );
        let eye0 = DVec3::new(
            rng.range(-50.0, 50.0),
            rng.range(-50.0, 50.0),
            rng.range(0.0, 900.0),
        );
        // The ring tile's box: somewhere in front of the eye at the record.
        let ahead = r0.transpose() * DVec3::new(rng.range(-0.5, 0.5), rng.range(-0.3, 0.3), 1.0);
        let centre = eye0 + ahead * rng.range(200.0, 20_000.0);
        let half = DVec3::new(
            rng.range(5.0, 3000.0),
            rng.range(5.0, 3000.0),
            rng.range(1.0, 500.0),
        );
        let ring = Aabb {
            min: centre - half,
            max: centre + half,
        };
        // A node's box within it.
        let pick = |rng: &mut Rng, lo: f64, hi: f64| {
            let (a, b) = (rng.range(lo, hi), rng.range(lo, hi));
            (a.min(b), a.max(b))
        };
        let (x0, x1) = pick(&mut rng, ring.min.x, ring.max.x);
        let (y0, y1) = pick(&mut rng, ring.min.y, ring.max.y);
        let (z0, z1) = pick(&mut rng, ring.min.z, ring.max.z);
        let node = Aabb {
            min: DVec3::new(x0, y0, z0),
            max: DVec3::new(x1, y1, z1),
        };
        // The tile's normal, its spread, the node's normal within it and the node's slack.
        let (up_ring, spread, up_node, slack) = if ellipsoid {
            let up = (DVec3::Z + unit(&mut rng) * 0.05).normalize();
            let spread = rng.range(0.0, 0.02);
            let tilt = unit(&mut rng) * spread * rng.next();
            (up, spread, (up + tilt).normalize(), rng.range(0.0, 1.0))
        } else {
            (DVec3::Z, 0.0, DVec3::Z, 0.0)
        };
        let corners = |r: DMat3, eye: DVec3, b: &Aabb| {
            let c = b.corners().map(|p| r * (p - eye));
            (
                c,
                ViewCorners {
                    x: c.map(|p| p.x),
                    y: c.map(|p| p.y),
                    z: c.map(|p| p.z),
                },
            )
        };
        let (ring0, ring_c) = corners(r0, eye0, &ring);
        let ring_z = ring0.iter().fold(f64::INFINITY, |a, p| a.min(p.z));
        if ring_z <= 1.0 {
            continue;
        }
        let a = f.tan_left.abs().max(f.tan_right.abs());
        let b = f.tan_up.abs().max(f.tan_down.abs());
        let turn = (2.0 + a * a + b * b).sqrt();
        let u0 = r0 * DVec3::Z;
        let optics = Optics {
            tau: 1.0,
            focal: 1000.0,
            near: 0.5,
            turn,
            up: u0,
            w_z: u0.z.abs(),
            frustum: f,
        };
        let view = ViewNow {
            eye: eye0,
            rotation: r0,
        };
        let normal = ellipsoid.then_some(RingNormal {
            up: up_ring,
            spread,
        });
        let Some(growth) = Growth::of(&optics, &view, normal, &ring_c, reach(&ring, eye0)) else {
            continue;
        };
        if growth.floor <= 1e-3 {
            continue;
        }
        // What the record takes of every normal within the tile's spread: its least gain
        // over the tile's ranges and |w_z| (a normal turned by the whole spread, any way).
        if ellipsoid {
            let ranges = clamped_ranges(&ring_c, &f);
            let turned = r0 * (up_ring + unit(&mut rng) * spread).normalize();
            assert!(
                gain_floor_over(turned, ranges.0, ranges.1) >= growth.floor,
                "case {case}: floor"
            );
            assert!(turned.z.abs() <= growth.w_z, "case {case}: w_z");
        }
        let gain = |r: DMat3, eye: DVec3| {
            let (c, _) = corners(r, eye, &node);
            if ellipsoid {
                spread_gain_of(&c, &f, r * up_node, slack)
            } else {
                vertical_gain_of(&c, &f, r * up_node)
            }
        };
        let then = gain(r0, eye0);
        // The eye moves and turns a little (a frame or a few of a fast flight).
        let turned = DMat3::from_axis_angle(unit(&mut rng), rng.range(0.0, 0.02)) * r0;
        let eye1 = eye0 + unit(&mut rng) * rng.range(0.0, 30.0);
        let (m, k) = ((eye1 - eye0).length(), frobenius(turned - r0));
        let Some(factor) = growth.gain(m, k, &optics) else {
            continue;
        };
        let now = gain(turned, eye1);
        assert!(
            now <= then * factor * (1.0 + 1e-9),
            "case {case}: gain {then} → {now}, more than ×{factor} (m {m}, k {k})"
        );
        if now > then {
            tight = tight.max((now - then) / (then * (factor - 1.0)));
        }
        checked += 1;
    }
    eprintln!("{checked} gains checked; the largest growth used {tight:.3} of the bound's");
    assert!(checked > 5_000, "{checked}");
}

#[test]
fn frobenius_bounds_a_turn() {
    let r0 = DMat3::from_rotation_z(0.3);
    let r1 = DMat3::from_rotation_z(0.3 + 1e-3);
    let k = frobenius(r1 - r0);
    let v = DVec3::new(100.0, -40.0, 7.0);
    assert!((r1 * v - r0 * v).length() <= k * v.length());
    assert!(k < 2e-3);
}

/// Records made together fall due in waves; the budget spreads their walks: over a long
/// run of records walked afresh as the rule says, no frame walks more than
/// [`AGED_WALKS_PER_FRAME`] for age unless one has waited [`AGE_GRACE`] frames past due,
/// none waits longer, and the busiest frame walks fewer than without the budget.
#[test]
fn records_due_by_age_are_walked_a_few_a_frame() {
    // 110 ring tiles (the 16385² plane's at 720p), all recorded in frame 0.
    let tiles: Vec<(u32, u32, u32)> = (0..110u32).map(|i| (i % 6, i * 7 % 23, i / 5)).collect();
    let run = |budget: bool| {
        let mut made = vec![0u64; tiles.len()];
        let (mut busiest, mut oldest_over) = (0u32, 0u64);
        for frame in 1..400u64 {
            let mut aged = 0u32;
            for (t, &(l, x, y)) in tiles.iter().enumerate() {
                let (age, due) = (frame - made[t], max_age(l, x, y));
                let walk = if budget {
                    walk_for_age(age, due, aged)
                } else {
                    age >= due
                };
                if walk {
                    if budget && aged >= AGED_WALKS_PER_FRAME {
                        assert!(age >= due + AGE_GRACE, "frame {frame}: walked over budget");
                    }
                    aged += 1;
                    made[t] = frame;
                } else {
                    oldest_over = oldest_over.max(age.saturating_sub(due - 1));
                }
            }
            busiest = busiest.max(aged);
        }
        (busiest, oldest_over)
    };
    let (with, waited) = run(true);
    let (without, _) = run(false);
    assert!(
        waited <= AGE_GRACE,
        "a record waited {waited} frames past due"
    );
    assert!(waited > 0, "no record waited: the budget never bit");
    assert!(
        with < without,
        "busiest frame {with} with the budget, {without} without"
    );
    // Not due: never walked for age; due with room: walked; due without room: waits,
    // until the grace is spent.
    assert!(!walk_for_age(15, 16, 0));
    assert!(walk_for_age(16, 16, AGED_WALKS_PER_FRAME - 1));
    assert!(!walk_for_age(16, 16, AGED_WALKS_PER_FRAME));
    assert!(!walk_for_age(16 + AGE_GRACE - 1, 16, AGED_WALKS_PER_FRAME));
    assert!(walk_for_age(16 + AGE_GRACE, 16, AGED_WALKS_PER_FRAME));
}

#[test]
fn ages_are_staggered_between_32_and_47() {
    let ages: std::collections::HashSet<u64> = (0..64).map(|t| max_age(t % 5, t, t / 3)).collect();
    assert!(ages.len() > 8);
    assert!(ages.iter().all(|a| (32..48).contains(a)));
}

/// A part outside the frustum that `still_outside` keeps culled after a move and a turn is
/// wholly outside one plane of the new view (every corner checked), over random frusta,
/// boxes, moves (mostly forward, as a flight's) and turns; it keeps every part the bound of
/// a move in any direction kept, and more.
#[test]
fn a_culled_part_kept_culled_is_outside_the_new_frustum() {
    let mut rng = Rng(0x5eed_c011);
    let (mut kept, mut kept_any_way, mut checked) = (0u32, 0u32, 0u32);
    for case in 0..40_000 {
        let f = crate::camera::Frustum::symmetric(rng.range(40f64, 110.0).to_radians(), 16, 9);
        let near = rng.range(0.1, 2.0);
        let planes = FrustumPlanes::of(&f, near);
        let r0 = DMat3::from_axis_angle(unit(&mut rng), rng.range(0.0, 3.0));
        let eye0 = DVec3::new(rng.range(-50.0, 50.0), rng.range(-50.0, 50.0), 300.0);
        // A box anywhere around the eye, up to 600 m away.
        let centre = eye0 + unit(&mut rng) * rng.range(5.0, 600.0);
        let half = DVec3::new(
            rng.range(1.0, 200.0),
            rng.range(1.0, 200.0),
            rng.range(1.0, 50.0),
        );
        let b = Aabb {
            min: centre - half,
            max: centre + half,
        };
        let corners = |r: DMat3, eye: DVec3| {
            let c = b.corners().map(|p| r * (p - eye));
            ViewCorners {
                x: c.map(|p| p.x),
                y: c.map(|p| p.y),
                z: c.map(|p| p.z),
            }
        };
        let margins = planes.margins(&corners(r0, eye0));
        if margins.iter().all(|&d| d <= 0.0) {
            continue;
        }
        // A move, mostly along the view axis, and a small turn.
        let forward = r0.transpose() * DVec3::Z;
        let eye1 = eye0 + forward * rng.range(0.0, 40.0) + unit(&mut rng) * rng.range(0.0, 2.0);
        let r1 = DMat3::from_axis_angle(unit(&mut rng), rng.range(0.0, 0.005)) * r0;
        let (m, k) = ((eye1 - eye0).length(), frobenius(r1 - r0));
        let reach = reach(&b, eye0);
        let drift = moved(reach, m, k) - m;
        let step = r1 * (eye1 - eye0);
        checked += 1;
        let still = planes.still_outside(&margins, step, drift);
        // The bound of a move in any direction (margin past μ) keeps a part only if this
        // one does.
        let any_way = moved(reach, m, k) < planes.outside_margin(&corners(r0, eye0)) * (1.0 - ROOM);
        assert!(!any_way || still, "case {case}: kept by the old bound only");
        (kept, kept_any_way) = (kept + still as u32, kept_any_way + any_way as u32);
        if still {
            assert!(
                planes.outside_margin(&corners(r1, eye1)) > 0.0,
                "case {case}: kept culled but inside the new frustum"
            );
        }
    }
    eprintln!(
        "{kept} culled parts kept of {checked} ({kept_any_way} by the bound of any direction)"
    );
    assert!(checked > 5_000, "{checked}");
    assert!(
        kept > kept_any_way + checked / 20,
        "{kept} kept, {kept_any_way} before"
    );
}
