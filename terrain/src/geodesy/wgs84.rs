//! WGS84 geodesy in f64: geodetic ⇄ Earth-centred Earth-fixed (ECEF) ⇄ local East-North-Up (ENU).
//!
//! Angles are degrees at this API (as on the wire and in config), radians inside.

use glam::{DMat3, DVec3};

/// WGS84 semi-major axis (equatorial radius), metres.
pub const WGS84_A: f64 = 6_378_137.0;
/// WGS84 flattening.
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;
/// WGS84 semi-minor axis (polar radius), metres: `a (1 − f)` ≈ 6 356 752.314 245.
pub const WGS84_B: f64 = WGS84_A * (1.0 - WGS84_F);
/// WGS84 first eccentricity squared: `f (2 − f)`.
pub const WGS84_E2: f64 = WGS84_F * (2.0 - WGS84_F);
/// WGS84 second eccentricity squared: `e² / (1 − e²)`.
pub const WGS84_EP2: f64 = WGS84_E2 / (1.0 - WGS84_E2);

/// A WGS84 geodetic position: latitude and longitude in degrees, ellipsoidal height in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geodetic {
    /// Geodetic latitude, degrees, north positive.
    pub lat_deg: f64,
    /// Longitude, degrees, east positive.
    pub lon_deg: f64,
    /// Height above the WGS84 ellipsoid, metres.
    pub alt_m: f64,
}

impl Geodetic {
    /// Builds a geodetic position from degrees and metres.
    pub const fn new(lat_deg: f64, lon_deg: f64, alt_m: f64) -> Self {
        Self {
            lat_deg,
            lon_deg,
            alt_m,
        }
    }
}

/// Prime-vertical radius of curvature N(φ), from sin φ.
fn prime_vertical_radius(sin_lat: f64) -> f64 {
    WGS84_A / (1.0 - WGS84_E2 * sin_lat * sin_lat).sqrt()
}

/// Converts a geodetic position to ECEF metres (x towards 0°N 0°E, z towards the north pole).
pub fn geodetic_to_ecef(g: Geodetic) -> DVec3 {
    let (sin_lat, cos_lat) = g.lat_deg.to_radians().sin_cos();
    let (sin_lon, cos_lon) = g.lon_deg.to_radians().sin_cos();
    let n = prime_vertical_radius(sin_lat);
    let r = (n + g.alt_m) * cos_lat;
    DVec3::new(
        r * cos_lon,
        r * sin_lon,
        (n * (1.0 - WGS84_E2) + g.alt_m) * sin_lat,
    )
}

/// Converts ECEF metres to a geodetic position (longitude in (−180°, 180°]).
///
/// Bowring's formula iterated to convergence (two or three rounds near the Earth's surface):
/// better than 1e-12° and 1 µm from −500 m to beyond geostationary altitude. Valid for any point
/// more than ~50 km from the Earth's centre; on the polar axis the longitude is 0.
pub fn ecef_to_geodetic(ecef: DVec3) -> Geodetic {
    let p = ecef.x.hypot(ecef.y);
    let z = ecef.z;
    let lon = ecef.y.atan2(ecef.x);
    let one_minus_f = 1.0 - WGS84_F;

    // Parametric (reduced) latitude β as the starting point, then Bowring's update.
    let mut beta = z.atan2(one_minus_f * p);
    let mut lat = beta;
    for _ in 0..8 {
        let (sin_b, cos_b) = beta.sin_cos();
        let next = (z + WGS84_EP2 * WGS84_B * sin_b * sin_b * sin_b)
            .atan2(p - WGS84_E2 * WGS84_A * cos_b * cos_b * cos_b);
        let done = (next - lat).abs() < 1e-15;
        lat = next;
        let (sin_l, cos_l) = lat.sin_cos();
        beta = (one_minus_f * sin_l).atan2(cos_l);
        if done {
            break;
        }
    }

    let (sin_lat, cos_lat) = lat.sin_cos();
    let n = prime_vertical_radius(sin_lat);
    // Stable at the poles and the equator alike.
    let alt = p * cos_lat + z * sin_lat - n * (1.0 - WGS84_E2 * sin_lat * sin_lat);
    let mut lon_deg = lon.to_degrees();
    if lon_deg <= -180.0 {
        // atan2 gives −π for y = −0.0 (e.g. cos/sin of −180° rounding); keep (−180, 180].
        lon_deg += 360.0;
    }
    Geodetic::new(lat.to_degrees(), lon_deg, alt)
}

