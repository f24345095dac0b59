//! Value checks, versions and framing: every bad value is named, a bad request or side
//! packet is left out (and a bad request keeps its ID, to be answered as invalid) while the
//! rest of the message stands; broken framing drops the message with the offset named.

use super::super::*;
use crate::codec::protocol::DecodeError;
use crate::codec::wire::ByteOrder;
use crate::pose::PoseError;
use crate::stats::DropReason;

const O: ByteOrder = ByteOrder::Big;

fn ig(v: CigiVersion) -> Vec<u8> {
    IgControl {
        ig_mode: 1,
        host_frame: 77,
        ..IgControl::default()
    }
    .encode_as(v, O)
}

fn ownship() -> Vec<u8> {
    EntityControl {
        entity_state: 1,
        yaw_deg: 90.0,
        lat_deg: 47.0,
        lon_deg: 11.0,
        alt_m: 2000.0,
        ..EntityControl::default()
    }
    .encode(O)
    .to_vec()
}

fn msg(v: CigiVersion, packets: &[Vec<u8>]) -> Vec<u8> {
    let mut b = ig(v);
    b.extend(ownship());
    for p in packets {
        b.extend(p);
    }
    b
}

/// Decodes a message holding `packet` after the ownship: the packet is rejected with a
/// message naming `field`; the ownship pose and everything else survive.
fn rejected(packet: Vec<u8>, field: &str) -> RejectedPacket {
    let m = decode(&msg(CigiVersion::V3_3, &[packet])).unwrap();
    assert!(m.ownship_pose().is_some(), "the ownship survives");
    assert_eq!(m.rejected.len(), 1, "{:?}", m.rejected);
    let r = m.rejected[0].clone();
    assert_eq!(r.offset, 24 + 48);
    assert!(
        r.error.to_string().contains(field),
        "{} lacks {field}",
        r.error
    );
    r
}

fn accepted(packet: Vec<u8>) -> CigiMessage {
    let m = decode(&msg(CigiVersion::V3_3, &[packet])).unwrap();
    assert!(m.rejected.is_empty(), "{:?}", m.rejected);
    m
}

fn field(e: &DecodeError) -> &'static str {
    match e {
        DecodeError::Invalid { error, .. } => error.field(),
        other => panic!("not a value error: {other}"),
    }
}

fn hat_hot() -> HatHotRequest {
    HatHotRequest {
        request_id: 31,
        request_type: HatHotRequestType::Hot,
        point: [47.1, 11.2, 3000.0],
        ..HatHotRequest::default()
    }
}

#[test]
fn hat_hot_requests_are_checked_and_rejects_keep_their_id() {
    let v = CigiVersion::V3_3;
    let ok = accepted(hat_hot().encode(v, O).to_vec());
    assert_eq!(ok.requests, vec![CigiRequest::HatHot(hat_hot())]);
    for (point, name) in [
        ([95.0, 11.0, 0.0], "hat_hot_request.latitude"),
        ([-90.5, 11.0, 0.0], "hat_hot_request.latitude"),
        ([45.0, 180.5, 0.0], "hat_hot_request.longitude"),
        ([45.0, 11.0, f64::NAN], "hat_hot_request.altitude"),
        ([f64::INFINITY, 11.0, 0.0], "hat_hot_request.latitude"),
    ] {
        let bad = HatHotRequest { point, ..hat_hot() };
        let r = rejected(bad.encode(v, O).to_vec(), name);
        assert_eq!((r.packet_id, r.request_id), (HAT_HOT_REQUEST_ID, Some(31)));
        // NaN != NaN: compare the request's bytes, which keep every field.
        let back = r.request.expect("the request decoded").encode(v, O);
        assert_eq!(back, bad.encode(v, O).to_vec());
        assert_eq!(field(&r.error), name);
        assert_eq!(r.error.reason(), DropReason::Invalid);
    }
    // Entity-relative offsets have no latitude range, only finiteness.
    let rel = HatHotRequest {
        coordinate_system: CoordinateSystem::Entity,
        point: [500.0, 1e6, -20.0],
        ..hat_hot()
    };
    accepted(rel.encode(v, O).to_vec());
    let rel_nan = HatHotRequest {
        point: [500.0, f64::NAN, -20.0],
        ..rel
    };
    rejected(rel_nan.encode(v, O).to_vec(), "hat_hot_request.y_offset");
    // The reserved request type 3 is named, and the ID still comes back.
    let mut b = hat_hot().encode(v, O);
    b[4] |= 0x03;
    let r = rejected(b.to_vec(), "request type 3 is reserved");
    assert_eq!(r.request_id, Some(31));
    assert_eq!(r.request, None, "a reserved type cannot be decoded");
    assert_eq!(r.error.reason(), DropReason::Malformed);
}

