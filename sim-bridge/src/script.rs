//! Scripted flights: timed waypoints (the `aerie fly --path` / `aerie-send --path` file) and
//! straight passes, sampled at any time with their derivative (the velocity and attitude rates
//! a simulator would send). One implementation shared by the renderer's `fly` and `aerie-send`.
//!
//! Waypoint file: one waypoint per line, `t_s,x_m,y_m,z_m,heading_deg,pitch_deg,roll_deg`
//! (local ENU metres, degrees); blank lines and `#` comments are ignored; times strictly
//! increase. Between waypoints everything is linear in time; the heading turns the shorter way
//! round. Before the first and after the last waypoint the pose is held (zero velocity).
//!
//! A file whose first line (after blank lines and comments) is `geo` holds geodetic waypoints
//! instead: `t_s,lat_deg,lon_deg,alt_m,heading_deg,pitch_deg,roll_deg` (WGS84 degrees, metres
//! in the data's vertical datum; heading from true north at the aircraft, pitch and roll
//! against its own horizon). Latitude and altitude are linear in time, longitude too along the
//! shorter way round (a path may cross ±180°); the position of a sample is then
//! `[lat, lon, alt]` with lon in [−180, 180), and its velocity in deg/s, deg/s, m/s.

/// One sample of a scripted flight: plain f64 arrays in local ENU metres and degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScriptSample {
    /// East, north, up, metres.
    pub position: [f64; 3],
    /// Heading in [0, 360), pitch, roll, degrees.
    pub attitude_deg: [f64; 3],
    /// d(position)/dt, m/s.
    pub velocity: [f64; 3],
    /// d(heading, pitch, roll)/dt, deg/s (heading along the shorter arc).
    pub rates_deg_s: [f64; 3],
}

/// Timed waypoints, linearly interpolated.
#[derive(Clone, Debug, PartialEq)]
pub struct Waypoints {
    /// `[t, x|lat, y|lon, z|alt, heading, pitch, roll]`; geodetic longitudes unwrapped (each
    /// within 180° of the one before) so that interpolation takes the shorter way.
    points: Vec<[f64; 7]>,
    frame: WaypointFrame,
}

/// What a waypoint file's positions are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WaypointFrame {
    /// Local ENU metres `x, y, z`.
    Local,
    /// WGS84 `lat, lon` (degrees) and altitude (metres): a file headed `geo`.
    Geodetic,
}

const GEO_FIELDS: [&str; 7] = [
    "t_s",
    "lat_deg",
    "lon_deg",
    "alt_m",
    "heading_deg",
    "pitch_deg",
    "roll_deg",
];

const FIELDS: [&str; 7] = [
    "t_s",
    "x_m",
    "y_m",
    "z_m",
    "heading_deg",
    "pitch_deg",
    "roll_deg",
];

