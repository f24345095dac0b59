//! Tests of the entity table (`entities.rs`).

use super::*;

fn control(id: u16, lat: f64, lon: f64, alt: f64, att: [f64; 3]) -> EntityControlUpdate {
    EntityControlUpdate {
        id,
        state: 1,
        attached: false,
        parent: 0,
        entity_type: 7,
        alpha: 255,
        lat_or_x: lat,
        lon_or_y: lon,
        alt_or_z: alt,
        attitude_deg: att,
    }
}

fn flat(height: f64) -> impl Fn(f64, f64) -> Answer<Surface> {
    move |_, _| {
        Answer::Ready(Surface {
            height_m: height,
            normal_enu: [0.0, 0.0, 1.0],
        })
    }
}

fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
    (a - b).length() < tol
}

#[test]
fn body_axes_follow_heading_pitch_roll() {
    let m = body_to_enu(0.0, 0.0, 0.0);
    assert!(close(m.x_axis, DVec3::Y, 1e-12), "forward is north");
    assert!(close(m.y_axis, DVec3::X, 1e-12), "right is east");
    assert!(close(m.z_axis, -DVec3::Z, 1e-12), "down is down");
    let m = body_to_enu(90.0, 0.0, 0.0);
    assert!(
        close(m.x_axis, DVec3::X, 1e-12),
        "heading 90: forward is east"
    );
    assert!(close(m.y_axis, -DVec3::Y, 1e-12), "right of east is south");
    let m = body_to_enu(0.0, 90.0, 0.0);
    assert!(close(m.x_axis, DVec3::Z, 1e-12), "nose up");
    let m = body_to_enu(0.0, 0.0, 90.0);
    assert!(close(m.y_axis, -DVec3::Z, 1e-12), "right wing down");
    // A general attitude: the columns stay orthonormal and right-handed.
    let m = body_to_enu(123.0, -17.0, 41.0);
    assert!((m.determinant() - 1.0).abs() < 1e-12);
    assert!(close(m.x_axis.cross(m.y_axis), m.z_axis, 1e-12));
    // Forward at heading 123, pitch −17: its horizontal part points 123° from north.
    let f = m.x_axis;
    assert!((f.x.atan2(f.y).to_degrees() - 123.0).abs() < 1e-9);
    assert!((f.z.asin().to_degrees() + 17.0).abs() < 1e-9);
}

#[test]
fn entity_relative_points_land_where_the_geodesy_says() {
    let mut t = EntityTable::default();
    let origin = Geodetic::new(47.25, 11.4, 1500.0);
    assert_eq!(
        t.apply_control(
            &control(
                5,
                origin.lat_deg,
                origin.lon_deg,
                origin.alt_m,
                [90.0, 0.0, 0.0]
            ),
            1
        ),
        EntityChange::Created
    );
    let ltp = LocalTangentPlane::new(origin);
    // 100 m ahead of an east-facing entity is 100 m east; 50 m "down" is 50 m lower.
    for (offset, want) in [
        ([100.0, 0.0, 0.0], DVec3::new(100.0, 0.0, 0.0)),
        ([0.0, 20.0, 0.0], DVec3::new(0.0, -20.0, 0.0)),
        ([0.0, 0.0, 50.0], DVec3::new(0.0, 0.0, -50.0)),
    ] {
        let placed = t
            .anchor(5, offset)
            .unwrap()
            .place(&flat(0.0))
            .ready()
            .unwrap();
        let got = ltp.geodetic_to_enu(placed.point);
        assert!(close(got, want, 1e-6), "{offset:?}: {got} vs {want}");
    }
    // Pitched up 30° heading north: 1 km ahead is 866 m north and 500 m up.
    t.apply_control(
        &control(
            6,
            origin.lat_deg,
            origin.lon_deg,
            origin.alt_m,
            [0.0, 30.0, 0.0],
        ),
        2,
    );
    let p = t.anchor(6, [1000.0, 0.0, 0.0]).unwrap().place(&flat(0.0));
    let got = ltp.geodetic_to_enu(p.ready().unwrap().point);
    let want = DVec3::new(0.0, 1000.0 * 30f64.to_radians().cos(), 500.0);
    assert!(close(got, want, 1e-6), "{got} vs {want}");
    // The body axes at the point: forward still 30° up, 1 km away (the tangent planes
    // differ by 0.009°).
    let axes = p.ready().unwrap().body_to_enu();
    assert!((axes.x_axis.z.asin().to_degrees() - 30.0).abs() < 0.02);
}

