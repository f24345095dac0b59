use super::*;

fn utm(zone: u8, south: bool) -> TransverseMercator {
    TransverseMercator {
        lon0_deg: f64::from(zone) * 6.0 - 183.0,
        k0: 0.9996,
        false_easting: 500_000.0,
        false_northing: if south { 10_000_000.0 } else { 0.0 },
    }
}

/// PROJ's own test points (builtins.gie, `+proj=utm +zone=30` and `+proj=etmerc`, GRS80).
/// GRS80's flattening differs from WGS84's by 1.6e-11, which moves these points by < 0.1 mm,
/// so the published values hold to 1 mm on WGS84.
#[test]
fn matches_the_proj_test_suite_points() {
    let z30 = utm(30, false);
    let etm = TransverseMercator {
        lon0_deg: 0.0,
        k0: 1.0,
        false_easting: 0.0,
        false_northing: 0.0,
    };
    let cases = [
        (
            z30,
            1.0,
            2.0,
            1_057_002.405_491_297_6,
            110_955.141_175_949_29,
        ),
        (
            z30,
            -1.0,
            2.0,
            1_057_002.405_491_297_6,
            -110_955.141_175_949_2,
        ),
        (z30, 1.0, -2.0, 611_263.812_278_906, 110_547.105_696_804_21),
        (
            z30,
            -1.0,
            -2.0,
            611_263.812_278_906,
            -110_547.105_696_804_21,
        ),
        (etm, 1.0, 2.0, 222_650.796_797_585_27, 110_642.229_411_933_2),
        (
            etm,
            -1.0,
            -2.0,
            -222_650.796_797_585_27,
            -110_642.229_411_933_2,
        ),
    ];
    for (p, lat, lon, e, n) in cases {
        let (ge, gn) = p.forward(lat, lon);
        assert!(
            (ge - e).abs() < 1e-3 && (gn - n).abs() < 1e-3,
            "({lat}, {lon}): {ge}, {gn} vs {e}, {n}"
        );
        let (la, lo) = p.inverse(e, n).unwrap();
        let off = ((la - lat).to_radians() * WGS84_A).hypot((lo - lon).to_radians() * WGS84_A);
        assert!(off < 1e-3, "inverse ({lat}, {lon}): {la}, {lo}: {off} m");
    }
}

/// Against `proj4rs`'s `utm` (Poder/Engsager's series: an independent derivation) on WGS84,
/// over every zone's full width from 80° S to 84° N and half a zone beyond its edges: forward
/// and inverse agree to a micrometre, and inverse ∘ forward returns to the start to 1e-6 m.
#[test]
fn agrees_with_an_independent_implementation_and_round_trips() {
    use proj4rs::proj::Proj;
    use proj4rs::transform::transform;
    let geo = Proj::from_proj_string("+proj=longlat +ellps=WGS84 +no_defs").unwrap();
    let mut worst_fwd = 0.0f64;
    let mut worst_inv = 0.0f64;
    let mut worst_trip = 0.0f64;
    for (zone, south) in [
        (1u8, false),
        (17, true),
        (32, false),
        (33, true),
        (60, false),
    ] {
        let us = utm(zone, south);
        let def = format!(
            "+proj=utm +zone={zone} +ellps=WGS84{} +no_defs",
            if south { " +south" } else { "" }
        );
        let theirs = Proj::from_proj_string(&def).unwrap();
        for i in 0..=24 {
            let lat = if south {
                -80.0 + 80.0 * i as f64 / 24.0
            } else {
                84.0 * i as f64 / 24.0
            };
            for j in 0..=12 {
                // The zone's edges are ±3° from its meridian; go 4.5° out.
                let lon = us.lon0_deg - 4.5 + 9.0 * j as f64 / 12.0;
                let (e, n) = us.forward(lat, lon);
                let mut pt = (lon.to_radians(), lat.to_radians(), 0.0);
                transform(&geo, &theirs, &mut pt).unwrap();
                worst_fwd = worst_fwd.max((pt.0 - e).hypot(pt.1 - n));
                let (la, lo) = us.inverse(e, n).unwrap();
                let (e2, n2) = us.forward(la, lo);
                worst_trip = worst_trip.max((e2 - e).hypot(n2 - n));
                let mut back = (e, n, 0.0);
                transform(&theirs, &geo, &mut back).unwrap();
                let dlon = (back.0.to_degrees() - lo + 180.0).rem_euclid(360.0) - 180.0;
                let m = ((back.1.to_degrees() - la).to_radians() * WGS84_A)
                    .hypot(dlon.to_radians() * WGS84_A * la.to_radians().cos());
                worst_inv = worst_inv.max(m);
            }
        }
    }
    eprintln!(
        "transverse Mercator vs proj4rs: forward {worst_fwd:.1e} m, inverse {worst_inv:.1e} m; round trip {worst_trip:.1e} m"
    );
    assert!(worst_fwd < 1e-6, "forward off by {worst_fwd} m");
    assert!(worst_inv < 1e-6, "inverse off by {worst_inv} m");
    assert!(worst_trip < 1e-6, "round trip off by {worst_trip} m");
}

/// On the central meridian the northing is k0 times the meridian arc, here integrated
/// numerically (Simpson on M(φ)), independent of any series.
#[test]
fn central_meridian_northing_is_the_scaled_meridian_arc() {
    let arc = |phi: f64| {
        let n = 20_000;
        let h = phi / n as f64;
        let m = |p: f64| WGS84_A * (1.0 - WGS84_E2) / (1.0 - WGS84_E2 * p.sin().powi(2)).powf(1.5);
        let mut s = m(0.0) + m(phi);
        for i in 1..n {
            s += if i % 2 == 1 { 4.0 } else { 2.0 } * m(i as f64 * h);
        }
        s * h / 3.0
    };
    let p = utm(31, false);
    for lat in [0.0, 10.0, 45.0, 60.0, 84.0] {
        let (e, n) = p.forward(lat, 3.0);
        assert!((e - 500_000.0).abs() < 1e-9);
        let want = 0.9996 * arc(f64::to_radians(lat));
        assert!((n - want).abs() < 1e-6, "{lat}: {n} vs {want}");
    }
}

#[test]
fn refuses_points_outside_the_projection() {
    let p = utm(32, false);
    assert!(p.inverse(f64::NAN, 0.0).is_err());
    assert!(p.inverse(500_000.0 + 1.7e7, 0.0).is_err());
    let (la, lo) = p.inverse(500_000.0, 0.0).unwrap();
    assert!(la.abs() < 1e-12 && (lo - 9.0).abs() < 1e-12);
}