impl Waypoints {
    /// Parses the text of a waypoint file; errors name `source:line` and the reason.
    pub fn parse(text: &str, source: &str) -> Result<Self, String> {
        let mut points: Vec<[f64; 7]> = Vec::new();
        let mut frame = None;
        for (n, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let at = |reason: String| format!("{source}:{}: {reason}", n + 1);
            let kind = match frame {
                Some(f) => f,
                None if line.eq_ignore_ascii_case("geo") => {
                    frame = Some(WaypointFrame::Geodetic);
                    continue;
                }
                None => *frame.insert(WaypointFrame::Local),
            };
            let fields = match kind {
                WaypointFrame::Local => FIELDS,
                WaypointFrame::Geodetic => GEO_FIELDS,
            };
            let parts: Vec<&str> = line.split(',').map(str::trim).collect();
            if parts.len() != 7 {
                return Err(at(format!(
                    "expected 7 values {} , got {}",
                    fields.join(","),
                    parts.len()
                )));
            }
            let mut p = [0.0; 7];
            for ((slot, text), name) in p.iter_mut().zip(&parts).zip(fields) {
                *slot = text
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| at(format!("{name} = {text:?} is not a finite number")))?;
            }
            if kind == WaypointFrame::Geodetic {
                if !(-90.0..=90.0).contains(&p[1]) {
                    return Err(at(format!("lat_deg = {} is outside [-90, 90]", p[1])));
                }
                if let Some(prev) = points.last() {
                    // Unwrapped: within 180° of the previous longitude.
                    p[2] = prev[2] + ((p[2] - prev[2] + 540.0).rem_euclid(360.0) - 180.0);
                }
            }
            if let Some(prev) = points.last() {
                if p[0] <= prev[0] {
                    return Err(at(format!(
                        "time {} s does not increase (previous {} s)",
                        p[0], prev[0]
                    )));
                }
            }
            points.push(p);
        }
        if points.is_empty() {
            return Err(format!("{source}: no waypoints"));
        }
        Ok(Self {
            points,
            frame: frame.unwrap_or(WaypointFrame::Local),
        })
    }

    /// Local metres or geodetic degrees (a file headed `geo`).
    pub fn frame(&self) -> WaypointFrame {
        self.frame
    }

    /// Time of the last waypoint, seconds.
    pub fn duration(&self) -> f64 {
        self.points.last().map(|p| p[0]).unwrap_or(0.0)
    }

    /// The waypoints as `[t, x, y, z, heading, pitch, roll]` rows (geodetic: `[t, lat, lon,
    /// alt, …]`, longitudes unwrapped).
    pub fn points(&self) -> &[[f64; 7]] {
        &self.points
    }

    /// The flight at time `t` (seconds on the file's clock). At a waypoint's time the
    /// derivative is the outgoing segment's (the one the flight is about to fly).
    pub fn sample(&self, t: f64) -> ScriptSample {
        let pts = &self.points;
        let k = pts.partition_point(|p| p[0] <= t);
        let (a, b) = match k {
            0 => (&pts[0], &pts[0]),
            k if k == pts.len() => (&pts[k - 1], &pts[k - 1]),
            k => (&pts[k - 1], &pts[k]),
        };
        let dt = b[0] - a[0];
        let s = if dt > 0.0 { (t - a[0]) / dt } else { 0.0 };
        // Derivatives are zero on the held ends (a == b).
        let rate = |d: f64| if dt > 0.0 { d / dt } else { 0.0 };
        let dh = (b[4] - a[4] + 540.0).rem_euclid(360.0) - 180.0;
        let lerp = |i: usize| a[i] + (b[i] - a[i]) * s;
        let second = match self.frame {
            WaypointFrame::Local => lerp(2),
            WaypointFrame::Geodetic => (lerp(2) + 180.0).rem_euclid(360.0) - 180.0,
        };
        ScriptSample {
            position: [lerp(1), second, lerp(3)],
            attitude_deg: [(a[4] + dh * s).rem_euclid(360.0), lerp(5), lerp(6)],
            velocity: [rate(b[1] - a[1]), rate(b[2] - a[2]), rate(b[3] - a[3])],
            rates_deg_s: [rate(dh), rate(b[5] - a[5]), rate(b[6] - a[6])],
        }
    }
}

/// A straight pass: constant attitude, moving horizontally along the heading at a constant
/// speed (pitch and roll are attitude only; the altitude stays), like `aerie fly`'s default
/// pass. Lasts forever; the sender decides how long.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Straight {
    /// Start position, ENU metres.
    pub start: [f64; 3],
    /// Heading, pitch, roll, degrees.
    pub attitude_deg: [f64; 3],
    /// Ground speed, m/s.
    pub speed_mps: f64,
}

