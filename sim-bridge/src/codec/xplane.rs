//! X-Plane `RPOS` position output (X-Plane 10–12 "Exchanging Data with X-Plane"; sent when a
//! client asks with an `RPOS` request carrying a rate): 69 bytes, little-endian (X-Plane's native
//! order on x86/ARM hosts), longitude first.
//!
//! | off | type | field |
//! |----:|------|-------|
//! | 0 | char[4] + 1 | `"RPOS"` and one internal-use byte (ignored) |
//! | 5 | f64 | longitude, degrees |
//! | 13 | f64 | latitude, degrees |
//! | 21 | f64 | elevation above mean sea level, m |
//! | 29 | f32 | height above ground, m |
//! | 33 | f32 | pitch, degrees |
//! | 37 | f32 | true heading, degrees |
//! | 41 | f32 | roll, degrees |
//! | 45 | f32 | vx: east velocity, m/s (OpenGL x) |
//! | 49 | f32 | vy: up velocity, m/s (OpenGL y) |
//! | 53 | f32 | vz: south velocity, m/s (OpenGL z) |
//! | 57 | f32 | P: body roll rate, rad/s |
//! | 61 | f32 | Q: body pitch rate, rad/s |
//! | 65 | f32 | R: body yaw rate, rad/s |
//!
//! The body rates are turned into heading/pitch/roll (Euler) rates for extrapolation; near
//! ±90° pitch (where that is singular) the rates are dropped and the two-pose estimate is used.

use super::protocol::{validated, DecodeError, Protocol};
use super::wire::{ByteOrder, Rd, Wr};
use crate::pose::{Pose, PosePosition};

/// The first four bytes.
pub const HEADER: &[u8; 4] = b"RPOS";
/// Datagram size in bytes.
pub const SIZE: usize = 69;

const P: Protocol = Protocol::XPlane;

/// The fields of an `RPOS` datagram, in wire units.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rpos {
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Elevation above mean sea level, metres.
    pub ele_m: f64,
    /// Height above ground, metres.
    pub agl_m: f32,
    /// Pitch, degrees.
    pub pitch_deg: f32,
    /// True heading, degrees.
    pub heading_deg: f32,
    /// Roll, degrees.
    pub roll_deg: f32,
    /// East velocity, m/s.
    pub vx_east: f32,
    /// Up velocity, m/s.
    pub vy_up: f32,
    /// South velocity, m/s.
    pub vz_south: f32,
    /// Body roll rate, rad/s.
    pub p_rad_s: f32,
    /// Body pitch rate, rad/s.
    pub q_rad_s: f32,
    /// Body yaw rate, rad/s.
    pub r_rad_s: f32,
}

/// Body rates (p, q, r) → Euler rates (heading, pitch, roll) for attitude (θ pitch, φ roll),
/// all radians. `None` within 0.06° of ±90° pitch, where the conversion is singular.
pub fn body_to_euler_rates(p: f64, q: f64, r: f64, pitch: f64, roll: f64) -> Option<[f64; 3]> {
    let (sin_phi, cos_phi) = roll.sin_cos();
    let cos_theta = pitch.cos();
    if cos_theta.abs() < 1e-3 {
        return None;
    }
    let a = q * sin_phi + r * cos_phi;
    let heading_rate = a / cos_theta;
    let pitch_rate = q * cos_phi - r * sin_phi;
    let roll_rate = p + a * pitch.tan();
    Some([heading_rate, pitch_rate, roll_rate])
}

/// Euler rates (heading, pitch, roll) → body rates (p, q, r), radians; inverse of
/// [`body_to_euler_rates`].
pub fn euler_to_body_rates(rates: [f64; 3], pitch: f64, roll: f64) -> [f64; 3] {
    let [psi_dot, theta_dot, phi_dot] = rates;
    let (sin_phi, cos_phi) = roll.sin_cos();
    let (sin_theta, cos_theta) = pitch.sin_cos();
    [
        phi_dot - psi_dot * sin_theta,
        theta_dot * cos_phi + psi_dot * cos_theta * sin_phi,
        -theta_dot * sin_phi + psi_dot * cos_theta * cos_phi,
    ]
}

