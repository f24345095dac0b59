//! Host → IG terrain requests: HAT/HOT Request (24), Line of Sight Segment Request (25) and
//! Line of Sight Vector Request (26), per minor version (3.2 added update periods and the
//! segment's destination entity).

use crate::codec::protocol::DecodeError;
use crate::codec::wire::{ByteOrder, Rd, Wr};
use crate::pose::PosePosition;

use super::format::*;
use super::version::CigiVersion;

/// What a HAT/HOT Request asks for (byte 4 bits 0–1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum HatHotRequestType {
    /// 0: height above terrain, answered by a HAT/HOT Response (102).
    #[default]
    Hat,
    /// 1: height of terrain, answered by a HAT/HOT Response (102).
    Hot,
    /// 2: both, with the surface normal and material, answered by an Extended Response (103).
    Extended,
}

impl HatHotRequestType {
    fn from_bits(bits: u8) -> Option<Self> {
        match bits & 0x03 {
            0 => Some(Self::Hat),
            1 => Some(Self::Hot),
            2 => Some(Self::Extended),
            _ => None,
        }
    }
    fn bits(self) -> u8 {
        match self {
            Self::Hat => 0,
            Self::Hot => 1,
            Self::Extended => 2,
        }
    }
}

/// The coordinate system of a request's point (or a response's intersection point).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum CoordinateSystem {
    /// 0: latitude, longitude (°), altitude above mean sea level (m).
    #[default]
    Geodetic,
    /// 1: x (forward), y (right), z (down) metres from the reference point of the request's
    /// entity, in its body axes.
    Entity,
}

impl CoordinateSystem {
    fn from_bit(set: bool) -> Self {
        if set {
            Self::Entity
        } else {
            Self::Geodetic
        }
    }
    fn bit(self) -> u8 {
        u8::from(self == Self::Entity)
    }
}

/// Basic or extended line-of-sight request (byte 4 bit 0).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LosRequestType {
    /// 0: answered by a Line of Sight Response (104): valid, visible, range.
    #[default]
    Basic,
    /// 1: answered by a Line of Sight Extended Response (105): also the point, normal, material.
    Extended,
}

impl LosRequestType {
    fn from_bit(set: bool) -> Self {
        if set {
            Self::Extended
        } else {
            Self::Basic
        }
    }
    fn bit(self) -> u8 {
        u8::from(self == Self::Extended)
    }
}

/// A point as three numbers and the coordinate system they are in, as a [`PosePosition`]
/// when geodetic (entity-relative points need the entity's pose: the IG session resolves them).
fn geodetic(cs: CoordinateSystem, p: [f64; 3]) -> Option<PosePosition> {
    (cs == CoordinateSystem::Geodetic).then_some(PosePosition::Geodetic {
        lat_deg: p[0],
        lon_deg: p[1],
        alt_m: p[2],
    })
}