impl Straight {
    /// Parses `x,y,z,heading,pitch,roll,speed_mps`; errors name the field.
    pub fn parse(s: &str) -> Result<Self, String> {
        const NAMES: [&str; 7] = ["x", "y", "z", "heading", "pitch", "roll", "speed_mps"];
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        if parts.len() != 7 {
            return Err(format!(
                "expected 7 values {}, got {}",
                NAMES.join(","),
                parts.len()
            ));
        }
        let mut v = [0.0; 7];
        for ((slot, text), name) in v.iter_mut().zip(&parts).zip(NAMES) {
            *slot = text
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("{name} = {text:?} is not a finite number"))?;
        }
        if !(-90.0..=90.0).contains(&v[4]) {
            return Err(format!("pitch = {} is outside [-90, 90]", v[4]));
        }
        Ok(Self {
            start: [v[0], v[1], v[2]],
            attitude_deg: [v[3].rem_euclid(360.0), v[4], v[5]],
            speed_mps: v[6],
        })
    }

    /// The pass at time `t`.
    pub fn sample(&self, t: f64) -> ScriptSample {
        let h = self.attitude_deg[0].to_radians();
        let v = [h.sin() * self.speed_mps, h.cos() * self.speed_mps, 0.0];
        ScriptSample {
            position: [
                self.start[0] + v[0] * t,
                self.start[1] + v[1] * t,
                self.start[2],
            ],
            attitude_deg: self.attitude_deg,
            velocity: v,
            rates_deg_s: [0.0; 3],
        }
    }
}

/// Either kind of scripted flight.
#[derive(Clone, Debug, PartialEq)]
pub enum Script {
    /// Timed waypoints.
    Waypoints(Waypoints),
    /// A straight pass.
    Straight(Straight),
}

impl Script {
    /// The natural duration: the last waypoint's time; `None` for a straight pass.
    pub fn duration(&self) -> Option<f64> {
        match self {
            Script::Waypoints(w) => Some(w.duration()),
            Script::Straight(_) => None,
        }
    }

    /// The flight at time `t`.
    pub fn sample(&self, t: f64) -> ScriptSample {
        match self {
            Script::Waypoints(w) => w.sample(t),
            Script::Straight(s) => s.sample(t),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9)
    }

    #[test]
    fn interpolates_with_derivative_and_short_heading_arc() {
        let w = Waypoints::parse(
            "# t,x,y,z,h,p,r\n0,0,0,100,350,0,0\n\n10,1000,0,200,10,-10,20 # turn\n",
            "f.csv",
        )
        .unwrap();
        let s = w.sample(5.0);
        assert!(close(s.position, [500.0, 0.0, 150.0]));
        assert!(s.attitude_deg[0].abs() < 1e-9 || (s.attitude_deg[0] - 360.0).abs() < 1e-9);
        assert!((s.attitude_deg[1] + 5.0).abs() < 1e-9 && (s.attitude_deg[2] - 10.0).abs() < 1e-9);
        assert!(close(s.velocity, [100.0, 0.0, 10.0]), "{:?}", s.velocity);
        // 350° → 10° is +20° over 10 s, not −340°.
        assert!(
            close(s.rates_deg_s, [2.0, -1.0, 2.0]),
            "{:?}",
            s.rates_deg_s
        );
        // Held (and still) outside the waypoints.
        assert!(close(w.sample(-1.0).position, [0.0, 0.0, 100.0]));
        assert!(close(w.sample(99.0).position, [1000.0, 0.0, 200.0]));
        assert_eq!(w.sample(99.0).velocity, [0.0; 3]);
        assert_eq!(w.duration(), 10.0);
    }

    #[test]
    fn derivative_matches_finite_differences() {
        let w = Waypoints::parse(
            "0,0,0,0,10,0,0\n2,40,-20,6,300,4,-8\n5,40,70,0,20,0,0\n",
            "p",
        )
        .unwrap();
        for t in [0.3, 1.7, 2.5, 4.9] {
            let (a, b) = (w.sample(t - 1e-4), w.sample(t + 1e-4));
            let s = w.sample(t);
            for i in 0..3 {
                let dv = (b.position[i] - a.position[i]) / 2e-4;
                assert!((dv - s.velocity[i]).abs() < 1e-6, "t {t} axis {i}");
                let mut da = b.attitude_deg[i] - a.attitude_deg[i];
                da = (da + 540.0).rem_euclid(360.0) - 180.0;
                assert!(
                    (da / 2e-4 - s.rates_deg_s[i]).abs() < 1e-6,
                    "t {t} angle {i}"
                );
            }
        }
    }

