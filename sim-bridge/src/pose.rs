//! The aircraft pose one simulator frame sends, and its validation.

use glam::DVec3;

use crate::geodesy::{Geodetic, LocalTangentPlane};

/// Lowest geodetic altitude a pose may have, metres (below the Dead Sea shore, with margin).
pub const MIN_ALT_M: f64 = -1000.0;
/// Highest geodetic altitude a pose may have, metres.
pub const MAX_ALT_M: f64 = 100_000.0;

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
}

impl PoseError {
    /// The dotted name of the offending field.
    pub fn field(&self) -> &'static str {
        match self {
            PoseError::NotFinite { field, .. } | PoseError::OutOfRange { field, .. } => field,
        }
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

    /// Checks that every value is finite, latitude is in [−90, 90], longitude in [−180, 360),
    /// geodetic altitude in [−1,000, 100,000] m and pitch in [−90, 90]. Returns the first problem
    /// found, naming its field.
    pub fn validate(&self) -> Result<(), PoseError> {
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
                in_range(
                    "position.alt_m",
                    alt_m,
                    (MIN_ALT_M..=MAX_ALT_M).contains(&alt_m),
                    "[-1000, 100000] m",
                )?;
            }
            PosePosition::LocalEnu { x, y, z } => {
                finite("position.x", x)?;
                finite("position.y", y)?;
                finite("position.z", z)?;
            }
        }
        let [heading, pitch, roll] = self.attitude_deg;
        finite("attitude_deg.heading", heading)?;
        in_range(
            "attitude_deg.pitch",
            pitch,
            (-90.0..=90.0).contains(&pitch),
            "[-90, 90]",
        )?;
        finite("attitude_deg.roll", roll)?;
        finite("sim_time_s", self.sim_time_s)?;
        if let Some([e, n, u]) = self.velocity_enu {
            finite("velocity_enu.east", e)?;
            finite("velocity_enu.north", n)?;
            finite("velocity_enu.up", u)?;
        }
        if let Some([h, p, r]) = self.angular_rates_deg_s {
            finite("angular_rates_deg_s.heading", h)?;
            finite("angular_rates_deg_s.pitch", p)?;
            finite("angular_rates_deg_s.roll", r)?;
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
        with_position(0.0, 0.0, -1000.0).validate().unwrap();
        with_position(0.0, 0.0, 100_000.0).validate().unwrap();
        expect_err(with_position(0.0, 0.0, -1000.5), "position.alt_m", false);
        expect_err(with_position(0.0, 0.0, 100_001.0), "position.alt_m", false);
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
}
