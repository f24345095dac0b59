//! Packet IDs and sizes, the version and magic numbers, and the checks every packet shares.
//! IDs and sizes are the CCL's `CIGI_*_PACKET_ID_V3*` / `CIGI_*_PACKET_SIZE_V3*` defines
//! (`include/CigiBase*.h`); where a size differs between minor versions both are given.

use crate::codec::protocol::{DecodeError, Protocol};
use crate::codec::wire::{ByteOrder, Rd};
use crate::pose::PoseError;

/// IG Control packet ID.
pub const IG_CONTROL_ID: u8 = 1;
/// IG Control size in bytes, CIGI 3.2 and 3.3 (`CIGI_IG_CTRL_PACKET_SIZE_V3_2`).
pub const IG_CONTROL_SIZE: u8 = 24;
/// IG Control size in bytes, CIGI 3.0 and 3.1 (`CIGI_IG_CTRL_PACKET_SIZE_V3`).
pub const IG_CONTROL_SIZE_V3_0: u8 = 16;
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
/// Start of Frame size in bytes, CIGI 3.2 and 3.3 (`CIGI_SOF_PACKET_SIZE_V3_2`).
pub const START_OF_FRAME_SIZE: u8 = 24;
/// Start of Frame size in bytes, CIGI 3.0 and 3.1 (`CIGI_SOF_PACKET_SIZE_V3`).
pub const START_OF_FRAME_SIZE_V3_0: u8 = 16;
/// Conformal Clamped Entity Control packet ID.
pub const CONFORMAL_CLAMPED_ENTITY_CONTROL_ID: u8 = 3;
/// Conformal Clamped Entity Control size in bytes.
pub const CONFORMAL_CLAMPED_ENTITY_CONTROL_SIZE: u8 = 24;
/// Rate Control packet ID.
pub const RATE_CONTROL_ID: u8 = 8;
/// Rate Control size in bytes (3.0 through 3.3).
pub const RATE_CONTROL_SIZE: u8 = 32;
/// Celestial Sphere Control packet ID.
pub const CELESTIAL_SPHERE_CONTROL_ID: u8 = 9;
/// Celestial Sphere Control size in bytes.
pub const CELESTIAL_SPHERE_CONTROL_SIZE: u8 = 16;
/// Atmosphere Control packet ID.
pub const ATMOSPHERE_CONTROL_ID: u8 = 10;
/// Atmosphere Control size in bytes.
pub const ATMOSPHERE_CONTROL_SIZE: u8 = 32;
/// HAT/HOT Request packet ID.
pub const HAT_HOT_REQUEST_ID: u8 = 24;
/// HAT/HOT Request size in bytes (3.0 through 3.3).
pub const HAT_HOT_REQUEST_SIZE: u8 = 32;
/// Line of Sight Segment Request packet ID.
pub const LOS_SEGMENT_REQUEST_ID: u8 = 25;
/// Line of Sight Segment Request size in bytes (3.0 through 3.3).
pub const LOS_SEGMENT_REQUEST_SIZE: u8 = 64;
/// Line of Sight Vector Request packet ID.
pub const LOS_VECTOR_REQUEST_ID: u8 = 26;
/// Line of Sight Vector Request size in bytes (3.0 through 3.3).
pub const LOS_VECTOR_REQUEST_SIZE: u8 = 56;
/// HAT/HOT Response packet ID (IG → host).
pub const HAT_HOT_RESPONSE_ID: u8 = 102;
/// HAT/HOT Response size in bytes.
pub const HAT_HOT_RESPONSE_SIZE: u8 = 16;
/// HAT/HOT Extended Response packet ID (IG → host).
pub const HAT_HOT_EXTENDED_RESPONSE_ID: u8 = 103;
/// HAT/HOT Extended Response size in bytes.
pub const HAT_HOT_EXTENDED_RESPONSE_SIZE: u8 = 40;
/// Line of Sight Response packet ID (IG → host).
pub const LOS_RESPONSE_ID: u8 = 104;
/// Line of Sight Response size in bytes.
pub const LOS_RESPONSE_SIZE: u8 = 16;
/// Line of Sight Extended Response packet ID (IG → host).
pub const LOS_EXTENDED_RESPONSE_ID: u8 = 105;
/// Line of Sight Extended Response size in bytes.
pub const LOS_EXTENDED_RESPONSE_SIZE: u8 = 56;
/// CIGI major version read here.
pub const MAJOR_VERSION: u8 = 3;
/// The newest CIGI minor version aerie speaks (3.3); hosts of 3.0–3.2 are answered in theirs.
pub const MINOR_VERSION: u8 = 3;
/// The byte-swap magic as written by the sender in its own byte order.
pub const BYTE_SWAP_MAGIC: u16 = 0x8000;
/// Entity ID of the ownship.
pub const OWNSHIP: u16 = 0;
/// At most this many distinct views are tracked; packets for further view IDs are ignored.
pub const MAX_VIEWS: usize = 64;
/// IG mode value "Reset/Standby".
pub const IG_MODE_STANDBY: u8 = 0;
/// IG mode value "Operate".
pub const IG_MODE_OPERATE: u8 = 1;

