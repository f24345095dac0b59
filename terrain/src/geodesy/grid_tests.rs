use super::*;
use crate::geodesy::wgs84::ecef_to_geodetic;

/// A 3" grid whose south-west sample is at (lat, lon).
fn grid(lat: f64, lon: f64) -> GeoGrid {
    let d = 1.0 / 1200.0;
    let (sx, sy) = crate::load::geographic_spacing_m(lat + 0.5, d, d);
    GeoGrid::of(
        Some(&GeoReference::Geographic {
            south_lat_deg: lat,
            west_lon_deg: lon,
            dlat_deg: d,
            dlon_deg: d,
        }),
        sx,
        sy,
    )
    .expect("geographic")
}

/// World position of sample (col, row) at height h, through ECEF written out here.
fn world_ref(g: &GeoGrid, col: f64, row: f64, h: f64) -> DVec3 {
    g.world.ecef_to_enu(g.ecef_of_sample(col, row, h))
}

#[test]
fn geographic_and_utm_references_make_a_grid() {
    let proj = GeoReference::Projected {
        crs: "EPSG:32611".into(),
        easting: 0.0,
        northing: 0.0,
    };
    assert!(GeoGrid::of(Some(&proj), 30.0, 30.0).is_some());
    let lv95 = GeoReference::Projected {
        crs: "EPSG:2056".into(),
        easting: 2_600_000.0,
        northing: 1_200_000.0,
    };
    assert!(GeoGrid::of(Some(&lv95), 30.0, 30.0).is_none());
    let why = GeoGrid::of_projected(Some(&lv95), 30.0, 30.0, DVec2::ONE).unwrap_err();
    assert!(why.contains("EPSG:2056"), "{why}");
    assert!(GeoGrid::of(None, 30.0, 30.0).is_none());
    let bad = GeoReference::Geographic {
        south_lat_deg: 10.0,
        west_lon_deg: 0.0,
        dlat_deg: 0.0,
        dlon_deg: 1.0,
    };
    assert!(GeoGrid::of(Some(&bad), 30.0, 30.0).is_none());
}

#[test]
fn the_origin_sample_is_the_world_origin_and_up_is_z_there() {
    let g = grid(47.0, 11.0);
    assert!(g.world_of_grid(DVec2::ZERO, 0.0).length() < 1e-9);
    let up = g.world_of_grid(DVec2::ZERO, 1000.0);
    assert!(
        (up - DVec3::new(0.0, 0.0, 1000.0)).length() < 1e-6,
        "{up:?}"
    );
    let axes = g.local_enu_axes(47.0, 11.0);
    assert!((axes.z_axis - DVec3::Z).length() < 1e-12);
}

#[test]
fn grid_and_world_round_trip_at_the_seam_and_high_latitude() {
    for (lat, lon) in [(0.0, 0.0), (59.5, 179.5), (-34.0, -179.9), (79.0, 20.0)] {
        let g = grid(lat, lon);
        for (gx, gy, h) in [
            (0.0, 0.0, 0.0),
            (70_000.0, 110_000.0, 2500.0),
            (-500.0, 3.0, -80.0),
        ] {
            let p = g.world_of_grid(DVec2::new(gx, gy), h);
            let back = g.grid_of_world(p);
            assert!(
                (back - DVec3::new(gx, gy, h)).length() < 1e-5,
                "({lat}, {lon}) {gx},{gy},{h} -> {back:?}"
            );
        }
    }
}

#[test]
fn far_samples_drop_below_the_origin_plane_by_the_curvature() {
    // 100 km north of the origin: ≈ d²/2M below z = 0.
    let g = grid(0.0, 0.0);
    let rows = 100_000.0 / (WGS84_A * (1.0 - WGS84_E2) * (1.0f64 / 1200.0).to_radians());
    let p = world_ref(&g, 0.0, rows, 0.0);
    let drop = 100_000.0f64.powi(2) / (2.0 * WGS84_A * (1.0 - WGS84_E2));
    assert!((p.z + drop).abs() < 0.5, "{p:?} vs drop {drop}");
}

/// Brute force: dense true positions of a node between and at its heights.
fn dense_points(g: &GeoGrid, lo: DVec2, hi: DVec2, h: [f32; 2]) -> Vec<(DVec3, f64, f64)> {
    let n = 40;
    let mut out = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let gx = lo.x + (hi.x - lo.x) * i as f64 / n as f64;
            let gy = lo.y + (hi.y - lo.y) * j as f64 / n as f64;
            let (lat, lon) = g.lat_lon_of_grid(DVec2::new(gx, gy));
            for t in [0.0, 0.37, 1.0] {
                let hh = h[0] as f64 + (h[1] - h[0]) as f64 * t;
                let e = geodetic_to_ecef(Geodetic::new(lat, lon, hh));
                out.push((g.world.ecef_to_enu(e), lat, lon));
            }
        }
    }
    out
}

