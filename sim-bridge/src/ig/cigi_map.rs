//! CIGI packets ↔ the session's own terms: requests, entity updates and environment in; the
//! session's responses out as the response packets of the host's version. Pure conversions.

use crate::codec::cigi::{
    AtmosphereControl, CelestialSphereControl, CigiRequest, CigiResponse, CoordinateSystem,
    EntityControl, HatHotExtendedResponse, HatHotRequestType, HatHotResponse, HatHotResponseType,
    LosExtendedResponse, LosRequestType, LosResponse as WireLos, HAT_HOT_REQUEST_ID,
    LOS_SEGMENT_REQUEST_ID, LOS_VECTOR_REQUEST_ID,
};
use crate::geodesy::Geodetic;

use super::entities::EntityControlUpdate;
use super::environment::{Atmosphere, Celestial};
use super::requests::{
    HostRequest, HotKind, HotRequest, HotResponse, LosRequest, LosResponse, LosShape, RequestPoint,
    Response,
};

fn point(cs: CoordinateSystem, entity: u16, p: [f64; 3]) -> RequestPoint {
    match cs {
        CoordinateSystem::Geodetic => RequestPoint::Geodetic(Geodetic::new(p[0], p[1], p[2])),
        CoordinateSystem::Entity => RequestPoint::Entity {
            entity,
            offset_m: p,
        },
    }
}

/// A decoded request in the session's terms.
pub fn request(r: &CigiRequest) -> HostRequest {
    match r {
        CigiRequest::HatHot(h) => HostRequest::Hot(HotRequest {
            id: h.request_id,
            kind: match h.request_type {
                HatHotRequestType::Hat => HotKind::Hat,
                HatHotRequestType::Hot => HotKind::Hot,
                HatHotRequestType::Extended => HotKind::Extended,
            },
            at: point(h.coordinate_system, h.entity_id, h.point),
            period: h.update_period,
        }),
        CigiRequest::LosSegment(s) => {
            // An entity-relative destination is relative to the destination entity when its
            // ID is valid, else to the source's entity (ICD, Destination Entity ID Valid).
            let to_entity = if s.destination_entity_id_valid {
                s.destination_entity_id
            } else {
                s.entity_id
            };
            HostRequest::Los(LosRequest {
                id: s.request_id,
                extended: s.request_type == LosRequestType::Extended,
                shape: LosShape::Segment {
                    from: point(s.source_coordinate_system, s.entity_id, s.source),
                    to: point(s.destination_coordinate_system, to_entity, s.destination),
                },
                period: s.update_period,
            })
        }
        CigiRequest::LosVector(v) => HostRequest::Los(LosRequest {
            id: v.request_id,
            extended: v.request_type == LosRequestType::Extended,
            shape: LosShape::Vector {
                from: point(v.source_coordinate_system, v.entity_id, v.source),
                azimuth_deg: v.azimuth_deg.into(),
                elevation_deg: v.elevation_deg.into(),
                min_range_m: v.min_range_m.into(),
                max_range_m: v.max_range_m.into(),
            },
            period: v.update_period,
        }),
    }
}

/// The request a rejected request packet stands for (answered invalid, so the host is not
/// left waiting): a HAT/HOT or a basic LOS of that ID.
pub fn rejected_request(packet_id: u8, id: u16) -> Option<HostRequest> {
    let nowhere = RequestPoint::Geodetic(Geodetic::new(0.0, 0.0, 0.0));
    match packet_id {
        HAT_HOT_REQUEST_ID => Some(HostRequest::Hot(HotRequest {
            id,
            kind: HotKind::Hat,
            at: nowhere,
            period: 0,
        })),
        LOS_SEGMENT_REQUEST_ID | LOS_VECTOR_REQUEST_ID => Some(HostRequest::Los(LosRequest {
            id,
            extended: false,
            shape: LosShape::Segment {
                from: nowhere,
                to: nowhere,
            },
            period: 0,
        })),
        _ => None,
    }
}

