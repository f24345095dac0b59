//! The geoid: heights above the WGS84 ellipsoid ↔ heights above mean sea level, for hosts that
//! send ellipsoidal (GNSS) altitudes while the terrain is in its own datum (orthometric, MSL
//! for SRTM; PROTOCOL.md "Datums and placement").
//!
//! The undulation N (the geoid's height above the ellipsoid) is EGM96's, synthesised from the
//! model's degree-360 spherical-harmonic coefficients by the `egm96` crate (built without its
//! raster features, so nothing is downloaded and no grid is interpolated): H = h − N. A
//! synthesis costs about a millisecond, so [`GeoidCache`] keeps the last one and recomputes
//! only when the point has moved more than [`GeoidCache::RECOMPUTE_DEG`] — the geoid's slope
//! is below 10⁻⁴ almost everywhere, so the value reused is within a centimetre.

/// EGM96 geoid undulation N at (lat, lon) in degrees: the geoid's height above the WGS84
/// ellipsoid, metres (a height above the ellipsoid h is h − N above mean sea level).
pub fn egm96_undulation_m(lat_deg: f64, lon_deg: f64) -> f64 {
    egm96::egm96_compute_altitude_offset(lat_deg, lon_deg)
}

/// The last undulation computed, reused while the point stays close.
#[derive(Debug, Clone, Copy, Default)]
pub struct GeoidCache {
    last: Option<(f64, f64, f64)>,
}

impl GeoidCache {
    /// Largest move (latitude or longitude, degrees) before N is synthesised again: 0.001° is
    /// at most 111 m, over which N changes by a centimetre or less.
    pub const RECOMPUTE_DEG: f64 = 1e-3;

    /// N at (lat, lon), metres; non-finite input gives NaN (the caller rejects the pose).
    pub fn undulation_m(&mut self, lat_deg: f64, lon_deg: f64) -> f64 {
        if !(lat_deg.is_finite() && lon_deg.is_finite()) {
            return f64::NAN;
        }
        if let Some((lat, lon, n)) = self.last {
            let dlon = ((lon_deg - lon + 180.0).rem_euclid(360.0) - 180.0).abs();
            if (lat_deg - lat).abs() <= Self::RECOMPUTE_DEG && dlon <= Self::RECOMPUTE_DEG {
                return n;
            }
        }
        let n = egm96_undulation_m(lat_deg, lon_deg);
        self.last = Some((lat_deg, lon_deg, n));
        n
    }

    /// A height above the ellipsoid at (lat, lon) → above mean sea level (EGM96), metres.
    pub fn msl_of_ellipsoidal(&mut self, lat_deg: f64, lon_deg: f64, h_m: f64) -> f64 {
        h_m - self.undulation_m(lat_deg, lon_deg)
    }
}

/// N for many places at once (entities, terrain-query points): kept per cell of
/// [`GeoidCache::RECOMPUTE_DEG`] (N synthesised at the cell's centre, ≤ 1 cm from the point's
/// own), at most [`GeoidCells::MAX_CELLS`] cells before they are forgotten.
#[derive(Debug, Clone, Default)]
pub struct GeoidCells {
    cells: std::collections::HashMap<(i64, i64), f64>,
}

impl GeoidCells {
    pub const MAX_CELLS: usize = 4096;

    /// N at (lat, lon), metres; NaN for non-finite input.
    pub fn undulation_m(&mut self, lat_deg: f64, lon_deg: f64) -> f64 {
        if !(lat_deg.is_finite() && lon_deg.is_finite()) {
            return f64::NAN;
        }
        let step = GeoidCache::RECOMPUTE_DEG;
        let cells = (360.0 / step).round() as i64;
        let key = (
            (lat_deg / step).round() as i64,
            (lon_deg.rem_euclid(360.0) / step).round() as i64 % cells,
        );
        if let Some(&n) = self.cells.get(&key) {
            return n;
        }
        if self.cells.len() >= Self::MAX_CELLS {
            self.cells.clear();
        }
        let n = egm96_undulation_m(key.0 as f64 * step, key.1 as f64 * step);
        self.cells.insert(key, n);
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// NGA's published EGM96 check points (the model's test file: latitude, longitude east,
    /// N in metres, given to the millimetre from the 15′ grid).
    const NGA_CHECK: [(f64, f64, f64); 6] = [
        (38.628_155, 269.779_155, -31.628),
        (-14.621_217, 305.021_114, -2.969),
        (46.874_319, 102.448_729, -43.575),
        (-23.617_446, 133.874_712, 15.871),
        (38.625_473, 359.999_500, 50.066),
        (-0.466_744, 0.002_300, 17.329),
    ];

    #[test]
    fn undulation_matches_the_published_egm96_check_points() {
        let t = std::time::Instant::now();
        for (lat, lon, want) in NGA_CHECK {
            let n = egm96_undulation_m(lat, lon);
            assert!(
                (n - want).abs() < 0.05,
                "({lat}, {lon}): N = {n:.3}, NGA {want}"
            );
            // Longitudes east of 180° are the same meridians as west ones.
            let w = egm96_undulation_m(lat, lon - 360.0);
            assert!((w - n).abs() < 1e-6, "({lat}, {lon}): {w} vs {n}");
        }
        eprintln!(
            "EGM96 synthesis: {:.2} ms a point",
            t.elapsed().as_secs_f64() * 1e3 / 12.0
        );
    }

    #[test]
    fn the_cache_reuses_close_points_and_recomputes_far_ones() {
        let mut c = GeoidCache::default();
        let (lat, lon, want) = NGA_CHECK[2];
        let n = c.undulation_m(lat, lon);
        assert!((n - want).abs() < 0.05);
        // 50 m away: the value kept, within a centimetre of the model there.
        let near = c.undulation_m(lat + 4e-4, lon);
        assert_eq!(near, n);
        assert!((egm96_undulation_m(lat + 4e-4, lon) - n).abs() < 0.01);
        // Another continent: recomputed.
        let (lat2, lon2, want2) = NGA_CHECK[3];
        assert!((c.undulation_m(lat2, lon2) - want2).abs() < 0.05);
        assert!((c.msl_of_ellipsoidal(lat2, lon2, 1000.0) - (1000.0 - want2)).abs() < 0.05);
        assert!(c.undulation_m(f64::NAN, 0.0).is_nan());
    }
}