#[test]
fn node_boxes_hold_every_position_and_normals_stay_within_the_spread() {
    let cases = [
        (0.0, 0.0, 20_000.0, [-50.0f32, 3000.0f32]),
        (60.0, 10.0, 300_000.0, [0.0, 4000.0]),
        (79.0, 179.0, 150_000.0, [-400.0, 1200.0]),
        (-45.0, -179.5, 800_000.0, [0.0, 8800.0]),
        (47.0, 11.0, 1_500.0, [500.0, 510.0]),
    ];
    for (lat, lon, side, h) in cases {
        let g = grid(lat, lon);
        let lo = DVec2::new(side * 0.25, side * 0.5);
        let hi = lo + DVec2::splat(side);
        let node = g.node_geometry(lo, hi, h[0], h[1]);
        let b = node.aabb;
        for (p, plat, plon) in dense_points(&g, lo, hi, h) {
            assert!(
                p.cmpge(b.min - 1e-6).all() && p.cmple(b.max + 1e-6).all(),
                "({lat}, {lon}) side {side}: {p:?} outside {b:?}"
            );
            let n = g.local_enu_axes(plat, plon).z_axis;
            let angle = n.dot(node.up).clamp(-1.0, 1.0).acos();
            assert!(angle <= node.spread + 1e-12, "{angle} > {}", node.spread);
        }
        // And the box is not loose: within a few metres plus the padding of the far corners.
        let tight = dense_points(&g, lo, hi, h).iter().fold(
            (DVec3::INFINITY, DVec3::NEG_INFINITY),
            |(a, c), (p, _, _)| (a.min(*p), c.max(*p)),
        );
        let slack = (b.max - tight.1)
            .max_element()
            .max((tight.0 - b.min).max_element());
        assert!(
            slack < 0.002 * side + 1.0,
            "side {side}: box {slack} m loose"
        );
    }
}

/// Largest distance between the true surface and the two triangles (SW–NE diagonal) of the
/// cell whose south-west corner is sample (c, r), `step` samples wide, heights along the
/// vertices' own normals.
fn measured_cell_error(g: &GeoGrid, c: f64, r: f64, step: f64, h: [f64; 4]) -> f64 {
    let v = |i: f64, j: f64, hh: f64| g.ecef_of_sample(c + i * step, r + j * step, hh);
    let (sw, se, nw, ne) = (
        v(0., 0., h[0]),
        v(1., 0., h[1]),
        v(0., 1., h[2]),
        v(1., 1., h[3]),
    );
    let n = 24;
    let mut worst: f64 = 0.0;
    for j in 0..=n {
        for i in 0..=n {
            let (u, w) = (i as f64 / n as f64, j as f64 / n as f64);
            let (drawn, hh) = if u >= w {
                (
                    sw * (1.0 - u) + se * (u - w) + ne * w,
                    h[0] * (1.0 - u) + h[1] * (u - w) + h[3] * w,
                )
            } else {
                (
                    sw * (1.0 - w) + nw * (w - u) + ne * u,
                    h[0] * (1.0 - w) + h[2] * (w - u) + h[3] * u,
                )
            };
            let truth = g.ecef_of_sample(c + u * step, r + w * step, hh);
            worst = worst.max((drawn - truth).length());
        }
    }
    worst
}

