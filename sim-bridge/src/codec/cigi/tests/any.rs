//! Every packet type behind one enum, so that the tests can encode and decode any of them in
//! any version and byte order the same way.

use super::super::*;
use crate::codec::protocol::DecodeError;
use crate::codec::wire::{ByteOrder, Rd};

#[derive(Clone, Debug, PartialEq)]
pub(super) enum Any {
    Ig(IgControl),
    Sof(StartOfFrame),
    Entity(EntityControl),
    Clamp(ConformalClampedEntityControl),
    Rate(RateControl),
    Celestial(CelestialSphereControl),
    Atmosphere(AtmosphereControl),
    HatHotReq(HatHotRequest),
    LosSegReq(LosSegmentRequest),
    LosVecReq(LosVectorRequest),
    Resp(CigiResponse),
    ViewCtrl(ViewControl),
    ViewDef(ViewDefinition),
}

impl Any {
    pub(super) fn encode(&self, v: CigiVersion, o: ByteOrder) -> Vec<u8> {
        match self {
            Any::Ig(p) => p.encode_as(v, o),
            Any::Sof(p) => p.encode(v, o),
            Any::Entity(p) => p.encode(o).to_vec(),
            Any::Clamp(p) => p.encode(o).to_vec(),
            Any::Rate(p) => p.encode(v, o).to_vec(),
            Any::Celestial(p) => p.encode(o).to_vec(),
            Any::Atmosphere(p) => p.encode(o).to_vec(),
            Any::HatHotReq(p) => p.encode(v, o).to_vec(),
            Any::LosSegReq(p) => p.encode(v, o).to_vec(),
            Any::LosVecReq(p) => p.encode(v, o).to_vec(),
            Any::Resp(p) => {
                let mut out = Vec::new();
                p.encode_into(v, o, &mut out);
                out
            }
            Any::ViewCtrl(p) => p.encode(o).to_vec(),
            Any::ViewDef(p) => p.encode(o).to_vec(),
        }
    }

    /// Decodes `b` as the same kind of packet as `self`.
    pub(super) fn decode_like(
        &self,
        b: &[u8],
        v: CigiVersion,
        o: ByteOrder,
    ) -> Result<Any, DecodeError> {
        Ok(match self {
            Any::Ig(_) => Any::Ig(IgControl::decode(b, v, o)?),
            // The Start of Frame carries its own version and byte order (checked apart).
            Any::Sof(_) => Any::Sof(StartOfFrame::decode_with_version(b)?.0),
            Any::Entity(_) => Any::Entity(EntityControl::decode(b, v, o)?),
            Any::Clamp(_) => Any::Clamp(ConformalClampedEntityControl::decode(b, o)?),
            Any::Rate(_) => Any::Rate(RateControl::decode(b, v, o)?),
            Any::Celestial(_) => Any::Celestial(CelestialSphereControl::decode(b, o)?),
            Any::Atmosphere(_) => Any::Atmosphere(AtmosphereControl::decode(b, o)?),
            Any::HatHotReq(_) => Any::HatHotReq(HatHotRequest::decode(b, v, o)?),
            Any::LosSegReq(_) => Any::LosSegReq(LosSegmentRequest::decode(b, v, o)?),
            Any::LosVecReq(_) => Any::LosVecReq(LosVectorRequest::decode(b, v, o)?),
            Any::Resp(_) => Any::Resp(CigiResponse::decode(b, v, o).expect("a response ID")?),
            Any::ViewCtrl(_) => {
                Any::ViewCtrl(ViewControl::decode(&Rd::new(b, o)).ok_or(DecodeError::truncated(P))?)
            }
            Any::ViewDef(_) => Any::ViewDef(
                ViewDefinition::decode(&Rd::new(b, o)).ok_or(DecodeError::truncated(P))?,
            ),
        })
    }

    /// What survives a trip through `v`: fields `v` does not carry come back as their
    /// decoder's default.
    pub(super) fn as_in(&self, v: CigiVersion) -> Any {
        let v32 = v.is_3_2_or_later();
        let mut a = self.clone();
        match &mut a {
            Any::Ig(p) => {
                p.minor_version = if v32 { v.minor() } else { 0 };
                p.smoothing &= v.has_smoothing();
                if !v32 {
                    p.last_ig_frame = 0;
                }
            }
            Any::Sof(p) if !v32 => p.last_host_frame = 0,
            Any::Entity(p) => p.smoothing &= v.has_smoothing(),
            Any::Rate(p) if !v32 => p.frame = RateFrame::WorldOrParent,
            Any::HatHotReq(p) if !v32 => p.update_period = 0,
            Any::LosSegReq(p) if !v32 => {
                p.update_period = 0;
                p.destination_entity_id_valid = false;
                p.destination_entity_id = 0;
            }
            Any::LosVecReq(p) if !v32 => p.update_period = 0,
            Any::Resp(r) => match r {
                CigiResponse::HatHot(p) if !v32 => p.host_frame_lsn = 0,
                CigiResponse::HatHotExtended(p) if !v32 => p.host_frame_lsn = 0,
                CigiResponse::Los(p) if !v32 => p.host_frame_lsn = 0,
                CigiResponse::LosExtended(p) => {
                    if v32 {
                        p.point_coordinate_system = if p.entity_id_valid {
                            CoordinateSystem::Entity
                        } else {
                            CoordinateSystem::Geodetic
                        };
                    } else {
                        p.host_frame_lsn = 0;
                    }
                }
                _ => {}
            },
            _ => {}
        }
        if let Any::Resp(r) = &mut a {
            match r {
                CigiResponse::HatHot(p) => p.host_frame_lsn &= 0x0F,
                CigiResponse::HatHotExtended(p) => p.host_frame_lsn &= 0x0F,
                CigiResponse::Los(p) => p.host_frame_lsn &= 0x0F,
                CigiResponse::LosExtended(p) => p.host_frame_lsn &= 0x0F,
            }
        }
        a
    }
}

pub(super) const P: crate::codec::Protocol = crate::codec::Protocol::Cigi;