/// Finite, and when geodetic a latitude/longitude in range.
fn check_point(
    cs: CoordinateSystem,
    p: [f64; 3],
    names: [&'static str; 3],
    offsets: [&'static str; 3],
) -> Result<(), DecodeError> {
    match cs {
        CoordinateSystem::Geodetic => {
            lat_lon(names[0], p[0], names[1], p[1])?;
            finite64(names[2], p[2])
        }
        CoordinateSystem::Entity => {
            for (name, v) in offsets.iter().zip(p) {
                finite64(name, v)?;
            }
            Ok(())
        }
    }
}

/// HAT/HOT Request (packet 24, 32 bytes). Layout: CCL `CigiHatHotReqV3.cpp` (3.0/3.1) and
/// `CigiHatHotReqV3_2.cpp` (3.2/3.3): 2 request ID (u16); 4 bits 0–1 request type, bit 2
/// coordinate system; 5 update period (3.2+, reserved before); 6 entity ID (u16);
/// 8 latitude / x, 16 longitude / y, 24 altitude / z (f64).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HatHotRequest {
    /// HAT/HOT ID, echoed in the response.
    pub request_id: u16,
    /// HAT, HOT or extended.
    pub request_type: HatHotRequestType,
    /// Geodetic or entity-relative point.
    pub coordinate_system: CoordinateSystem,
    /// 0: answer once; n > 0: answer every n IG frames until a request with the same ID and
    /// period 0 (3.2+; always 0 in 3.0/3.1).
    pub update_period: u8,
    /// The entity the point is relative to (entity coordinate system only).
    pub entity_id: u16,
    /// Latitude ° / x offset m, longitude ° / y offset m, altitude m / z offset m.
    pub point: [f64; 3],
}

impl HatHotRequest {
    /// Encodes the packet as a host of `version` writes it.
    pub fn encode(
        &self,
        version: CigiVersion,
        order: ByteOrder,
    ) -> [u8; HAT_HOT_REQUEST_SIZE as usize] {
        let flags = self.request_type.bits() | (self.coordinate_system.bit() << 2);
        let period = if version.is_3_2_or_later() {
            self.update_period
        } else {
            0
        };
        let mut w = Wr::new(order, HAT_HOT_REQUEST_SIZE.into());
        w.u8(HAT_HOT_REQUEST_ID)
            .u8(HAT_HOT_REQUEST_SIZE)
            .u16(self.request_id)
            .u8(flags)
            .u8(period)
            .u16(self.entity_id);
        for v in self.point {
            w.f64(v);
        }
        w.finish()
    }

    /// Decodes the packet (`b` is exactly its 32 bytes) as `version` has it; a reserved
    /// request type (3) is an error naming the field.
    pub fn decode(b: &[u8], version: CigiVersion, order: ByteOrder) -> Result<Self, DecodeError> {
        let r = packet(b, HAT_HOT_REQUEST_ID, HAT_HOT_REQUEST_SIZE, order)?;
        let flags = r.u8(4).ok_or_else(cut)?;
        let request_type = HatHotRequestType::from_bits(flags).ok_or_else(|| {
            DecodeError::malformed(P, "HAT/HOT Request byte 4: request type 3 is reserved")
        })?;
        let read = || -> Option<Self> {
            Some(Self {
                request_id: r.u16(2)?,
                request_type,
                coordinate_system: CoordinateSystem::from_bit(flags & 0x04 != 0),
                update_period: if version.is_3_2_or_later() {
                    r.u8(5)?
                } else {
                    0
                },
                entity_id: r.u16(6)?,
                point: [r.f64(8)?, r.f64(16)?, r.f64(24)?],
            })
        };
        read().ok_or_else(cut)
    }

    /// The point is finite; a geodetic one has latitude −90…90 and longitude −180…180 (CCL
    /// `CigiBaseHatHotReq.cpp` setters).
    pub fn check(&self) -> Result<(), DecodeError> {
        check_point(
            self.coordinate_system,
            self.point,
            [
                "hat_hot_request.latitude",
                "hat_hot_request.longitude",
                "hat_hot_request.altitude",
            ],
            [
                "hat_hot_request.x_offset",
                "hat_hot_request.y_offset",
                "hat_hot_request.z_offset",
            ],
        )
    }

    /// The point as a geodetic [`PosePosition`], when the request is geodetic.
    pub fn geodetic_point(&self) -> Option<PosePosition> {
        geodetic(self.coordinate_system, self.point)
    }
}

/// Line of Sight Segment Request (packet 25, 64 bytes). Layout: CCL `CigiLosSegReqV3.cpp`
/// (3.0/3.1) and `CigiLosSegReqV3_2.cpp` (3.2/3.3): 2 LOS ID (u16); 4 bit 0 request type,
/// bit 1 source coordinate system, bit 2 destination coordinate system, bit 3 response
/// coordinate system, bit 4 destination entity ID valid (3.2+); 5 alpha threshold (u8);
/// 6 entity ID (u16); 8/16/24 source lat/x, lon/y, alt/z (f64); 32/40/48 destination
/// (f64); 56 material mask (u32); 60 update period (u8, 3.2+); 62 destination entity ID
/// (u16, 3.2+).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LosSegmentRequest {
    /// LOS ID, echoed in the response.
    pub request_id: u16,
    /// Basic or extended.
    pub request_type: LosRequestType,
    /// Coordinate system of the source point.
    pub source_coordinate_system: CoordinateSystem,
    /// Coordinate system of the destination point.
    pub destination_coordinate_system: CoordinateSystem,
    /// Coordinate system the extended response's intersection point is to be given in.
    pub response_coordinate_system: CoordinateSystem,
    /// `destination_entity_id` is valid (3.2+): the destination is relative to that entity.
    pub destination_entity_id_valid: bool,
    /// Intersections with surfaces of alpha below this are ignored (0–255).
    pub alpha_threshold: u8,
    /// The entity the source (and an entity-relative destination) is relative to.
    pub entity_id: u16,
    /// Source: latitude ° / x m, longitude ° / y m, altitude m / z m.
    pub source: [f64; 3],
    /// Destination, same units.
    pub destination: [f64; 3],
    /// Material mask: which material classes are tested (aerie's terrain is one class).
    pub material_mask: u32,
    /// 0: answer once; n > 0: every n IG frames until cancelled (3.2+; 0 before).
    pub update_period: u8,
    /// The destination's entity (3.2+; when `destination_entity_id_valid`).
    pub destination_entity_id: u16,
}

