//! aerie against the CCL's own bytes (`ccl_bytes.rs`): every reference packet decodes to the
//! values the generator set, and aerie encodes those values to exactly the CCL's bytes, in
//! both byte orders and in the version the vector was packed for.

use super::super::*;
use super::any::Any;
use super::ccl_bytes::VECTORS;
use crate::codec::wire::ByteOrder;

pub(super) fn hex(s: &str) -> Vec<u8> {
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap())
        .collect()
}

/// The vector's bytes in `order`.
pub(super) fn vector(name: &str, order: ByteOrder) -> Vec<u8> {
    let (_, le, be) = VECTORS
        .iter()
        .find(|(n, _, _)| *n == name)
        .unwrap_or_else(|| panic!("no vector {name}"));
    hex(match order {
        ByteOrder::Little => le,
        ByteOrder::Big => be,
    })
}

/// The values `ccl_vectors.cpp` put in each packet (every field the newest version has; the
/// older versions' vectors are compared with what survives in them, [`Any::as_in`]).
pub(super) fn generator_values(kind: &str) -> Any {
    match kind {
        "ig_control" => Any::Ig(IgControl {
            database: -3,
            ig_mode: 2,
            timestamp_valid: true,
            smoothing: true,
            minor_version: 3,
            host_frame: 0x0102_0304,
            timestamp: 123_456,
            last_ig_frame: 0xA0B0_C0D0,
        }),
        "start_of_frame" => Any::Sof(StartOfFrame {
            database: -2,
            ig_status: 7,
            ig_mode: 1,
            timestamp_valid: true,
            earth_reference_model: 0,
            ig_frame: 42,
            timestamp: 0x0102_0304,
            last_host_frame: 12345,
        }),
        "entity_control" => Any::Entity(EntityControl {
            entity_id: 0x1234,
            entity_state: 1,
            attached: true,
            collision_detection: true,
            inherit_alpha: false,
            ground_clamp: 2,
            animation_backward: true,
            animation_loop: true,
            animation_state: 2,
            smoothing: true,
            alpha: 200,
            entity_type: 0x0102,
            parent_id: 7,
            roll_deg: -10.5,
            pitch_deg: 2.25,
            yaw_deg: 270.0,
            lat_deg: 45.5,
            lon_deg: -122.25,
            alt_m: 1500.125,
        }),
        "conformal_clamped" => Any::Clamp(ConformalClampedEntityControl {
            entity_id: 77,
            yaw_deg: 123.5,
            lat_deg: -33.875,
            lon_deg: 151.25,
        }),
        "rate_control" => Any::Rate(RateControl {
            entity_id: 9,
            articulated_part_id: 3,
            apply_to_articulated_part: true,
            frame: RateFrame::Local,
            linear_m_s: [1.5, -2.5, 0.25],
            angular_deg_s: [10.0, -20.0, 30.0],
        }),
        "celestial" => Any::Celestial(CelestialSphereControl {
            hour: 14,
            minute: 35,
            ephemeris_enabled: true,
            sun_enabled: true,
            moon_enabled: false,
            star_field_enabled: true,
            date_valid: true,
            month: 6,
            day: 21,
            year: 2026,
            star_field_intensity_pct: 55.5,
        }),
        "atmosphere" => Any::Atmosphere(AtmosphereControl {
            atmospheric_model_enabled: true,
            humidity_pct: 65,
            air_temperature_c: -5.5,
            visibility_m: 25_000.0,
            horizontal_wind_m_s: 12.5,
            vertical_wind_m_s: -1.25,
            wind_direction_deg: 270.0,
            barometric_pressure_mbar: 1013.25,
        }),
        "hat_hot_request" => Any::HatHotReq(HatHotRequest {
            request_id: 0xBEEF,
            request_type: HatHotRequestType::Extended,
            coordinate_system: CoordinateSystem::Geodetic,
            update_period: 3,
            entity_id: 5,
            point: [47.25, 11.375, 2000.5],
        }),
        "hat_hot_response" => Any::Resp(CigiResponse::HatHot(HatHotResponse {
            request_id: 0xBEEF,
            valid: true,
            response_type: HatHotResponseType::Hot,
            host_frame_lsn: 0xB,
            height_m: 1234.5,
        })),
        "hat_hot_extended_response" => {
            Any::Resp(CigiResponse::HatHotExtended(HatHotExtendedResponse {
                request_id: 0xBEEF,
                valid: true,
                host_frame_lsn: 9,
                hat_m: 765.25,
                hot_m: 1234.75,
                material_code: 0,
                normal_azimuth_deg: 30.5,
                normal_elevation_deg: 80.25,
            }))
        }
        "los_segment_request" => Any::LosSegReq(LosSegmentRequest {
            request_id: 0x0102,
            request_type: LosRequestType::Extended,
            source_coordinate_system: CoordinateSystem::Geodetic,
            destination_coordinate_system: CoordinateSystem::Entity,
            response_coordinate_system: CoordinateSystem::Entity,
            destination_entity_id_valid: true,
            alpha_threshold: 128,
            entity_id: 3,
            source: [46.5, 7.25, 3000.0],
            destination: [10.5, -20.25, 5.0],
            material_mask: 0xF0F0_0001,
            update_period: 2,
            destination_entity_id: 0x4321,
        }),
        "los_vector_request" => Any::LosVecReq(LosVectorRequest {
            request_id: 0x0A0B,
            request_type: LosRequestType::Basic,
            source_coordinate_system: CoordinateSystem::Entity,
            response_coordinate_system: CoordinateSystem::Geodetic,
            alpha_threshold: 10,
            entity_id: 4,
            azimuth_deg: -45.5,
            elevation_deg: -10.25,
            min_range_m: 1.5,
            max_range_m: 10_000.0,
            source: [1.0, 2.0, -3.0],
            material_mask: 0xFFFF_FFFF,
            update_period: 4,
        }),
        "los_response" => Any::Resp(CigiResponse::Los(LosResponse {
            request_id: 0x0102,
            valid: true,
            entity_id_valid: false,
            visible: false,
            host_frame_lsn: 5,
            response_count: 1,
            entity_id: 0,
            range_m: 4321.125,
        })),
        "los_extended_response" => Any::Resp(CigiResponse::LosExtended(LosExtendedResponse {
            request_id: 0x0102,
            valid: true,
            entity_id_valid: true,
            range_valid: true,
            visible: false,
            point_coordinate_system: CoordinateSystem::Entity,
            host_frame_lsn: 0xE,
            response_count: 1,
            entity_id: 12,
            range_m: 987.5,
            point: [10.5, -4.25, 2.0],
            rgba: [1, 2, 3, 4],
            material_code: 0,
            normal_azimuth_deg: -90.5,
            normal_elevation_deg: 45.25,
        })),
        "view_control" => Any::ViewCtrl(ViewControl {
            view_id: 2,
            group_id: 1,
            enable: 0x3F,
            entity_id: 0,
            offset_m: [1.5, -0.5, 0.25],
            roll_pitch_yaw_deg: [0.0, -5.0, 60.0],
        }),
        "view_definition" => Any::ViewDef(ViewDefinition {
            view_id: 2,
            group_id: 1,
            enable: 0x0F,
            mirror_mode: 2,
            pixel_replication: 3,
            orthographic: true,
            reorder: true,
            view_type: 5,
            near_m: 0.5,
            far_m: 50_000.0,
            left_deg: -30.0,
            right_deg: 30.0,
            top_deg: 20.0,
            bottom_deg: -20.0,
        }),
        other => panic!("no generator values for {other}"),
    }
}