#[test]
fn cell_sag_bounds_the_interpolation_error_and_is_the_flat_one_at_the_equator() {
    for (lat, lon) in [(0.0, 0.0), (30.0, 5.0), (60.0, 100.0), (84.0, -179.0)] {
        let g = grid(lat, lon);
        for step in [16.0, 256.0, 4096.0] {
            for h in [[0.0; 4], [0.0, 3000.0, 1200.0, 200.0], [8000.0; 4]] {
                let (lo_h, hi_h) = (0.0f32, h.iter().cloned().fold(0.0, f64::max) as f32);
                let row = 600.0;
                let lo = DVec2::new(0.0, row * g.spacing_y);
                let hi = DVec2::new(step * g.spacing_x, (row + step) * g.spacing_y);
                let bound = g.cell_sag_m(lo, hi, step as u32, lo_h, hi_h);
                let got = measured_cell_error(&g, 0.0, row, step, h);
                assert!(
                    got <= bound,
                    "({lat}, {lon}) step {step} h {h:?}: measured {got} > bound {bound}"
                );
            }
        }
    }
    // Full resolution is the reference itself.
    let g0 = grid(10.0, 0.0);
    assert_eq!(
        g0.cell_sag_m(DVec2::ZERO, DVec2::splat(100.0), 1, 0.0, 3000.0),
        0.0
    );
    // Equator, flat ground: the flat path's w²/8R within 10 %.
    let g = grid(0.0, 0.0);
    let step = 1024.0;
    let bound = g.cell_sag_m(
        DVec2::ZERO,
        DVec2::new(step * g.spacing_x, step * g.spacing_y),
        step as u32,
        0.0,
        0.0,
    );
    let w = (step / 1200.0f64).to_radians() * WGS84_A * 2f64.sqrt();
    let flat = w * w / (8.0 * 6_371_000.0);
    assert!(
        bound > flat * 0.9 && bound < flat * 1.1,
        "{bound} vs {flat}"
    );
    let got = measured_cell_error(&g, 0.0, 0.0, step, [0.0; 4]);
    assert!(got > bound * 0.5, "bound {bound} loose against {got}");
}

#[test]
fn ecef_of_sample_is_the_geodetic_point() {
    let g = grid(-12.0, 130.0);
    let e = g.ecef_of_sample(600.0, 1200.0, 321.0);
    let back = ecef_to_geodetic(e);
    assert!((back.lat_deg - (-11.0)).abs() < 1e-9);
    assert!((back.lon_deg - 130.5).abs() < 1e-9);
    assert!((back.alt_m - 321.0).abs() < 1e-6);
}

/// A UTM grid (zone 32N, 30 m) whose south-west sample is at (easting, northing).
fn utm_grid(easting: f64, northing: f64, south: bool) -> GeoGrid {
    let crs = if south { "EPSG:32732" } else { "EPSG:32632" };
    let geo = GeoReference::Projected {
        crs: crs.into(),
        easting,
        northing,
    };
    GeoGrid::of_projected(Some(&geo), 30.0, 30.0, DVec2::splat(400_000.0))
        .expect("placed")
        .expect("projected")
}

/// On UTM grids — a zone's centre, its edge near the equator, 70° N, the south — node boxes
/// hold every position, normals stay within the spread, and the cell slack bounds the
/// measured interpolation error.
#[test]
fn utm_node_boxes_and_cell_slack_hold() {
    let cases = [
        (
            utm_grid(480_000.0, 5_200_000.0, false),
            20_000.0,
            [-50.0f32, 3000.0f32],
        ),
        (
            utm_grid(170_000.0, 50_000.0, false),
            300_000.0,
            [0.0, 4000.0],
        ),
        (
            utm_grid(640_000.0, 7_700_000.0, false),
            150_000.0,
            [-400.0, 1200.0],
        ),
        (
            utm_grid(180_000.0, 5_000_000.0, true),
            60_000.0,
            [0.0, 8800.0],
        ),
    ];
    for (g, side, h) in cases {
        assert!(g.world_of_grid(DVec2::ZERO, 0.0).length() < 1e-6);
        let lo = DVec2::new(side * 0.25, side * 0.5);
        let hi = lo + DVec2::splat(side);
        let node = g.node_geometry(lo, hi, h[0], h[1]);
        let b = node.aabb;
        for (p, plat, plon) in dense_points(&g, lo, hi, h) {
            assert!(
                p.cmpge(b.min - 1e-6).all() && p.cmple(b.max + 1e-6).all(),
                "side {side}: {p:?} outside {b:?}"
            );
            let n = g.local_enu_axes(plat, plon).z_axis;
            let angle = n.dot(node.up).clamp(-1.0, 1.0).acos();
            assert!(angle <= node.spread + 1e-12, "{angle} > {}", node.spread);
        }
        for step in [4.0, 64.0, 1024.0] {
            for hv in [[0.0; 4], [0.0, 2000.0, 3000.0, 800.0]] {
                let row = 600.0;
                let lo = DVec2::new(0.0, row * g.spacing_y);
                let hi = DVec2::new(step * g.spacing_x, (row + step) * g.spacing_y);
                let bound = g.cell_sag_m(lo, hi, step as u32, 0.0, 3000.0);
                let got = measured_cell_error(&g, 0.0, row, step, hv);
                assert!(got <= bound, "step {step}: measured {got} > bound {bound}");
            }
        }
    }
}