impl LosSegmentRequest {
    /// Encodes the packet as a host of `version` writes it (update period, destination entity
    /// and its valid bit only in 3.2+).
    pub fn encode(
        &self,
        version: CigiVersion,
        order: ByteOrder,
    ) -> [u8; LOS_SEGMENT_REQUEST_SIZE as usize] {
        let v32 = version.is_3_2_or_later();
        let flags = self.request_type.bit()
            | (self.source_coordinate_system.bit() << 1)
            | (self.destination_coordinate_system.bit() << 2)
            | (self.response_coordinate_system.bit() << 3)
            | (u8::from(v32 && self.destination_entity_id_valid) << 4);
        let mut w = Wr::new(order, LOS_SEGMENT_REQUEST_SIZE.into());
        w.u8(LOS_SEGMENT_REQUEST_ID)
            .u8(LOS_SEGMENT_REQUEST_SIZE)
            .u16(self.request_id)
            .u8(flags)
            .u8(self.alpha_threshold)
            .u16(self.entity_id);
        for v in self.source.iter().chain(&self.destination) {
            w.f64(*v);
        }
        w.u32(self.material_mask);
        if v32 {
            w.u8(self.update_period)
                .u8(0)
                .u16(self.destination_entity_id);
        } else {
            w.u32(0);
        }
        w.finish()
    }

    /// Decodes the packet (`b` is exactly its 64 bytes) as `version` has it.
    pub fn decode(b: &[u8], version: CigiVersion, order: ByteOrder) -> Result<Self, DecodeError> {
        let r = packet(b, LOS_SEGMENT_REQUEST_ID, LOS_SEGMENT_REQUEST_SIZE, order)?;
        let v32 = version.is_3_2_or_later();
        let read = || -> Option<Self> {
            let flags = r.u8(4)?;
            Some(Self {
                request_id: r.u16(2)?,
                request_type: LosRequestType::from_bit(flags & 0x01 != 0),
                source_coordinate_system: CoordinateSystem::from_bit(flags & 0x02 != 0),
                destination_coordinate_system: CoordinateSystem::from_bit(flags & 0x04 != 0),
                response_coordinate_system: CoordinateSystem::from_bit(flags & 0x08 != 0),
                destination_entity_id_valid: v32 && flags & 0x10 != 0,
                alpha_threshold: r.u8(5)?,
                entity_id: r.u16(6)?,
                source: [r.f64(8)?, r.f64(16)?, r.f64(24)?],
                destination: [r.f64(32)?, r.f64(40)?, r.f64(48)?],
                material_mask: r.u32(56)?,
                update_period: if v32 { r.u8(60)? } else { 0 },
                destination_entity_id: if v32 { r.u16(62)? } else { 0 },
            })
        };
        read().ok_or_else(cut)
    }

    /// Both points finite; geodetic ones with latitude −90…90, longitude −180…180 (CCL
    /// `CigiBaseLosSegReq.cpp` setters).
    pub fn check(&self) -> Result<(), DecodeError> {
        check_point(
            self.source_coordinate_system,
            self.source,
            [
                "los_segment_request.source_latitude",
                "los_segment_request.source_longitude",
                "los_segment_request.source_altitude",
            ],
            [
                "los_segment_request.source_x",
                "los_segment_request.source_y",
                "los_segment_request.source_z",
            ],
        )?;
        check_point(
            self.destination_coordinate_system,
            self.destination,
            [
                "los_segment_request.destination_latitude",
                "los_segment_request.destination_longitude",
                "los_segment_request.destination_altitude",
            ],
            [
                "los_segment_request.destination_x",
                "los_segment_request.destination_y",
                "los_segment_request.destination_z",
            ],
        )
    }

