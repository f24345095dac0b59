//! The host's environment settings that have a terrain meaning: Celestial Sphere Control (date,
//! time of day, the ephemeris flag → where the sun is) and Atmosphere Control (visibility →
//! the renderer's haze distance). Pure: the IG's time comes in as a number.

/// What the host set with Celestial Sphere Control (packet 9), as the IG keeps it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Celestial {
    /// Gregorian year, month (1–12) and day (1–31), UTC; `None` when the host said the date is
    /// not valid (the IG then has no date to place the sun by).
    pub date: Option<(i32, u32, u32)>,
    /// Time of day, seconds after midnight UTC, as the host set it (CIGI carries hour and
    /// minute).
    pub seconds_utc: f64,
    /// Ephemeris model enabled: the time of day runs on from the host's setting with the IG's
    /// clock; disabled, it stays where the host put it.
    pub ephemeris: bool,
    /// Sun, moon and star field enables.
    pub sun_enabled: bool,
    /// Moon enable.
    pub moon_enabled: bool,
    /// Star field enable.
    pub stars_enabled: bool,
    /// Star field intensity, percent.
    pub star_intensity_pct: f32,
    /// The IG's time (seconds, the frame clock) when the packet arrived: where the ephemeris
    /// clock starts from.
    pub set_at_s: f64,
}

impl Celestial {
    /// The date and time at IG time `now_s`: advanced by the time since the packet when the
    /// ephemeris runs, as set otherwise. (Seconds may pass 86,400: [`julian_day`] carries the
    /// day over.)
    pub fn at(&self, now_s: f64) -> Celestial {
        let mut c = *self;
        if c.ephemeris && now_s.is_finite() && now_s > c.set_at_s {
            c.seconds_utc += now_s - c.set_at_s;
            c.set_at_s = now_s;
        }
        c
    }

    /// Julian day (UT) of the date and time, if the date is valid.
    pub fn julian_day(&self) -> Option<f64> {
        let (y, m, d) = self.date?;
        Some(julian_day_0h(y, m, d)? + self.seconds_utc / 86_400.0)
    }
}

/// What the host set with Atmosphere Control (packet 10).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Atmosphere {
    /// Atmospheric model enabled (weather beyond visibility is an IG choice).
    pub model_enabled: bool,
    /// Global humidity, percent.
    pub humidity_pct: f32,
    /// Air temperature, °C.
    pub air_temp_c: f32,
    /// Visibility range, metres (the renderer's haze distance).
    pub visibility_m: f32,
    /// Horizontal wind speed, m/s.
    pub horizontal_wind_m_s: f32,
    /// Vertical wind speed, m/s.
    pub vertical_wind_m_s: f32,
    /// Wind direction, degrees from true north (the direction it blows from).
    pub wind_direction_deg: f32,
    /// Barometric pressure, millibars.
    pub pressure_mb: f32,
}

/// The environment as the host set it: `None` until the first packet of each kind.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Environment {
    /// The last Celestial Sphere Control.
    pub celestial: Option<Celestial>,
    /// The last Atmosphere Control.
    pub atmosphere: Option<Atmosphere>,
}

impl Environment {
    /// Visibility range in metres, if the host set one (positive and finite).
    pub fn visibility_m(&self) -> Option<f64> {
        let v = f64::from(self.atmosphere?.visibility_m);
        (v.is_finite() && v > 0.0).then_some(v)
    }

    /// Unit vector towards the sun in the local east-north-up frame at (`lat_deg`, `lon_deg`)
    /// at IG time `now_s` (the ephemeris clock applied), if the host set a valid date.
    pub fn sun_direction_enu(&self, now_s: f64, lat_deg: f64, lon_deg: f64) -> Option<[f64; 3]> {
        sun_direction_enu(&self.celestial?.at(now_s), lat_deg, lon_deg)
    }
}

/// Julian day at 0 h UT of a Gregorian date (Meeus, *Astronomical Algorithms*, ch. 7); `None`
/// for a month or day out of range.
pub fn julian_day_0h(year: i32, month: u32, day: u32) -> Option<f64> {
    if !(1..=12).contains(&month) || !(1..=31).contains(&day) {
        return None;
    }
    let (y, m) = if month <= 2 {
        (f64::from(year) - 1.0, f64::from(month) + 12.0)
    } else {
        (f64::from(year), f64::from(month))
    };
    let a = (y / 100.0).floor();
    let b = 2.0 - a + (a / 4.0).floor();
    Some(
        (365.25 * (y + 4716.0)).floor() + (30.6001 * (m + 1.0)).floor() + f64::from(day) + b
            - 1524.5,
    )
}

