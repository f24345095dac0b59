//! Packet IDs and sizes, the version and magic numbers, and the checks every packet shares.

use crate::codec::protocol::{DecodeError, Protocol};
use crate::codec::wire::ByteOrder;
use crate::pose::PoseError;

/// IG Control packet ID.
pub const IG_CONTROL_ID: u8 = 1;
/// IG Control size in bytes.
pub const IG_CONTROL_SIZE: u8 = 24;
/// Entity Control packet ID.
pub const ENTITY_CONTROL_ID: u8 = 2;
/// Entity Control size in bytes.
pub const ENTITY_CONTROL_SIZE: u8 = 48;
/// View Control packet ID.
pub const VIEW_CONTROL_ID: u8 = 16;
/// View Control size in bytes.
pub const VIEW_CONTROL_SIZE: u8 = 32;
/// View Definition packet ID.
pub const VIEW_DEFINITION_ID: u8 = 21;
/// View Definition size in bytes.
pub const VIEW_DEFINITION_SIZE: u8 = 32;
/// Start of Frame packet ID (IG → host).
pub const START_OF_FRAME_ID: u8 = 101;
/// Start of Frame size in bytes.
pub const START_OF_FRAME_SIZE: u8 = 24;
/// CIGI major version read here.
pub const MAJOR_VERSION: u8 = 3;
/// CIGI minor version written in Start of Frame (3.3).
pub const MINOR_VERSION: u8 = 3;
/// The byte-swap magic as written by the sender in its own byte order.
pub const BYTE_SWAP_MAGIC: u16 = 0x8000;
/// Entity ID of the ownship.
pub const OWNSHIP: u16 = 0;
/// At most this many distinct views are tracked; packets for further view IDs are ignored.
pub const MAX_VIEWS: usize = 64;
/// IG mode value "Operate".
pub const IG_MODE_OPERATE: u8 = 1;

pub(super) const P: Protocol = Protocol::Cigi;

pub(super) fn cut() -> DecodeError {
    DecodeError::truncated(P)
}

pub(super) fn finite32(field: &'static str, v: f32) -> Result<(), DecodeError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(DecodeError::Invalid {
            protocol: P,
            error: PoseError::NotFinite {
                field,
                value: v.into(),
            },
        })
    }
}

/// The byte order of a CIGI message from its byte-swap magic at offset 6: `80 00` is the magic
/// 0x8000 written big-endian, `00 80` little-endian (a receiver reading natively sees 0x0080
/// when it must swap).
pub(super) fn byte_order(b: &[u8]) -> Result<ByteOrder, DecodeError> {
    match b.get(6..8) {
        Some([0x80, 0x00]) => Ok(ByteOrder::Big),
        Some([0x00, 0x80]) => Ok(ByteOrder::Little),
        Some(other) => Err(DecodeError::malformed(
            P,
            format!(
                "byte-swap magic at offset 6 is {:02x} {:02x}, expected 80 00 or 00 80",
                other[0], other[1]
            ),
        )),
        None => Err(cut()),
    }
}
