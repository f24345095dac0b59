//! IG → host answers: HAT/HOT Response (102), HAT/HOT Extended Response (103), Line of Sight
//! Response (104) and Line of Sight Extended Response (105), per minor version (3.2 put the
//! host frame's four low bits into byte 4's upper nibble). Decoders are for hosts and tests.

use crate::codec::protocol::DecodeError;
use crate::codec::wire::{ByteOrder, Wr};

use super::format::*;
use super::requests::CoordinateSystem;
use super::version::CigiVersion;

/// Which height a HAT/HOT Response (102) carries (byte 4 bit 1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum HatHotResponseType {
    /// 0: height above terrain.
    #[default]
    Hat,
    /// 1: height of terrain.
    Hot,
}

/// The host frame's low nibble in byte 4 bits 4–7, 3.2+ only.
fn lsn_bits(version: CigiVersion, lsn: u8) -> u8 {
    if version.is_3_2_or_later() {
        (lsn & 0x0F) << 4
    } else {
        0
    }
}

fn lsn_of(version: CigiVersion, b4: u8) -> u8 {
    if version.is_3_2_or_later() {
        b4 >> 4
    } else {
        0
    }
}

/// HAT/HOT Response (packet 102, 16 bytes). Layout: CCL `CigiHatHotRespV3.cpp` (3.0/3.1) and
/// `CigiHatHotRespV3_2.cpp` (3.2/3.3): 2 HAT/HOT ID (u16); 4 bit 0 valid, bit 1 response
/// type, bits 4–7 host frame number LSN (3.2+); 8 height (f64, m; 0 when invalid).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HatHotResponse {
    /// The request's HAT/HOT ID.
    pub request_id: u16,
    /// The height is valid (false: no terrain there, or not answerable).
    pub valid: bool,
    /// HAT or HOT.
    pub response_type: HatHotResponseType,
    /// The four low bits of the host frame the answer was computed for (3.2+; 0 before).
    pub host_frame_lsn: u8,
    /// Height above terrain or height of terrain, metres.
    pub height_m: f64,
}

impl HatHotResponse {
    /// Encodes the packet in `version`'s layout and `order`.
    pub fn encode(
        &self,
        version: CigiVersion,
        order: ByteOrder,
    ) -> [u8; HAT_HOT_RESPONSE_SIZE as usize] {
        let b4 = u8::from(self.valid)
            | (u8::from(self.response_type == HatHotResponseType::Hot) << 1)
            | lsn_bits(version, self.host_frame_lsn);
        let mut w = Wr::new(order, HAT_HOT_RESPONSE_SIZE.into());
        w.u8(HAT_HOT_RESPONSE_ID)
            .u8(HAT_HOT_RESPONSE_SIZE)
            .u16(self.request_id)
            .u8(b4)
            .u8(0)
            .u16(0)
            .f64(self.height_m);
        w.finish()
    }

    /// Decodes the packet (`b` is exactly its 16 bytes).
    pub fn decode(b: &[u8], version: CigiVersion, order: ByteOrder) -> Result<Self, DecodeError> {
        let r = packet(b, HAT_HOT_RESPONSE_ID, HAT_HOT_RESPONSE_SIZE, order)?;
        let read = || -> Option<Self> {
            let b4 = r.u8(4)?;
            Some(Self {
                request_id: r.u16(2)?,
                valid: b4 & 0x01 != 0,
                response_type: if b4 & 0x02 != 0 {
                    HatHotResponseType::Hot
                } else {
                    HatHotResponseType::Hat
                },
                host_frame_lsn: lsn_of(version, b4),
                height_m: r.f64(8)?,
            })
        };
        read().ok_or_else(cut)
    }
}

