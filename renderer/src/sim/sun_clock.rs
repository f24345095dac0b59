//! The sun from a date and time (`--time` on `render` and `fly`): where the sun stands over the
//! eye at that moment, turned into the world axes the terrain is lit in. The ephemeris is the
//! one a CIGI host's Celestial Sphere Control drives (`aerie_sim_bridge::ig::environment`,
//! NOAA's solar position after Meeus, about 0.01°), so a still image, a scripted flight and a
//! hosted run light the same place at the same time alike.

use glam::DVec3;

use aerie_sim_bridge::ig::environment::sun_direction_enu_at;

use crate::sim::geo_mapping::GeoMapping;

/// Julian day of the Unix epoch (1970-01-01 00:00 UT).
const JD_UNIX_EPOCH: f64 = 2_440_587.5;

/// A moment in UTC from which a flight's clock runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SunClock {
    /// Julian day (UT) of the start.
    jd0: f64,
}

impl SunClock {
    /// Parses an RFC 3339 date and time in UTC: `2026-06-21T12:00:00Z` (`T` or a space,
    /// seconds and fractions optional, `Z` optional; no other offset). Errors say what was
    /// expected.
    pub fn parse(s: &str) -> Result<Self, String> {
        let t = s.trim();
        let full = match t.len() {
            // YYYY-MM-DDTHH:MM, with or without Z: humantime wants the seconds.
            16 => format!("{t}:00"),
            17 if t.ends_with(['Z', 'z']) => format!("{}:00Z", &t[..16]),
            _ => t.to_string(),
        };
        let at = humantime::parse_rfc3339_weak(&full).map_err(|e| {
            format!("{s:?}: {e}; expected a UTC date and time such as 2026-06-21T12:00:00Z")
        })?;
        let unix = match at.duration_since(std::time::UNIX_EPOCH) {
            Ok(d) => d.as_secs_f64(),
            Err(e) => -e.duration().as_secs_f64(),
        };
        Ok(Self {
            jd0: JD_UNIX_EPOCH + unix / 86_400.0,
        })
    }

    /// Julian day (UT) `t_s` seconds after the start.
    pub fn julian_day(&self, t_s: f64) -> f64 {
        self.jd0 + t_s / 86_400.0
    }

    /// Unit vector towards the sun in the world frame of `mapping`'s dataset, for an eye at
    /// world point `eye`, `t_s` seconds after the start: the sun's direction in the
    /// east-north-up frame at the eye's latitude and longitude, turned into world axes.
    pub fn sun_world(&self, t_s: f64, mapping: &GeoMapping, eye: DVec3) -> Option<[f64; 3]> {
        let (lat, lon, _) = mapping.world_to_geodetic(eye);
        let local = sun_direction_enu_at(self.julian_day(t_s), lat, lon)?;
        Some(enu_at_to_world(mapping, lat, lon, local))
    }
}

/// A direction given in the east-north-up frame at (`lat_deg`, `lon_deg`) in the world axes of
/// `mapping`'s dataset (east-north-up at its origin on the ellipsoid).
pub fn enu_at_to_world(mapping: &GeoMapping, lat_deg: f64, lon_deg: f64, v: [f64; 3]) -> [f64; 3] {
    (mapping.grid().local_enu_axes(lat_deg, lon_deg) * DVec3::from_array(v)).to_array()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn srtm_n47e011() -> GeoMapping {
        GeoMapping::of_grid(
            &Some(aerie_terrain::GeoReference::Geographic {
                south_lat_deg: 47.0,
                west_lon_deg: 11.0,
                dlat_deg: 1.0 / 1200.0,
                dlon_deg: 1.0 / 1200.0,
            }),
            [62.97, 92.6],
            "test",
        )
        .unwrap()
    }

    fn elevation_deg(v: [f64; 3]) -> f64 {
        v[2].clamp(-1.0, 1.0).asin().to_degrees()
    }

    #[test]
    fn parses_utc_moments_and_counts_julian_days() {
        let j2000 = SunClock::parse("2000-01-01T12:00:00Z").unwrap();
        assert!((j2000.julian_day(0.0) - 2_451_545.0).abs() < 1e-9);
        for same in [
            "2000-01-01 12:00:00",
            "2000-01-01T12:00Z",
            "2000-01-01T12:00",
        ] {
            assert_eq!(SunClock::parse(same).unwrap(), j2000, "{same}");
        }
        assert!((j2000.julian_day(43_200.0) - 2_451_545.5).abs() < 1e-9);
        for bad in [
            "",
            "noon",
            "2000-13-01T12:00:00Z",
            "2000-01-01T25:00:00Z",
            "12:00",
        ] {
            let e = SunClock::parse(bad).unwrap_err();
            assert!(e.contains("2026-06-21T12:00:00Z"), "{bad:?}: {e}");
        }
    }

    #[test]
    fn the_solstice_noon_sun_over_innsbruck_stands_at_90_minus_latitude_plus_the_tilt() {
        let m = srtm_n47e011();
        // Innsbruck (47.27 N, 11.39 E): true solar noon on 2026-06-21 is at 11:16 UTC
        // (12:00 − 11.39° · 4 min − the equation of time, −1.8 min).
        let clock = SunClock::parse("2026-06-21T11:16:00Z").unwrap();
        let eye = m.to_world(47.27, 11.39, 3000.0);
        let sun = clock.sun_world(0.0, &m, eye).unwrap();
        // In the eye's own east-north-up frame: due south, 90 − 47.27 + 23.44 high.
        let axes = m.grid().local_enu_axes(47.27, 11.39);
        let local = axes.transpose() * DVec3::from_array(sun);
        assert!(
            (elevation_deg(local.to_array()) - 66.17).abs() < 0.05,
            "{local:?}"
        );
        assert!(local.x.abs() < 0.01 && local.y < 0.0, "{local:?}");
        // Six hours on the flight's clock: the sun has gone west and low.
        let evening = clock.sun_world(6.0 * 3600.0, &m, eye).unwrap();
        let local = axes.transpose() * DVec3::from_array(evening);
        assert!(
            local.x < -0.5 && elevation_deg(local.to_array()) < 25.0,
            "{local:?}"
        );
    }

    #[test]
    fn the_world_direction_turns_with_the_eye_away_from_the_origin() {
        let m = srtm_n47e011();
        let clock = SunClock::parse("2026-03-20T12:00:00Z").unwrap();
        // At the origin the world axes are the local ones.
        let at_origin = clock
            .sun_world(0.0, &m, m.to_world(47.0, 11.0, 0.0))
            .unwrap();
        let local = sun_direction_enu_at(clock.julian_day(0.0), 47.0, 11.0).unwrap();
        for i in 0..3 {
            assert!(
                (at_origin[i] - local[i]).abs() < 1e-9,
                "{at_origin:?} {local:?}"
            );
        }
        // 9° of longitude east the local frame has turned by about 9° · sin 47° about up:
        // the world vector differs from the local one, and is its image under the axes.
        let eye = m.to_world(47.5, 20.0, 0.0);
        let w = clock.sun_world(0.0, &m, eye).unwrap();
        let l = sun_direction_enu_at(clock.julian_day(0.0), 47.5, 20.0).unwrap();
        let back = m.grid().local_enu_axes(47.5, 20.0).transpose() * DVec3::from_array(w);
        assert!((back - DVec3::from_array(l)).length() < 1e-9);
        assert!((DVec3::from_array(w) - DVec3::from_array(l)).length() > 0.05);
        assert!((DVec3::from_array(w).length() - 1.0).abs() < 1e-9);
    }
}