#[test]
fn los_requests_are_checked() {
    let v = CigiVersion::V3_2;
    let seg = LosSegmentRequest {
        request_id: 8,
        source: [47.0, 11.0, 3000.0],
        destination: [47.1, 11.1, 1000.0],
        update_period: 1,
        ..LosSegmentRequest::default()
    };
    assert_eq!(
        accepted(seg.encode(v, O).to_vec()).requests,
        vec![CigiRequest::LosSegment(seg)]
    );
    let bad = LosSegmentRequest {
        destination: [47.1, -181.0, 1000.0],
        ..seg
    };
    let r = rejected(
        bad.encode(v, O).to_vec(),
        "los_segment_request.destination_longitude",
    );
    assert_eq!(r.request_id, Some(8));
    let rel = LosSegmentRequest {
        destination_coordinate_system: CoordinateSystem::Entity,
        ..bad
    };
    accepted(rel.encode(v, O).to_vec());

    let vec_ok = LosVectorRequest {
        request_id: 9,
        azimuth_deg: -179.0,
        elevation_deg: -5.0,
        min_range_m: 10.0,
        max_range_m: 10_000.0,
        source: [47.0, 11.0, 3000.0],
        ..LosVectorRequest::default()
    };
    accepted(vec_ok.encode(v, O).to_vec());
    for (bad, name) in [
        (
            LosVectorRequest {
                azimuth_deg: 181.0,
                ..vec_ok
            },
            "los_vector_request.azimuth",
        ),
        (
            LosVectorRequest {
                elevation_deg: -90.5,
                ..vec_ok
            },
            "los_vector_request.elevation",
        ),
        (
            LosVectorRequest {
                min_range_m: -1.0,
                ..vec_ok
            },
            "los_vector_request.min_range",
        ),
        (
            LosVectorRequest {
                max_range_m: 5.0,
                ..vec_ok
            },
            "los_vector_request.max_range",
        ),
        (
            LosVectorRequest {
                max_range_m: f32::NAN,
                ..vec_ok
            },
            "los_vector_request.max_range",
        ),
        (
            LosVectorRequest {
                source: [91.0, 11.0, 0.0],
                ..vec_ok
            },
            "los_vector_request.source_latitude",
        ),
    ] {
        let r = rejected(bad.encode(v, O).to_vec(), name);
        assert_eq!(
            (r.packet_id, r.request_id),
            (LOS_VECTOR_REQUEST_ID, Some(9))
        );
        assert!(matches!(r.request, Some(CigiRequest::LosVector(x)) if x.request_id == 9));
        assert_eq!(field(&r.error), name);
    }
}

