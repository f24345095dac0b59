//! Bodies of the `cargo fuzz` targets (`sim-bridge/fuzz/`, one per byte-level parser). They
//! live here, not in the fuzz crate, so that `cargo test` compiles and runs them over the
//! checked-in seed corpus (`sim-bridge/fuzz/corpus/<target>/`): a change that breaks a target
//! breaks the build, and a seed that trips an invariant fails a test.
//!
//! Each takes arbitrary bytes, must not panic, and checks what must hold for any input that
//! decodes (the fuzzer reports a violated `assert!` like a crash). Each returns whether the
//! input decoded, so the seed test can check that the corpus reaches past the first checks.

use std::path::Path;

use crate::codec::{self, cigi, fgfs, native, xplane, Protocol, ProtocolChoice};
use crate::ingest::{input_channel, InputParams};
use crate::record;
use crate::shm;

/// A target body: arbitrary bytes in, "decoded" out.
pub type TargetBody = fn(&[u8]) -> bool;

/// The fuzz targets: name (= `fuzz/fuzz_targets/<name>.rs` and `fuzz/corpus/<name>/`) and body.
pub const TARGETS: [(&str, TargetBody); 7] = [
    ("native", decode_native),
    ("cigi", decode_cigi),
    ("xplane", decode_xplane),
    ("fgfs", decode_fgfs),
    ("auto", decode_auto),
    ("shm", decode_shm),
    ("recording", parse_recording),
];

/// aerie native v1: a decoded datagram is valid and survives encode → decode unchanged.
/// Mutated bytes almost never keep their CRC right, so the same bytes with the CRC rewritten
/// are decoded as well: the field checks behind the CRC get fuzzed too.
pub fn decode_native(b: &[u8]) -> bool {
    if b.len() >= native::SIZE {
        let mut fixed = b.to_vec();
        let crc = crc32fast::hash(&fixed[..native::SIZE - 4]);
        fixed[native::SIZE - 4..native::SIZE].copy_from_slice(&crc.to_le_bytes());
        check_native(&fixed);
    }
    check_native(b)
}

fn check_native(b: &[u8]) -> bool {
    let Ok(p) = native::decode(b) else {
        return false;
    };
    assert_eq!(p.pose.validate(), Ok(()));
    let again = native::decode(&native::encode(&p.pose, p.sequence)).expect("re-encoded");
    assert_eq!(again, p);
    true
}

/// CIGI host message (any 3.x version): the ownship pose (if any) is valid; every request,
/// entity and environment packet kept passed its checks and survives re-encoding in the
/// host's version; rejected packets lie inside the message; every packet is counted; the
/// Start of Frame answer decodes in the host's version and byte order naming the host's
/// frame. The same bytes read as an IG → host message never panic either.
pub fn decode_cigi(b: &[u8]) -> bool {
    let _ = cigi::decode_ig_message(b);
    let Ok(m) = cigi::decode(b) else {
        return false;
    };
    let (v, o) = (m.version, m.byte_order);
    if let Some(p) = m.ownship_pose() {
        assert_eq!(p.validate(), Ok(()));
    }
    for r in &m.requests {
        let again =
            cigi::decode(&[cigi::IgControl::default().encode_as(v, o), r.encode(v, o)].concat())
                .expect("a kept request re-encodes");
        assert_eq!(again.requests, [*r]);
    }
    for e in m.entities.iter().filter(|e| e.entity_id != cigi::OWNSHIP) {
        assert_eq!(e.check(), Ok(()));
        assert_eq!(
            cigi::EntityControl::decode(&e.encode(o), v, o).as_ref(),
            Ok(e)
        );
    }
    for c in &m.conformal_clamped {
        assert_eq!(c.check(), Ok(()));
    }
    for r in &m.rate_controls {
        assert_eq!(r.check(), Ok(()));
    }
    if let Some(c) = m.celestial {
        assert_eq!(c.check(), Ok(()));
    }
    if let Some(a) = m.atmosphere {
        assert_eq!(a.check(), Ok(()));
    }
    let start = usize::from(v.ig_control_size());
    for r in &m.rejected {
        assert!(r.offset >= start && r.offset < b.len());
    }
    assert!(m.packet_counts.get(cigi::IG_CONTROL_ID) >= 1);
    assert!(m.packet_counts.total() >= 1 + m.requests.len() as u64 + m.rejected.len() as u64);
    let answer = m.answer(7, 9);
    assert_eq!(answer.len(), usize::from(v.start_of_frame_size()));
    let (sof, sof_v, order) =
        cigi::StartOfFrame::decode_with_version(&answer).expect("answer decodes");
    assert_eq!((sof_v, order), (v, o));
    if v.is_3_2_or_later() {
        assert_eq!(sof.last_host_frame, m.ig_control.host_frame);
    }
    let mut views = cigi::ViewTable::default();
    views.apply(&m);
    assert!(views.views().len() <= cigi::MAX_VIEWS);
    true
}

