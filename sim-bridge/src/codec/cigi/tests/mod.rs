//! Golden bytes written by hand from the CIGI 3.3 ICD field tables (packet ID, size, then
//! each field at its byte offset), in both byte orders.
use super::*;
use crate::codec::wire::ByteOrder;
use crate::pose::PosePosition;
use crate::stats::DropReason;

/// IG Control, big-endian: database 5, IG mode Operate, timestamp valid, minor version 3,
/// host frame 12345 (0x3039), timestamp 123456 (0x0001E240), last IG frame 7.
const IG_CONTROL_BE: [u8; 24] = [
    0x01, 0x18, // 0: packet ID 1, 1: size 24
    0x03, // 2: major version 3
    0x05, // 3: database number 5
    0x35, // 4: minor version 3 << 4 | timestamp valid 0x04 | IG mode 1
    0x00, // 5: reserved
    0x80, 0x00, // 6: byte-swap magic 0x8000, big-endian
    0x00, 0x00, 0x30, 0x39, // 8: host frame number
    0x00, 0x01, 0xE2, 0x40, // 12: timestamp (10 µs ticks)
    0x00, 0x00, 0x00, 0x07, // 16: last IG frame number
    0x00, 0x00, 0x00, 0x00, // 20: reserved
];

/// The same IG Control as a little-endian host writes it.
const IG_CONTROL_LE: [u8; 24] = [
    0x01, 0x18, 0x03, 0x05, 0x35, 0x00, //
    0x00, 0x80, // magic 0x8000 little-endian: a big-endian reader sees 0x0080
    0x39, 0x30, 0x00, 0x00, //
    0x40, 0xE2, 0x01, 0x00, //
    0x07, 0x00, 0x00, 0x00, //
    0x00, 0x00, 0x00, 0x00,
];

/// Entity Control for entity 0, big-endian: active, alpha 255, type 0x0102, parent 0,
/// roll −10.0 (0xC1200000), pitch 2.5 (0x40200000), yaw 90.0 (0x42B40000),
/// lat 45.0 (0x4046800000000000), lon 11.0 (0x4026000000000000), alt 1500.0 (0x4097700000000000).
const ENTITY_BE: [u8; 48] = [
    0x02, 0x30, // 0: packet ID 2, 1: size 48
    0x00, 0x00, // 2: entity ID 0
    0x01, // 4: entity state active (bits 0-1), attach 0 (bit 2)
    0x00, // 5: animation flags
    0xFF, // 6: alpha
    0x00, // 7: reserved
    0x01, 0x02, // 8: entity type
    0x00, 0x00, // 10: parent ID
    0xC1, 0x20, 0x00, 0x00, // 12: roll
    0x40, 0x20, 0x00, 0x00, // 16: pitch
    0x42, 0xB4, 0x00, 0x00, // 20: yaw
    0x40, 0x46, 0x80, 0x00, 0x00, 0x00, 0x00, 0x00, // 24: latitude
    0x40, 0x26, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, // 32: longitude
    0x40, 0x97, 0x70, 0x00, 0x00, 0x00, 0x00, 0x00, // 40: altitude
];

fn reversed_fields(be: &[u8], widths: &[usize]) -> Vec<u8> {
    // Re-writes a big-endian packet little-endian, field by field.
    let mut out = Vec::new();
    let mut off = 0;
    for &w in widths {
        out.extend(be[off..off + w].iter().rev());
        off += w;
    }
    assert_eq!(off, be.len());
    out
}

const ENTITY_WIDTHS: [usize; 15] = [1, 1, 2, 1, 1, 1, 1, 2, 2, 4, 4, 4, 8, 8, 8];

/// View Control, big-endian: view 2, group 1, all six enables, entity 0,
/// x 1.5 (0x3FC00000), y −0.5 (0xBF000000), z 0.25 (0x3E800000),
/// roll 0, pitch −5.0 (0xC0A00000), yaw 60.0 (0x42700000).
const VIEW_CONTROL_BE: [u8; 32] = [
    0x10, 0x20, // 0: packet ID 16, 1: size 32
    0x00, 0x02, // 2: view ID
    0x01, // 4: group ID
    0x3F, // 5: enables x, y, z, roll, pitch, yaw
    0x00, 0x00, // 6: entity ID
    0x3F, 0xC0, 0x00, 0x00, // 8: x offset
    0xBF, 0x00, 0x00, 0x00, // 12: y offset
    0x3E, 0x80, 0x00, 0x00, // 16: z offset
    0x00, 0x00, 0x00, 0x00, // 20: roll
    0xC0, 0xA0, 0x00, 0x00, // 24: pitch
    0x42, 0x70, 0x00, 0x00, // 28: yaw
];