#[test]
fn attached_chains_compose_and_loops_are_refused() {
    let mut t = EntityTable::default();
    let origin = Geodetic::new(-33.9, 151.2, 100.0);
    t.apply_control(
        &control(
            1,
            origin.lat_deg,
            origin.lon_deg,
            origin.alt_m,
            [90.0, 0.0, 0.0],
        ),
        1,
    );
    // A child 10 m ahead of its parent, turned a further 90° (so it faces south).
    let child = EntityControlUpdate {
        attached: true,
        parent: 1,
        ..control(2, 10.0, 0.0, 0.0, [90.0, 0.0, 0.0])
    };
    t.apply_control(&child, 1);
    let ltp = LocalTangentPlane::new(origin);
    // 5 m ahead of the child = 10 m east, then 5 m south.
    let p = t.anchor(2, [5.0, 0.0, 0.0]).unwrap().place(&flat(0.0));
    let got = ltp.geodetic_to_enu(p.ready().unwrap().point);
    assert!(close(got, DVec3::new(10.0, -5.0, 0.0), 1e-6), "{got}");
    assert!(close(
        p.ready().unwrap().body_to_enu().x_axis,
        -DVec3::Y,
        1e-5
    ));
    // A loop: 3 → 4 → 3.
    for (id, parent) in [(3, 4), (4, 3)] {
        t.apply_control(
            &EntityControlUpdate {
                attached: true,
                parent,
                ..control(id, 0.0, 0.0, 0.0, [0.0; 3])
            },
            1,
        );
    }
    assert_eq!(t.anchor(3, [0.0; 3]), Err(AnchorError::ChainTooDeep(3)));
    assert_eq!(t.anchor(9, [0.0; 3]), Err(AnchorError::UnknownEntity(9)));
    let orphan = EntityControlUpdate {
        attached: true,
        parent: 77,
        ..control(8, 0.0, 0.0, 0.0, [0.0; 3])
    };
    t.apply_control(&orphan, 1);
    assert_eq!(t.anchor(8, [0.0; 3]), Err(AnchorError::UnknownEntity(77)));
}

#[test]
fn clamped_entities_sit_on_the_terrain_and_follow_its_slope() {
    let mut t = EntityTable::default();
    assert_eq!(
        t.apply_clamped(12, 0.0, 46.0, 7.0, 3),
        EntityChange::Created
    );
    // A slope rising to the north by 10°: normal tilted towards the south.
    let tilt = 10f64.to_radians();
    let ground = move |_: f64, _: f64| {
        Answer::Ready(Surface {
            height_m: 640.0,
            normal_enu: [0.0, -tilt.sin(), tilt.cos()],
        })
    };
    let a = t.anchor(12, [0.0, 0.0, 0.0]).unwrap();
    let p = a.place(&ground).ready().unwrap();
    assert!((p.point.alt_m - 640.0).abs() < 1e-9);
    // Facing north up the slope: nose up by 10°.
    assert!((p.body_to_enu().x_axis.z.asin().to_degrees() - 10.0).abs() < 1e-9);
    assert!(p.body_to_enu().y_axis.z.abs() < 1e-12, "no roll");
    // Not ready or no terrain: said so.
    assert_eq!(a.place(&|_, _| Answer::Pending), Answer::Pending);
    assert_eq!(a.place(&|_, _| Answer::NoTerrain), Answer::NoTerrain);
}

