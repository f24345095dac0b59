use super::*;
use aerie_terrain::geodesy::GeoGrid;
use aerie_terrain::GeoReference;
use glam::DVec2;

fn stamped(frame: u64, arrival_s: f64) -> Stamped {
    Stamped {
        pose: Pose {
            position: PosePosition::LocalEnu {
                x: frame as f64,
                y: 0.0,
                z: 100.0,
            },
            attitude_deg: [0.0; 3],
            sim_time_s: frame as f64 / 60.0,
            frame,
            velocity_enu: None,
            angular_rates_deg_s: None,
        },
        arrival_s,
        sample: frame,
    }
}

fn frames(h: &FrameHistory) -> Vec<u64> {
    h.entries.iter().map(|s| s.pose.frame).collect()
}

#[test]
fn serial_frame_numbers_wrap() {
    assert_eq!(frame_diff(5, 3), 2);
    assert_eq!(frame_diff(3, 5), -2);
    assert_eq!(frame_diff(1, u64::from(u32::MAX)), 2);
    assert_eq!(frame_diff(u64::from(u32::MAX), 1), -2);
}

#[test]
fn newest_minus_k_with_reordering() {
    let mut h = FrameHistory::new(8);
    for f in [10, 12, 11, 14, 13] {
        assert_eq!(h.insert(stamped(f, 0.0)), Inserted::Kept, "{f}");
    }
    assert_eq!(frames(&h), [10, 11, 12, 13, 14]);
    assert_eq!(h.insert(stamped(12, 1.0)), Inserted::Duplicate);
    let p = h.pick(0).unwrap();
    assert_eq!((p.target, p.sample.pose.frame, p.exact), (14, 14, true));
    let p = h.pick(2).unwrap();
    assert_eq!((p.target, p.sample.pose.frame, p.exact), (12, 12, true));
    // Fewer than k + 1 frames seen: nothing yet (never a frame after the target).
    assert!(h.pick(5).is_none());
    assert_eq!(h.pick(4).unwrap().sample.pose.frame, 10);
    assert!(FrameHistory::new(4).pick(0).is_none());
}

#[test]
fn gap_renders_the_newest_frame_before_the_target() {
    let mut h = FrameHistory::new(8);
    for f in [20, 21, 23, 24] {
        h.insert(stamped(f, 0.0));
    }
    // 22 was lost: newest − 2 = 22 → 21, not exact.
    let p = h.pick(2).unwrap();
    assert_eq!((p.target, p.sample.pose.frame, p.exact), (22, 21, false));
    // The late 22 fills the gap.
    assert_eq!(h.insert(stamped(22, 0.1)), Inserted::Kept);
    let p = h.pick(2).unwrap();
    assert_eq!((p.sample.pose.frame, p.exact), (22, true));
}

#[test]
fn capacity_and_wraparound() {
    let mut h = FrameHistory::new(4);
    let max = u64::from(u32::MAX);
    for f in [max - 2, max - 1, max, 0, 1] {
        assert_eq!(h.insert(stamped(f, 0.0)), Inserted::Kept, "{f}");
    }
    // Wrapped frame numbers are newer; the oldest was dropped to keep 4.
    assert_eq!(frames(&h), [max - 1, max, 0, 1]);
    assert_eq!(h.newest(), Some(1));
    let p = h.pick(2).unwrap();
    assert_eq!((p.sample.pose.frame, p.exact), (max, true));
    // Older than everything kept while full.
    assert_eq!(h.insert(stamped(max - 3, 0.0)), Inserted::TooOld);
    // A host restart far behind: start over.
    assert_eq!(h.insert(stamped(max - 1000, 0.0)), Inserted::Restart);
    assert_eq!(frames(&h), [max - 1000]);
}