/// A local East-North-Up frame tangent to the WGS84 ellipsoid at an origin (z along the
/// ellipsoid normal, so terrain away from the origin drops below z = 0 by ≈ d²/2R).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalTangentPlane {
    origin: Geodetic,
    origin_ecef: DVec3,
    /// Columns: the east, north and up unit vectors expressed in ECEF.
    axes: DMat3,
}

impl LocalTangentPlane {
    /// Builds the frame tangent at `origin` (the origin's height is the plane's z = 0).
    pub fn new(origin: Geodetic) -> Self {
        let (sin_lat, cos_lat) = origin.lat_deg.to_radians().sin_cos();
        let (sin_lon, cos_lon) = origin.lon_deg.to_radians().sin_cos();
        let east = DVec3::new(-sin_lon, cos_lon, 0.0);
        let north = DVec3::new(-sin_lat * cos_lon, -sin_lat * sin_lon, cos_lat);
        let up = DVec3::new(cos_lat * cos_lon, cos_lat * sin_lon, sin_lat);
        Self {
            origin,
            origin_ecef: geodetic_to_ecef(origin),
            axes: DMat3::from_cols(east, north, up),
        }
    }

    /// The geodetic origin this frame was built at.
    pub fn origin(&self) -> Geodetic {
        self.origin
    }

    /// The origin in ECEF metres.
    pub fn origin_ecef(&self) -> DVec3 {
        self.origin_ecef
    }

    /// Rotation whose columns are the east, north and up unit vectors in ECEF
    /// (ENU → ECEF for directions; its transpose maps ECEF directions to ENU).
    pub fn enu_axes(&self) -> DMat3 {
        self.axes
    }

    /// ECEF metres → ENU metres relative to the origin.
    pub fn ecef_to_enu(&self, ecef: DVec3) -> DVec3 {
        let d = ecef - self.origin_ecef;
        DVec3::new(
            self.axes.x_axis.dot(d),
            self.axes.y_axis.dot(d),
            self.axes.z_axis.dot(d),
        )
    }

    /// ENU metres relative to the origin → ECEF metres.
    pub fn enu_to_ecef(&self, enu: DVec3) -> DVec3 {
        self.origin_ecef + self.axes * enu
    }

    /// Geodetic position → ENU metres relative to the origin.
    pub fn geodetic_to_enu(&self, g: Geodetic) -> DVec3 {
        self.ecef_to_enu(geodetic_to_ecef(g))
    }

