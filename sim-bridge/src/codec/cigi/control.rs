//! The two packets that open every message: IG Control (host → IG) and Start of Frame
//! (IG → host), per minor version.

use crate::codec::protocol::DecodeError;
use crate::codec::wire::{ByteOrder, Rd, Wr};

use super::format::*;
use super::version::CigiVersion;

/// IG mode (IG Control byte 4 bits 0–1, Start of Frame byte 5 bits 0–1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum IgMode {
    /// 0: Reset (in IG Control) / Standby (in Start of Frame).
    ResetOrStandby,
    /// 1: Operate.
    Operate,
    /// 2: Debug.
    Debug,
    /// 3: Offline Maintenance.
    OfflineMaintenance,
}

impl IgMode {
    /// The mode of the 2-bit field `bits` (upper bits ignored).
    pub fn from_bits(bits: u8) -> Self {
        match bits & 0x03 {
            0 => IgMode::ResetOrStandby,
            1 => IgMode::Operate,
            2 => IgMode::Debug,
            _ => IgMode::OfflineMaintenance,
        }
    }

    /// The 2-bit wire value.
    pub fn bits(self) -> u8 {
        match self {
            IgMode::ResetOrStandby => 0,
            IgMode::Operate => 1,
            IgMode::Debug => 2,
            IgMode::OfflineMaintenance => 3,
        }
    }
}

/// IG Control (packet 1). Layouts: CCL `CigiIGCtrlV3.cpp` (3.0/3.1, 16 bytes),
/// `CigiIGCtrlV3_2.cpp` (3.2, 24 bytes), `CigiIGCtrlV3_3.cpp` (3.3, 24 bytes):
///
/// | off | 3.0/3.1 | 3.2 | 3.3 |
/// |---:|---|---|---|
/// | 2 | major version 3 | same | same |
/// | 3 | database number (i8) | same | same |
/// | 4 | bits 0–1 IG mode, bit 2 timestamp valid | + bits 4–7 minor version | + bit 3 smoothing |
/// | 6 | byte-swap magic 0x8000 | same | same |
/// | 8 | host frame (u32) | same | same |
/// | 12 | timestamp, 10 µs ticks (u32) | same | same |
/// | 16 | — | last IG frame received (u32) | same |
/// | 20 | — | reserved | reserved |
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct IgControl {
    /// Database number (signed; 0 = no change).
    pub database: i8,
    /// IG mode (0 Reset/Standby, 1 Operate, 2 Debug, 3 Offline Maintenance); see [`IgMode`].
    pub ig_mode: u8,
    /// Timestamp field is valid.
    pub timestamp_valid: bool,
    /// Extrapolation/interpolation (smoothing) enable (3.3; false before).
    pub smoothing: bool,
    /// The minor-version nibble as written (upper nibble of byte 4; reserved, 0, in 3.0/3.1).
    /// The version the message is read in is [`CigiVersion::from_ig_control`]'s.
    pub minor_version: u8,
    /// Host frame counter.
    pub host_frame: u32,
    /// Host timestamp, 10 µs ticks.
    pub timestamp: u32,
    /// The last IG frame number the host received (3.2+; 0 in 3.0/3.1, which lack it).
    pub last_ig_frame: u32,
}

impl IgControl {
    /// The IG mode as an enum.
    pub fn mode(&self) -> IgMode {
        IgMode::from_bits(self.ig_mode)
    }

    /// Encodes the 24-byte (3.2/3.3) layout in `order`, with the minor-version nibble and the
    /// smoothing bit exactly as in `self` (host side; tests and the example sender).
    pub fn encode(&self, order: ByteOrder) -> [u8; IG_CONTROL_SIZE as usize] {
        let flags = ((self.minor_version & 0x0F) << 4)
            | (u8::from(self.smoothing) << 3)
            | (u8::from(self.timestamp_valid) << 2)
            | (self.ig_mode & 0x03);
        let mut w = Wr::new(order, IG_CONTROL_SIZE.into());
        self.head(&mut w, IG_CONTROL_SIZE, flags);
        w.u32(self.last_ig_frame).u32(0);
        w.finish()
    }

    /// Encodes the packet as a host of `version` writes it: 16 bytes for 3.0/3.1 (no minor
    /// version, last IG frame or smoothing), 24 for 3.2/3.3 with the version's minor nibble
    /// (smoothing only in 3.3).
    pub fn encode_as(&self, version: CigiVersion, order: ByteOrder) -> Vec<u8> {
        let size = version.ig_control_size();
        let mut flags = (u8::from(self.timestamp_valid) << 2) | (self.ig_mode & 0x03);
        if version.is_3_2_or_later() {
            flags |= version.minor() << 4;
        }
        if version.has_smoothing() {
            flags |= u8::from(self.smoothing) << 3;
        }
        let mut w = Wr::new(order, size.into());
        self.head(&mut w, size, flags);
        if version.is_3_2_or_later() {
            w.u32(self.last_ig_frame).u32(0);
        }
        w.buf
    }

    fn head(&self, w: &mut Wr, size: u8, flags: u8) {
        w.u8(IG_CONTROL_ID)
            .u8(size)
            .u8(MAJOR_VERSION)
            .u8(self.database as u8)
            .u8(flags)
            .u8(0)
            .u16(BYTE_SWAP_MAGIC)
            .u32(self.host_frame)
            .u32(self.timestamp);
    }

    /// Decodes an IG Control of `version`'s size (`b` is exactly the packet) in `order`.
    pub fn decode(b: &[u8], version: CigiVersion, order: ByteOrder) -> Result<Self, DecodeError> {
        let r = packet(b, IG_CONTROL_ID, version.ig_control_size(), order)?;
        Self::read(&r, version).ok_or_else(cut)
    }