/// X-Plane `RPOS`: a decoded pose is valid.
pub fn decode_xplane(b: &[u8]) -> bool {
    let Ok(p) = xplane::decode(b) else {
        return false;
    };
    assert_eq!(p.validate(), Ok(()));
    true
}

/// FlightGear FGNetFDM (v24 or v25): a decoded pose is valid, the datagram has its version's
/// size, and the head re-encodes (in that version) to the same bytes.
pub fn decode_fgfs(b: &[u8]) -> bool {
    let Ok(p) = fgfs::decode(b) else {
        return false;
    };
    assert_eq!(p.validate(), Ok(()));
    let version = u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    assert_eq!(fgfs::size_of_version(version), Some(b.len()));
    let head = fgfs::decode_fields(b).expect("decoded once");
    let again = if version == fgfs::VERSION_25 {
        fgfs::encode_v25(&head).to_vec()
    } else {
        fgfs::encode(&head).to_vec()
    };
    // Bytes 4..8 are FlightGear's padding word, not read; 88.. is the skipped tail.
    assert_eq!(&again[..4], &b[..4]);
    assert_eq!(&again[8..88], &b[8..88]);
    true
}

/// Auto-detection and the whole ingest path: detection agrees with decoding, a decoded pose is
/// valid, and feeding the datagram to an input (sequence check, counters, hand-over,
/// extrapolation) keeps `received = accepted + no_pose + dropped`.
pub fn decode_auto(b: &[u8]) -> bool {
    let decoded = codec::decode(ProtocolChoice::Auto, b);
    let (mut ingest, mut reader) = input_channel(InputParams::default());
    // Twice: the second is a duplicate (or dropped again) and must not panic either.
    ingest.datagram(b, 1.0);
    ingest.datagram(b, 1.01);
    let s = reader.stats();
    assert_eq!(s.received, 2);
    assert_eq!(s.received, s.accepted + s.no_pose + s.dropped_total());
    let frame = reader.pose_at(1.05);
    match decoded {
        Ok(d) => {
            assert_eq!(Some(d.protocol), codec::detect(b));
            if let Some(p) = d.pose {
                assert_eq!(p.validate(), Ok(()));
                assert!(s.accepted >= 1);
                let f = frame.expect("an accepted pose reaches the reader");
                assert!(f.pose.attitude_deg.iter().all(|a| a.is_finite()));
            }
            if d.protocol == Protocol::Aerie {
                assert!(d.sequence.is_some());
            }
            true
        }
        Err(_) => {
            assert_eq!(s.accepted, 0);
            false
        }
    }
}

/// A byte copy of the shared-memory file: decodes or names the problem; a decoded pose
/// validates or names its field (never panics either way).
pub fn decode_shm(b: &[u8]) -> bool {
    let Ok(snap) = shm::decode_snapshot(b) else {
        return false;
    };
    if let Some(p) = snap.pose {
        if let Err(e) = p.validate() {
            assert!(!e.field().is_empty());
        }
    }
    true
}

