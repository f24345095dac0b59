//! The aircraft pose one simulator frame sends, and its validation.

use glam::DVec3;

use crate::geodesy::{Geodetic, LocalTangentPlane};
use crate::stats::DropReason;

/// Lowest geodetic altitude a pose may have, metres (below the deepest ocean floor).
pub const MIN_ALT_M: f64 = -12_000.0;
/// Highest geodetic altitude a pose may have, metres (low Earth orbit, with margin).
pub const MAX_ALT_M: f64 = 1_000_000.0;
/// Default bound on local ENU positions, metres (each axis within ±this).
pub const DEFAULT_WORLD_BOUND_M: f64 = 1.0e7;
/// Largest world bound a configuration may ask for, metres: the bound every decoder applies
/// before the configured one (f64 still resolves 0.1 µm out there).
pub const MAX_WORLD_BOUND_M: f64 = 1.0e9;
/// Fastest plausible velocity component, m/s (above orbital speed).
pub const MAX_SPEED_M_S: f64 = 10_000.0;
/// Fastest plausible heading/pitch/roll rate, degrees per second (ten turns a second).
pub const MAX_RATE_DEG_S: f64 = 3600.0;
/// Largest plausible heading or roll magnitude, degrees (two turns either way: senders may
/// send [0, 360), [−180, 180) or a slightly unwrapped angle, never more).
pub const MAX_ANGLE_DEG: f64 = 720.0;
/// Largest plausible simulation time magnitude, seconds (some senders use Unix time).
pub const MAX_SIM_TIME_S: f64 = 1.0e10;

/// Plausibility limits of an input: what a decoded pose may be before it is drawn. The
/// physical ranges are fixed; the world bound on local positions is configurable
/// (`[input] world_bound_m`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseLimits {
    /// Local ENU positions must have every axis within ±this, metres; in (0, [`MAX_WORLD_BOUND_M`]].
    pub world_bound_m: f64,
}

impl Default for PoseLimits {
    fn default() -> Self {
        Self {
            world_bound_m: DEFAULT_WORLD_BOUND_M,
        }
    }
}

impl PoseLimits {
    /// The widest limits any configuration may set: what every decoder checks.
    pub const CEILING: PoseLimits = PoseLimits {
        world_bound_m: MAX_WORLD_BOUND_M,
    };

    /// Limits with this world bound, or why it is not a usable bound.
    pub fn with_world_bound(world_bound_m: f64) -> Result<Self, String> {
        if world_bound_m.is_finite() && world_bound_m > 0.0 && world_bound_m <= MAX_WORLD_BOUND_M {
            Ok(Self { world_bound_m })
        } else {
            Err(format!(
                "world bound must be a number of metres in (0, {MAX_WORLD_BOUND_M:e}], got {world_bound_m}"
            ))
        }
    }
}

/// Where the aircraft is: WGS84 geodetic, or already in the world's local ENU frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PosePosition {
    /// WGS84 latitude/longitude in degrees and ellipsoidal height in metres.
    Geodetic {
        /// Latitude, degrees, in [−90, 90].
        lat_deg: f64,
        /// Longitude, degrees, in [−180, 360).
        lon_deg: f64,
        /// Height above the WGS84 ellipsoid, metres.
        alt_m: f64,
    },
    /// Metres in the world's local East-North-Up frame (z up).
    LocalEnu {
        /// East, metres.
        x: f64,
        /// North, metres.
        y: f64,
        /// Up, metres.
        z: f64,
    },
}

impl PosePosition {
    /// The three numbers the wire formats carry — (lat, lon, alt) or local (x, y, z) — and
    /// whether they are local ENU metres (the formats' "local" flag).
    pub fn wire(&self) -> ([f64; 3], bool) {
        match *self {
            PosePosition::Geodetic {
                lat_deg,
                lon_deg,
                alt_m,
            } => ([lat_deg, lon_deg, alt_m], false),
            PosePosition::LocalEnu { x, y, z } => ([x, y, z], true),
        }
    }

