//! FlightGear `--native-fdm=socket,out,<hz>,<host>,<port>,udp`: the `FGNetFDM` struct, version 24
//! (FlightGear's `src/Network/net_fdm.hxx`), 408 bytes, every field in network byte order
//! (big-endian; doubles byte-swapped as 8-byte units), angles in radians.
//!
//! aerie reads the head of the struct; the rest (engines, fuel, gear, environment, control
//! surfaces) is skipped:
//!
//! | off | type | field |
//! |----:|------|-------|
//! | 0 | u32 | version = 24 |
//! | 4 | u32 | padding |
//! | 8 | f64 | longitude, rad |
//! | 16 | f64 | latitude, rad |
//! | 24 | f64 | altitude above sea level, m |
//! | 32 | f32 | agl, m |
//! | 36 | f32 | phi (roll), rad |
//! | 40 | f32 | theta (pitch), rad |
//! | 44 | f32 | psi (true heading), rad |
//! | 48 | f32 | alpha, rad |
//! | 52 | f32 | beta, rad |
//! | 56 | f32 | phidot (roll rate), rad/s |
//! | 60 | f32 | thetadot (pitch rate), rad/s |
//! | 64 | f32 | psidot (yaw rate), rad/s |
//! | 68 | f32 | vcas, knots |
//! | 72 | f32 | climb rate, ft/s |
//! | 76 | f32 | v_north, ft/s |
//! | 80 | f32 | v_east, ft/s |
//! | 84 | f32 | v_down, ft/s |
//! | 88.. | | body velocities, accelerations, stall, engines ×4, tanks ×4, wheels ×3, time, surfaces |
//! | 404 | 4 | trailing padding (struct aligned to 8) |

use super::protocol::{validated, DecodeError, Protocol};
use super::wire::{ByteOrder, Rd, Wr};
use crate::pose::{Pose, PosePosition};

/// `FG_NET_FDM_VERSION` read here.
pub const VERSION: u32 = 24;
/// `sizeof(FGNetFDM)` for version 24.
pub const SIZE: usize = 408;
/// Feet → metres.
pub const FOOT_M: f64 = 0.3048;

const P: Protocol = Protocol::Fgfs;

/// The pose-related head of an `FGNetFDM` struct, in wire units.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FdmPose {
    /// Longitude, radians.
    pub longitude: f64,
    /// Latitude, radians.
    pub latitude: f64,
    /// Altitude above sea level, metres.
    pub altitude: f64,
    /// Height above ground, metres.
    pub agl: f32,
    /// Roll, radians.
    pub phi: f32,
    /// Pitch, radians.
    pub theta: f32,
    /// True heading, radians.
    pub psi: f32,
    /// Angle of attack, radians.
    pub alpha: f32,
    /// Sideslip, radians.
    pub beta: f32,
    /// Roll rate, rad/s.
    pub phidot: f32,
    /// Pitch rate, rad/s.
    pub thetadot: f32,
    /// Heading rate, rad/s.
    pub psidot: f32,
    /// Calibrated airspeed, knots.
    pub vcas: f32,
    /// Climb rate, ft/s.
    pub climb_rate: f32,
    /// North velocity, ft/s.
    pub v_north: f32,
    /// East velocity, ft/s.
    pub v_east: f32,
    /// Down velocity, ft/s.
    pub v_down: f32,
}

impl FdmPose {
    /// The pose (FGNetFDM has no sim time or frame counter: both 0).
    pub fn to_pose(&self) -> Pose {
        Pose {
            position: PosePosition::Geodetic {
                lat_deg: self.latitude.to_degrees(),
                lon_deg: self.longitude.to_degrees(),
                alt_m: self.altitude,
            },
            attitude_deg: [self.psi, self.theta, self.phi].map(|a| f64::from(a).to_degrees()),
            sim_time_s: 0.0,
            frame: 0,
            velocity_enu: Some([
                f64::from(self.v_east) * FOOT_M,
                f64::from(self.v_north) * FOOT_M,
                -f64::from(self.v_down) * FOOT_M,
            ]),
            angular_rates_deg_s: Some(
                [self.psidot, self.thetadot, self.phidot].map(|a| f64::from(a).to_degrees()),
            ),
        }
    }

