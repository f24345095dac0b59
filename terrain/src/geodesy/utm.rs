//! Projected grids: which CRSs aerie can place on the ellipsoid (UTM on WGS84, EPSG 326zz
//! north and 327zz south) and the projection both ways, (easting, northing) ⇄ (lat, lon), by
//! [`super::tmerc`] (Krüger's series to n⁶, Karney 2011: micrometres within a zone). Pure.
//!
//! Every other projected CRS is named by its EPSG code in [`projected_crs`]'s refusal; such
//! grids stay on a local flat plane and [`flat_plane_warning`] says so.

use super::tmerc::TransverseMercator;

/// A UTM zone on WGS84.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UtmZone {
    /// 1..=60.
    pub zone: u8,
    pub north: bool,
}

impl UtmZone {
    /// The zone of an EPSG code: 32601..=32660 (north), 32701..=32760 (south).
    pub fn of_epsg(code: u32) -> Option<Self> {
        let (north, zone) = match code {
            32601..=32660 => (true, code - 32600),
            32701..=32760 => (false, code - 32700),
            _ => return None,
        };
        Some(Self {
            zone: zone as u8,
            north,
        })
    }

    /// The zone's central meridian, degrees.
    pub fn central_meridian_deg(&self) -> f64 {
        f64::from(self.zone) * 6.0 - 183.0
    }

    /// The zone's transverse Mercator projection (k0 = 0.9996, false easting 500 km, false
    /// northing 10 000 km in the south).
    pub fn projection(&self) -> TransverseMercator {
        TransverseMercator {
            lon0_deg: self.central_meridian_deg(),
            k0: 0.9996,
            false_easting: 500_000.0,
            false_northing: if self.north { 0.0 } else { 10_000_000.0 },
        }
    }

    /// (easting, northing) in metres → (latitude, longitude) in degrees, or why not (a point
    /// outside the projection's domain).
    pub fn lat_lon(&self, easting: f64, northing: f64) -> Result<(f64, f64), String> {
        self.projection()
            .inverse(easting, northing)
            .map_err(|e| format!("UTM {self}: {e}"))
    }

    /// (latitude, longitude) in degrees → (easting, northing) in metres in this zone.
    pub fn easting_northing(&self, lat_deg: f64, lon_deg: f64) -> (f64, f64) {
        self.projection().forward(lat_deg, lon_deg)
    }
}

impl std::fmt::Display for UtmZone {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "zone {}{}",
            self.zone,
            if self.north { 'N' } else { 'S' }
        )
    }
}

/// A projected grid's CRS (`EPSG:<code>` as the GeoTIFF loader writes it) as a UTM zone, or
/// the reason it cannot be placed on the ellipsoid, naming the code.
pub fn projected_crs(crs: &str) -> Result<UtmZone, String> {
    let code = crs
        .strip_prefix("EPSG:")
        .and_then(|c| c.trim().parse::<u32>().ok())
        .ok_or_else(|| format!("projected CRS `{crs}` has no EPSG code: only UTM on WGS84 (EPSG:326zz, EPSG:327zz) can be placed on the ellipsoid"))?;
    UtmZone::of_epsg(code).ok_or_else(|| {
        format!("projected CRS EPSG:{code} is not UTM on WGS84 (EPSG:32601..32660, 32701..32760): it cannot be placed on the ellipsoid")
    })
}