/// The sun's apparent declination and the equation of time at Julian day `jd` (UT), by NOAA's
/// solar calculator (after Meeus): `(declination_deg, equation_of_time_minutes)`. Good to about
/// 0.01° for dates within a few centuries of 2000.
pub fn solar_declination_eot(jd: f64) -> (f64, f64) {
    let t = (jd - 2451545.0) / 36525.0;
    let l0 = (280.46646 + t * (36000.76983 + t * 0.0003032)).rem_euclid(360.0);
    let m = 357.52911 + t * (35999.05029 - 0.0001537 * t);
    let e = 0.016708634 - t * (0.000042037 + 0.0000001267 * t);
    let mr = m.to_radians();
    let center = mr.sin() * (1.914602 - t * (0.004817 + 0.000014 * t))
        + (2.0 * mr).sin() * (0.019993 - 0.000101 * t)
        + (3.0 * mr).sin() * 0.000289;
    let true_long = l0 + center;
    let omega = (125.04 - 1934.136 * t).to_radians();
    let apparent_long = (true_long - 0.00569 - 0.00478 * omega.sin()).to_radians();
    let mean_obliquity =
        23.0 + (26.0 + (21.448 - t * (46.815 + t * (0.00059 - t * 0.001813))) / 60.0) / 60.0;
    let obliquity = (mean_obliquity + 0.00256 * omega.cos()).to_radians();
    let declination = (obliquity.sin() * apparent_long.sin()).asin();
    let y = (obliquity / 2.0).tan().powi(2);
    let l0r = l0.to_radians();
    let eot = y * (2.0 * l0r).sin() - 2.0 * e * mr.sin()
        + 4.0 * e * y * mr.sin() * (2.0 * l0r).cos()
        - 0.5 * y * y * (4.0 * l0r).sin()
        - 1.25 * e * e * (2.0 * mr).sin();
    (declination.to_degrees(), 4.0 * eot.to_degrees())
}

/// Unit vector towards the sun's centre in the local east-north-up frame at (`lat_deg`,
/// `lon_deg`), for the celestial date and time (geometric: no atmospheric refraction, which
/// lifts the sun by about 0.5° on the horizon and under 0.02° above 45°). `None` without a
/// valid date or for non-finite input.
pub fn sun_direction_enu(celestial: &Celestial, lat_deg: f64, lon_deg: f64) -> Option<[f64; 3]> {
    sun_direction_enu_at(celestial.julian_day()?, lat_deg, lon_deg)
}