#[test]
fn picks_agree_for_any_arrival_order() {
    // Two machines receiving the same frames in different orders and at different times
    // render the same pose for the same target once the target has arrived.
    let order_a = [1u64, 2, 3, 4, 5, 6, 7, 8];
    let order_b = [2u64, 1, 4, 3, 6, 5, 8, 7];
    let (mut a, mut b) = (FrameHistory::new(16), FrameHistory::new(16));
    for (fa, fb) in order_a.iter().zip(order_b) {
        a.insert(stamped(*fa, 0.0));
        b.insert(stamped(fb, 0.5));
        for k in 0..3 {
            if let (Some(pa), Some(pb)) = (a.pick(k), b.pick(k)) {
                assert!(pa.sample.pose.frame <= pa.target);
                if pa.target == pb.target && pa.exact && pb.exact {
                    assert_eq!(pa.sample.pose, pb.sample.pose);
                }
            }
        }
    }
    assert_eq!(
        a.pick(1).unwrap().sample.pose,
        b.pick(1).unwrap().sample.pose
    );
}

fn inn_valley() -> GeoMapping {
    // N47E011 at 3": spacing at the centre latitude 47.5°.
    let (sx, sy) = aerie_terrain::load::geographic_spacing_m(47.5, 1.0 / 1200.0, 1.0 / 1200.0);
    GeoMapping {
        south_lat_deg: 47.0,
        west_lon_deg: 11.0,
        dlat_deg: 1.0 / 1200.0,
        dlon_deg: 1.0 / 1200.0,
        spacing_x: sx,
        spacing_y: sy,
        projected: None,
    }
}

#[test]
fn geodetic_lands_on_the_sample_grid() {
    let g = inn_valley();
    // Sample (col 600, row 300) is at lon 11.5°, lat 47.25°.
    let p = g.to_local(47.25, 11.5, 2500.0);
    assert!((p.x - 600.0 * g.spacing_x).abs() < 1e-6, "{p}");
    assert!((p.y - 300.0 * g.spacing_y).abs() < 1e-6, "{p}");
    assert_eq!(p.z, 2500.0);
    let (lat, lon, alt) = g.to_geodetic(p);
    assert!((lat - 47.25).abs() < 1e-12 && (lon - 11.5).abs() < 1e-12 && alt == 2500.0);
    // Longitudes given in [180, 360) or across the antimeridian go the short way.
    let w = GeoMapping {
        west_lon_deg: 179.5,
        ..g
    };
    let a = w.to_local(47.0, -179.75, 0.0);
    assert!((a.x - 900.0 * g.spacing_x).abs() < 1e-6, "{a}");
    let b = w.to_local(47.0, 180.25, 0.0);
    assert!((a.x - b.x).abs() < 1e-6);
}

#[test]
fn geodetic_pose_needs_a_geo_reference() {
    let pose = Pose {
        position: PosePosition::Geodetic {
            lat_deg: 47.1,
            lon_deg: 11.2,
            alt_m: 3000.0,
        },
        attitude_deg: [90.0, -5.0, 10.0],
        sim_time_s: 0.0,
        frame: 1,
        velocity_enu: None,
        angular_rates_deg_s: None,
    };
    let e = aircraft_pose(&pose, Err("gen.f32: no geo-reference")).unwrap_err();
    assert!(
        e.contains("geodetic") && e.contains("gen.f32: no geo-reference"),
        "{e}"
    );
    let g = inn_valley();
    let a = aircraft_pose(&pose, Ok(&g)).unwrap();
    assert_eq!(a.position, g.to_world(47.1, 11.2, 3000.0));
    // 0.2° east of the origin the local north leans by about 0.15° from world north.
    let h = a.attitude.heading.to_degrees();
    assert!((h - 90.0).abs() > 0.05 && (h - 90.0).abs() < 0.3, "{h}");
    assert_eq!(
        a.attitude,
        g.attitude_at(47.1, 11.2, Attitude::from_degrees(90.0, -5.0, 10.0))
    );
    // At the origin itself the local and world frames agree.
    let at_origin = Pose {
        position: PosePosition::Geodetic {
            lat_deg: 47.0,
            lon_deg: 11.0,
            alt_m: 3000.0,
        },
        ..pose
    };
    let o = aircraft_pose(&at_origin, Ok(&g)).unwrap();
    assert!((o.position - DVec3::new(0.0, 0.0, 3000.0)).length() < 1e-6);
    assert!((o.attitude.heading.to_degrees() - 90.0).abs() < 1e-9);
    assert!((o.attitude.roll.to_degrees() - 10.0).abs() < 1e-9);
    // Local poses need nothing.
    let local = Pose {
        position: PosePosition::LocalEnu {
            x: 1.0,
            y: 2.0,
            z: 3.0,
        },
        ..pose
    };
    let a = aircraft_pose(&local, Err("none")).unwrap();
    assert_eq!(a.position, DVec3::new(1.0, 2.0, 3.0));
}

