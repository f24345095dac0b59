//! FlightGear `--native-fdm=socket,out,<hz>,<host>,<port>,udp`: the `FGNetFDM` struct of
//! FlightGear's `src/Network/net_fdm.hxx`, every field in network byte order (big-endian;
//! doubles byte-swapped as 8-byte units), angles in radians. Two versions are read:
//!
//! - **24** (release 2020.3 and earlier since 2013), 408 bytes;
//! - **25** (the `next` branch since October 2020, commit 4049acd8 "Bump the protocol
//!   version"), 552 bytes: after `fuel_quantity[4]` (offset 288) it adds `uint32_t
//!   tank_selected[4]` (304) and four `double[4]` (`capacity_m3` 320, `unusable_m3`,
//!   `density_kgpm3`, `level_m3`), moving the gear, environment and control surfaces from
//!   offset 304 to 448; it renames `v_wind_body_*` to `v_body_u/v/w`. Neither version has
//!   padding beyond the explicit `padding` word. (FlightGear's writer discards the `htonl` of
//!   `tank_selected`, so those four words go out in the sender's byte order; aerie skips them.)
//!
//! Both start with the same head, which is what aerie reads (the rest — engines, fuel, gear,
//! environment, control surfaces — is skipped; only its size is checked):
//!
//! | off | type | field |
//! |----:|------|-------|
//! | 0 | u32 | version = 24 or 25 |
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
//!
//! The whole field list of both versions, with the offsets a C compiler gives them, is in the
//! tests (`fgfs_tests.rs`), which build golden packets field by field from it.

use super::protocol::{validated, DecodeError, Protocol};
use super::wire::{ByteOrder, Rd, Wr};
use crate::pose::{Pose, PosePosition};

/// `FG_NET_FDM_VERSION` of release 2020.3 (and [`encode`]'s).
pub const VERSION: u32 = 24;
/// `sizeof(FGNetFDM)` for version 24.
pub const SIZE: usize = 408;
/// `FG_NET_FDM_VERSION` of the `next` branch (and [`encode_v25`]'s).
pub const VERSION_25: u32 = 25;
/// `sizeof(FGNetFDM)` for version 25.
pub const SIZE_25: usize = 552;
/// The versions read, with their struct sizes.
pub const VERSIONS: [(u32, usize); 2] = [(VERSION, SIZE), (VERSION_25, SIZE_25)];
/// Size of the head shared by every version (what aerie reads).
const HEAD_SIZE: usize = 88;
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

/// `sizeof(FGNetFDM)` for `version`, if it is one read here.
pub fn size_of_version(version: u32) -> Option<usize> {
    VERSIONS
        .iter()
        .find(|(v, _)| *v == version)
        .map(|(_, size)| *size)
}

/// Whether a datagram looks like an `FGNetFDM` (for detection): a known version in its first
/// four bytes, or exactly a known version's size (whatever its version says, so that a wrong
/// version is reported as such rather than as an unknown protocol).
pub fn looks_like(bytes: &[u8]) -> bool {
    VERSIONS
        .iter()
        .any(|&(v, size)| bytes.starts_with(&v.to_be_bytes()) || bytes.len() == size)
}

/// Encodes a version-24 `FGNetFDM` with the given head; everything after offset 88 is zero.
pub fn encode(f: &FdmPose) -> [u8; SIZE] {
    let mut out = [0u8; SIZE];
    out[..HEAD_SIZE].copy_from_slice(&head(VERSION, f));
    out
}

/// Encodes a version-25 `FGNetFDM` with the given head; everything after offset 88 is zero.
pub fn encode_v25(f: &FdmPose) -> [u8; SIZE_25] {
    let mut out = [0u8; SIZE_25];
    out[..HEAD_SIZE].copy_from_slice(&head(VERSION_25, f));
    out
}

/// The 88-byte head both versions share.
fn head(version: u32, f: &FdmPose) -> [u8; HEAD_SIZE] {
    let mut w = Wr::new(ByteOrder::Big, HEAD_SIZE);
    w.u32(version)
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
    let Some(size) = size_of_version(version) else {
        // The error carries one expected version: the nearest one read here.
        return Err(DecodeError::BadVersion {
            protocol: P,
            found: version,
            expected: if version < VERSION {
                VERSION
            } else {
                VERSION_25
            },
        });
    };
    if b.len() != size {
        return Err(DecodeError::BadSize {
            protocol: P,
            len: b.len(),
            expected: size,
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
#[path = "fgfs_tests.rs"]
mod tests;
