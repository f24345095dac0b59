use super::*;
use crate::stats::DropReason;
use proptest::prelude::*;

fn geo(lat_deg: f64, lon_deg: f64, alt_m: f64) -> PosePosition {
    PosePosition::Geodetic {
        lat_deg,
        lon_deg,
        alt_m,
    }
}

fn local(x: f64, y: f64, z: f64) -> PosePosition {
    PosePosition::LocalEnu { x, y, z }
}

fn requests() -> [TerrainRequest; 4] {
    [
        TerrainRequest::HeightOfTerrain {
            at: geo(47.25, 11.35, 2000.0),
        },
        TerrainRequest::LineOfSight {
            from: geo(47.25, 11.35, 2000.0),
            to: local(1.0, -2.0, 3.0),
        },
        TerrainRequest::LineOfSightVector {
            from: local(-500.0, 250.0, 1200.0),
            azimuth_deg: 45.0,
            elevation_deg: -5.0,
            min_range_m: 10.0,
            max_range_m: 10_000.0,
        },
        TerrainRequest::HeightOfTerrain {
            at: local(30_000.5, 12.0, 0.0),
        },
    ]
}

fn replies() -> Vec<TerrainReply> {
    let n = [0.6, 0.0, 0.8];
    vec![
        TerrainReply::HeightOfTerrain(Answer::Ready(Surface {
            height_m: 1234.5,
            normal_enu: n,
        })),
        TerrainReply::HeightOfTerrain(Answer::NoTerrain),
        TerrainReply::HeightOfTerrain(Answer::Pending),
        TerrainReply::LineOfSight(Answer::Ready(None)),
        TerrainReply::LineOfSight(Answer::Ready(Some(LosHit {
            range_m: 4321.25,
            point: geo(47.3, 11.4, 1800.0),
            normal_enu: [0.0, 0.0, 1.0],
        }))),
        TerrainReply::LineOfSight(Answer::Ready(Some(LosHit {
            range_m: 0.0,
            point: local(10.0, 20.0, -30.0),
            normal_enu: n,
        }))),
        TerrainReply::LineOfSight(Answer::NoTerrain),
        TerrainReply::LineOfSight(Answer::Pending),
    ]
}

/// Rewrites the CRC after a deliberate edit, so that the edit is what gets rejected.
fn recrc(b: &mut [u8]) {
    let n = b.len() - 4;
    let crc = crc32fast::hash(&b[..n]);
    b[n..].copy_from_slice(&crc.to_le_bytes());
}

fn put_f64(b: &mut [u8], off: usize, v: f64) {
    b[off..off + 8].copy_from_slice(&v.to_le_bytes());
    recrc(b);
}

fn query_error(b: &[u8]) -> String {
    match decode_query(b).unwrap_err() {
        DecodeError::Malformed { what, .. } => what,
        e => panic!("expected malformed, got {e}"),
    }
}

fn reply_error(b: &[u8]) -> String {
    match decode_reply(b).unwrap_err() {
        DecodeError::Malformed { what, .. } => what,
        e => panic!("expected malformed, got {e}"),
    }
}

#[test]
fn queries_round_trip() {
    for (i, q) in requests().into_iter().enumerate() {
        let id = 0xDEAD_BEE0 + i as u32;
        let b = encode_query(id, &q);
        assert_eq!(b.len(), QUERY_SIZE);
        assert!(is_query(&b));
        assert_eq!(decode_query(&b), Ok((id, q)));
    }
}

#[test]
fn replies_round_trip() {
    for (i, r) in replies().into_iter().enumerate() {
        let b = encode_reply(i as u32, &r);
        assert_eq!(b.len(), REPLY_SIZE);
        assert!(!is_query(&b));
        assert_eq!(decode_reply(&b), Ok((i as u32, r)), "{r:?}");
    }
}

/// A LOS segment query written byte by byte from the PROTOCOL.md table.
#[test]
fn golden_query_bytes() {
    let mut g = Vec::new();
    g.extend_from_slice(b"AERQ");
    g.extend_from_slice(&[1, 0]); // version 1
    g.push(2); // kind: LOS segment
    g.push(0b10); // flags: the end point is local
    g.extend_from_slice(&[0x04, 0x03, 0x02, 0x01]); // id 0x01020304
    g.extend_from_slice(&[76, 0]); // size
    g.extend_from_slice(&[0, 0]); // reserved
    for v in [47.25f64, 11.35, 2000.0, 1.0, -2.0, 3.0, 0.0] {
        g.extend_from_slice(&v.to_le_bytes());
    }
    assert_eq!(g.len(), 72);
    let crc = crc32fast::hash(&g);
    g.extend_from_slice(&crc.to_le_bytes());
    assert_eq!(encode_query(0x0102_0304, &requests()[1]), g);
    assert_eq!(decode_query(&g), Ok((0x0102_0304, requests()[1])));
    // The vector kind's tail: azimuth, elevation, min, max at 40, 48, 56, 64.
    let v = encode_query(7, &requests()[2]);
    assert_eq!((v[6], v[7]), (KIND_LOS_VECTOR, QFLAG_FROM_LOCAL));
    for (off, want) in [
        (16, -500.0f64),
        (40, 45.0),
        (48, -5.0),
        (56, 10.0),
        (64, 10_000.0),
    ] {
        assert_eq!(&v[off..off + 8], &want.to_le_bytes(), "offset {off}");
    }
}