/// View Definition, big-endian: view 2, group 1, near/far/left/right/top/bottom enabled,
/// mirror none, perspective; near 0.5 (0x3F000000), far 50000 (0x47435000),
/// left −30 (0xC1F00000), right 30 (0x41F00000), top 20 (0x41A00000), bottom −20 (0xC1A00000).
const VIEW_DEFINITION_BE: [u8; 32] = [
    0x15, 0x20, // 0: packet ID 21, 1: size 32
    0x00, 0x02, // 2: view ID
    0x01, // 4: group ID
    0x3F, // 5: enables (bits 0-5), mirror mode 0 (bits 6-7)
    0x00, // 6: pixel replication 0, projection perspective, reorder 0, view type 0
    0x00, // 7: reserved
    0x3F, 0x00, 0x00, 0x00, // 8: near
    0x47, 0x43, 0x50, 0x00, // 12: far
    0xC1, 0xF0, 0x00, 0x00, // 16: left
    0x41, 0xF0, 0x00, 0x00, // 20: right
    0x41, 0xA0, 0x00, 0x00, // 24: top
    0xC1, 0xA0, 0x00, 0x00, // 28: bottom
];

const VIEW_WIDTHS: [usize; 12] = [1, 1, 2, 1, 1, 2, 4, 4, 4, 4, 4, 4];
const VIEW_DEF_WIDTHS: [usize; 13] = [1, 1, 2, 1, 1, 1, 1, 4, 4, 4, 4, 4, 4];

fn expected_ig() -> IgControl {
    IgControl {
        database: 5,
        ig_mode: 1,
        timestamp_valid: true,
        smoothing: false,
        minor_version: 3,
        host_frame: 12345,
        timestamp: 123_456,
        last_ig_frame: 7,
    }
}

fn expected_entity() -> EntityControl {
    EntityControl {
        entity_id: 0,
        entity_state: 1,
        attached: false,
        alpha: 255,
        entity_type: 0x0102,
        parent_id: 0,
        roll_deg: -10.0,
        pitch_deg: 2.5,
        yaw_deg: 90.0,
        lat_deg: 45.0,
        lon_deg: 11.0,
        alt_m: 1500.0,
        ..EntityControl::default()
    }
}

fn message(parts: &[&[u8]]) -> Vec<u8> {
    parts.concat()
}

fn le_entity() -> Vec<u8> {
    reversed_fields(&ENTITY_BE, &ENTITY_WIDTHS)
}

#[test]
fn golden_ig_control_both_orders() {
    assert_eq!(expected_ig().encode(ByteOrder::Big), IG_CONTROL_BE);
    assert_eq!(expected_ig().encode(ByteOrder::Little), IG_CONTROL_LE);
    for (bytes, order) in [
        (IG_CONTROL_BE, ByteOrder::Big),
        (IG_CONTROL_LE, ByteOrder::Little),
    ] {
        let m = decode(&bytes).unwrap();
        assert_eq!(m.byte_order, order);
        assert_eq!(m.ig_control, expected_ig());
        assert_eq!(m.ownship, None);
        assert_eq!(m.ownship_pose(), None);
    }
}

#[test]
fn golden_entity_control_both_orders() {
    assert_eq!(expected_entity().encode(ByteOrder::Big), ENTITY_BE);
    assert_eq!(
        expected_entity().encode(ByteOrder::Little).to_vec(),
        le_entity()
    );
    for (ig, ent) in [
        (IG_CONTROL_BE.to_vec(), ENTITY_BE.to_vec()),
        (IG_CONTROL_LE.to_vec(), le_entity()),
    ] {
        let m = decode(&message(&[&ig, &ent])).unwrap();
        assert_eq!(m.ownship, Some(expected_entity()));
        let p = m.ownship_pose().unwrap();
        assert_eq!(
            p.position,
            PosePosition::Geodetic {
                lat_deg: 45.0,
                lon_deg: 11.0,
                alt_m: 1500.0
            }
        );
        assert_eq!(p.attitude_deg, [90.0, 2.5, -10.0]);
        assert_eq!(p.frame, 12345);
        assert!((p.sim_time_s - 1.23456).abs() < 1e-12);
    }
}