#[test]
fn destroy_rates_reset_and_the_bound() {
    let mut t = EntityTable::default();
    t.apply_control(&control(0, 1.0, 2.0, 3.0, [0.0; 3]), 1);
    t.apply_control(&control(4, 1.0, 2.0, 3.0, [0.0; 3]), 1);
    assert_eq!(
        t.apply_rates(4, EntityRates::default(), 2),
        EntityChange::Updated
    );
    assert_eq!(
        t.apply_rates(99, EntityRates::default(), 2),
        EntityChange::Ignored
    );
    assert!(t.get(4).unwrap().rates.is_some());
    let inactive = EntityControlUpdate {
        state: 0,
        ..control(4, 1.0, 2.0, 3.0, [0.0; 3])
    };
    assert_eq!(t.apply_control(&inactive, 3), EntityChange::Updated);
    assert_eq!(t.get(4).unwrap().state, EntityState::Inactive);
    assert_eq!((t.len(), t.active()), (2, 1));
    let destroy = EntityControlUpdate {
        state: 2,
        ..inactive
    };
    assert_eq!(t.apply_control(&destroy, 4), EntityChange::Destroyed);
    assert_eq!(t.apply_control(&destroy, 4), EntityChange::Ignored);
    assert_eq!(t.len(), 1);
    for id in 1..=MAX_ENTITIES as u16 {
        t.apply_control(&control(id, 0.0, 0.0, 0.0, [0.0; 3]), 5);
    }
    assert_eq!(t.len(), MAX_ENTITIES);
    let one_more = control(MAX_ENTITIES as u16 + 1, 0.0, 0.0, 0.0, [0.0; 3]);
    assert_eq!(t.apply_control(&one_more, 5), EntityChange::Full);
    // Known entities still update when full.
    assert_eq!(
        t.apply_control(&control(3, 5.0, 5.0, 5.0, [0.0; 3]), 6),
        EntityChange::Updated
    );
    assert_eq!(t.clear_host_entities(), MAX_ENTITIES - 1);
    assert_eq!(t.len(), 1);
    assert!(t.get(OWNSHIP_ID).is_some());
}

fn placed_point(t: &EntityTable, id: u16) -> Geodetic {
    t.anchor(id, [0.0; 3])
        .unwrap()
        .place(&flat(0.0))
        .ready()
        .unwrap()
        .point
}

