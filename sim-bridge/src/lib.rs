//! Pose input for aerie: the aircraft pose a flight simulator sends each frame, its validation,
//! and the WGS84 geodesy that places geodetic poses in the world's local East-North-Up frame.
//!
//! Transports (UDP, shared memory), packet codecs, extrapolation and record/replay build on
//! these types. Everything here is f64; degrees at the API boundary, radians inside.

pub mod geodesy;
pub mod pose;

pub use geodesy::{
    ecef_to_geodetic, geodetic_to_ecef, Geodetic, LocalTangentPlane, WGS84_A, WGS84_B, WGS84_E2,
    WGS84_EP2, WGS84_F,
};
pub use pose::{Pose, PoseError, PosePosition};