/// HAT/HOT Extended Response (packet 103, 40 bytes). Layout: CCL `CigiHatHotXRespV3.cpp`
/// (3.0/3.1) and `CigiHatHotXRespV3_2.cpp` (3.2/3.3): 2 HAT/HOT ID (u16); 4 bit 0 valid,
/// bits 4–7 host frame number LSN (3.2+); 8 HAT (f64, m); 16 HOT (f64, m); 24 material code
/// (u32); 28 normal vector azimuth (f32, °, −180…180); 32 normal vector elevation (f32, °,
/// −90…90); 36 reserved.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HatHotExtendedResponse {
    /// The request's HAT/HOT ID.
    pub request_id: u16,
    /// The heights are valid.
    pub valid: bool,
    /// The four low bits of the host frame the answer was computed for (3.2+; 0 before).
    pub host_frame_lsn: u8,
    /// Height above terrain, metres.
    pub hat_m: f64,
    /// Height of terrain, metres.
    pub hot_m: f64,
    /// Material code of the surface (0 until land cover exists).
    pub material_code: u32,
    /// Surface normal azimuth, degrees clockwise from north.
    pub normal_azimuth_deg: f32,
    /// Surface normal elevation, degrees up from the horizontal (90 = level ground).
    pub normal_elevation_deg: f32,
}

impl HatHotExtendedResponse {
    /// Encodes the packet in `version`'s layout and `order`.
    pub fn encode(
        &self,
        version: CigiVersion,
        order: ByteOrder,
    ) -> [u8; HAT_HOT_EXTENDED_RESPONSE_SIZE as usize] {
        let b4 = u8::from(self.valid) | lsn_bits(version, self.host_frame_lsn);
        let mut w = Wr::new(order, HAT_HOT_EXTENDED_RESPONSE_SIZE.into());
        w.u8(HAT_HOT_EXTENDED_RESPONSE_ID)
            .u8(HAT_HOT_EXTENDED_RESPONSE_SIZE)
            .u16(self.request_id)
            .u8(b4)
            .u8(0)
            .u16(0)
            .f64(self.hat_m)
            .f64(self.hot_m)
            .u32(self.material_code)
            .f32(self.normal_azimuth_deg)
            .f32(self.normal_elevation_deg)
            .u32(0);
        w.finish()
    }

    /// Decodes the packet (`b` is exactly its 40 bytes).
    pub fn decode(b: &[u8], version: CigiVersion, order: ByteOrder) -> Result<Self, DecodeError> {
        let r = packet(
            b,
            HAT_HOT_EXTENDED_RESPONSE_ID,
            HAT_HOT_EXTENDED_RESPONSE_SIZE,
            order,
        )?;
        let read = || -> Option<Self> {
            let b4 = r.u8(4)?;
            Some(Self {
                request_id: r.u16(2)?,
                valid: b4 & 0x01 != 0,
                host_frame_lsn: lsn_of(version, b4),
                hat_m: r.f64(8)?,
                hot_m: r.f64(16)?,
                material_code: r.u32(24)?,
                normal_azimuth_deg: r.f32(28)?,
                normal_elevation_deg: r.f32(32)?,
            })
        };
        read().ok_or_else(cut)
    }
}

/// Line of Sight Response (packet 104, 16 bytes). Layout: CCL `CigiLosRespV3.cpp` (3.0/3.1)
/// and `CigiLosRespV3_2.cpp` (3.2/3.3): 2 LOS ID (u16); 4 bit 0 valid, bit 1 entity ID valid,
/// bit 2 visible, bits 4–7 host frame number LSN (3.2+); 5 response count (u8); 6 entity ID
/// (u16); 8 range (f64, m).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LosResponse {
    /// The request's LOS ID.
    pub request_id: u16,
    /// The test was made (false: no terrain there, or not answerable); range is meaningful
    /// only when valid and not visible.
    pub valid: bool,
    /// `entity_id` names an entity that was hit (aerie hits terrain only: false).
    pub entity_id_valid: bool,
    /// The destination is visible from the source (segment: nothing in between; vector:
    /// nothing hit within the range).
    pub visible: bool,
    /// The four low bits of the host frame the answer was computed for (3.2+; 0 before).
    pub host_frame_lsn: u8,
    /// How many responses answer this request (aerie reports the first hit only: 1).
    pub response_count: u8,
    /// The entity hit, when `entity_id_valid`.
    pub entity_id: u16,
    /// Range from the source to the intersection, metres.
    pub range_m: f64,
}

impl LosResponse {
    /// Encodes the packet in `version`'s layout and `order`.
    pub fn encode(
        &self,
        version: CigiVersion,
        order: ByteOrder,
    ) -> [u8; LOS_RESPONSE_SIZE as usize] {
        let b4 = u8::from(self.valid)
            | (u8::from(self.entity_id_valid) << 1)
            | (u8::from(self.visible) << 2)
            | lsn_bits(version, self.host_frame_lsn);
        let mut w = Wr::new(order, LOS_RESPONSE_SIZE.into());
        w.u8(LOS_RESPONSE_ID)
            .u8(LOS_RESPONSE_SIZE)
            .u16(self.request_id)
            .u8(b4)
            .u8(self.response_count)
            .u16(self.entity_id)
            .f64(self.range_m);
        w.finish()
    }