    /// The position in world ENU metres; geodetic positions go through `ltp`.
    pub fn to_enu(&self, ltp: &LocalTangentPlane) -> DVec3 {
        match *self {
            PosePosition::Geodetic {
                lat_deg,
                lon_deg,
                alt_m,
            } => ltp.geodetic_to_enu(Geodetic::new(lat_deg, lon_deg, alt_m)),
            PosePosition::LocalEnu { x, y, z } => DVec3::new(x, y, z),
        }
    }
}

/// One pose sample from the flight simulator, in wire units (degrees, metres, seconds).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Aircraft (eye reference) position.
    pub position: PosePosition,
    /// Heading (clockwise from north), pitch (nose up +), roll (right wing down +), degrees,
    /// applied in that order (aerospace Z-Y-X).
    pub attitude_deg: [f64; 3],
    /// Simulation time of this sample, seconds.
    pub sim_time_s: f64,
    /// Simulator frame number of this sample.
    pub frame: u64,
    /// Velocity in the local ENU frame, m/s, if the simulator sends it.
    pub velocity_enu: Option<[f64; 3]>,
    /// Rates of heading, pitch and roll (same order as `attitude_deg`), degrees per second,
    /// if the simulator sends them.
    pub angular_rates_deg_s: Option<[f64; 3]>,
}

/// Why a pose was rejected; every variant names the offending field.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PoseError {
    /// The field is NaN or infinite.
    #[error("pose field `{field}` is not finite ({value})")]
    NotFinite {
        /// Dotted field name, e.g. `attitude_deg.pitch`.
        field: &'static str,
        /// The offending value.
        value: f64,
    },
    /// The field is finite but outside its allowed range.
    #[error("pose field `{field}` = {value} is outside {range}")]
    OutOfRange {
        /// Dotted field name, e.g. `position.lat_deg`.
        field: &'static str,
        /// The offending value.
        value: f64,
        /// The allowed range in interval notation, e.g. `[-180, 360)`.
        range: &'static str,
    },
    /// The field is finite and well formed but physically implausible (a position beyond the
    /// world bound, a speed above orbital speed, …): an outlier, not drawn.
    #[error("pose field `{field}` = {value} is implausible (beyond ±{limit})")]
    Implausible {
        /// Dotted field name, e.g. `position.x`.
        field: &'static str,
        /// The offending value.
        value: f64,
        /// The plausibility limit on its magnitude.
        limit: f64,
    },
}

impl PoseError {
    /// The dotted name of the offending field.
    pub fn field(&self) -> &'static str {
        match self {
            PoseError::NotFinite { field, .. }
            | PoseError::OutOfRange { field, .. }
            | PoseError::Implausible { field, .. } => field,
        }
    }

    /// The counter this rejection is reported under: outliers are counted apart from
    /// malformed values.
    pub fn reason(&self) -> DropReason {
        match self {
            PoseError::Implausible { .. } => DropReason::Implausible,
            _ => DropReason::Invalid,
        }
    }
}

/// Finite, and within ±`limit`.
fn plausible(field: &'static str, value: f64, limit: f64) -> Result<(), PoseError> {
    finite(field, value)?;
    if value.abs() <= limit {
        Ok(())
    } else {
        Err(PoseError::Implausible {
            field,
            value,
            limit,
        })
    }
}

fn finite(field: &'static str, value: f64) -> Result<(), PoseError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(PoseError::NotFinite { field, value })
    }
}

fn in_range(
    field: &'static str,
    value: f64,
    ok: bool,
    range: &'static str,
) -> Result<(), PoseError> {
    finite(field, value)?;
    if ok {
        Ok(())
    } else {
        Err(PoseError::OutOfRange {
            field,
            value,
            range,
        })
    }
}

impl Pose {
    /// Attitude (heading, pitch, roll) in radians.
    pub fn attitude_rad(&self) -> DVec3 {
        DVec3::from_array(self.attitude_deg).map(f64::to_radians)
    }

    /// [`validate_within`](Self::validate_within) the widest configurable limits
    /// ([`PoseLimits::CEILING`]): what every decoder checks.
    pub fn validate(&self) -> Result<(), PoseError> {
        self.validate_within(&PoseLimits::CEILING)
    }