/// An Entity Control as the entity table takes it.
pub fn entity_control(e: &EntityControl) -> EntityControlUpdate {
    EntityControlUpdate {
        id: e.entity_id,
        state: e.entity_state,
        attached: e.attached,
        parent: e.parent_id,
        entity_type: e.entity_type,
        alpha: e.alpha,
        lat_or_x: e.lat_deg,
        lon_or_y: e.lon_deg,
        alt_or_z: e.alt_m,
        attitude_deg: [e.yaw_deg.into(), e.pitch_deg.into(), e.roll_deg.into()],
    }
}

/// Celestial Sphere Control, set at IG time `now_s`.
pub fn celestial(c: &CelestialSphereControl, now_s: f64) -> Celestial {
    Celestial {
        date: c
            .date_valid
            .then_some((i32::from(c.year), u32::from(c.month), u32::from(c.day))),
        seconds_utc: f64::from(c.hour) * 3600.0 + f64::from(c.minute) * 60.0,
        ephemeris: c.ephemeris_enabled,
        sun_enabled: c.sun_enabled,
        moon_enabled: c.moon_enabled,
        stars_enabled: c.star_field_enabled,
        star_intensity_pct: c.star_field_intensity_pct,
        set_at_s: now_s,
    }
}

/// Atmosphere Control.
pub fn atmosphere(a: &AtmosphereControl) -> Atmosphere {
    Atmosphere {
        model_enabled: a.atmospheric_model_enabled,
        humidity_pct: a.humidity_pct.into(),
        air_temp_c: a.air_temperature_c,
        visibility_m: a.visibility_m,
        horizontal_wind_m_s: a.horizontal_wind_m_s,
        vertical_wind_m_s: a.vertical_wind_m_s,
        wind_direction_deg: a.wind_direction_deg,
        pressure_mb: a.barometric_pressure_mbar,
    }
}

/// The response packet for `r`, carrying the 4 low bits of the last host frame.
pub fn response(r: &Response, host_frame: u32) -> CigiResponse {
    let lsn = (host_frame & 0x0F) as u8;
    match r {
        Response::Hot(h) => hot(h, lsn),
        Response::Los(l) => los(l, lsn),
    }
}

fn hot(h: &HotResponse, lsn: u8) -> CigiResponse {
    match h.kind {
        HotKind::Hat | HotKind::Hot => CigiResponse::HatHot(HatHotResponse {
            request_id: h.id,
            valid: h.valid,
            response_type: if h.kind == HotKind::Hot {
                HatHotResponseType::Hot
            } else {
                HatHotResponseType::Hat
            },
            host_frame_lsn: lsn,
            height_m: if h.kind == HotKind::Hot {
                h.hot_m
            } else {
                h.hat_m
            },
        }),
        HotKind::Extended => CigiResponse::HatHotExtended(HatHotExtendedResponse {
            request_id: h.id,
            valid: h.valid,
            host_frame_lsn: lsn,
            hat_m: h.hat_m,
            hot_m: h.hot_m,
            material_code: h.material_code,
            normal_azimuth_deg: h.normal_azimuth_deg,
            normal_elevation_deg: h.normal_elevation_deg,
        }),
    }
}

fn los(l: &LosResponse, lsn: u8) -> CigiResponse {
    // No entity is hit-tested: the entity ID is never valid, and an intersection point is
    // always geodetic (the response coordinate system "entity" means the intersected
    // entity's, and there is none).
    if !l.extended {
        return CigiResponse::Los(WireLos {
            request_id: l.id,
            valid: l.valid,
            entity_id_valid: false,
            visible: l.visible,
            host_frame_lsn: lsn,
            response_count: l.count,
            entity_id: 0,
            range_m: l.range_m,
        });
    }
    CigiResponse::LosExtended(LosExtendedResponse {
        request_id: l.id,
        valid: l.valid,
        entity_id_valid: false,
        range_valid: l.valid,
        visible: l.visible,
        point_coordinate_system: CoordinateSystem::Geodetic,
        host_frame_lsn: lsn,
        response_count: l.count,
        entity_id: 0,
        range_m: l.range_m,
        point: [l.point.lat_deg, l.point.lon_deg, l.point.alt_m],
        // Terrain has no colour to report yet: opaque black, as "unknown".
        rgba: [0, 0, 0, 255],
        material_code: l.material_code,
        normal_azimuth_deg: l.normal_azimuth_deg,
        normal_elevation_deg: l.normal_elevation_deg,
    })
}