    /// The source as a geodetic [`PosePosition`], when geodetic.
    pub fn geodetic_source(&self) -> Option<PosePosition> {
        geodetic(self.source_coordinate_system, self.source)
    }

    /// The destination as a geodetic [`PosePosition`], when geodetic.
    pub fn geodetic_destination(&self) -> Option<PosePosition> {
        geodetic(self.destination_coordinate_system, self.destination)
    }
}

/// Line of Sight Vector Request (packet 26, 56 bytes). Layout: CCL `CigiLosVectReqV3.cpp`
/// (3.0/3.1) and `CigiLosVectReqV3_2.cpp` (3.2/3.3): 2 LOS ID (u16); 4 bit 0 request type,
/// bit 1 source coordinate system, bit 2 response coordinate system; 5 alpha threshold (u8);
/// 6 entity ID (u16); 8 azimuth, 12 elevation (f32, °); 16 minimum range, 20 maximum range
/// (f32, m); 24/32/40 source lat/x, lon/y, alt/z (f64); 48 material mask (u32); 52 update
/// period (u8, 3.2+).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LosVectorRequest {
    /// LOS ID, echoed in the response.
    pub request_id: u16,
    /// Basic or extended.
    pub request_type: LosRequestType,
    /// Coordinate system of the source point (and of the vector's angles: geodetic = the
    /// local north-east-down frame at the source, entity = the entity's body axes).
    pub source_coordinate_system: CoordinateSystem,
    /// Coordinate system the extended response's intersection point is to be given in.
    pub response_coordinate_system: CoordinateSystem,
    /// Intersections with surfaces of alpha below this are ignored.
    pub alpha_threshold: u8,
    /// The entity an entity-relative source is relative to.
    pub entity_id: u16,
    /// Azimuth, degrees clockwise from north (or the entity's X axis), −180…180.
    pub azimuth_deg: f32,
    /// Elevation, degrees up from the horizontal, −90…90.
    pub elevation_deg: f32,
    /// Minimum range, metres (≥ 0): intersections nearer are ignored.
    pub min_range_m: f32,
    /// Maximum range, metres (≥ minimum).
    pub max_range_m: f32,
    /// Source: latitude ° / x m, longitude ° / y m, altitude m / z m.
    pub source: [f64; 3],
    /// Material mask.
    pub material_mask: u32,
    /// 0: answer once; n > 0: every n IG frames until cancelled (3.2+; 0 before).
    pub update_period: u8,
}

impl LosVectorRequest {
    /// Encodes the packet as a host of `version` writes it (update period only in 3.2+).
    pub fn encode(
        &self,
        version: CigiVersion,
        order: ByteOrder,
    ) -> [u8; LOS_VECTOR_REQUEST_SIZE as usize] {
        let flags = self.request_type.bit()
            | (self.source_coordinate_system.bit() << 1)
            | (self.response_coordinate_system.bit() << 2);
        let mut w = Wr::new(order, LOS_VECTOR_REQUEST_SIZE.into());
        w.u8(LOS_VECTOR_REQUEST_ID)
            .u8(LOS_VECTOR_REQUEST_SIZE)
            .u16(self.request_id)
            .u8(flags)
            .u8(self.alpha_threshold)
            .u16(self.entity_id)
            .f32(self.azimuth_deg)
            .f32(self.elevation_deg)
            .f32(self.min_range_m)
            .f32(self.max_range_m);
        for v in self.source {
            w.f64(v);
        }
        w.u32(self.material_mask);
        let period = if version.is_3_2_or_later() {
            self.update_period
        } else {
            0
        };
        w.u8(period).u8(0).u16(0);
        w.finish()
    }

    /// Decodes the packet (`b` is exactly its 56 bytes) as `version` has it.
    pub fn decode(b: &[u8], version: CigiVersion, order: ByteOrder) -> Result<Self, DecodeError> {
        let r = packet(b, LOS_VECTOR_REQUEST_ID, LOS_VECTOR_REQUEST_SIZE, order)?;
        Self::read(&r, version).ok_or_else(cut)
    }