/// A LOS hit answer written byte by byte from the PROTOCOL.md table.
#[test]
fn golden_reply_bytes() {
    let mut g = Vec::new();
    g.extend_from_slice(b"AERA");
    g.extend_from_slice(&[1, 0]);
    g.push(2); // kind: LOS
    g.push(0); // status: ready
    g.extend_from_slice(&9u32.to_le_bytes());
    g.extend_from_slice(&[84, 0]);
    g.push(0b01); // hit, geodetic point
    g.push(0);
    for v in [0.0f64, 4321.25, 0.0, 0.0, 1.0, 47.3, 11.4, 1800.0] {
        g.extend_from_slice(&v.to_le_bytes());
    }
    assert_eq!(g.len(), 80);
    let crc = crc32fast::hash(&g);
    g.extend_from_slice(&crc.to_le_bytes());
    assert_eq!(encode_reply(9, &replies()[4]), g);
    // HOT ready: height at 16, normal at 32, no flags; no terrain: status 1, all zero.
    let h = encode_reply(1, &replies()[0]);
    assert_eq!((h[6], h[7], h[14]), (KIND_HOT, STATUS_READY, 0));
    assert_eq!(&h[16..24], &1234.5f64.to_le_bytes());
    assert_eq!(&h[32..40], &0.6f64.to_le_bytes());
    let n = encode_reply(1, &replies()[1]);
    assert_eq!(n[7], STATUS_NO_TERRAIN);
    assert!(n[14..80].iter().all(|&x| x == 0));
    assert_eq!(encode_reply(1, &replies()[7])[7], STATUS_PENDING);
}

#[test]
fn header_errors_are_named() {
    let good = encode_query(1, &requests()[0]);
    let reason = |b: &[u8]| decode_query(b).unwrap_err().reason();
    let mut b = good.clone();
    b[3] = b'P';
    assert_eq!(reason(&b), DropReason::Unknown);
    assert!(!is_query(&b));
    let mut b = good.clone();
    b[4] = 2;
    let e = decode_query(&b).unwrap_err();
    assert_eq!(e.reason(), DropReason::BadVersion);
    assert!(e.to_string().contains("version 2"), "{e}");
    assert_eq!(reason(&good[..75]), DropReason::BadSize);
    assert_eq!(reason(&good[..5]), DropReason::Malformed);
    let mut long = good.clone();
    long.push(0);
    assert_eq!(reason(&long), DropReason::BadSize);
    let mut b = good.clone();
    b[20] ^= 1;
    assert_eq!(reason(&b), DropReason::BadCrc);
    let mut b = good.clone();
    b[12] = 70;
    recrc(&mut b);
    assert!(query_error(&b).contains("offset 12"));
    let mut b = good.clone();
    b[14] = 1;
    recrc(&mut b);
    assert!(query_error(&b).contains("offset 14"));
    let mut b = good.clone();
    b[6] = 4;
    recrc(&mut b);
    assert!(query_error(&b).contains("kind 4 (offset 6)"));
    // Bit 1 (end point local) means nothing for a HOT query.
    let mut b = good.clone();
    b[7] = QFLAG_TO_LOCAL;
    recrc(&mut b);
    assert!(query_error(&b).contains("offset 7"));
    // Answers: same header checks.
    let good = encode_reply(1, &replies()[0]);
    assert_eq!(
        decode_reply(&good[..83]).unwrap_err().reason(),
        DropReason::BadSize
    );
    let mut b = good.clone();
    b[50] ^= 0x10;
    assert_eq!(decode_reply(&b).unwrap_err().reason(), DropReason::BadCrc);
    let mut b = good.clone();
    b[15] = 1;
    recrc(&mut b);
    assert!(reply_error(&b).contains("offset 15"));
    for (off, value, want) in [
        (6, 3u8, "kind 3 (offset 6)"),
        (7, 3, "status 3 (offset 7)"),
        (14, 1, "offset 14"),
    ] {
        let mut b = good.clone();
        b[off] = value;
        recrc(&mut b);
        assert!(reply_error(&b).contains(want), "{}", reply_error(&b));
    }
}