impl Rpos {
    /// The pose this datagram describes (no sim time or frame counter in `RPOS`: both 0).
    pub fn to_pose(&self) -> Pose {
        let euler = body_to_euler_rates(
            self.p_rad_s.into(),
            self.q_rad_s.into(),
            self.r_rad_s.into(),
            f64::from(self.pitch_deg).to_radians(),
            f64::from(self.roll_deg).to_radians(),
        );
        Pose {
            position: PosePosition::Geodetic {
                lat_deg: self.lat_deg,
                lon_deg: self.lon_deg,
                alt_m: self.ele_m,
            },
            attitude_deg: [
                self.heading_deg.into(),
                self.pitch_deg.into(),
                self.roll_deg.into(),
            ],
            sim_time_s: 0.0,
            frame: 0,
            velocity_enu: Some([
                self.vx_east.into(),
                -f64::from(self.vz_south),
                self.vy_up.into(),
            ]),
            angular_rates_deg_s: euler.map(|r| r.map(f64::to_degrees)),
        }
    }

    /// The datagram X-Plane would send for `pose` (geodetic; a local pose gives 0/0/z).
    pub fn from_pose(pose: &Pose, agl_m: f32) -> Self {
        let (lat_deg, lon_deg, ele_m) = match pose.position {
            PosePosition::Geodetic {
                lat_deg,
                lon_deg,
                alt_m,
            } => (lat_deg, lon_deg, alt_m),
            PosePosition::LocalEnu { z, .. } => (0.0, 0.0, z),
        };
        let [heading, pitch, roll] = pose.attitude_deg;
        let [ve, vn, vu] = pose.velocity_enu.unwrap_or([0.0; 3]);
        let [p, q, r] = euler_to_body_rates(
            pose.angular_rates_deg_s
                .unwrap_or([0.0; 3])
                .map(f64::to_radians),
            pitch.to_radians(),
            roll.to_radians(),
        );
        Self {
            lon_deg,
            lat_deg,
            ele_m,
            agl_m,
            pitch_deg: pitch as f32,
            heading_deg: heading as f32,
            roll_deg: roll as f32,
            vx_east: ve as f32,
            vy_up: vu as f32,
            vz_south: -vn as f32,
            p_rad_s: p as f32,
            q_rad_s: q as f32,
            r_rad_s: r as f32,
        }
    }
}

/// The request that makes X-Plane stream `RPOS` to the requesting socket: `"RPOS"`, a NUL,
/// the rate in positions per second as ASCII digits, a NUL (X-Plane's UDP reference; rate 0
/// stops the stream). X-Plane listens for it on its UDP port (49000 by default).
pub fn rpos_request(rate_hz: u32) -> Vec<u8> {
    let mut b = b"RPOS\0".to_vec();
    b.extend_from_slice(rate_hz.to_string().as_bytes());
    b.push(0);
    b
}

/// Encodes an `RPOS` datagram (header byte 4 is written as 0).
pub fn encode(r: &Rpos) -> [u8; SIZE] {
    let mut w = Wr::new(ByteOrder::Little, SIZE);
    w.raw(HEADER)
        .u8(0)
        .f64(r.lon_deg)
        .f64(r.lat_deg)
        .f64(r.ele_m);
    for v in [
        r.agl_m,
        r.pitch_deg,
        r.heading_deg,
        r.roll_deg,
        r.vx_east,
        r.vy_up,
        r.vz_south,
        r.p_rad_s,
        r.q_rad_s,
        r.r_rad_s,
    ] {
        w.f32(v);
    }
    w.finish()
}