/// "hat_hot_request_3_2" → ("hat_hot_request", 3.2).
fn split(name: &str) -> (&str, CigiVersion) {
    let (kind, minor) = name.rsplit_once("_3_").unwrap();
    (
        kind,
        CigiVersion::from_minor(minor.parse().unwrap()).unwrap(),
    )
}

#[test]
fn every_ccl_vector_decodes_to_the_generator_values_and_encodes_back() {
    let mut kinds = std::collections::BTreeSet::new();
    for (name, _, _) in VECTORS {
        let (kind, v) = split(name);
        kinds.insert(kind);
        let want = generator_values(kind).as_in(v);
        for order in [ByteOrder::Little, ByteOrder::Big] {
            let bytes = vector(name, order);
            let got = want
                .decode_like(&bytes, v, order)
                .unwrap_or_else(|e| panic!("{name} {order:?}: {e}"));
            assert_eq!(got, want, "{name} {order:?} decoded");
            assert_eq!(want.encode(v, order), bytes, "{name} {order:?} encoded");
            if v == CigiVersion::V3_0 {
                // 3.1 has 3.0's bytes for every one of these packets.
                assert_eq!(
                    want.encode(CigiVersion::V3_1, order),
                    bytes,
                    "{name} as 3.1"
                );
            }
        }
    }
    // Every packet type aerie reads or writes has a CCL vector.
    assert_eq!(kinds.len(), 16, "{kinds:?}");
}

#[test]
fn the_3_3_vectors_also_stand_for_3_2_where_the_layouts_agree() {
    // A 3.2-packed packet of a class without a 3.3 variant is the 3.3 packet too.
    for kind in [
        "rate_control",
        "hat_hot_request",
        "hat_hot_response",
        "hat_hot_extended_response",
        "los_segment_request",
        "los_vector_request",
        "los_response",
        "los_extended_response",
    ] {
        let want = generator_values(kind).as_in(CigiVersion::V3_3);
        for order in [ByteOrder::Little, ByteOrder::Big] {
            let bytes = vector(&format!("{kind}_3_2"), order);
            assert_eq!(want.encode(CigiVersion::V3_3, order), bytes, "{kind}");
        }
    }
}