/// A level pose 900 km from the dataset's origin: the camera's up is the ellipsoid normal
/// there (the horizon stays level), its heading measured from the local north.
#[test]
fn level_pose_far_from_the_origin_keeps_the_horizon_level() {
    use aerie_terrain::geodesy::{geodetic_to_ecef, Geodetic};
    let g = inn_valley();
    let grid = g.grid();
    // ≈ 900 km: 6° north and 8° east of the south-west corner.
    let (lat, lon) = (53.0, 19.5);
    let d = (g.to_world(lat, lon, 0.0) - g.to_world(47.0, 11.0, 0.0)).length();
    assert!(d > 850_000.0 && d < 1_000_000.0, "{d}");
    for heading in [0.0, 37.0, 90.0, 211.0] {
        let pose = Pose {
            position: PosePosition::Geodetic {
                lat_deg: lat,
                lon_deg: lon,
                alt_m: 10_000.0,
            },
            attitude_deg: [heading, 0.0, 0.0],
            sim_time_s: 0.0,
            frame: 1,
            velocity_enu: None,
            angular_rates_deg_s: None,
        };
        let a = aircraft_pose(&pose, Ok(&g)).unwrap();
        // The normal, straight from ECEF: the unit vector at (lat, lon) in world axes.
        let e0 = geodetic_to_ecef(Geodetic::new(lat, lon, 0.0));
        let e1 = geodetic_to_ecef(Geodetic::new(lat, lon, 10_000.0));
        let normal = grid.ecef_to_world_rotation() * (e1 - e0) / 10_000.0;
        let m = a.attitude.body_to_world();
        let up = -m.z_axis;
        assert!(
            (up - normal).length() < 1e-9,
            "heading {heading}: up {up:?} vs {normal:?}"
        );
        // Level: the wings are horizontal there, the nose points along the local heading.
        let north = grid.local_enu_axes(lat, lon).y_axis;
        let east = grid.local_enu_axes(lat, lon).x_axis;
        let want = north * heading.to_radians().cos() + east * heading.to_radians().sin();
        assert!((m.x_axis - want).length() < 1e-9, "heading {heading}");
        assert!(m.y_axis.dot(normal).abs() < 1e-9);
        // And the eye is at exactly that point, 10 km up the normal.
        assert!((a.position - g.to_world(lat, lon, 0.0) - normal * 10_000.0).length() < 1e-5);
    }
    // Without the local frame the same pose would tilt by the 8° of arc between the two
    // normals: what the flat mapping drew.
    let world_up = DVec3::Z;
    let tilt = world_up
        .angle_between(grid.local_enu_axes(lat, lon).z_axis)
        .to_degrees();
    assert!(tilt > 7.0, "{tilt}");
}

#[test]
fn world_and_geodetic_round_trip_across_the_seam() {
    let w = GeoMapping {
        west_lon_deg: 179.5,
        ..inn_valley()
    };
    let p = w.to_world(47.3, -179.6, 1234.0);
    let (lat, lon, alt) = w.world_to_geodetic(p);
    assert!((lat - 47.3).abs() < 1e-9 && (lon + 179.6).abs() < 1e-9 && (alt - 1234.0).abs() < 1e-6);
    // 0.9° east of the west edge, not 359.1° west.
    assert!(p.x > 60_000.0 && p.x < 70_000.0, "{p}");
}