    /// Decodes the packet (`b` is exactly its 16 bytes).
    pub fn decode(b: &[u8], version: CigiVersion, order: ByteOrder) -> Result<Self, DecodeError> {
        let r = packet(b, LOS_RESPONSE_ID, LOS_RESPONSE_SIZE, order)?;
        let read = || -> Option<Self> {
            let b4 = r.u8(4)?;
            Some(Self {
                request_id: r.u16(2)?,
                valid: b4 & 0x01 != 0,
                entity_id_valid: b4 & 0x02 != 0,
                visible: b4 & 0x04 != 0,
                host_frame_lsn: lsn_of(version, b4),
                response_count: r.u8(5)?,
                entity_id: r.u16(6)?,
                range_m: r.f64(8)?,
            })
        };
        read().ok_or_else(cut)
    }
}

/// Line of Sight Extended Response (packet 105, 56 bytes). Layout: CCL `CigiLosXRespV3.cpp`
/// (3.0/3.1) and `CigiLosXRespV3_2.cpp` (3.2/3.3): 2 LOS ID (u16); 4 bit 0 valid, bit 1
/// entity ID valid, bit 2 range valid, bit 3 visible, then bit 4 intersection point
/// coordinate system (3.0/3.1) or bits 4–7 host frame number LSN (3.2+); 5 response count
/// (u8); 6 entity ID (u16); 8 range (f64, m); 16/24/32 intersection latitude / x, longitude /
/// y, altitude / z (f64); 40 red, 41 green, 42 blue, 43 alpha (u8); 44 material code (u32);
/// 48 normal azimuth, 52 normal elevation (f32, °).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LosExtendedResponse {
    /// The request's LOS ID.
    pub request_id: u16,
    /// The test was made.
    pub valid: bool,
    /// `entity_id` names an entity that was hit (aerie hits terrain only: false).
    pub entity_id_valid: bool,
    /// `range_m` is valid (there was an intersection).
    pub range_valid: bool,
    /// The destination is visible from the source.
    pub visible: bool,
    /// The coordinate system of `point`. On the wire only in 3.0/3.1 (bit 4); a 3.2+ packet
    /// does not carry it and decodes, as the CCL decodes it, as entity when `entity_id_valid`
    /// and geodetic otherwise.
    pub point_coordinate_system: CoordinateSystem,
    /// The four low bits of the host frame the answer was computed for (3.2+; 0 before).
    pub host_frame_lsn: u8,
    /// How many responses answer this request (aerie: 1).
    pub response_count: u8,
    /// The entity hit, when `entity_id_valid`.
    pub entity_id: u16,
    /// Range from the source to the intersection, metres.
    pub range_m: f64,
    /// Intersection: latitude ° / x m, longitude ° / y m, altitude m / z m.
    pub point: [f64; 3],
    /// Red, green, blue, alpha of the surface at the intersection.
    pub rgba: [u8; 4],
    /// Material code of the surface (0 until land cover exists).
    pub material_code: u32,
    /// Surface normal azimuth, degrees clockwise from north.
    pub normal_azimuth_deg: f32,
    /// Surface normal elevation, degrees up from the horizontal.
    pub normal_elevation_deg: f32,
}

impl LosExtendedResponse {
    /// Encodes the packet in `version`'s layout and `order`.
    pub fn encode(
        &self,
        version: CigiVersion,
        order: ByteOrder,
    ) -> [u8; LOS_EXTENDED_RESPONSE_SIZE as usize] {
        let mut b4 = u8::from(self.valid)
            | (u8::from(self.entity_id_valid) << 1)
            | (u8::from(self.range_valid) << 2)
            | (u8::from(self.visible) << 3);
        if version.is_3_2_or_later() {
            b4 |= lsn_bits(version, self.host_frame_lsn);
        } else if self.point_coordinate_system == CoordinateSystem::Entity {
            b4 |= 0x10;
        }
        let mut w = Wr::new(order, LOS_EXTENDED_RESPONSE_SIZE.into());
        w.u8(LOS_EXTENDED_RESPONSE_ID)
            .u8(LOS_EXTENDED_RESPONSE_SIZE)
            .u16(self.request_id)
            .u8(b4)
            .u8(self.response_count)
            .u16(self.entity_id)
            .f64(self.range_m);
        for v in self.point {
            w.f64(v);
        }
        w.raw(&self.rgba)
            .u32(self.material_code)
            .f32(self.normal_azimuth_deg)
            .f32(self.normal_elevation_deg);
        w.finish()
    }