#[test]
fn rates_dead_reckon_from_the_last_placement() {
    let mut t = EntityTable::default();
    let origin = Geodetic::new(47.25, 11.4, 1500.0);
    t.apply_control(
        &control(
            3,
            origin.lat_deg,
            origin.lon_deg,
            origin.alt_m,
            [90.0, 0.0, 0.0],
        ),
        1,
    );
    let placed = t.get(3).unwrap().placed;
    // 50 m/s forward, climbing 5 m/s (z down: −5), body axes.
    let rates = EntityRates {
        linear_m_s: [50.0, 0.0, -5.0],
        angular_deg_s: [0.0; 3],
        world_frame: false,
    };
    t.apply_rates(3, rates, 2);
    assert_eq!(
        t.get(3).unwrap().placed,
        placed,
        "rates are not a placement"
    );
    let ltp = LocalTangentPlane::new(origin);
    let at = |dt: f64| ltp.geodetic_to_enu(placed_point(&t.advanced(|_| dt), 3));
    // Heading east: 2 s later 100 m east and 10 m higher.
    assert!(
        close(at(2.0), DVec3::new(100.0, 0.0, 10.0), 1e-3),
        "{}",
        at(2.0)
    );
    assert!(close(at(0.0), DVec3::ZERO, 1e-6));
    // Stopped after MAX_DEAD_RECKONING_S.
    assert!(close(at(1e6), at(MAX_DEAD_RECKONING_S), 1e-9));
    // A new placement restarts from the host's position.
    t.apply_control(
        &control(
            3,
            origin.lat_deg,
            origin.lon_deg,
            origin.alt_m,
            [0.0, 0.0, 0.0],
        ),
        3,
    );
    assert!(t.get(3).unwrap().placed > placed);
    assert!(
        t.get(3).unwrap().rates.is_some(),
        "rates stay until changed"
    );
    // A steady turn: 36°/s for 10 s at 50 m/s is a full circle of radius 79.6 m, back home,
    // heading as it started; a quarter turn ends 79.6 m east and 79.6 m north.
    let turning = EntityRates {
        linear_m_s: [50.0, 0.0, 0.0],
        angular_deg_s: [0.0, 0.0, 36.0],
        world_frame: false,
    };
    t.apply_rates(3, turning, 4);
    let full = t.advanced(|_| 10.0);
    assert!(ltp.geodetic_to_enu(placed_point(&full, 3)).length() < 0.5);
    assert!((full.get(3).unwrap().attitude_deg[0] - 0.0).abs() < 1e-9);
    let r = 50.0 / 36f64.to_radians();
    let quarter = ltp.geodetic_to_enu(placed_point(&t.advanced(|_| 2.5), 3));
    assert!(
        close(quarter, DVec3::new(r, r, 0.0), 0.2),
        "{quarter} vs {r}"
    );
    // World-frame rates (north-east-down) ignore the attitude.
    t.apply_rates(
        3,
        EntityRates {
            linear_m_s: [10.0, 0.0, 0.0],
            angular_deg_s: [0.0; 3],
            world_frame: true,
        },
        5,
    );
    let north = ltp.geodetic_to_enu(placed_point(&t.advanced(|_| 1.0), 3));
    assert!(close(north, DVec3::new(0.0, 10.0, 0.0), 1e-3), "{north}");
}

#[test]
fn clamped_vehicles_drive_along_the_ground_and_children_follow_parents() {
    let mut t = EntityTable::default();
    t.apply_clamped(20, 0.0, 47.0, 11.0, 1);
    t.apply_rates(
        20,
        EntityRates {
            linear_m_s: [10.0, 0.0, -50.0],
            angular_deg_s: [5.0, 5.0, 0.0],
            world_frame: false,
        },
        1,
    );
    // A trailer 8 m behind the truck.
    let trailer = EntityControlUpdate {
        attached: true,
        parent: 20,
        ..control(21, -8.0, 0.0, 0.0, [0.0; 3])
    };
    t.apply_control(&trailer, 1);
    let moved = t.advanced(|_| 3.0);
    let ground = |_: f64, _: f64| {
        Answer::Ready(Surface {
            height_m: 600.0,
            normal_enu: [0.0, 0.0, 1.0],
        })
    };
    let truck = moved
        .anchor(20, [0.0; 3])
        .unwrap()
        .place(&ground)
        .ready()
        .unwrap();
    let ltp = LocalTangentPlane::new(Geodetic::new(47.0, 11.0, 600.0));
    let p = ltp.geodetic_to_enu(truck.point);
    // 30 m north, on the ground (the climb rate and pitch/roll rates do not lift it); the
    // move is taken at sea level, 600 m below this plane: 1e-4 longer here.
    assert!(close(p, DVec3::new(0.0, 30.0, 0.0), 1e-2), "{p}");
    assert!(
        truck.body_to_enu().y_axis.z.abs() < 1e-9,
        "no roll on flat ground"
    );
    let tr = moved
        .anchor(21, [0.0; 3])
        .unwrap()
        .place(&ground)
        .ready()
        .unwrap();
    let q = ltp.geodetic_to_enu(tr.point);
    assert!(close(q, DVec3::new(0.0, 22.0, 0.0), 1e-2), "{q}");
    // Destroying the truck takes the trailer with it.
    let destroy = EntityControlUpdate {
        state: 2,
        ..control(20, 0.0, 0.0, 0.0, [0.0; 3])
    };
    assert_eq!(t.apply_control(&destroy, 2), EntityChange::Destroyed);
    assert!(t.get(21).is_none() && t.is_empty());
}