#[test]
fn entities_and_environment_are_checked() {
    let other = EntityControl {
        entity_id: 5,
        entity_state: 1,
        yaw_deg: 10.0,
        lat_deg: 47.0,
        lon_deg: 11.0,
        ..EntityControl::default()
    };
    let m = accepted(other.encode(O).to_vec());
    assert_eq!(m.entities.len(), 2);
    for (bad, name) in [
        (
            EntityControl {
                roll_deg: f32::NAN,
                ..other
            },
            "entity_control.roll",
        ),
        (
            EntityControl {
                yaw_deg: -1.0,
                ..other
            },
            "entity_control.yaw",
        ),
        (
            EntityControl {
                lat_deg: 90.5,
                ..other
            },
            "entity_control.latitude",
        ),
        (
            EntityControl {
                entity_state: 3,
                ..other
            },
            "entity_control.entity_state",
        ),
    ] {
        let r = rejected(bad.encode(O).to_vec(), name);
        assert_eq!((r.packet_id, r.request_id), (ENTITY_CONTROL_ID, None));
    }
    // Attached entities carry offsets, not latitudes.
    let attached = EntityControl {
        attached: true,
        lat_deg: 120.0,
        ..other
    };
    accepted(attached.encode(O).to_vec());

    let clamp = ConformalClampedEntityControl {
        entity_id: 3,
        yaw_deg: 45.0,
        lat_deg: 47.0,
        lon_deg: 11.0,
    };
    accepted(clamp.encode(O).to_vec());
    rejected(
        ConformalClampedEntityControl {
            lon_deg: 200.0,
            ..clamp
        }
        .encode(O)
        .to_vec(),
        "conformal_clamped_entity_control.longitude",
    );
    let rate = RateControl {
        entity_id: 3,
        angular_deg_s: [0.0, f32::INFINITY, 0.0],
        ..RateControl::default()
    };
    rejected(
        rate.encode(CigiVersion::V3_3, O).to_vec(),
        "rate_control.pitch_rate",
    );

    let sky = CelestialSphereControl {
        hour: 23,
        minute: 59,
        date_valid: true,
        month: 12,
        day: 31,
        year: 2026,
        star_field_intensity_pct: 100.0,
        ..CelestialSphereControl::default()
    };
    assert_eq!(accepted(sky.encode(O).to_vec()).celestial, Some(sky));
    for (bad, name) in [
        (
            CelestialSphereControl { hour: 24, ..sky },
            "celestial_sphere_control.hour",
        ),
        (
            CelestialSphereControl { minute: 60, ..sky },
            "celestial_sphere_control.minute",
        ),
        (
            CelestialSphereControl { month: 13, ..sky },
            "celestial_sphere_control.date.month",
        ),
        (
            CelestialSphereControl { day: 0, ..sky },
            "celestial_sphere_control.date.day",
        ),
        (
            CelestialSphereControl {
                star_field_intensity_pct: 100.5,
                ..sky
            },
            "celestial_sphere_control.star_field_intensity",
        ),
    ] {
        rejected(bad.encode(O).to_vec(), name);
    }
    // An invalid date is not checked when the host says the date is not valid.
    let undated = CelestialSphereControl {
        date_valid: false,
        month: 0,
        day: 0,
        ..sky
    };
    accepted(undated.encode(O).to_vec());
    // The largest MMDDYYYY a u32 holds decodes to month 4294, which is rejected, not wrapped.
    let mut b = sky.encode(O);
    b[8..12].copy_from_slice(&u32::MAX.to_be_bytes());
    rejected(b.to_vec(), "celestial_sphere_control.date.month");

    let air = AtmosphereControl {
        humidity_pct: 100,
        visibility_m: 0.0,
        wind_direction_deg: 360.0,
        barometric_pressure_mbar: 1013.0,
        ..AtmosphereControl::default()
    };
    assert_eq!(accepted(air.encode(O).to_vec()).atmosphere, Some(air));
    for (bad, name) in [
        (
            AtmosphereControl {
                humidity_pct: 101,
                ..air
            },
            "atmosphere_control.humidity",
        ),
        (
            AtmosphereControl {
                visibility_m: -1.0,
                ..air
            },
            "atmosphere_control.visibility_range",
        ),
        (
            AtmosphereControl {
                wind_direction_deg: 360.5,
                ..air
            },
            "atmosphere_control.wind_direction",
        ),
        (
            AtmosphereControl {
                air_temperature_c: f32::NAN,
                ..air
            },
            "atmosphere_control.air_temperature",
        ),
        (
            AtmosphereControl {
                barometric_pressure_mbar: -0.5,
                ..air
            },
            "atmosphere_control.barometric_pressure",
        ),
    ] {
        rejected(bad.encode(O).to_vec(), name);
    }
}

#[test]
fn a_bad_ownship_still_drops_the_whole_message() {
    let mut b = ig(CigiVersion::V3_0);
    b.extend(
        EntityControl {
            lat_deg: 95.0,
            ..EntityControl::default()
        }
        .encode(O),
    );
    b.extend(hat_hot().encode(CigiVersion::V3_0, O));
    let e = decode(&b).unwrap_err();
    assert!(matches!(
        e,
        DecodeError::Invalid {
            error: PoseError::OutOfRange { .. },
            ..
        }
    ));
}