#[test]
fn golden_views_both_orders() {
    let vc = ViewControl {
        view_id: 2,
        group_id: 1,
        enable: 0x3F,
        entity_id: 0,
        offset_m: [1.5, -0.5, 0.25],
        roll_pitch_yaw_deg: [0.0, -5.0, 60.0],
    };
    let vd = ViewDefinition {
        view_id: 2,
        group_id: 1,
        enable: 0x3F,
        near_m: 0.5,
        far_m: 50_000.0,
        left_deg: -30.0,
        right_deg: 30.0,
        top_deg: 20.0,
        bottom_deg: -20.0,
        ..ViewDefinition::default()
    };
    assert_eq!(vc.encode(ByteOrder::Big), VIEW_CONTROL_BE);
    assert_eq!(vd.encode(ByteOrder::Big), VIEW_DEFINITION_BE);
    let vc_le = reversed_fields(&VIEW_CONTROL_BE, &VIEW_WIDTHS);
    let vd_le = reversed_fields(&VIEW_DEFINITION_BE, &VIEW_DEF_WIDTHS);
    assert_eq!(vc.encode(ByteOrder::Little).to_vec(), vc_le);
    assert_eq!(vd.encode(ByteOrder::Little).to_vec(), vd_le);
    for bytes in [
        message(&[&IG_CONTROL_BE, &VIEW_CONTROL_BE, &VIEW_DEFINITION_BE]),
        message(&[&IG_CONTROL_LE, &vc_le, &vd_le]),
    ] {
        let m = decode(&bytes).unwrap();
        assert_eq!(m.view_controls, vec![vc]);
        assert_eq!(m.view_definitions, vec![vd]);
        let mut t = ViewTable::default();
        assert!(t.apply(&m));
        assert!(!t.apply(&m), "same packets again change nothing");
        let v = t.get(2).unwrap();
        assert_eq!(v.offset_m, [Some(1.5), Some(-0.5), Some(0.25)]);
        assert_eq!(v.roll_pitch_yaw_deg, [Some(0.0), Some(-5.0), Some(60.0)]);
        assert_eq!(v.near_m(), Some(0.5));
        assert_eq!(v.far_m(), Some(50_000.0));
        assert_eq!(v.half_angles_deg(), Some([-30.0, 30.0, 20.0, -20.0]));
    }
}

#[test]
fn golden_start_of_frame_both_orders() {
    // Start of Frame: database 5, status 0, Operate, timestamp valid, WGS84, minor 3,
    // IG frame 42, timestamp 0x01020304, last host frame 12345.
    let be: [u8; 24] = [
        0x65, 0x18, // 0: packet ID 101, 1: size 24
        0x03, // 2: major version
        0x05, // 3: database number
        0x00, // 4: IG status
        0x35, // 5: minor 3 << 4 | earth model 0 (bit 3) | timestamp valid 0x04 | Operate 1
        0x80, 0x00, // 6: byte-swap magic
        0x00, 0x00, 0x00, 0x2A, // 8: IG frame number
        0x01, 0x02, 0x03, 0x04, // 12: timestamp
        0x00, 0x00, 0x30, 0x39, // 16: last host frame number
        0x00, 0x00, 0x00, 0x00, // 20: reserved
    ];
    let le = reversed_fields(&be, &[1, 1, 1, 1, 1, 1, 2, 4, 4, 4, 4]);
    let m = decode(&IG_CONTROL_BE).unwrap();
    assert_eq!(m.answer(42, 0x0102_0304), be);
    let m = decode(&IG_CONTROL_LE).unwrap();
    assert_eq!(m.answer(42, 0x0102_0304).to_vec(), le);
    let (sof, order) = StartOfFrame::decode(&le).unwrap();
    assert_eq!(order, ByteOrder::Little);
    assert_eq!(
        (sof.ig_frame, sof.last_host_frame, sof.ig_mode),
        (42, 12345, 1)
    );
    assert_eq!(StartOfFrame::decode(&be).unwrap().0, sof);
}

#[test]
fn every_packet_is_counted_and_unknown_ones_are_skipped_by_size() {
    // An 8-byte user-defined packet (ID 200), a 12-byte Component Control-sized packet of an
    // ID aerie does not read (4), a Celestial Sphere Control (9, all zeros: valid), and an
    // entity other than the ownship before the ownship.
    let mut other_entity = ENTITY_BE;
    other_entity[3] = 7;
    let unknown8 = [200u8, 8, 1, 2, 3, 4, 5, 6];
    let unknown12 = [4u8, 12, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0];
    let celestial = [9u8, 16, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0];
    let m = decode(&message(&[
        &IG_CONTROL_BE,
        &unknown8,
        &other_entity,
        &unknown12,
        &ENTITY_BE,
        &celestial,
        &unknown8,
    ]))
    .unwrap();
    assert_eq!(m.skipped, 3);
    assert_eq!(m.ownship, Some(expected_entity()));
    let ids: Vec<u16> = m.entities.iter().map(|e| e.entity_id).collect();
    assert_eq!(ids, [7, 0], "every entity, in message order");
    assert_eq!(m.celestial, Some(CelestialSphereControl::default()));
    assert_eq!(
        m.packet_counts.as_slice(),
        [(1, 1), (2, 2), (4, 1), (9, 1), (200, 2)]
    );
    assert_eq!(
        m.packet_counts.to_string(),
        "1 IG Control ×1, 2 Entity Control ×2, 4 Component Control ×1, \
         9 Celestial Sphere Control ×1, 200 user-defined ×2"
    );
}