    /// The struct head FlightGear would send for `pose` (geodetic; a local pose gives 0/0/z).
    pub fn from_pose(pose: &Pose) -> Self {
        let (lat, lon, alt) = match pose.position {
            PosePosition::Geodetic {
                lat_deg,
                lon_deg,
                alt_m,
            } => (lat_deg, lon_deg, alt_m),
            PosePosition::LocalEnu { z, .. } => (0.0, 0.0, z),
        };
        let [h, p, r] = pose.attitude_deg.map(|a| a.to_radians() as f32);
        let [hd, pd, rd] = pose
            .angular_rates_deg_s
            .unwrap_or([0.0; 3])
            .map(|a| a.to_radians() as f32);
        let [ve, vn, vu] = pose
            .velocity_enu
            .unwrap_or([0.0; 3])
            .map(|v| (v / FOOT_M) as f32);
        Self {
            longitude: lon.to_radians(),
            latitude: lat.to_radians(),
            altitude: alt,
            phi: r,
            theta: p,
            psi: h,
            phidot: rd,
            thetadot: pd,
            psidot: hd,
            climb_rate: vu,
            v_north: vn,
            v_east: ve,
            v_down: -vu,
            ..Self::default()
        }
    }
}

/// Encodes a version-24 `FGNetFDM` with the given head; everything after offset 88 is zero.
pub fn encode(f: &FdmPose) -> [u8; SIZE] {
    let mut w = Wr::new(ByteOrder::Big, SIZE);
    w.u32(VERSION)
        .u32(0)
        .f64(f.longitude)
        .f64(f.latitude)
        .f64(f.altitude);
    for v in [
        f.agl,
        f.phi,
        f.theta,
        f.psi,
        f.alpha,
        f.beta,
        f.phidot,
        f.thetadot,
        f.psidot,
        f.vcas,
        f.climb_rate,
        f.v_north,
        f.v_east,
        f.v_down,
    ] {
        w.f32(v);
    }
    w.buf.resize(SIZE, 0);
    w.finish()
}

/// Decodes the head of an `FGNetFDM` without validating it.
pub fn decode_fields(b: &[u8]) -> Result<FdmPose, DecodeError> {
    let r = Rd::new(b, ByteOrder::Big);
    let Some(version) = r.u32(0) else {
        return Err(DecodeError::BadSize {
            protocol: P,
            len: b.len(),
            expected: SIZE,
        });
    };
    if version != VERSION {
        return Err(DecodeError::BadVersion {
            protocol: P,
            found: version,
            expected: VERSION,
        });
    }
    if b.len() != SIZE {
        return Err(DecodeError::BadSize {
            protocol: P,
            len: b.len(),
            expected: SIZE,
        });
    }
    let f = || -> Option<FdmPose> {
        Some(FdmPose {
            longitude: r.f64(8)?,
            latitude: r.f64(16)?,
            altitude: r.f64(24)?,
            agl: r.f32(32)?,
            phi: r.f32(36)?,
            theta: r.f32(40)?,
            psi: r.f32(44)?,
            alpha: r.f32(48)?,
            beta: r.f32(52)?,
            phidot: r.f32(56)?,
            thetadot: r.f32(60)?,
            psidot: r.f32(64)?,
            vcas: r.f32(68)?,
            climb_rate: r.f32(72)?,
            v_north: r.f32(76)?,
            v_east: r.f32(80)?,
            v_down: r.f32(84)?,
        })
    };
    f().ok_or_else(|| DecodeError::truncated(P))
}