#[test]
fn every_bad_query_value_is_named_with_its_offset() {
    let cases: [(usize, usize, f64, &str); 12] = [
        (0, 16, 90.5, "`at.lat_deg` (offset 16)"),
        (0, 24, 360.0, "`at.lon_deg` (offset 24)"),
        (0, 32, f64::NAN, "`at.alt_m` (offset 32) is not finite"),
        (0, 40, 1.0, "`unused[0]` (offset 40)"),
        (0, 64, -0.0, "`unused[3]` (offset 64)"),
        (1, 48, f64::INFINITY, "`to.y` (offset 48)"),
        (1, 56, 2e9, "`to.z` (offset 56)"),
        (1, 64, 5.0, "`unused` (offset 64)"),
        (2, 16, -2e9, "`from.x` (offset 16)"),
        (2, 48, 90.5, "`elevation_deg` (offset 48)"),
        (2, 56, -1.0, "`min_range_m` (offset 56)"),
        (2, 64, 5.0, "`max_range_m` (offset 64)"),
    ];
    for (which, off, value, want) in cases {
        let mut b = encode_query(1, &requests()[which]);
        put_f64(&mut b, off, value);
        let e = query_error(&b);
        assert!(e.contains(want), "{want}: {e}");
    }
    let mut b = encode_query(1, &requests()[2]);
    put_f64(&mut b, 40, 721.0);
    assert!(query_error(&b).contains("`azimuth_deg` (offset 40)"));
}

#[test]
fn every_bad_answer_value_is_named_with_its_offset() {
    let r = replies();
    let cases: [(usize, usize, f64, &str); 9] = [
        (0, 16, f64::NAN, "`height_m` (offset 16) is not finite"),
        (0, 16, 2e6, "`height_m` (offset 16)"),
        (0, 24, 1.0, "`range_m` (offset 24)"),
        (0, 32, 0.7, "normal (offset 32) has length"),
        (1, 16, 5.0, "`height_m` (offset 16)"),
        (3, 56, 1.0, "`point[0]` (offset 56)"),
        (4, 24, -1.0, "`range_m` (offset 24)"),
        (4, 56, 91.0, "`point.lat_deg` (offset 56)"),
        (6, 48, 1.0, "`normal.up` (offset 48)"),
    ];
    for (which, off, value, want) in cases {
        let mut b = encode_reply(1, &r[which]);
        put_f64(&mut b, off, value);
        let e = reply_error(&b);
        assert!(e.contains(want), "{want}: {e}");
    }
    // A clear line has no local-point flag; a HOT answer has no flags at all.
    let mut b = encode_reply(1, &r[3]);
    b[14] = AFLAG_POINT_LOCAL;
    recrc(&mut b);
    assert!(reply_error(&b).contains("offset 14"));
}

#[test]
fn truncations_never_panic() {
    for q in requests() {
        let b = encode_query(3, &q);
        for n in 0..b.len() {
            assert!(decode_query(&b[..n]).is_err());
            assert!(decode_reply(&b[..n]).is_err());
        }
    }
    for r in replies() {
        let b = encode_reply(3, &r);
        for n in 0..b.len() {
            assert!(decode_reply(&b[..n]).is_err());
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2048))]

    /// Arbitrary bodies behind each magic, with the CRC made right so that the field checks are
    /// reached, never panic; whatever decodes re-encodes to the same bytes.
    #[test]
    fn arbitrary_bodies_never_panic(
        body in prop::collection::vec(any::<u8>(), 0..100),
        reply in any::<bool>(),
        fix_header in any::<bool>(),
    ) {
        let (magic, size) = if reply { (REPLY_MAGIC, REPLY_SIZE) } else { (QUERY_MAGIC, QUERY_SIZE) };
        let mut b = magic.to_vec();
        b.extend_from_slice(&body);
        if fix_header {
            b.resize(size, 0);
            b[4..6].copy_from_slice(&QUERY_VERSION.to_le_bytes());
            b[12..14].copy_from_slice(&(size as u16).to_le_bytes());
            recrc(&mut b);
        }
        if reply {
            if let Ok((id, r)) = decode_reply(&b) {
                prop_assert_eq!(encode_reply(id, &r), b);
            }
        } else if let Ok((id, q)) = decode_query(&b) {
            prop_assert_eq!(encode_query(id, &q), b);
        }
    }

    /// Every valid geodetic HOT query survives the round trip.
    #[test]
    fn any_valid_hot_round_trips(
        lat in -90.0..=90.0f64, lon in -180.0..360.0f64, alt in -12_000.0..=1e6f64, id in any::<u32>(),
    ) {
        let q = TerrainRequest::HeightOfTerrain { at: geo(lat, lon, alt) };
        prop_assert_eq!(decode_query(&encode_query(id, &q)), Ok((id, q)));
    }
}