    /// ENU metres relative to the origin → geodetic position.
    pub fn enu_to_geodetic(&self, enu: DVec3) -> Geodetic {
        ecef_to_geodetic(self.enu_to_ecef(enu))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const MM: f64 = 1e-3;

    /// Meridional radius of curvature M(φ) = a(1−e²)/(1−e² sin²φ)^{3/2}, written out here so
    /// that the curvature tests do not reuse the code under test.
    fn meridional_radius(lat_deg: f64) -> f64 {
        let a = 6_378_137.0_f64;
        let f = 1.0 / 298.257_223_563_f64;
        let e2 = f * (2.0 - f);
        let s = lat_deg.to_radians().sin();
        a * (1.0 - e2) / (1.0 - e2 * s * s).powf(1.5)
    }

    /// Difference of two longitudes in degrees, wrapped to (−180, 180].
    fn lon_diff(a: f64, b: f64) -> f64 {
        let d = (a - b).rem_euclid(360.0);
        if d > 180.0 {
            d - 360.0
        } else {
            d
        }
    }

    fn assert_close(actual: DVec3, expected: DVec3, tol: f64) {
        assert!(
            (actual - expected).abs().max_element() <= tol,
            "{actual:?} vs {expected:?} (tolerance {tol})"
        );
    }

    #[test]
    fn constants_match_wgs84() {
        assert!((WGS84_B - 6_356_752.314_245).abs() < 1e-6);
        assert!((WGS84_E2 - 0.006_694_379_990_14).abs() < 1e-14);
    }

    #[test]
    fn equator_prime_meridian_is_on_x_axis() {
        let e = geodetic_to_ecef(Geodetic::new(0.0, 0.0, 0.0));
        assert_close(e, DVec3::new(6_378_137.0, 0.0, 0.0), 1e-9);
    }

    #[test]
    fn equator_90_east_is_on_y_axis() {
        let e = geodetic_to_ecef(Geodetic::new(0.0, 90.0, 100.0));
        assert_close(e, DVec3::new(0.0, 6_378_237.0, 0.0), 1e-6);
    }

    #[test]
    fn poles_are_on_z_axis_at_b() {
        let n = geodetic_to_ecef(Geodetic::new(90.0, 0.0, 0.0));
        assert_close(n, DVec3::new(0.0, 0.0, 6_356_752.314_245), 1e-6);
        let s = geodetic_to_ecef(Geodetic::new(-90.0, 123.0, 10.0));
        assert_close(s, DVec3::new(0.0, 0.0, -6_356_762.314_245), 1e-6);
    }

    #[test]
    fn pole_and_equator_back_to_geodetic() {
        let g = ecef_to_geodetic(DVec3::new(0.0, 0.0, 6_356_752.314_245 + 1000.0));
        assert!((g.lat_deg - 90.0).abs() < 1e-12 && (g.alt_m - 1000.0).abs() < MM);
        let g = ecef_to_geodetic(DVec3::new(0.0, 0.0, -6_356_752.314_245));
        assert!((g.lat_deg + 90.0).abs() < 1e-12 && g.alt_m.abs() < MM);
        for y in [0.0, -0.0, -1e-9] {
            let g = ecef_to_geodetic(DVec3::new(-6_378_137.0, y, 0.0));
            assert!(
                g.lat_deg.abs() < 1e-12 && (g.lon_deg - 180.0).abs() < 1e-9,
                "{g:?}"
            );
            assert!(g.alt_m.abs() < MM);
        }
        let g = ecef_to_geodetic(geodetic_to_ecef(Geodetic::new(0.0, -180.0, 0.0)));
        assert_eq!(g.lon_deg, 180.0);
    }

    #[test]
    fn surface_points_lie_on_the_ellipse() {
        // Independent check: (p/a)² + (z/b)² = 1 for h = 0.
        for lat in [-89.9, -60.0, -12.5, 0.0, 33.3, 45.0, 71.0, 89.99] {
            let e = geodetic_to_ecef(Geodetic::new(lat, 17.0, 0.0));
            let p = e.x.hypot(e.y);
            let q = (p / 6_378_137.0).powi(2) + (e.z / 6_356_752.314_245).powi(2);
            assert!((q - 1.0).abs() < 1e-12, "lat {lat}: {q}");
        }
    }

    #[test]
    fn height_is_distance_along_the_normal() {
        let lat: f64 = 37.0;
        let base = geodetic_to_ecef(Geodetic::new(lat, -122.0, 0.0));
        let high = geodetic_to_ecef(Geodetic::new(lat, -122.0, 12_345.0));
        assert!(((high - base).length() - 12_345.0).abs() < 1e-6);
        // The normal makes angle φ (geodetic latitude) with the equatorial plane.
        let d = (high - base).normalize();
        assert!((d.z.asin().to_degrees() - lat).abs() < 1e-9);
    }

    #[test]
    fn round_trip_at_extreme_altitudes() {
        for alt in [-11_000.0, 0.0, 400_000.0, 35_786_000.0] {
            for lat in [-89.999, -45.0, 0.0, 1e-9, 60.0, 89.999] {
                let g = Geodetic::new(lat, -179.999, alt);
                let back = ecef_to_geodetic(geodetic_to_ecef(g));
                assert!((back.lat_deg - lat).abs() < 1e-9, "{g:?} -> {back:?}");
                assert!(
                    lon_diff(back.lon_deg, g.lon_deg).abs() < 1e-9,
                    "{g:?} -> {back:?}"
                );
                assert!((back.alt_m - alt).abs() < MM, "{g:?} -> {back:?}");
            }
        }
    }

    #[test]
    fn one_km_north_at_45_drops_by_curvature() {
        let origin = Geodetic::new(45.0, 7.0, 0.0);
        let ltp = LocalTangentPlane::new(origin);
        let d = 1000.0;
        // Latitude step for a 1 km meridian arc, using M at the arc's midpoint.
        let mut dlat = (d / meridional_radius(45.0)).to_degrees();
        for _ in 0..3 {
            dlat = (d / meridional_radius(45.0 + dlat / 2.0)).to_degrees();
        }
        let enu = ltp.geodetic_to_enu(Geodetic::new(45.0 + dlat, 7.0, 0.0));
        let drop = d * d / (2.0 * meridional_radius(45.0));
        assert!((drop - 0.0785).abs() < 1e-3, "drop {drop}");
        assert!(enu.x.abs() < 1e-6, "{enu:?}");
        assert!((enu.y - d).abs() < MM, "{enu:?}");
        assert!((enu.z + drop).abs() < MM, "{enu:?} vs drop {drop}");
    }

    #[test]
    fn tangent_plane_point_rises_above_the_ellipsoid() {
        let ltp = LocalTangentPlane::new(Geodetic::new(45.0, 7.0, 250.0));
        let g = ltp.enu_to_geodetic(DVec3::new(0.0, 1000.0, 0.0));
        let rise = 1000.0_f64.powi(2) / (2.0 * meridional_radius(45.0));
        assert!((g.alt_m - 250.0 - rise).abs() < MM, "{g:?}");
        assert!(lon_diff(g.lon_deg, 7.0).abs() < 1e-12);
        assert!(g.lat_deg > 45.0);
    }

    #[test]
    fn origin_maps_to_zero_and_axes_are_orthonormal() {
        let ltp = LocalTangentPlane::new(Geodetic::new(-33.9, 151.2, 40.0));
        assert_close(ltp.geodetic_to_enu(ltp.origin()), DVec3::ZERO, 1e-9);
        let m = ltp.enu_axes();
        assert!((m.transpose() * m - DMat3::IDENTITY)
            .abs()
            .to_cols_array()
            .iter()
            .all(|v| *v < 1e-15));
        assert!((m.determinant() - 1.0).abs() < 1e-15);
        // East is horizontal; up is the origin's ellipsoid normal.
        assert_close(
            ltp.geodetic_to_enu(Geodetic::new(-33.9, 151.2, 1040.0)),
            DVec3::new(0.0, 0.0, 1000.0),
            1e-6,
        );
    }

    #[test]
    fn east_is_east_across_the_antimeridian() {
        let ltp = LocalTangentPlane::new(Geodetic::new(0.0, 179.9999, 0.0));
        let enu = ltp.geodetic_to_enu(Geodetic::new(0.0, -179.9999, 0.0));
        // 0.0002° of equator ≈ 22.26 m east.
        let expect = 0.0002_f64.to_radians() * 6_378_137.0;
        assert!((enu.x - expect).abs() < MM && enu.y.abs() < 1e-6, "{enu:?}");
    }

    #[test]
    fn far_from_origin_round_trip_stays_sub_millimetre() {
        // 10,000 km away: f64 keeps the round trip well under a millimetre.
        let ltp = LocalTangentPlane::new(Geodetic::new(10.0, 20.0, 0.0));
        let enu = DVec3::new(7.0e6, -7.0e6, -3.0e6);
        let back = ltp.geodetic_to_enu(ltp.enu_to_geodetic(enu));
        assert_close(back, enu, MM);
    }

    fn lat_strategy() -> impl Strategy<Value = f64> {
        prop_oneof![
            -89.9..=89.9_f64,
            Just(89.9),
            Just(-89.9),
            89.0..=89.9_f64,
            -89.9..=-89.0_f64,
        ]
    }

    fn lon_strategy() -> impl Strategy<Value = f64> {
        prop_oneof![
            -180.0..360.0_f64,
            Just(180.0),
            Just(-180.0),
            179.9..=180.0_f64,
            -180.0..=-179.9_f64,
        ]
    }

    fn alt_strategy() -> impl Strategy<Value = f64> {
        prop_oneof![-500.0..=50_000.0_f64, Just(-500.0), Just(50_000.0)]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2048))]

        #[test]
        fn geodetic_ecef_round_trip(lat in lat_strategy(), lon in lon_strategy(), alt in alt_strategy()) {
            let g = Geodetic::new(lat, lon, alt);
            let e = geodetic_to_ecef(g);
            let back = ecef_to_geodetic(e);
            prop_assert!((back.lat_deg - lat).abs() < 1e-9, "{:?} -> {:?}", g, back);
            prop_assert!(lon_diff(back.lon_deg, lon).abs() < 1e-9, "{:?} -> {:?}", g, back);
            prop_assert!(back.lon_deg > -180.0 && back.lon_deg <= 180.0);
            prop_assert!((back.alt_m - alt).abs() < MM, "{:?} -> {:?}", g, back);
            // And the position itself comes back within a millimetre.
            prop_assert!((geodetic_to_ecef(back) - e).length() < MM);
        }

        #[test]
        fn enu_round_trip(
            olat in lat_strategy(), olon in lon_strategy(), oalt in alt_strategy(),
            x in -200_000.0..200_000.0_f64, y in -200_000.0..200_000.0_f64, z in -500.0..50_000.0_f64,
        ) {
            let ltp = LocalTangentPlane::new(Geodetic::new(olat, olon, oalt));
            let enu = DVec3::new(x, y, z);
            let g = ltp.enu_to_geodetic(enu);
            let back = ltp.geodetic_to_enu(g);
            prop_assert!((back - enu).length() < MM, "{:?} -> {:?} -> {:?}", enu, g, back);
        }

        #[test]
        fn geodetic_enu_round_trip(
            olat in lat_strategy(), olon in lon_strategy(),
            dlat in -1.0..1.0_f64, dlon in -1.0..1.0_f64, alt in alt_strategy(),
        ) {
            let ltp = LocalTangentPlane::new(Geodetic::new(olat, olon, 0.0));
            let g = Geodetic::new((olat + dlat).clamp(-89.9, 89.9), olon + dlon, alt);
            let back = ltp.enu_to_geodetic(ltp.geodetic_to_enu(g));
            prop_assert!((back.lat_deg - g.lat_deg).abs() < 1e-9, "{:?} -> {:?}", g, back);
            prop_assert!(lon_diff(back.lon_deg, g.lon_deg).abs() < 1e-9, "{:?} -> {:?}", g, back);
            prop_assert!((back.alt_m - alt).abs() < MM, "{:?} -> {:?}", g, back);
        }

        #[test]
        fn distances_are_preserved_by_enu(
            olat in lat_strategy(), olon in lon_strategy(),
            a in prop::array::uniform3(-1e5..1e5_f64), b in prop::array::uniform3(-1e5..1e5_f64),
        ) {
            // ENU is a rigid transform of ECEF.
            let ltp = LocalTangentPlane::new(Geodetic::new(olat, olon, 0.0));
            let (a, b) = (DVec3::from_array(a), DVec3::from_array(b));
            let d_enu = (a - b).length();
            let d_ecef = (ltp.enu_to_ecef(a) - ltp.enu_to_ecef(b)).length();
            prop_assert!((d_enu - d_ecef).abs() < 1e-6);
        }
    }
}