/// Decodes and validates an `FGNetFDM` datagram.
pub fn decode(b: &[u8]) -> Result<Pose, DecodeError> {
    validated(P, decode_fields(b)?.to_pose())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::DropReason;

    /// The first 88 bytes of a golden FGNetFDM v24, written by hand from net_fdm.hxx, all
    /// big-endian: version 24, padding 0, longitude 0.25 rad (0x3FD0000000000000), latitude
    /// 0.75 rad (0x3FE8000000000000), altitude 1000.0 m (0x408F400000000000), agl 300.0
    /// (0x43960000), phi 0.125 (0x3E000000), theta −0.0625 (0xBD800000), psi 1.5 (0x3FC00000),
    /// alpha 0, beta 0, phidot 0.5 (0x3F000000), thetadot 0, psidot −0.25 (0xBE800000), vcas
    /// 250.0 (0x437A0000), climb 10.0 (0x41200000), v_north 100.0 (0x42C80000), v_east −50.0
    /// (0xC2480000), v_down −10.0 (0xC1200000).
    const HEAD: [u8; 88] = [
        0x00, 0x00, 0x00, 0x18, // 0: version 24
        0x00, 0x00, 0x00, 0x00, // 4: padding
        0x3F, 0xD0, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, // 8: longitude
        0x3F, 0xE8, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, // 16: latitude
        0x40, 0x8F, 0x40, 0x00, 0x00, 0x00, 0x00, 0x00, // 24: altitude
        0x43, 0x96, 0x00, 0x00, // 32: agl
        0x3E, 0x00, 0x00, 0x00, // 36: phi
        0xBD, 0x80, 0x00, 0x00, // 40: theta
        0x3F, 0xC0, 0x00, 0x00, // 44: psi
        0x00, 0x00, 0x00, 0x00, // 48: alpha
        0x00, 0x00, 0x00, 0x00, // 52: beta
        0x3F, 0x00, 0x00, 0x00, // 56: phidot
        0x00, 0x00, 0x00, 0x00, // 60: thetadot
        0xBE, 0x80, 0x00, 0x00, // 64: psidot
        0x43, 0x7A, 0x00, 0x00, // 68: vcas
        0x41, 0x20, 0x00, 0x00, // 72: climb rate
        0x42, 0xC8, 0x00, 0x00, // 76: v_north
        0xC2, 0x48, 0x00, 0x00, // 80: v_east
        0xC1, 0x20, 0x00, 0x00, // 84: v_down
    ];

    fn golden() -> Vec<u8> {
        let mut b = HEAD.to_vec();
        b.resize(SIZE, 0);
        b
    }

    #[test]
    fn struct_size_is_408() {
        // 8 (version, padding) + 3·8 + 6·4 (positions) + 10·4 (velocities) + 3·4 (accels)
        // + 2·4 (stall, slip) + 4 + 10·4·4 (engines) + 4 + 4·4 (tanks) + 4 + 4·3·4 (gear)
        // + 3·4 (time, warp, visibility) + 10·4 (surfaces) = 404, padded to 8 → 408.
        let fields: usize = 8 + 24 + 24 + 40 + 12 + 8 + 4 + 160 + 4 + 16 + 4 + 48 + 12 + 40;
        assert_eq!(fields, 404);
        assert_eq!(fields.div_ceil(8) * 8, SIZE);
    }

    #[test]
    fn golden_bytes() {
        let f = FdmPose {
            longitude: 0.25,
            latitude: 0.75,
            altitude: 1000.0,
            agl: 300.0,
            phi: 0.125,
            theta: -0.0625,
            psi: 1.5,
            phidot: 0.5,
            psidot: -0.25,
            vcas: 250.0,
            climb_rate: 10.0,
            v_north: 100.0,
            v_east: -50.0,
            v_down: -10.0,
            ..FdmPose::default()
        };
        assert_eq!(encode(&f).to_vec(), golden());
        assert_eq!(decode_fields(&golden()).unwrap(), f);
        let p = decode(&golden()).unwrap();
        let PosePosition::Geodetic {
            lat_deg,
            lon_deg,
            alt_m,
        } = p.position
        else {
            panic!("geodetic expected")
        };
        assert!((lat_deg - 42.971_834_634_8).abs() < 1e-9, "{lat_deg}");
        assert!((lon_deg - 14.323_944_878_3).abs() < 1e-9, "{lon_deg}");
        assert_eq!(alt_m, 1000.0);
        let want_att = [85.943_669_269_9, -3.580_986_219_6, 7.161_972_439_1];
        for (got, want) in p.attitude_deg.iter().zip(want_att) {
            assert!((got - want).abs() < 1e-9, "{:?}", p.attitude_deg);
        }
        // Heading, pitch, roll rates from psidot, thetadot, phidot.
        let rates = p.angular_rates_deg_s.unwrap();
        assert!((rates[0] + 14.323_944_878_3).abs() < 1e-9);
        assert_eq!(rates[1], 0.0);
        assert!((rates[2] - 28.647_889_756_5).abs() < 1e-9);
        // ft/s → m/s, down → up.
        assert_eq!(p.velocity_enu, Some([-15.24, 30.48, 3.048]));
    }

    #[test]
    fn bad_datagrams() {
        let r = |b: &[u8]| decode(b).unwrap_err().reason();
        assert_eq!(r(&golden()[..404]), DropReason::BadSize);
        assert_eq!(r(&golden()[..2]), DropReason::BadSize);
        let mut v25 = golden();
        v25[3] = 25;
        assert_eq!(r(&v25), DropReason::BadVersion);
        let mut b = golden();
        b[24..32].copy_from_slice(&(-50_000.0f64).to_be_bytes());
        assert_eq!(r(&b), DropReason::Implausible);
        let mut b = golden();
        b[44..48].copy_from_slice(&f32::NAN.to_be_bytes());
        assert_eq!(r(&b), DropReason::Invalid);
    }

    #[test]
    fn pose_round_trip_within_f32() {
        let p = decode(&golden()).unwrap();
        let q = decode(&encode(&FdmPose::from_pose(&p))).unwrap();
        assert_eq!(q.position, p.position);
        for i in 0..3 {
            assert!((q.attitude_deg[i] - p.attitude_deg[i]).abs() < 1e-4);
            assert!((q.velocity_enu.unwrap()[i] - p.velocity_enu.unwrap()[i]).abs() < 1e-4);
        }
    }
}