    /// Checks that every value is finite, latitude is in [−90, 90], longitude in [−180, 360),
    /// pitch in [−90, 90], and that the pose is plausible: geodetic altitude in
    /// [[`MIN_ALT_M`], [`MAX_ALT_M`]], local positions within ±`limits.world_bound_m`, heading
    /// and roll within ±[`MAX_ANGLE_DEG`], velocity components within ±[`MAX_SPEED_M_S`],
    /// rates within ±[`MAX_RATE_DEG_S`], sim time within ±[`MAX_SIM_TIME_S`]. Returns the first
    /// problem found, naming its field.
    pub fn validate_within(&self, limits: &PoseLimits) -> Result<(), PoseError> {
        match self.position {
            PosePosition::Geodetic {
                lat_deg,
                lon_deg,
                alt_m,
            } => {
                in_range(
                    "position.lat_deg",
                    lat_deg,
                    (-90.0..=90.0).contains(&lat_deg),
                    "[-90, 90]",
                )?;
                in_range(
                    "position.lon_deg",
                    lon_deg,
                    (-180.0..360.0).contains(&lon_deg),
                    "[-180, 360)",
                )?;
                finite("position.alt_m", alt_m)?;
                if !(MIN_ALT_M..=MAX_ALT_M).contains(&alt_m) {
                    return Err(PoseError::Implausible {
                        field: "position.alt_m",
                        value: alt_m,
                        limit: if alt_m < 0.0 { -MIN_ALT_M } else { MAX_ALT_M },
                    });
                }
            }
            PosePosition::LocalEnu { x, y, z } => {
                let b = limits.world_bound_m;
                plausible("position.x", x, b)?;
                plausible("position.y", y, b)?;
                plausible("position.z", z, b)?;
            }
        }
        let [heading, pitch, roll] = self.attitude_deg;
        plausible("attitude_deg.heading", heading, MAX_ANGLE_DEG)?;
        in_range(
            "attitude_deg.pitch",
            pitch,
            (-90.0..=90.0).contains(&pitch),
            "[-90, 90]",
        )?;
        plausible("attitude_deg.roll", roll, MAX_ANGLE_DEG)?;
        plausible("sim_time_s", self.sim_time_s, MAX_SIM_TIME_S)?;
        if let Some([e, n, u]) = self.velocity_enu {
            plausible("velocity_enu.east", e, MAX_SPEED_M_S)?;
            plausible("velocity_enu.north", n, MAX_SPEED_M_S)?;
            plausible("velocity_enu.up", u, MAX_SPEED_M_S)?;
        }
        if let Some([h, p, r]) = self.angular_rates_deg_s {
            plausible("angular_rates_deg_s.heading", h, MAX_RATE_DEG_S)?;
            plausible("angular_rates_deg_s.pitch", p, MAX_RATE_DEG_S)?;
            plausible("angular_rates_deg_s.roll", r, MAX_RATE_DEG_S)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn geodetic_pose() -> Pose {
        Pose {
            position: PosePosition::Geodetic {
                lat_deg: 47.25,
                lon_deg: 11.35,
                alt_m: 1500.0,
            },
            attitude_deg: [270.0, 5.0, -12.0],
            sim_time_s: 12.5,
            frame: 750,
            velocity_enu: Some([-120.0, 3.0, 1.5]),
            angular_rates_deg_s: Some([0.5, 0.0, -2.0]),
        }
    }

    fn enu_pose() -> Pose {
        Pose {
            position: PosePosition::LocalEnu {
                x: 1.0e7,
                y: -2.0,
                z: 300.0,
            },
            velocity_enu: None,
            angular_rates_deg_s: None,
            ..geodetic_pose()
        }
    }

    fn with_position(lat_deg: f64, lon_deg: f64, alt_m: f64) -> Pose {
        Pose {
            position: PosePosition::Geodetic {
                lat_deg,
                lon_deg,
                alt_m,
            },
            ..geodetic_pose()
        }
    }

    fn expect_err(pose: Pose, field: &str, not_finite: bool) {
        let err = pose.validate().expect_err("pose should be rejected");
        assert_eq!(err.field(), field, "{err}");
        assert!(err.to_string().contains(field), "{err}");
        assert_eq!(
            matches!(err, PoseError::NotFinite { .. }),
            not_finite,
            "{err:?}"
        );
    }

    #[test]
    fn valid_poses_pass() {
        geodetic_pose().validate().unwrap();
        enu_pose().validate().unwrap();
        for (lat, lon) in [(90.0, -180.0), (-90.0, 359.999), (0.0, 0.0), (0.0, 180.0)] {
            with_position(lat, lon, -400.0).validate().unwrap();
        }
        for pitch in [-90.0, 90.0] {
            let p = Pose {
                attitude_deg: [-720.0, pitch, 540.0],
                ..geodetic_pose()
            };
            p.validate().unwrap();
        }
    }

    #[test]
    fn latitude_out_of_range_is_rejected() {
        expect_err(
            with_position(90.000001, 0.0, 0.0),
            "position.lat_deg",
            false,
        );
        expect_err(with_position(-91.0, 0.0, 0.0), "position.lat_deg", false);
        expect_err(with_position(f64::NAN, 0.0, 0.0), "position.lat_deg", true);
    }

    #[test]
    fn longitude_range_is_half_open() {
        expect_err(with_position(0.0, 360.0, 0.0), "position.lon_deg", false);
        expect_err(
            with_position(0.0, -180.000001, 0.0),
            "position.lon_deg",
            false,
        );
        expect_err(
            with_position(0.0, f64::INFINITY, 0.0),
            "position.lon_deg",
            true,
        );
    }

    #[test]
    fn non_finite_altitude_is_rejected() {
        expect_err(
            with_position(0.0, 0.0, f64::NEG_INFINITY),
            "position.alt_m",
            true,
        );
    }

    #[test]
    fn altitude_out_of_range_is_rejected() {
        with_position(0.0, 0.0, MIN_ALT_M).validate().unwrap();
        with_position(0.0, 0.0, MAX_ALT_M).validate().unwrap();
        for alt in [MIN_ALT_M - 0.5, MAX_ALT_M + 1.0, 1.797e308, -1.797e308] {
            let e = with_position(0.0, 0.0, alt).validate().unwrap_err();
            assert_eq!(e.field(), "position.alt_m", "{e}");
            assert_eq!(e.reason(), DropReason::Implausible, "{e}");
        }
    }

    #[test]
    fn non_finite_local_position_is_rejected() {
        for (i, field) in ["position.x", "position.y", "position.z"]
            .into_iter()
            .enumerate()
        {
            let mut v = [0.0; 3];
            v[i] = f64::NAN;
            let p = Pose {
                position: PosePosition::LocalEnu {
                    x: v[0],
                    y: v[1],
                    z: v[2],
                },
                ..enu_pose()
            };
            expect_err(p, field, true);
        }
    }

    #[test]
    fn attitude_errors_name_the_angle() {
        let names = [
            "attitude_deg.heading",
            "attitude_deg.pitch",
            "attitude_deg.roll",
        ];
        for (i, field) in names.into_iter().enumerate() {
            let mut attitude_deg = [0.0; 3];
            attitude_deg[i] = f64::NAN;
            expect_err(
                Pose {
                    attitude_deg,
                    ..geodetic_pose()
                },
                field,
                true,
            );
        }
        for pitch in [90.5, -90.5] {
            expect_err(
                Pose {
                    attitude_deg: [0.0, pitch, 0.0],
                    ..geodetic_pose()
                },
                "attitude_deg.pitch",
                false,
            );
        }
    }

    #[test]
    fn non_finite_sim_time_is_rejected() {
        expect_err(
            Pose {
                sim_time_s: f64::INFINITY,
                ..geodetic_pose()
            },
            "sim_time_s",
            true,
        );
    }

    #[test]
    fn optional_vectors_are_checked_when_present() {
        let vel = ["velocity_enu.east", "velocity_enu.north", "velocity_enu.up"];
        let rates = [
            "angular_rates_deg_s.heading",
            "angular_rates_deg_s.pitch",
            "angular_rates_deg_s.roll",
        ];
        for i in 0..3 {
            let mut v = [1.0; 3];
            v[i] = f64::NAN;
            expect_err(
                Pose {
                    velocity_enu: Some(v),
                    ..geodetic_pose()
                },
                vel[i],
                true,
            );
            expect_err(
                Pose {
                    angular_rates_deg_s: Some(v),
                    ..geodetic_pose()
                },
                rates[i],
                true,
            );
        }
    }

    #[test]
    fn attitude_in_radians() {
        let r = Pose {
            attitude_deg: [180.0, -90.0, 45.0],
            ..geodetic_pose()
        }
        .attitude_rad();
        let expect = DVec3::new(
            std::f64::consts::PI,
            -std::f64::consts::FRAC_PI_2,
            std::f64::consts::FRAC_PI_4,
        );
        assert!((r - expect).abs().max_element() < 1e-15);
    }

    #[test]
    fn position_to_enu() {
        let ltp = LocalTangentPlane::new(Geodetic::new(47.25, 11.35, 1000.0));
        let enu = geodetic_pose().position.to_enu(&ltp);
        assert!(
            (enu - DVec3::new(0.0, 0.0, 500.0)).length() < 1e-6,
            "{enu:?}"
        );
        let local = enu_pose().position.to_enu(&ltp);
        assert_eq!(local, DVec3::new(1.0e7, -2.0, 300.0));
    }

    fn implausible(pose: Pose, limits: &PoseLimits, field: &str) {
        let e = pose.validate_within(limits).expect_err("outlier accepted");
        assert_eq!(e.field(), field, "{e}");
        assert!(matches!(e, PoseError::Implausible { .. }), "{e:?}");
        assert_eq!(e.reason(), DropReason::Implausible);
    }

    #[test]
    fn absurd_finite_values_are_implausible() {
        let l = PoseLimits::default();
        for v in [f64::MAX, -f64::MAX, 1.797e308, 1.8e7] {
            for (i, field) in ["position.x", "position.y", "position.z"]
                .iter()
                .enumerate()
            {
                let mut p = [0.0; 3];
                p[i] = v;
                let pose = Pose {
                    position: PosePosition::LocalEnu {
                        x: p[0],
                        y: p[1],
                        z: p[2],
                    },
                    ..enu_pose()
                };
                implausible(pose, &l, field);
            }
        }
        let big = f64::MAX;
        let base = geodetic_pose();
        implausible(
            Pose {
                attitude_deg: [big, 0.0, 0.0],
                ..base
            },
            &l,
            "attitude_deg.heading",
        );
        implausible(
            Pose {
                attitude_deg: [0.0, 0.0, -big],
                ..base
            },
            &l,
            "attitude_deg.roll",
        );
        implausible(
            Pose {
                velocity_enu: Some([0.0, big, 0.0]),
                ..base
            },
            &l,
            "velocity_enu.north",
        );
        implausible(
            Pose {
                angular_rates_deg_s: Some([0.0, 0.0, big]),
                ..base
            },
            &l,
            "angular_rates_deg_s.roll",
        );
        implausible(
            Pose {
                sim_time_s: big,
                ..base
            },
            &l,
            "sim_time_s",
        );
        // Fast but physical values pass.
        Pose {
            velocity_enu: Some([7_800.0, -300.0, 50.0]),
            angular_rates_deg_s: Some([720.0, -360.0, 1_000.0]),
            ..base
        }
        .validate_within(&l)
        .unwrap();
    }

    #[test]
    fn world_bound_is_configurable() {
        let far = Pose {
            position: PosePosition::LocalEnu {
                x: 5.0e7,
                y: 0.0,
                z: 0.0,
            },
            ..enu_pose()
        };
        implausible(far, &PoseLimits::default(), "position.x");
        let wide = PoseLimits::with_world_bound(1.0e8).unwrap();
        far.validate_within(&wide).unwrap();
        // What the decoders check is the widest configurable bound.
        far.validate().unwrap();
        implausible(
            far,
            &PoseLimits::with_world_bound(1.0e3).unwrap(),
            "position.x",
        );
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY, 2.0 * MAX_WORLD_BOUND_M] {
            assert!(PoseLimits::with_world_bound(bad).is_err(), "{bad}");
        }
    }
}