    /// Decodes the packet (`b` is exactly its 56 bytes).
    pub fn decode(b: &[u8], version: CigiVersion, order: ByteOrder) -> Result<Self, DecodeError> {
        let r = packet(
            b,
            LOS_EXTENDED_RESPONSE_ID,
            LOS_EXTENDED_RESPONSE_SIZE,
            order,
        )?;
        let read = || -> Option<Self> {
            let b4 = r.u8(4)?;
            let entity_id_valid = b4 & 0x02 != 0;
            let entity_point = if version.is_3_2_or_later() {
                entity_id_valid
            } else {
                b4 & 0x10 != 0
            };
            Some(Self {
                request_id: r.u16(2)?,
                valid: b4 & 0x01 != 0,
                entity_id_valid,
                range_valid: b4 & 0x04 != 0,
                visible: b4 & 0x08 != 0,
                point_coordinate_system: if entity_point {
                    CoordinateSystem::Entity
                } else {
                    CoordinateSystem::Geodetic
                },
                host_frame_lsn: lsn_of(version, b4),
                response_count: r.u8(5)?,
                entity_id: r.u16(6)?,
                range_m: r.f64(8)?,
                point: [r.f64(16)?, r.f64(24)?, r.f64(32)?],
                rgba: r.bytes::<4>(40)?,
                material_code: r.u32(44)?,
                normal_azimuth_deg: r.f32(48)?,
                normal_elevation_deg: r.f32(52)?,
            })
        };
        read().ok_or_else(cut)
    }
}

/// One IG → host answer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CigiResponse {
    /// HAT/HOT Response (102).
    HatHot(HatHotResponse),
    /// HAT/HOT Extended Response (103).
    HatHotExtended(HatHotExtendedResponse),
    /// Line of Sight Response (104).
    Los(LosResponse),
    /// Line of Sight Extended Response (105).
    LosExtended(LosExtendedResponse),
}

impl CigiResponse {
    /// The request ID it answers.
    pub fn request_id(&self) -> u16 {
        match self {
            CigiResponse::HatHot(r) => r.request_id,
            CigiResponse::HatHotExtended(r) => r.request_id,
            CigiResponse::Los(r) => r.request_id,
            CigiResponse::LosExtended(r) => r.request_id,
        }
    }

    /// Appends the packet, in `version`'s layout and `order`, to `out` (an IG message being
    /// built after its Start of Frame).
    pub fn encode_into(&self, version: CigiVersion, order: ByteOrder, out: &mut Vec<u8>) {
        match self {
            CigiResponse::HatHot(r) => out.extend_from_slice(&r.encode(version, order)),
            CigiResponse::HatHotExtended(r) => out.extend_from_slice(&r.encode(version, order)),
            CigiResponse::Los(r) => out.extend_from_slice(&r.encode(version, order)),
            CigiResponse::LosExtended(r) => out.extend_from_slice(&r.encode(version, order)),
        }
    }

    /// Decodes a response packet (`b` is exactly the packet) by its ID; `None` for other IDs.
    pub fn decode(
        b: &[u8],
        version: CigiVersion,
        order: ByteOrder,
    ) -> Option<Result<Self, DecodeError>> {
        Some(match *b.first()? {
            HAT_HOT_RESPONSE_ID => HatHotResponse::decode(b, version, order).map(Self::HatHot),
            HAT_HOT_EXTENDED_RESPONSE_ID => {
                HatHotExtendedResponse::decode(b, version, order).map(Self::HatHotExtended)
            }
            LOS_RESPONSE_ID => LosResponse::decode(b, version, order).map(Self::Los),
            LOS_EXTENDED_RESPONSE_ID => {
                LosExtendedResponse::decode(b, version, order).map(Self::LosExtended)
            }
            _ => return None,
        })
    }
}