#[test]
fn broken_messages_are_rejected_with_a_reason() {
    let reason = |b: &[u8]| decode(b).unwrap_err().reason();
    // Size byte 0 would loop forever; size past the end; cut header.
    assert_eq!(
        reason(&message(&[&IG_CONTROL_BE, &[50, 0]])),
        DropReason::Malformed
    );
    assert_eq!(
        reason(&message(&[&IG_CONTROL_BE, &[50, 16, 0]])),
        DropReason::Malformed
    );
    assert_eq!(
        reason(&message(&[&IG_CONTROL_BE, &[50]])),
        DropReason::Malformed
    );
    assert_eq!(
        reason(&message(&[&IG_CONTROL_BE, &ENTITY_BE[..40]])),
        DropReason::Malformed
    );
    // Known packet with the wrong size.
    let mut e = ENTITY_BE.to_vec();
    e[1] = 40;
    e.truncate(40);
    assert_eq!(
        reason(&message(&[&IG_CONTROL_BE, &e])),
        DropReason::Malformed
    );
    // Not starting with IG Control, wrong version, short, bad magic.
    assert_eq!(reason(&ENTITY_BE), DropReason::Malformed);
    let mut v2 = IG_CONTROL_BE;
    v2[2] = 2;
    assert_eq!(reason(&v2), DropReason::BadVersion);
    assert_eq!(reason(&IG_CONTROL_BE[..20]), DropReason::BadSize);
    let mut magic = IG_CONTROL_BE;
    magic[6] = 0x12;
    assert_eq!(reason(&magic), DropReason::Malformed);
    // Ownship out of range / not finite / attached.
    let mut lat = ENTITY_BE;
    lat[24..32].copy_from_slice(&95.0f64.to_be_bytes());
    assert_eq!(
        reason(&message(&[&IG_CONTROL_BE, &lat])),
        DropReason::Invalid
    );
    let mut roll = ENTITY_BE;
    roll[12..16].copy_from_slice(&f32::NAN.to_be_bytes());
    assert_eq!(
        reason(&message(&[&IG_CONTROL_BE, &roll])),
        DropReason::Invalid
    );
    let mut attached = ENTITY_BE;
    attached[4] |= 0x04;
    assert_eq!(
        reason(&message(&[&IG_CONTROL_BE, &attached])),
        DropReason::Unsupported
    );
    // A NaN in an enabled view field; the same NaN with the field disabled is fine.
    let mut vc = VIEW_CONTROL_BE;
    vc[24..28].copy_from_slice(&f32::NAN.to_be_bytes());
    assert_eq!(
        reason(&message(&[&IG_CONTROL_BE, &vc])),
        DropReason::Invalid
    );
    vc[5] = 0x2F;
    decode(&message(&[&IG_CONTROL_BE, &vc])).unwrap();
}

#[test]
fn disabled_view_fields_keep_their_values() {
    let mut t = ViewTable::default();
    let full = ViewControl {
        view_id: 1,
        enable: 0x3F,
        offset_m: [1.0, 2.0, 3.0],
        roll_pitch_yaw_deg: [4.0, 5.0, 6.0],
        ..ViewControl::default()
    };
    t.apply_control(&full);
    let yaw_only = ViewControl {
        view_id: 1,
        enable: view_enable::YAW,
        offset_m: [9.0; 3],
        roll_pitch_yaw_deg: [9.0, 9.0, -45.0],
        ..ViewControl::default()
    };
    assert!(t.apply_control(&yaw_only));
    let v = t.get(1).unwrap();
    assert_eq!(v.offset_m, [Some(1.0), Some(2.0), Some(3.0)]);
    assert_eq!(v.roll_pitch_yaw_deg, [Some(4.0), Some(5.0), Some(-45.0)]);
    // The table is bounded.
    for id in 0..200u16 {
        t.apply_control(&ViewControl {
            view_id: id,
            ..ViewControl::default()
        });
    }
    assert_eq!(t.views().len(), MAX_VIEWS);
    assert!(t.views().windows(2).all(|w| w[0].view_id < w[1].view_id));
}

mod any;
mod ccl;
mod ccl_bytes;
mod checks;
mod roundtrip;