/// The warning for a projected grid that is drawn on a local flat plane (x, y its metres,
/// curvature as the d²/2R drop) because its CRS is not UTM on WGS84: its CRS's name and why.
/// `None` for UTM grids: those are drawn on the ellipsoid ([`crate::geodesy::GeoGrid`]).
pub fn flat_plane_warning(crs: &str) -> Option<String> {
    let why = projected_crs(crs).err()?;
    Some(format!(
        "WARNING: {crs} grid drawn on a local flat plane, not the WGS84 ellipsoid ({why}); distances far from its origin carry the projection's scale error and geodetic poses are refused"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geodesy::wgs84::{WGS84_A, WGS84_E2};

    /// The meridian arc from the equator to latitude φ (radians), metres: Simpson's rule on
    /// M(φ) = a(1 − e²)/(1 − e² sin²φ)^{3/2}, independent of any projection code.
    fn meridian_arc(phi: f64) -> f64 {
        let n = 20_000;
        let h = phi / n as f64;
        let m = |p: f64| WGS84_A * (1.0 - WGS84_E2) / (1.0 - WGS84_E2 * p.sin().powi(2)).powf(1.5);
        let mut s = m(0.0) + m(phi);
        for i in 1..n {
            s += if i % 2 == 1 { 4.0 } else { 2.0 } * m(i as f64 * h);
        }
        s * h / 3.0
    }

    #[test]
    fn epsg_codes_name_utm_zones_and_others_are_refused_by_code() {
        assert_eq!(
            UtmZone::of_epsg(32632),
            Some(UtmZone {
                zone: 32,
                north: true
            })
        );
        assert_eq!(
            UtmZone::of_epsg(32760),
            Some(UtmZone {
                zone: 60,
                north: false
            })
        );
        assert_eq!(UtmZone::of_epsg(32600), None);
        assert_eq!(UtmZone::of_epsg(32661), None);
        assert_eq!(
            projected_crs("EPSG:32611"),
            Ok(UtmZone {
                zone: 11,
                north: true
            })
        );
        let lv95 = projected_crs("EPSG:2056").unwrap_err();
        assert!(
            lv95.contains("EPSG:2056") && lv95.contains("not UTM"),
            "{lv95}"
        );
        let unknown = projected_crs("projected (unknown CRS)").unwrap_err();
        assert!(unknown.contains("no EPSG code"), "{unknown}");
        let w = flat_plane_warning("EPSG:2056").unwrap();
        assert!(w.starts_with("WARNING") && w.contains("EPSG:2056"), "{w}");
        assert_eq!(flat_plane_warning("EPSG:32632"), None);
        assert_eq!(
            UtmZone {
                zone: 32,
                north: true
            }
            .central_meridian_deg(),
            9.0
        );
    }

    /// On the central meridian the northing is 0.9996 times the meridian arc: the inverse's
    /// latitude there, from 100 km to 9 300 km north and south, is within 1 mm of the arc.
    #[test]
    fn inverse_on_the_central_meridian_matches_the_meridian_arc() {
        let mut worst = 0.0f64;
        for north in [true, false] {
            let z = UtmZone { zone: 33, north };
            for k in 1..=93 {
                let arc = k as f64 * 100_000.0;
                let northing = if north { arc } else { 10_000_000.0 - arc };
                let (lat, lon) = z.lat_lon(500_000.0, northing).unwrap();
                assert!((lon - 15.0).abs() < 1e-9, "{lon}");
                let got = 0.9996 * meridian_arc(lat.abs().to_radians());
                assert_eq!(lat > 0.0, north);
                worst = worst.max((got - arc).abs());
            }
        }
        assert!(worst < 1e-3, "inverse off the meridian arc by {worst} m");
        eprintln!(
            "UTM inverse on the central meridian: within {:.2e} m",
            worst
        );
    }

    /// A published point (the Python `utm` package's example: 51.2° N, 7.5° E is 395 201.31 E,
    /// 5 673 135.24 N in zone 32U), and round trips near the central meridian to 5 cm.
    #[test]
    fn inverse_matches_a_published_point_and_round_trips() {
        let z = UtmZone {
            zone: 32,
            north: true,
        };
        let (lat, lon) = z.lat_lon(395_201.310_381, 5_673_135.241_182).unwrap();
        // Metres on the ground: the series is truncated, so 105 km off the central meridian
        // the inverse is within about a centimetre (reported, bounded at 2 cm).
        let off_m = ((lat - 51.2).to_radians() * 6.37e6)
            .hypot((lon - 7.5).to_radians() * 6.37e6 * 51.2f64.to_radians().cos());
        eprintln!("UTM inverse at the published point: {off_m:.4} m off");
        assert!(off_m < 0.02, "{lat}, {lon}: {off_m} m");
        // Round trips close to a micrometre everywhere in the zone, its edge included (the
        // `utm` crate's series, used before, left 0.63 m there).
        for (lat, lon) in [
            (0.5, 6.0),
            (0.5, 8.0),
            (47.3, 10.8),
            (60.0, 12.0),
            (83.9, 6.0),
        ] {
            let (e, n) = z.easting_northing(lat, lon);
            let (la, lo) = z.lat_lon(e, n).unwrap();
            let (e2, n2) = z.easting_northing(la, lo);
            assert!(
                (e2 - e).hypot(n2 - n) < 1e-6
                    && (la - lat).abs() < 1e-10
                    && (lo - lon).abs() < 1e-10,
                "({lat}, {lon}): {e},{n} vs {e2},{n2}"
            );
        }
        assert!(z.lat_lon(f64::NAN, 0.0).is_err());
    }
}