/// A recording file: parses or names the byte offset; parsed records keep their order and
/// size limits, and the header and records cover every byte.
pub fn parse_recording(b: &[u8]) -> bool {
    let Ok(packets) = record::parse_recording(b, Path::new("fuzz.aerie-rec")) else {
        return false;
    };
    let mut last = 0;
    // The header may be longer than this version's (bytes 10..12 give its size; newer writers
    // may add fields), and the records start after it.
    let mut total = usize::from(u16::from_le_bytes([b[10], b[11]]));
    assert!(total >= record::HEADER_SIZE);
    for p in &packets {
        assert!(p.t_ns >= last);
        assert!(p.bytes.len() <= record::MAX_PACKET);
        last = p.t_ns;
        total += record::RECORD_HEADER_SIZE + p.bytes.len();
    }
    assert_eq!(total, b.len(), "every byte belongs to a record");
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codec::ByteOrder;
    use crate::pose::{Pose, PosePosition};
    use std::path::PathBuf;

    fn corpus_dir() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus")
    }

    /// Every target runs over its checked-in seeds without panicking, and some seeds of each
    /// decode (the corpus gets past the magic and size checks), some do not.
    #[test]
    fn fuzz_targets_run_over_the_seed_corpus() {
        for (name, body) in TARGETS {
            let dir = corpus_dir().join(name);
            let entries = std::fs::read_dir(&dir)
                .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
                .map(|e| e.unwrap().path())
                .collect::<Vec<_>>();
            assert!(entries.len() >= 3, "{name}: {} seeds", entries.len());
            let mut ok = 0;
            for path in &entries {
                let bytes = std::fs::read(path).unwrap();
                if body(&bytes) {
                    ok += 1;
                }
            }
            assert!(
                ok >= 1 && ok < entries.len(),
                "{name}: {ok} of {} seeds decode",
                entries.len()
            );
        }
    }

    /// The fuzz crate declares exactly these targets, each calling its body here.
    #[test]
    fn fuzz_crate_declares_every_target() {
        let fuzz = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fuzz");
        let manifest = std::fs::read_to_string(fuzz.join("Cargo.toml")).unwrap();
        for (name, _) in TARGETS {
            assert!(
                manifest.contains(&format!("name = \"{name}\"")),
                "{name} missing in fuzz/Cargo.toml"
            );
            let src = std::fs::read_to_string(fuzz.join(format!("fuzz_targets/{name}.rs")))
                .unwrap_or_else(|e| panic!("fuzz_targets/{name}.rs: {e}"));
            let body = match name {
                "recording" => "parse_recording".to_string(),
                n => format!("decode_{n}"),
            };
            assert!(
                src.contains(&format!("fuzzing::{body}(")),
                "fuzz_targets/{name}.rs does not call fuzzing::{body}"
            );
        }
    }

    /// Random bytes (a poor man's fuzzer, deterministic) never panic a target.
    #[test]
    fn random_bytes_never_panic_a_target() {
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        for _ in 0..2000 {
            let len = (next() % 500) as usize;
            let bytes: Vec<u8> = (0..len).map(|_| next() as u8).collect();
            for (_, body) in TARGETS {
                body(&bytes);
            }
        }
    }

    fn pose(local: bool) -> Pose {
        Pose {
            position: if local {
                PosePosition::LocalEnu {
                    x: 1200.0,
                    y: -300.0,
                    z: 2500.0,
                }
            } else {
                PosePosition::Geodetic {
                    lat_deg: 47.26,
                    lon_deg: 11.35,
                    alt_m: 1800.0,
                }
            },
            attitude_deg: [92.0, 3.0, -8.0],
            sim_time_s: 10.0,
            frame: 600,
            velocity_enu: Some([120.0, -4.0, 1.0]),
            angular_rates_deg_s: Some([1.0, 0.0, -3.0]),
        }
    }

    fn cigi_message(order: ByteOrder, extra: &[u8]) -> Vec<u8> {
        let mut b = cigi::IgControl {
            ig_mode: 1,
            timestamp_valid: true,
            minor_version: 3,
            host_frame: 42,
            timestamp: 100_000,
            ..cigi::IgControl::default()
        }
        .encode(order)
        .to_vec();
        b.extend_from_slice(extra);
        b.extend(
            cigi::EntityControl {
                entity_state: 1,
                alpha: 255,
                roll_deg: -8.0,
                pitch_deg: 3.0,
                yaw_deg: 92.0,
                lat_deg: 47.26,
                lon_deg: 11.35,
                alt_m: 1800.0,
                ..cigi::EntityControl::default()
            }
            .encode(order),
        );
        b
    }

    /// One of each request and environment packet, valid, in `v` and `order`.
    fn cigi_requests(v: cigi::CigiVersion, order: ByteOrder) -> Vec<u8> {
        let mut b = cigi::HatHotRequest {
            request_id: 1,
            request_type: cigi::HatHotRequestType::Extended,
            update_period: 2,
            point: [47.26, 11.35, 3000.0],
            ..cigi::HatHotRequest::default()
        }
        .encode(v, order)
        .to_vec();
        b.extend(
            cigi::LosSegmentRequest {
                request_id: 2,
                source: [47.26, 11.35, 3000.0],
                destination: [47.3, 11.4, 1000.0],
                ..cigi::LosSegmentRequest::default()
            }
            .encode(v, order),
        );
        b.extend(
            cigi::LosVectorRequest {
                request_id: 3,
                elevation_deg: -10.0,
                max_range_m: 10_000.0,
                source: [47.26, 11.35, 3000.0],
                ..cigi::LosVectorRequest::default()
            }
            .encode(v, order),
        );
        b.extend(
            cigi::CelestialSphereControl {
                hour: 12,
                date_valid: true,
                month: 6,
                day: 21,
                year: 2026,
                ..cigi::CelestialSphereControl::default()
            }
            .encode(order),
        );
        b.extend(
            cigi::AtmosphereControl {
                visibility_m: 20_000.0,
                ..cigi::AtmosphereControl::default()
            }
            .encode(order),
        );
        b
    }

    /// Writes the seed corpus (`cargo test -p aerie-sim-bridge -- --ignored write_seed_corpus`);
    /// the files are checked in.
    #[test]
    #[ignore]
    fn write_seed_corpus() {
        let mut seeds: Vec<(&str, &str, Vec<u8>)> = Vec::new();
        let n_local = native::encode(&pose(true), 7).to_vec();
        let n_geo = native::encode(&pose(false), 8).to_vec();
        let mut n_crc = n_geo.clone();
        n_crc[40] ^= 1;
        seeds.push(("native", "local", n_local.clone()));
        seeds.push(("native", "geodetic", n_geo.clone()));
        seeds.push(("native", "bad_crc", n_crc));
        seeds.push(("native", "short", n_geo[..60].to_vec()));
        let view = cigi::ViewDefinition {
            view_id: 3,
            ..cigi::ViewDefinition::default()
        }
        .encode(ByteOrder::Big);
        let unknown = [200u8, 8, 0, 0, 0, 0, 0, 0];
        seeds.push(("cigi", "big", cigi_message(ByteOrder::Big, &[])));
        seeds.push(("cigi", "little", cigi_message(ByteOrder::Little, &[])));
        seeds.push((
            "cigi",
            "view_and_unknown",
            cigi_message(ByteOrder::Big, &[&view[..], &unknown].concat()),
        ));
        let c = cigi_message(ByteOrder::Big, &[]);
        seeds.push(("cigi", "cut", c[..50].to_vec()));
        let requests = cigi_requests(cigi::CigiVersion::V3_3, ByteOrder::Little);
        seeds.push((
            "cigi",
            "requests_and_environment",
            cigi_message(ByteOrder::Little, &requests),
        ));
        let mut v30 = cigi::IgControl {
            ig_mode: 1,
            host_frame: 9,
            ..cigi::IgControl::default()
        }
        .encode_as(cigi::CigiVersion::V3_0, ByteOrder::Big);
        v30.extend(cigi_requests(cigi::CigiVersion::V3_0, ByteOrder::Big));
        seeds.push(("cigi", "v3_0_requests", v30));
        let mut answer =
            cigi::StartOfFrame::default().encode(cigi::CigiVersion::V3_2, ByteOrder::Big);
        cigi::CigiResponse::Los(cigi::LosResponse {
            request_id: 4,
            valid: true,
            ..cigi::LosResponse::default()
        })
        .encode_into(cigi::CigiVersion::V3_2, ByteOrder::Big, &mut answer);
        seeds.push(("cigi", "ig_answer", answer));
        let x = xplane::encode(&xplane::Rpos::from_pose(&pose(false), 12.0)).to_vec();
        seeds.push(("xplane", "rpos", x.clone()));
        seeds.push(("xplane", "short", x[..40].to_vec()));
        seeds.push(("xplane", "request", xplane::rpos_request(60)));
        let f = fgfs::encode(&fgfs::FdmPose::from_pose(&pose(false))).to_vec();
        let mut f_ver = f.clone();
        f_ver[3] = 23;
        seeds.push(("fgfs", "fdm", f.clone()));
        seeds.push(("fgfs", "version23", f_ver));
        seeds.push(("fgfs", "short", f[..100].to_vec()));
        let f25 = fgfs::encode_v25(&fgfs::FdmPose::from_pose(&pose(false))).to_vec();
        seeds.push(("fgfs", "fdm_v25", f25.clone()));
        seeds.push(("fgfs", "v25_as_v24_size", f25[..fgfs::SIZE].to_vec()));
        for (name, b) in [
            ("native", n_geo.clone()),
            ("cigi", cigi_message(ByteOrder::Little, &[])),
            ("xplane", x.clone()),
            ("fgfs", f.clone()),
            ("fgfs_v25", f25.clone()),
            ("text", b"hello".to_vec()),
        ] {
            seeds.push(("auto", name, b));
        }
        let dir = tempfile::tempdir().unwrap();
        let shm_file = dir.path().join("pose");
        let mut w = shm::ShmWriter::create(&shm_file).unwrap();
        seeds.push(("shm", "never_written", std::fs::read(&shm_file).unwrap()));
        w.write(&pose(true));
        let s = std::fs::read(&shm_file).unwrap();
        seeds.push(("shm", "local", s.clone()));
        let mut bad = s.clone();
        bad[0] = b'X';
        seeds.push(("shm", "bad_magic", bad));
        let mut bad = s.clone();
        bad[shm::SHM_CRC_END] ^= 1;
        seeds.push(("shm", "bad_crc", bad));
        let rec = dir.path().join("r.aerie-rec");
        record::write_recording(
            &rec,
            &[
                record::RecordedPacket {
                    t_ns: 0,
                    bytes: n_geo.clone(),
                },
                record::RecordedPacket {
                    t_ns: 16_000_000,
                    bytes: b"junk".to_vec(),
                },
            ],
        )
        .unwrap();
        let r = std::fs::read(&rec).unwrap();
        seeds.push(("recording", "two", r.clone()));
        seeds.push(("recording", "cut", r[..r.len() - 3].to_vec()));
        seeds.push((
            "recording",
            "header_only",
            r[..record::HEADER_SIZE].to_vec(),
        ));
        seeds.push(("recording", "not_a_recording", b"AERIEREX".to_vec()));
        for (target, name, bytes) in seeds {
            let d = corpus_dir().join(target);
            std::fs::create_dir_all(&d).unwrap();
            std::fs::write(d.join(format!("seed_{name}")), bytes).unwrap();
        }
    }
}