#[test]
fn the_version_comes_from_the_ig_control() {
    let base = IgControl::default().encode(O);
    for (nibble, want) in [
        (0u8, CigiVersion::V3_2),
        (1, CigiVersion::V3_2),
        (2, CigiVersion::V3_2),
        (3, CigiVersion::V3_3),
        (7, CigiVersion::V3_3),
        (15, CigiVersion::V3_3),
    ] {
        let mut b = base;
        b[4] = (b[4] & 0x0F) | (nibble << 4);
        let m = decode(&b).unwrap();
        assert_eq!(m.version, want, "nibble {nibble}");
        assert_eq!(m.ig_control.minor_version, nibble, "kept as written");
        assert_eq!(m.answer(1, 2).len(), 24);
    }
    // A 16-byte IG Control is 3.0 (3.1 writes the same bytes), whatever its reserved nibble.
    let short = IgControl {
        smoothing: true,
        last_ig_frame: 9,
        host_frame: 5,
        ..IgControl::default()
    }
    .encode_as(CigiVersion::V3_1, O);
    assert_eq!(short.len(), 16);
    assert_eq!(
        short,
        IgControl {
            host_frame: 5,
            ..IgControl::default()
        }
        .encode_as(CigiVersion::V3_0, O)
    );
    let mut reserved = short.clone();
    reserved[4] |= 0x30;
    for b in [short, reserved] {
        let m = decode(&b).unwrap();
        assert_eq!(m.version, CigiVersion::V3_0);
        assert_eq!(m.ig_control.host_frame, 5);
        assert!(!m.ig_control.smoothing);
        assert_eq!(m.ig_control.last_ig_frame, 0);
        // Answered with a 16-byte Start of Frame: no minor version, no last host frame.
        let sof = m.answer(3, 4);
        assert_eq!(sof.len(), 16);
        assert_eq!((sof[0], sof[1], sof[2], sof[5] >> 4), (101, 16, 3, 0));
    }
    // 3.2 and 3.3 answers carry their own minor version and the host frame.
    for v in [CigiVersion::V3_2, CigiVersion::V3_3] {
        for o in [ByteOrder::Little, ByteOrder::Big] {
            let m = decode(
                &IgControl {
                    host_frame: 0xABCD,
                    ..IgControl::default()
                }
                .encode_as(v, o),
            )
            .unwrap();
            let sof = m.answer(3, 4);
            assert_eq!(sof[5] >> 4, v.minor());
            let (s, sv, so) = StartOfFrame::decode_with_version(&sof).unwrap();
            assert_eq!((s.last_host_frame, sv, so), (0xABCD, v, o));
        }
    }
}

#[test]
fn framing_errors_name_their_offset() {
    let what = |b: &[u8]| match decode(b).unwrap_err() {
        DecodeError::Malformed { what, .. } => what,
        other => panic!("{other}"),
    };
    // IG Control of neither size, or cut short of its size.
    let mut b = ig(CigiVersion::V3_3);
    b[1] = 20;
    assert!(what(&b).contains("size byte is 20"));
    let b = ig(CigiVersion::V3_0);
    assert_eq!(
        decode(&b[..12]).unwrap_err(),
        DecodeError::BadSize {
            protocol: crate::codec::Protocol::Cigi,
            len: 12,
            expected: 16
        }
    );
    let b = ig(CigiVersion::V3_2);
    assert_eq!(decode(&b[..20]).unwrap_err().reason(), DropReason::BadSize);
    // A known packet with another size: the message is dropped, the offset named.
    for v in CigiVersion::ALL {
        let mut req = hat_hot().encode(v, O).to_vec();
        req[1] = 24;
        req.truncate(24);
        let s = usize::from(v.ig_control_size()) + 48;
        assert!(
            what(&msg(v, &[req]))
                .contains(&format!("packet 24 at offset {s} has size 24, expected 32")),
            "{v}"
        );
    }
    // A packet running past the end, a size below 2, a cut header.
    let mut cut = hat_hot().encode(CigiVersion::V3_3, O).to_vec();
    cut.truncate(20);
    assert!(what(&msg(CigiVersion::V3_3, &[cut])).contains("runs past the end"));
    assert!(what(&msg(CigiVersion::V3_3, &[vec![26, 1]])).contains("has size 1"));
    assert!(what(&msg(CigiVersion::V3_3, &[vec![26]])).contains("header cut at offset 72"));
    // A second IG Control is left out, not obeyed.
    let m = decode(&msg(CigiVersion::V3_3, &[ig(CigiVersion::V3_3)])).unwrap();
    assert_eq!(m.rejected.len(), 1);
    assert_eq!(m.rejected[0].packet_id, IG_CONTROL_ID);
    assert_eq!(m.ig_control.host_frame, 77);
}

#[test]
fn ig_messages_with_broken_answers_are_errors() {
    let v = CigiVersion::V3_3;
    let mut b = StartOfFrame::default().encode(v, O);
    b.extend(LosResponse::default().encode(v, O));
    let m = decode_ig_message(&b).unwrap();
    assert_eq!(m.responses.len(), 1);
    b.extend([104, 12, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
    assert!(decode_ig_message(&b).is_err(), "a 12-byte LOS Response");
    assert!(decode_ig_message(&[101, 20, 3]).is_err());
    assert!(decode_ig_message(&b[..10]).is_err());
}