/// [`sun_direction_enu`] at Julian day `jd` (UT).
pub fn sun_direction_enu_at(jd: f64, lat_deg: f64, lon_deg: f64) -> Option<[f64; 3]> {
    if !(jd.is_finite() && lat_deg.is_finite() && lon_deg.is_finite()) {
        return None;
    }
    let (decl_deg, eot_min) = solar_declination_eot(jd);
    // Minutes after midnight UT from the Julian day itself, so a run-on ephemeris clock
    // carries into the next day on its own.
    let minutes_ut = (jd + 0.5).rem_euclid(1.0) * 1440.0;
    let true_solar_min = minutes_ut + eot_min + 4.0 * lon_deg;
    let hour_angle = (true_solar_min / 4.0 - 180.0).to_radians();
    let (sin_lat, cos_lat) = lat_deg.to_radians().sin_cos();
    let (sin_d, cos_d) = decl_deg.to_radians().sin_cos();
    let up = sin_lat * sin_d + cos_lat * cos_d * hour_angle.cos();
    let east = -cos_d * hour_angle.sin();
    let north = cos_lat * sin_d - sin_lat * cos_d * hour_angle.cos();
    let n = (east * east + north * north + up * up).sqrt();
    Some([east / n, north / n, up / n])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn celestial(date: (i32, u32, u32), h: u32, m: u32, s: f64) -> Celestial {
        Celestial {
            date: Some(date),
            seconds_utc: f64::from(h * 3600 + m * 60) + s,
            ephemeris: false,
            sun_enabled: true,
            moon_enabled: false,
            stars_enabled: false,
            star_intensity_pct: 0.0,
            set_at_s: 0.0,
        }
    }

    /// The angle between the computed direction and the one given by an azimuth (clockwise
    /// from north) and a zenith angle, degrees.
    fn off_by_deg(v: [f64; 3], azimuth_deg: f64, zenith_deg: f64) -> f64 {
        let (sa, ca) = azimuth_deg.to_radians().sin_cos();
        let (sz, cz) = zenith_deg.to_radians().sin_cos();
        let want = [sz * sa, sz * ca, cz];
        let dot: f64 = v.iter().zip(want).map(|(a, b)| a * b).sum();
        dot.clamp(-1.0, 1.0).acos().to_degrees()
    }

    #[test]
    fn julian_days_match_meeus() {
        // Meeus, example 7.a (1957 Oct 4.81) and the J2000 epoch.
        assert_eq!(julian_day_0h(2000, 1, 1), Some(2_451_544.5));
        let jd = julian_day_0h(1957, 10, 4).unwrap() + 0.81;
        assert!((jd - 2_436_116.31).abs() < 1e-9, "{jd}");
        assert_eq!(julian_day_0h(2000, 13, 1), None);
        assert_eq!(julian_day_0h(2000, 2, 0), None);
    }

    #[test]
    fn declination_matches_meeus_example_25a() {
        // Meeus example 25.a: 1992 October 13.0 TD, apparent declination −7°47'06" (the
        // ~1 min between TD and UT moves it by 0.0003°).
        let (decl, _) = solar_declination_eot(julian_day_0h(1992, 10, 13).unwrap());
        let want = -(7.0 + 47.0 / 60.0 + 6.0 / 3600.0);
        assert!((decl - want).abs() < 0.01, "{decl} vs {want}");
    }

    /// Published positions from NREL's Solar Position Algorithm (Reda & Andreas 2004, its
    /// worked example; and the reference table its `spa.c` generates, Δt = 0): azimuth
    /// clockwise from north and topocentric zenith with refraction, which at these zenith
    /// angles is under 0.03°.
    #[test]
    fn sun_directions_match_published_positions() {
        let cases = [
            // SPA paper example: 17 Oct 2003 12:30:30 at UTC−7, Golden, Colorado.
            (
                (2003, 10, 17),
                (19, 30, 30.0),
                39.742476,
                -105.1786,
                194.34024,
                50.11162,
            ),
            // Auckland, 15 Mar 2010 00:30 UTC (the sun in the north at local noon).
            (
                (2010, 3, 15),
                (0, 30, 0.0),
                -36.840556,
                174.74,
                0.047502,
                34.572436,
            ),
            // Brasília, 15 Dec 2010 12:30 UTC and 15 Jun 2010 12:30 UTC.
            (
                (2010, 12, 15),
                (12, 30, 0.0),
                -15.793889,
                -47.882778,
                107.808808,
                37.525486,
            ),
            (
                (2010, 6, 15),
                (12, 30, 0.0),
                -15.793889,
                -47.882778,
                46.250557,
                55.629466,
            ),
        ];
        for (date, (h, m, s), lat, lon, az, zen) in cases {
            let v = sun_direction_enu(&celestial(date, h, m, s), lat, lon).unwrap();
            let off = off_by_deg(v, az, zen);
            assert!(off < 0.1, "{date:?} {h}:{m}: {off}° off ({v:?})");
            let norm: f64 = v.iter().map(|x| x * x).sum();
            assert!((norm - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn ephemeris_runs_the_clock_and_crosses_midnight() {
        let mut c = celestial((2010, 12, 14), 23, 30, 0.0);
        c.set_at_s = 100.0;
        // Frozen without the ephemeris: an hour later the sun has not moved.
        assert_eq!(c.at(3700.0), c);
        c.ephemeris = true;
        // With it, an hour later is 00:30 on the 15th: the Auckland-style check on another
        // published row (15 Dec 2010 00:30 UTC, Auckland: azimuth 346.427128, zenith 13.924050).
        let later = c.at(3700.0);
        assert_eq!(later.seconds_utc, 24.5 * 3600.0);
        let v = sun_direction_enu(&later, -36.840556, 174.74).unwrap();
        let off = off_by_deg(v, 346.427128, 13.924050);
        assert!(off < 0.1, "{off}");
        // Going back in IG time never runs the clock backwards.
        assert_eq!(later.at(50.0), later);
        // No date, no sun.
        c.date = None;
        assert_eq!(sun_direction_enu(&c, 0.0, 0.0), None);
        let env = Environment {
            celestial: Some(c),
            atmosphere: None,
        };
        assert_eq!(env.sun_direction_enu(0.0, 0.0, 0.0), None);
        assert_eq!(env.visibility_m(), None);
    }

    #[test]
    fn visibility_only_when_positive() {
        let mut env = Environment {
            celestial: None,
            atmosphere: Some(Atmosphere {
                visibility_m: 12_000.0,
                ..Atmosphere::default()
            }),
        };
        assert_eq!(env.visibility_m(), Some(12_000.0));
        env.atmosphere.as_mut().unwrap().visibility_m = 0.0;
        assert_eq!(env.visibility_m(), None);
        env.atmosphere.as_mut().unwrap().visibility_m = f32::NAN;
        assert_eq!(env.visibility_m(), None);
    }
}