    fn read(r: &Rd, version: CigiVersion) -> Option<Self> {
        let flags = r.u8(4)?;
        Some(Self {
            database: r.u8(3)? as i8,
            ig_mode: flags & 0x03,
            timestamp_valid: flags & 0x04 != 0,
            smoothing: version.has_smoothing() && flags & 0x08 != 0,
            minor_version: flags >> 4,
            host_frame: r.u32(8)?,
            timestamp: r.u32(12)?,
            last_ig_frame: if version.is_3_2_or_later() {
                r.u32(16)?
            } else {
                0
            },
        })
    }
}

/// Start of Frame (packet 101), IG → host. Layouts: CCL `CigiSOFV3.cpp` (3.0/3.1, 16 bytes),
/// `CigiSOFV3_2.cpp` (3.2/3.3, 24 bytes):
///
/// | off | 3.0/3.1 | 3.2/3.3 |
/// |---:|---|---|
/// | 2 | major version 3 | same |
/// | 3 | database number (i8; negative while loading) | same |
/// | 4 | IG status code | same |
/// | 5 | bits 0–1 IG mode, bit 2 timestamp valid, bit 3 earth model | + bits 4–7 minor version |
/// | 6 | byte-swap magic 0x8000 | same |
/// | 8 | IG frame (u32) | same |
/// | 12 | timestamp, 10 µs ticks (u32) | same |
/// | 16 | — | last host frame received (u32) |
/// | 20 | — | reserved |
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StartOfFrame {
    /// Database number loaded (negative while loading).
    pub database: i8,
    /// IG status code (0 = normal).
    pub ig_status: u8,
    /// IG mode (0 Standby, 1 Operate, 2 Debug, 3 Offline Maintenance); see [`IgMode`].
    pub ig_mode: u8,
    /// Timestamp field is valid.
    pub timestamp_valid: bool,
    /// Earth reference model (0 = WGS84).
    pub earth_reference_model: u8,
    /// IG frame counter.
    pub ig_frame: u32,
    /// IG timestamp, 10 µs ticks.
    pub timestamp: u32,
    /// The host frame this answers (the last host frame counter received; 3.2+, 0 when
    /// decoded from a 3.0/3.1 packet, which lacks it).
    pub last_host_frame: u32,
}

impl StartOfFrame {
    /// Encodes the packet in `version`'s layout (16 or 24 bytes) and `order`.
    pub fn encode(&self, version: CigiVersion, order: ByteOrder) -> Vec<u8> {
        let size = version.start_of_frame_size();
        let mut flags = ((self.earth_reference_model & 0x01) << 3)
            | (u8::from(self.timestamp_valid) << 2)
            | (self.ig_mode & 0x03);
        if version.is_3_2_or_later() {
            flags |= version.minor() << 4;
        }
        let mut w = Wr::new(order, size.into());
        w.u8(START_OF_FRAME_ID)
            .u8(size)
            .u8(MAJOR_VERSION)
            .u8(self.database as u8)
            .u8(self.ig_status)
            .u8(flags)
            .u16(BYTE_SWAP_MAGIC)
            .u32(self.ig_frame)
            .u32(self.timestamp);
        if version.is_3_2_or_later() {
            w.u32(self.last_host_frame).u32(0);
        }
        w.buf
    }

    /// Decodes a Start of Frame at the start of `b` (host side), of either size; returns it
    /// with the message's byte order.
    pub fn decode(b: &[u8]) -> Result<(Self, ByteOrder), DecodeError> {
        Self::decode_with_version(b).map(|(s, _, o)| (s, o))
    }

    /// As [`decode`](Self::decode), also returning the version its size and minor nibble say
    /// (16 bytes: 3.0; 24 bytes: nibble 3+ is 3.3, else 3.2).
    pub fn decode_with_version(b: &[u8]) -> Result<(Self, CigiVersion, ByteOrder), DecodeError> {
        let (Some(&id), Some(&size), Some(&flags)) = (b.first(), b.get(1), b.get(5)) else {
            return Err(DecodeError::malformed(P, "not a Start of Frame packet"));
        };
        let version = match (id, size) {
            (START_OF_FRAME_ID, START_OF_FRAME_SIZE_V3_0) => CigiVersion::V3_0,
            (START_OF_FRAME_ID, START_OF_FRAME_SIZE) if flags >> 4 >= 3 => CigiVersion::V3_3,
            (START_OF_FRAME_ID, START_OF_FRAME_SIZE) => CigiVersion::V3_2,
            _ => {
                return Err(DecodeError::malformed(
                    P,
                    format!("packet ID {id} size {size} is not a Start of Frame (101, 16 or 24)"),
                ))
            }
        };
        if b.len() < usize::from(size) {
            return Err(DecodeError::malformed(
                P,
                format!("Start of Frame of {size} bytes cut at {}", b.len()),
            ));
        }
        let order = byte_order(b)?;
        let r = Rd::new(&b[..usize::from(size)], order);
        let read = || -> Option<Self> {
            Some(Self {
                database: r.u8(3)? as i8,
                ig_status: r.u8(4)?,
                ig_mode: flags & 0x03,
                timestamp_valid: flags & 0x04 != 0,
                earth_reference_model: (flags >> 3) & 0x01,
                ig_frame: r.u32(8)?,
                timestamp: r.u32(12)?,
                last_host_frame: if version.is_3_2_or_later() {
                    r.u32(16)?
                } else {
                    0
                },
            })
        };
        Ok((read().ok_or_else(cut)?, version, order))
    }
}