    #[test]
    fn errors_name_the_line_and_reason() {
        let e = Waypoints::parse("0,0,0,0,0,0,0\n1,2,3\n", "p.csv").unwrap_err();
        assert!(e.starts_with("p.csv:2:") && e.contains("expected 7"), "{e}");
        let e = Waypoints::parse("0,0,0,0,0,0,0\n0,0,0,0,0,0,0\n", "p.csv").unwrap_err();
        assert!(
            e.contains("p.csv:2:") && e.contains("does not increase"),
            "{e}"
        );
        let e = Waypoints::parse("0,0,nan,0,0,0,0\n", "p.csv").unwrap_err();
        assert!(e.contains("y_m"), "{e}");
        assert!(Waypoints::parse("# nothing\n", "p.csv")
            .unwrap_err()
            .contains("no waypoints"));
    }

    #[test]
    fn a_geo_file_interpolates_degrees_and_crosses_the_antimeridian_the_short_way() {
        let w = Waypoints::parse(
            "# over the date line\n\ngeo\n0,10,179.5,1000,90,0,0\n10,11,-179.5,2000,90,0,0\n",
            "g.csv",
        )
        .unwrap();
        assert_eq!(w.frame(), WaypointFrame::Geodetic);
        let s = w.sample(5.0);
        assert!(
            close(s.position, [10.5, -180.0, 1500.0]),
            "{:?}",
            s.position
        );
        let s = w.sample(7.5);
        assert!(
            close(s.position, [10.75, -179.75, 1750.0]),
            "{:?}",
            s.position
        );
        assert!(close(s.velocity, [0.1, 0.1, 100.0]), "{:?}", s.velocity);
        let local = Waypoints::parse("0,10,179.5,1000,90,0,0\n", "l.csv").unwrap();
        assert_eq!(local.frame(), WaypointFrame::Local);
        let e = Waypoints::parse("geo\n0,91,0,0,0,0,0\n", "g.csv").unwrap_err();
        assert!(e.starts_with("g.csv:2:") && e.contains("lat_deg"), "{e}");
        let e = Waypoints::parse("geo\n0,1,x,0,0,0,0\n", "g.csv").unwrap_err();
        assert!(e.contains("lon_deg"), "{e}");
        // `geo` is a header: anywhere else it is a bad waypoint line.
        let e = Waypoints::parse("0,0,0,0,0,0,0\ngeo\n", "g.csv").unwrap_err();
        assert!(e.starts_with("g.csv:2:"), "{e}");
        assert!(Waypoints::parse("geo\n", "g.csv")
            .unwrap_err()
            .contains("no waypoints"));
    }

    #[test]
    fn straight_pass_moves_along_heading_and_parses() {
        let s = Straight::parse("100,200,1500,90,-5,0,50").unwrap();
        let a = s.sample(2.0);
        assert!(
            close(a.position, [200.0, 200.0, 1500.0]),
            "{:?}",
            a.position
        );
        assert!(close(a.velocity, [50.0, 0.0, 0.0]));
        assert_eq!(a.attitude_deg, [90.0, -5.0, 0.0]);
        assert!(Straight::parse("1,2,3").unwrap_err().contains("expected 7"));
        assert!(Straight::parse("1,2,3,0,0,0,x")
            .unwrap_err()
            .contains("speed_mps"));
        assert!(Straight::parse("1,2,3,0,95,0,1")
            .unwrap_err()
            .contains("pitch"));
        assert_eq!(Script::Straight(s).duration(), None);
    }
}