pub(super) const P: Protocol = Protocol::Cigi;

pub(super) fn cut() -> DecodeError {
    DecodeError::truncated(P)
}

pub(super) fn finite32(field: &'static str, v: f32) -> Result<(), DecodeError> {
    finite64(field, v.into())
}

pub(super) fn finite64(field: &'static str, value: f64) -> Result<(), DecodeError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(DecodeError::Invalid {
            protocol: P,
            error: PoseError::NotFinite { field, value },
        })
    }
}

/// Finite and within `[lo, hi]` (`range` names the interval in the error).
pub(super) fn within(
    field: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    range: &'static str,
) -> Result<(), DecodeError> {
    finite64(field, value)?;
    if (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(DecodeError::Invalid {
            protocol: P,
            error: PoseError::OutOfRange {
                field,
                value,
                range,
            },
        })
    }
}

/// A latitude/longitude pair in range (both finite, −90…90 and −180…180).
pub(super) fn lat_lon(
    lat_field: &'static str,
    lat: f64,
    lon_field: &'static str,
    lon: f64,
) -> Result<(), DecodeError> {
    within(lat_field, lat, -90.0, 90.0, "[-90, 90]")?;
    within(lon_field, lon, -180.0, 180.0, "[-180, 180]")
}

/// A packet's bytes, checked to be exactly `size` long, as a reader in `order`.
pub(super) fn packet<'a>(
    b: &'a [u8],
    id: u8,
    size: u8,
    order: ByteOrder,
) -> Result<Rd<'a>, DecodeError> {
    match (b.first(), b.get(1)) {
        (Some(&i), Some(&s)) if i == id && s == size && b.len() == usize::from(size) => {
            Ok(Rd::new(b, order))
        }
        (Some(&i), Some(&s)) => Err(DecodeError::malformed(
            P,
            format!(
                "packet ID {i}, size byte {s}, {} bytes: expected packet {id} of {size} bytes",
                b.len()
            ),
        )),
        _ => Err(cut()),
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

/// Walks the packets of a message from byte `start` to the end, calling `f(id, offset,
/// packet)` for each with exactly its bytes. A header cut short, a size below 2 or a packet
/// running past the end stops the walk with the offset named.
pub(super) fn each_packet(
    b: &[u8],
    start: usize,
    mut f: impl FnMut(u8, usize, &[u8]) -> Result<(), DecodeError>,
) -> Result<(), DecodeError> {
    let mut off = start;
    while off < b.len() {
        let (id, size) = match b.get(off..off + 2) {
            Some(&[id, size]) => (id, usize::from(size)),
            _ => {
                return Err(DecodeError::malformed(
                    P,
                    format!("packet header cut at offset {off}"),
                ))
            }
        };
        if size < 2 {
            return Err(DecodeError::malformed(
                P,
                format!("packet {id} at offset {off} has size {size}"),
            ));
        }
        let Some(p) = b.get(off..off + size) else {
            return Err(DecodeError::malformed(
                P,
                format!(
                    "packet {id} at offset {off} (size {size}) runs past the end ({} bytes)",
                    b.len()
                ),
            ));
        };
        f(id, off, p)?;
        off += size;
    }
    Ok(())
}

/// A packet of a known ID whose size byte is not its size: the whole message is malformed
/// (its layout cannot be trusted), with the offset named.
pub(super) fn expect_size(id: u8, off: usize, p: &[u8], want: u8) -> Result<(), DecodeError> {
    if p.len() == usize::from(want) {
        Ok(())
    } else {
        Err(DecodeError::malformed(
            P,
            format!(
                "packet {id} at offset {off} has size {}, expected {want}",
                p.len()
            ),
        ))
    }
}
