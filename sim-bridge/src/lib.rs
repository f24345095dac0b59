//! Pose input for aerie: the aircraft pose a flight simulator sends each frame, how it gets
//! here (UDP, shared memory), how it is decoded and checked, and how the frame loop gets the
//! pose at its display time.
//!
//! ```text
//! UDP datagram ─► codec (aerie / CIGI / RPOS / FGNetFDM) ─► sequence check ─┐
//! shared memory ─► seqlock read ──────────────────────────────► validate ───┴► Ingest
//!   ─► triple buffer (lock-free) ─► PoseReader::pose_at(display time) ─► extrapolated pose
//! ```
//!
//! - [`udp::UdpReceiver`] / [`shm::ShmSource`]: transport threads; each returns a
//!   [`PoseReader`] for the frame loop.
//! - [`codec`]: the packet layouts (`sim-bridge/PROTOCOL.md`).
//! - [`timing`]: pure decisions (sequence acceptance, extrapolation, staleness).
//! - [`record`]: recordings of raw datagrams and their replay.
//! - [`script`] / [`send`]: scripted flights and the sending side (`aerie-send`).
//!
//! Everything is f64; degrees at the API boundary, radians inside.

pub mod codec;
pub mod fuzzing;
pub mod geodesy;
pub mod handoff;
pub mod ig;
pub mod ingest;
pub mod pose;
pub mod query;
pub mod record;
pub mod script;
pub mod send;
pub mod shm;
mod shm_layout;
pub mod stats;
pub mod timing;
pub mod udp;

pub use codec::{decode, detect, DecodeError, Decoded, Protocol, ProtocolChoice};
pub use geodesy::{
    ecef_to_geodetic, geodetic_to_ecef, Geodetic, LocalTangentPlane, WGS84_A, WGS84_B, WGS84_E2,
    WGS84_EP2, WGS84_F,
};
pub use ingest::{input_channel, Ingest, InputParams, PoseReader, PoseSample, Verdict};
pub use pose::{Pose, PoseError, PoseLimits, PosePosition};
pub use stats::{DropReason, StatsSnapshot};
pub use timing::{ExtrapolationParams, FramePose, Motion, StreamState};
pub use udp::{RposRequest, UdpConfig, UdpReceiver, DEFAULT_PORT};