#[test]
fn ccl_ig_controls_set_the_message_version() {
    for (name, v) in [
        ("ig_control_3_0", CigiVersion::V3_0),
        ("ig_control_3_2", CigiVersion::V3_2),
        ("ig_control_3_3", CigiVersion::V3_3),
    ] {
        for order in [ByteOrder::Little, ByteOrder::Big] {
            let m = decode(&vector(name, order)).unwrap();
            assert_eq!((m.version, m.byte_order), (v, order), "{name}");
            assert_eq!(m.ig_control.host_frame, 0x0102_0304);
            assert_eq!(m.ig_control.mode(), IgMode::Debug);
            // The answer is a Start of Frame of the host's version, byte for byte the CCL's
            // layout (the CCL's own SOF vector holds other values, so compare sizes and
            // the fields aerie put in).
            let sof = m.answer(42, 0x0102_0304);
            assert_eq!(sof.len(), usize::from(v.start_of_frame_size()));
            let (s, sv, so) = StartOfFrame::decode_with_version(&sof).unwrap();
            assert_eq!((sv, so), (v, order));
            assert_eq!(s.ig_frame, 42);
            let last = if v.is_3_2_or_later() { 0x0102_0304 } else { 0 };
            assert_eq!(s.last_host_frame, last);
        }
    }
}

#[test]
fn a_message_of_ccl_packets_decodes_whole() {
    for (v, ig, ent, rate) in [
        (
            CigiVersion::V3_0,
            "ig_control_3_0",
            "entity_control_3_0",
            "rate_control_3_0",
        ),
        (
            CigiVersion::V3_2,
            "ig_control_3_2",
            "entity_control_3_0",
            "rate_control_3_2",
        ),
        (
            CigiVersion::V3_3,
            "ig_control_3_3",
            "entity_control_3_3",
            "rate_control_3_2",
        ),
    ] {
        let s = if v.is_3_2_or_later() { "_3_2" } else { "_3_0" };
        for order in [ByteOrder::Little, ByteOrder::Big] {
            let names = [
                ig.to_string(),
                ent.to_string(),
                "conformal_clamped_3_0".into(),
                rate.to_string(),
                "celestial_3_0".into(),
                "atmosphere_3_0".into(),
                "view_control_3_0".into(),
                "view_definition_3_0".into(),
                format!("hat_hot_request{s}"),
                format!("los_segment_request{s}"),
                format!("los_vector_request{s}"),
            ];
            let bytes: Vec<u8> = names.iter().flat_map(|n| vector(n, order)).collect();
            let m = decode(&bytes).unwrap_or_else(|e| panic!("{v} {order:?}: {e}"));
            assert_eq!(m.version, v);
            assert!(m.rejected.is_empty(), "{:?}", m.rejected);
            assert_eq!(m.skipped, 0);
            assert_eq!(m.packet_counts.total(), names.len() as u64);
            let Any::Entity(e) = generator_values("entity_control").as_in(v) else {
                unreachable!()
            };
            assert_eq!(m.entities, vec![e]);
            assert_eq!(m.ownship, None, "entity 0x1234 is not the ownship");
            assert_eq!(m.conformal_clamped.len(), 1);
            assert_eq!(m.rate_controls.len(), 1);
            assert_eq!(m.celestial.map(|c| c.date_mmddyyyy()), Some(6_212_026));
            assert_eq!(m.atmosphere.map(|a| a.visibility_m), Some(25_000.0));
            assert_eq!((m.view_controls.len(), m.view_definitions.len()), (1, 1));
            let ids: Vec<_> = m.requests.iter().map(|r| r.request_id()).collect();
            assert_eq!(ids, [0xBEEF, 0x0102, 0x0A0B]);
            let periods: Vec<_> = m.requests.iter().map(|r| r.update_period()).collect();
            let want = if v.is_3_2_or_later() {
                [3, 2, 4]
            } else {
                [0, 0, 0]
            };
            assert_eq!(periods, want);
        }
    }
}

#[test]
fn an_ig_message_of_ccl_packets_decodes_as_a_host_reads_it() {
    for (v, sof, s) in [
        (CigiVersion::V3_0, "start_of_frame_3_0", "_3_0"),
        (CigiVersion::V3_2, "start_of_frame_3_2", "_3_2"),
        (CigiVersion::V3_3, "start_of_frame_3_3", "_3_2"),
    ] {
        for order in [ByteOrder::Little, ByteOrder::Big] {
            let kinds = [
                "hat_hot_response",
                "hat_hot_extended_response",
                "los_response",
                "los_extended_response",
            ];
            let mut bytes = vector(sof, order);
            for k in kinds {
                bytes.extend(vector(&format!("{k}{s}"), order));
            }
            let m = decode_ig_message(&bytes).unwrap_or_else(|e| panic!("{v}: {e}"));
            assert_eq!((m.version, m.byte_order), (v, order));
            let want: Vec<CigiResponse> = kinds
                .iter()
                .map(|k| match generator_values(k).as_in(v) {
                    Any::Resp(r) => r,
                    _ => unreachable!(),
                })
                .collect();
            assert_eq!(m.responses, want);
            assert_eq!(m.packet_counts.get(START_OF_FRAME_ID), 1);
            assert_eq!(m.packet_counts.total(), 5);
        }
    }
}