#[test]
fn protocols_parse() {
    assert_eq!("shm".parse::<InputProtocol>(), Ok(InputProtocol::Shm));
    assert_eq!(
        "cigi".parse::<InputProtocol>(),
        Ok(InputProtocol::Udp(ProtocolChoice::Only(
            aerie_sim_bridge::Protocol::Cigi
        )))
    );
    assert!("ftp".parse::<InputProtocol>().unwrap_err().contains("shm"));
}

/// Ellipsoidal host heights lose the EGM96 undulation before placement (NGA's check point in
/// Mongolia: N = −43.575 m, so 956.425 m above the ellipsoid is 1000 m above sea level); MSL
/// heights and local poses pass unchanged.
#[test]
fn ellipsoidal_host_heights_are_brought_to_msl_by_the_geoid() {
    let geodetic = |alt_m| Pose {
        position: PosePosition::Geodetic {
            lat_deg: 46.874_319,
            lon_deg: 102.448_729,
            alt_m,
        },
        attitude_deg: [0.0; 3],
        sim_time_s: 0.0,
        frame: 1,
        velocity_enu: None,
        angular_rates_deg_s: None,
    };
    let alt = |p: Pose| match p.position {
        PosePosition::Geodetic { alt_m, .. } => alt_m,
        PosePosition::LocalEnu { .. } => panic!("not geodetic"),
    };
    let mut ell = HostDatum::new(HostHeights::Ellipsoidal);
    let msl = alt(ell.pose_in_data_datum(&geodetic(956.425)));
    assert!((msl - 1000.0).abs() < 0.05, "{msl}");
    let mut plain = HostDatum::new(HostHeights::Msl);
    assert_eq!(alt(plain.pose_in_data_datum(&geodetic(956.425))), 956.425);
    let local = Pose {
        position: PosePosition::LocalEnu {
            x: 1.0,
            y: 2.0,
            z: 3.0,
        },
        ..geodetic(0.0)
    };
    assert_eq!(ell.pose_in_data_datum(&local), local);
    assert_eq!(
        "Ellipsoidal".parse::<HostHeights>(),
        Ok(HostHeights::Ellipsoidal)
    );
    assert!("egm96".parse::<HostHeights>().unwrap_err().contains("msl"));
}

/// What a local pose means far from the dataset's origin (PROTOCOL.md "Datums and placement"):
/// its attitude is against the origin's ENU axes, not the aircraft's. A level local pose
/// 100 km and 500 km north-east of the origin is tilted against the ground's own horizon
/// there by the angle between the two ellipsoid normals (0.9° and 4.5°), and z = 0 lies above
/// the ground's datum by the curvature drop; a geodetic pose at the same point is level there.
#[test]
fn local_poses_far_from_the_origin_keep_the_origins_frame() {
    let g = inn_valley();
    let grid = g.grid();
    for d_m in [100_000.0, 500_000.0] {
        let p = DVec3::new(d_m * 0.6, d_m * 0.8, 0.0);
        let local = Pose {
            position: PosePosition::LocalEnu {
                x: p.x,
                y: p.y,
                z: p.z,
            },
            attitude_deg: [0.0; 3],
            sim_time_s: 0.0,
            frame: 0,
            velocity_enu: None,
            angular_rates_deg_s: None,
        };
        let a = aircraft_pose(&local, Ok(&g)).unwrap();
        assert_eq!(a.position, p);
        let (lat, lon, alt) = g.world_to_geodetic(p);
        let up_there = grid.local_enu_axes(lat, lon).z_axis;
        // The local pose's up is the origin's: world z.
        let body_up = -a.attitude.body_to_world().z_axis;
        let tilt = body_up.dot(up_there).clamp(-1.0, 1.0).acos();
        let want = d_m / 6_371_000.0;
        assert!(
            (tilt - want).abs() < 0.01 * want,
            "{d_m} m: tilt {tilt} vs {want}"
        );
        // z = 0 there is above the ellipsoid by about d²/2R.
        let drop = d_m * d_m / (2.0 * 6_371_000.0);
        assert!((alt - drop).abs() < 0.01 * drop, "{d_m} m: {alt} vs {drop}");
        // The same point sent geodetically is level over its own ground.
        let geo = Pose {
            position: PosePosition::Geodetic {
                lat_deg: lat,
                lon_deg: lon,
                alt_m: alt,
            },
            ..local
        };
        let b = aircraft_pose(&geo, Ok(&g)).unwrap();
        let level_up = -b.attitude.body_to_world().z_axis;
        assert!(level_up.dot(up_there) > 1.0 - 1e-12);
        assert!((b.position - p).length() < 1e-3);
    }
}

