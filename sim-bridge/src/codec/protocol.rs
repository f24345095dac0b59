//! The wire protocols, which of them a port accepts, and why a datagram was not decoded.

use crate::pose::{Pose, PoseError};
use crate::stats::DropReason;

/// A supported wire protocol.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Protocol {
    /// aerie native v1 (little-endian, CRC-32).
    Aerie,
    /// CIGI 3.0–3.3 (the IG side: host messages read, answers written in the host's version).
    Cigi,
    /// X-Plane `RPOS` position output.
    XPlane,
    /// FlightGear `--native-fdm` (FGNetFDM v24 and v25).
    Fgfs,
}

impl Protocol {
    /// Every protocol, in detection order.
    pub const ALL: [Protocol; 4] = [
        Protocol::Aerie,
        Protocol::Cigi,
        Protocol::XPlane,
        Protocol::Fgfs,
    ];

    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Protocol::Aerie => "aerie",
            Protocol::Cigi => "cigi",
            Protocol::XPlane => "xplane",
            Protocol::Fgfs => "fgfs",
        }
    }
}

impl std::fmt::Display for Protocol {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Which protocol(s) a port accepts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ProtocolChoice {
    /// Detect each datagram's protocol from its first bytes ([`detect`]).
    #[default]
    Auto,
    /// Accept only this protocol; anything else is dropped as unknown.
    Only(Protocol),
}

impl std::str::FromStr for ProtocolChoice {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(match s.to_ascii_lowercase().as_str() {
            "auto" => ProtocolChoice::Auto,
            "aerie" | "native" => ProtocolChoice::Only(Protocol::Aerie),
            "cigi" => ProtocolChoice::Only(Protocol::Cigi),
            "xplane" | "x-plane" | "rpos" => ProtocolChoice::Only(Protocol::XPlane),
            "fgfs" | "flightgear" => ProtocolChoice::Only(Protocol::Fgfs),
            other => {
                return Err(format!(
                    "unknown protocol `{other}` (expected auto, aerie, cigi, xplane or fgfs)"
                ))
            }
        })
    }
}

/// Why a datagram could not be decoded.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DecodeError {
    /// No protocol recognised the first bytes.
    #[error("not a known pose protocol ({len} bytes)")]
    Unknown {
        /// Datagram length.
        len: usize,
    },
    /// The configured protocol's magic is absent.
    #[error("{protocol}: wrong magic")]
    BadMagic {
        /// The protocol the datagram was decoded as.
        protocol: Protocol,
    },
    /// Wrong length for a fixed-size packet.
    #[error("{protocol}: {len} bytes, expected {expected}")]
    BadSize {
        /// The protocol the datagram was decoded as.
        protocol: Protocol,
        /// Datagram length.
        len: usize,
        /// The protocol's size.
        expected: usize,
    },
    /// Unsupported version number.
    #[error("{protocol}: version {found}, this decoder reads version {expected}")]
    BadVersion {
        /// The protocol the datagram was decoded as.
        protocol: Protocol,
        /// The version in the packet.
        found: u32,
        /// The version decoded here.
        expected: u32,
    },
    /// CRC-32 mismatch.
    #[error("{protocol}: CRC-32 {found:#010x} does not match the computed {computed:#010x}")]
    BadCrc {
        /// The protocol the datagram was decoded as.
        protocol: Protocol,
        /// CRC in the packet.
        found: u32,
        /// CRC of the received bytes.
        computed: u32,
    },
    /// Structurally broken.
    #[error("{protocol}: malformed: {what}")]
    Malformed {
        /// The protocol the datagram was decoded as.
        protocol: Protocol,
        /// What is wrong, with its byte offset where it applies.
        what: String,
    },
    /// A pose field is non-finite or out of range.
    #[error("{protocol}: {error}")]
    Invalid {
        /// The protocol the datagram was decoded as.
        protocol: Protocol,
        /// The offending field.
        error: PoseError,
    },
    /// Well formed but not supported.
    #[error("{protocol}: unsupported: {what}")]
    Unsupported {
        /// The protocol the datagram was decoded as.
        protocol: Protocol,
        /// What is not supported.
        what: &'static str,
    },
}

impl DecodeError {
    /// The counter this error is reported under.
    pub fn reason(&self) -> DropReason {
        match self {
            DecodeError::Unknown { .. } | DecodeError::BadMagic { .. } => DropReason::Unknown,
            DecodeError::BadSize { .. } => DropReason::BadSize,
            DecodeError::BadVersion { .. } => DropReason::BadVersion,
            DecodeError::BadCrc { .. } => DropReason::BadCrc,
            DecodeError::Malformed { .. } => DropReason::Malformed,
            DecodeError::Invalid { error, .. } => error.reason(),
            DecodeError::Unsupported { .. } => DropReason::Unsupported,
        }
    }

    pub(crate) fn malformed(protocol: Protocol, what: impl Into<String>) -> Self {
        DecodeError::Malformed {
            protocol,
            what: what.into(),
        }
    }

    /// "Packet ends early" for a read that ran past a size already checked (defensive).
    pub(crate) fn truncated(protocol: Protocol) -> Self {
        Self::malformed(protocol, "packet ends inside a field")
    }
}

/// Validates a decoded pose within the widest configurable limits ([`Pose::validate`]; the
/// input applies its configured world bound after), tagging an error with the protocol.
pub(crate) fn validated(protocol: Protocol, pose: Pose) -> Result<Pose, DecodeError> {
    pose.validate()
        .map(|()| pose)
        .map_err(|error| DecodeError::Invalid { protocol, error })
}