    fn read(r: &Rd, version: CigiVersion) -> Option<Self> {
        let flags = r.u8(4)?;
        Some(Self {
            request_id: r.u16(2)?,
            request_type: LosRequestType::from_bit(flags & 0x01 != 0),
            source_coordinate_system: CoordinateSystem::from_bit(flags & 0x02 != 0),
            response_coordinate_system: CoordinateSystem::from_bit(flags & 0x04 != 0),
            alpha_threshold: r.u8(5)?,
            entity_id: r.u16(6)?,
            azimuth_deg: r.f32(8)?,
            elevation_deg: r.f32(12)?,
            min_range_m: r.f32(16)?,
            max_range_m: r.f32(20)?,
            source: [r.f64(24)?, r.f64(32)?, r.f64(40)?],
            material_mask: r.u32(48)?,
            update_period: if version.is_3_2_or_later() {
                r.u8(52)?
            } else {
                0
            },
        })
    }

    /// Azimuth −180…180, elevation −90…90, 0 ≤ minimum range ≤ maximum range, the source
    /// finite and, when geodetic, in range (CCL `CigiBaseLosVectReq.cpp` setters; the CCL's
    /// packer folds azimuths above 180 into −180…180 before sending).
    pub fn check(&self) -> Result<(), DecodeError> {
        within(
            "los_vector_request.azimuth",
            self.azimuth_deg.into(),
            -180.0,
            180.0,
            "[-180, 180]",
        )?;
        within(
            "los_vector_request.elevation",
            self.elevation_deg.into(),
            -90.0,
            90.0,
            "[-90, 90]",
        )?;
        within(
            "los_vector_request.min_range",
            self.min_range_m.into(),
            0.0,
            f64::MAX,
            "[0, inf)",
        )?;
        within(
            "los_vector_request.max_range",
            self.max_range_m.into(),
            self.min_range_m.into(),
            f64::MAX,
            "[min_range, inf)",
        )?;
        check_point(
            self.source_coordinate_system,
            self.source,
            [
                "los_vector_request.source_latitude",
                "los_vector_request.source_longitude",
                "los_vector_request.source_altitude",
            ],
            [
                "los_vector_request.source_x",
                "los_vector_request.source_y",
                "los_vector_request.source_z",
            ],
        )
    }

    /// The source as a geodetic [`PosePosition`], when geodetic.
    pub fn geodetic_source(&self) -> Option<PosePosition> {
        geodetic(self.source_coordinate_system, self.source)
    }
}

/// One terrain request of a host message, in message order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CigiRequest {
    /// HAT/HOT Request (24).
    HatHot(HatHotRequest),
    /// Line of Sight Segment Request (25).
    LosSegment(LosSegmentRequest),
    /// Line of Sight Vector Request (26).
    LosVector(LosVectorRequest),
}

impl CigiRequest {
    /// The request's ID (HAT/HOT ID or LOS ID), echoed in its response.
    pub fn request_id(&self) -> u16 {
        match self {
            CigiRequest::HatHot(r) => r.request_id,
            CigiRequest::LosSegment(r) => r.request_id,
            CigiRequest::LosVector(r) => r.request_id,
        }
    }

    /// The update period (0 = once).
    pub fn update_period(&self) -> u8 {
        match self {
            CigiRequest::HatHot(r) => r.update_period,
            CigiRequest::LosSegment(r) => r.update_period,
            CigiRequest::LosVector(r) => r.update_period,
        }
    }

    /// The request's value checks.
    pub fn check(&self) -> Result<(), DecodeError> {
        match self {
            CigiRequest::HatHot(r) => r.check(),
            CigiRequest::LosSegment(r) => r.check(),
            CigiRequest::LosVector(r) => r.check(),
        }
    }

    /// The packet ID it came in.
    pub fn packet_id(&self) -> u8 {
        match self {
            CigiRequest::HatHot(_) => HAT_HOT_REQUEST_ID,
            CigiRequest::LosSegment(_) => LOS_SEGMENT_REQUEST_ID,
            CigiRequest::LosVector(_) => LOS_VECTOR_REQUEST_ID,
        }
    }

    /// Encodes the request as a host of `version` writes it.
    pub fn encode(&self, version: CigiVersion, order: ByteOrder) -> Vec<u8> {
        match self {
            CigiRequest::HatHot(r) => r.encode(version, order).to_vec(),
            CigiRequest::LosSegment(r) => r.encode(version, order).to_vec(),
            CigiRequest::LosVector(r) => r.encode(version, order).to_vec(),
        }
    }
}