/// Decodes the fields of an `RPOS` datagram without validating them.
pub fn decode_fields(b: &[u8]) -> Result<Rpos, DecodeError> {
    if !b.starts_with(HEADER) {
        return Err(DecodeError::BadMagic { protocol: P });
    }
    if b.len() != SIZE {
        return Err(DecodeError::BadSize {
            protocol: P,
            len: b.len(),
            expected: SIZE,
        });
    }
    let r = Rd::new(b, ByteOrder::Little);
    let f = || -> Option<Rpos> {
        Some(Rpos {
            lon_deg: r.f64(5)?,
            lat_deg: r.f64(13)?,
            ele_m: r.f64(21)?,
            agl_m: r.f32(29)?,
            pitch_deg: r.f32(33)?,
            heading_deg: r.f32(37)?,
            roll_deg: r.f32(41)?,
            vx_east: r.f32(45)?,
            vy_up: r.f32(49)?,
            vz_south: r.f32(53)?,
            p_rad_s: r.f32(57)?,
            q_rad_s: r.f32(61)?,
            r_rad_s: r.f32(65)?,
        })
    };
    f().ok_or_else(|| DecodeError::truncated(P))
}

/// Decodes and validates an `RPOS` datagram.
pub fn decode(b: &[u8]) -> Result<Pose, DecodeError> {
    validated(P, decode_fields(b)?.to_pose())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::DropReason;

    /// Golden `RPOS` datagram written by hand from the field table above: lon 11.0
    /// (0x4026000000000000), lat 45.0 (0x4046800000000000), elevation 1500.0
    /// (0x4097700000000000), agl 250.0 (0x437A0000), pitch 2.5 (0x40200000), heading 90.0
    /// (0x42B40000), roll −10.0 (0xC1200000), vx 100.0 (0x42C80000), vy −2.0 (0xC0000000),
    /// vz 20.0 (0x41A00000), P 0, Q 0, R 0.5 (0x3F000000); all little-endian.
    const GOLDEN: [u8; 69] = [
        b'R', b'P', b'O', b'S', 0x00, // 0: header
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x26, 0x40, // 5: longitude
        0x00, 0x00, 0x00, 0x00, 0x00, 0x80, 0x46, 0x40, // 13: latitude
        0x00, 0x00, 0x00, 0x00, 0x00, 0x70, 0x97, 0x40, // 21: elevation MSL
        0x00, 0x00, 0x7A, 0x43, // 29: agl
        0x00, 0x00, 0x20, 0x40, // 33: pitch
        0x00, 0x00, 0xB4, 0x42, // 37: heading
        0x00, 0x00, 0x20, 0xC1, // 41: roll
        0x00, 0x00, 0xC8, 0x42, // 45: vx (east)
        0x00, 0x00, 0x00, 0xC0, // 49: vy (up)
        0x00, 0x00, 0xA0, 0x41, // 53: vz (south)
        0x00, 0x00, 0x00, 0x00, // 57: P
        0x00, 0x00, 0x00, 0x00, // 61: Q
        0x00, 0x00, 0x00, 0x3F, // 65: R
    ];

    fn golden_fields() -> Rpos {
        Rpos {
            lon_deg: 11.0,
            lat_deg: 45.0,
            ele_m: 1500.0,
            agl_m: 250.0,
            pitch_deg: 2.5,
            heading_deg: 90.0,
            roll_deg: -10.0,
            vx_east: 100.0,
            vy_up: -2.0,
            vz_south: 20.0,
            p_rad_s: 0.0,
            q_rad_s: 0.0,
            r_rad_s: 0.5,
        }
    }

    #[test]
    fn golden_bytes() {
        assert_eq!(encode(&golden_fields()), GOLDEN);
        assert_eq!(decode_fields(&GOLDEN).unwrap(), golden_fields());
        let p = decode(&GOLDEN).unwrap();
        assert_eq!(
            p.position,
            PosePosition::Geodetic {
                lat_deg: 45.0,
                lon_deg: 11.0,
                alt_m: 1500.0
            }
        );
        assert_eq!(p.attitude_deg, [90.0, 2.5, -10.0]);
        // East 100, north = −south = −20, up −2.
        assert_eq!(p.velocity_enu, Some([100.0, -20.0, -2.0]));
        // Pure body yaw rate r with roll φ = −10°, pitch θ = 2.5°:
        // heading rate = r cos φ / cos θ, pitch rate = −r sin φ, roll rate = r cos φ tan θ.
        let (phi, theta, r) = ((-10.0f64).to_radians(), 2.5f64.to_radians(), 0.5f64);
        let want = [
            r * phi.cos() / theta.cos(),
            -r * phi.sin(),
            r * phi.cos() * theta.tan(),
        ]
        .map(f64::to_degrees);
        let got = p.angular_rates_deg_s.unwrap();
        for i in 0..3 {
            assert!((got[i] - want[i]).abs() < 1e-9, "{got:?} vs {want:?}");
        }
        // The fifth header byte is X-Plane's internal use: any value is accepted.
        let mut b = GOLDEN;
        b[4] = b'4';
        assert_eq!(decode(&b).unwrap(), p);
    }

    /// X-Plane sends P, Q, R in radians per second (see PROTOCOL.md for the evidence): a
    /// level standard-rate turn (3°/s) arrives as R = 0.05236 and must come out as a 3°/s
    /// heading rate — read as degrees it would be 0.052°/s, 57× too slow.
    #[test]
    fn rpos_body_rates_are_radians_per_second() {
        let mut f = golden_fields();
        (f.pitch_deg, f.roll_deg) = (0.0, 0.0);
        (f.p_rad_s, f.q_rad_s, f.r_rad_s) = (0.0, 0.0, 3f32.to_radians());
        let rates = decode(&encode(&f)).unwrap().angular_rates_deg_s.unwrap();
        assert!((rates[0] - 3.0).abs() < 1e-5, "{rates:?}");
        assert!(rates[1].abs() < 1e-9 && rates[2].abs() < 1e-9, "{rates:?}");
        // A roll rate of 10°/s likewise.
        (f.r_rad_s, f.p_rad_s) = (0.0, 10f32.to_radians());
        let rates = decode(&encode(&f)).unwrap().angular_rates_deg_s.unwrap();
        assert!((rates[2] - 10.0).abs() < 1e-5, "{rates:?}");
    }

    #[test]
    fn request_bytes() {
        assert_eq!(rpos_request(60), b"RPOS\x0060\x00");
        assert_eq!(rpos_request(0), b"RPOS\x000\x00");
    }

    #[test]
    fn rates_round_trip_through_body_axes() {
        let rates = [3.0f64, -1.5, 12.0].map(f64::to_radians);
        let (pitch, roll) = (20f64.to_radians(), -35f64.to_radians());
        let body = euler_to_body_rates(rates, pitch, roll);
        let back = body_to_euler_rates(body[0], body[1], body[2], pitch, roll).unwrap();
        for i in 0..3 {
            assert!((back[i] - rates[i]).abs() < 1e-12);
        }
        assert_eq!(
            body_to_euler_rates(1.0, 1.0, 1.0, 90f64.to_radians(), 0.0),
            None
        );
    }

    #[test]
    fn pose_round_trip_within_f32() {
        let pose = decode(&GOLDEN).unwrap();
        let again = decode(&encode(&Rpos::from_pose(&pose, 250.0))).unwrap();
        assert_eq!(again.position, pose.position);
        for (a, b) in again
            .angular_rates_deg_s
            .unwrap()
            .iter()
            .zip(pose.angular_rates_deg_s.unwrap())
        {
            assert!((a - b).abs() < 1e-4);
        }
    }

    #[test]
    fn bad_datagrams() {
        let r = |b: &[u8]| decode(b).unwrap_err().reason();
        assert_eq!(r(&GOLDEN[..68]), DropReason::BadSize);
        assert_eq!(r(&[GOLDEN.as_slice(), &[0]].concat()), DropReason::BadSize);
        assert_eq!(r(b"RREF"), DropReason::Unknown);
        let mut b = GOLDEN;
        b[13..21].copy_from_slice(&(-91.0f64).to_le_bytes());
        assert_eq!(r(&b), DropReason::Invalid);
        let mut b = GOLDEN;
        b[45..49].copy_from_slice(&f32::INFINITY.to_le_bytes());
        assert_eq!(r(&b), DropReason::Invalid);
    }
}