/// A UTM grid (zone 32N, sample (0, 0) at 650 km E, 5200 km N, 30 m) and its mapping.
fn utm_grid() -> (GeoMapping, GeoGrid) {
    let geo = Some(GeoReference::Projected {
        crs: "EPSG:32632".into(),
        easting: 650_000.0,
        northing: 5_200_000.0,
    });
    let m = GeoMapping::of_grid(&geo, [30.0, 30.0], "utm.tif").expect("a UTM grid maps");
    let grid = GeoGrid::of(geo.as_ref(), 30.0, 30.0).expect("a UTM grid is placed");
    (m, grid)
}

#[test]
fn geodetic_poses_on_a_utm_grid_land_on_its_samples_and_the_drawn_surface() {
    let (m, grid) = utm_grid();
    assert!(m.projected.is_some() && m.dlat_deg == 0.0);
    // Sample (col 1000, row 700): grid metres (30 km, 21 km) from sample (0, 0).
    let g = DVec2::new(30_000.0, 21_000.0);
    let (lat, lon) = grid.lat_lon_of_grid(g);
    let local = m.to_local(lat, lon, 1234.0);
    assert!((local.truncate() - g).length() < 1e-6, "{local}");
    assert_eq!(local.z, 1234.0);
    let (lat2, lon2, alt2) = m.to_geodetic(local);
    assert!((lat2 - lat).abs() < 1e-10 && (lon2 - lon).abs() < 1e-10 && alt2 == 1234.0);
    // The eye sits where the renderer draws that sample at that height.
    let world = m.to_world(lat, lon, 1234.0);
    assert!(
        (world - grid.world_of_grid(g, 1234.0)).length() < 1e-6,
        "{world}"
    );
    let (lat3, lon3, alt3) = m.world_to_geodetic(world);
    assert!((lat3 - lat).abs() < 1e-9 && (lon3 - lon).abs() < 1e-9 && (alt3 - 1234.0).abs() < 1e-6);
    // Level at the aircraft is level against the ellipsoid normal there, not the origin's.
    let level = m.attitude_at(lat, lon, Attitude::from_degrees(0.0, 0.0, 0.0));
    let up_there = grid.local_enu_axes(lat, lon).col(2);
    let body_down = level.body_to_world() * DVec3::Z;
    assert!(
        (body_down + up_there).length() < 1e-9,
        "{body_down} vs {up_there}"
    );
}

#[test]
fn geodetic_poses_on_other_projected_crs_are_refused_naming_it() {
    let geo = Some(GeoReference::Projected {
        crs: "EPSG:2056".into(),
        easting: 2_600_000.0,
        northing: 1_200_000.0,
    });
    let err = GeoMapping::of_grid(&geo, [10.0, 10.0], "swiss.tif").unwrap_err();
    assert!(
        err.contains("swiss.tif") && err.contains("EPSG:2056"),
        "{err}"
    );
}
