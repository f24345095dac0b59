use super::*;
use crate::pose::PosePosition;
use crate::shm_layout::{header_word, W_ATT, W_FRAME, W_POS, W_RATES, W_TIME, W_VEL};
use crate::stats::DropReason;
use std::mem::offset_of;

struct TempShm(PathBuf);
impl TempShm {
    fn new(tag: &str) -> Self {
        let dir = if Path::new("/dev/shm").is_dir() {
            PathBuf::from("/dev/shm")
        } else {
            std::env::temp_dir()
        };
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.subsec_nanos())
            .unwrap_or(0);
        Self(dir.join(format!("aerie-test-{tag}-{}-{nanos}", std::process::id())))
    }
}
impl Drop for TempShm {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

#[test]
fn layout_matches_the_c_header() {
    assert_eq!(offset_of!(ShmPose, magic), 0);
    assert_eq!(offset_of!(ShmPose, version), 4);
    assert_eq!(offset_of!(ShmPose, size), 6);
    assert_eq!(offset_of!(ShmPose, seq), 8);
    assert_eq!(offset_of!(ShmPose, flags), 16);
    assert_eq!(offset_of!(ShmPose, reserved), 20);
    assert_eq!(offset_of!(ShmPose, frame), W_FRAME * 8);
    assert_eq!(offset_of!(ShmPose, sim_time_s), W_TIME * 8);
    assert_eq!(offset_of!(ShmPose, position), W_POS * 8);
    assert_eq!(offset_of!(ShmPose, attitude_deg), W_ATT * 8);
    assert_eq!(offset_of!(ShmPose, velocity_enu), W_VEL * 8);
    assert_eq!(offset_of!(ShmPose, rates_deg_s), W_RATES * 8);
    assert_eq!(offset_of!(ShmPose, crc), SHM_CRC_END);
    assert_eq!(SHM_MAGIC, 0x5350_4541);
    // The C header states the same offsets.
    let h = include_str!("../include/aerie_pose.h");
    for needle in [
        "AERIE_POSE_SIZE 144",
        "AERIE_POSE_VERSION 2",
        "AERIE_POSE_CRC_START 16",
        "AERIE_POSE_CRC_END 136",
        "offsetof(struct aerie_pose, crc) == 136",
        "AERIE_POSE_MAGIC 0x53504541u",
        "offsetof(struct aerie_pose, seq) == 8",
        "offsetof(struct aerie_pose, position) == 40",
        "offsetof(struct aerie_pose, rates_deg_s) == 112",
    ] {
        assert!(h.contains(needle), "aerie_pose.h lacks `{needle}`");
    }
}

#[test]
fn write_then_read_and_header_checks() {
    let f = TempShm::new("rw");
    let mut w = ShmWriter::create(&f.0).unwrap();
    let mut r = ShmReader::open(&f.0).unwrap();
    assert_eq!(r.read(), ShmRead::NotWritten);
    let p = Pose {
        position: PosePosition::Geodetic {
            lat_deg: 47.1,
            lon_deg: 11.2,
            alt_m: 1234.5,
        },
        attitude_deg: [10.0, -2.0, 30.0],
        sim_time_s: 99.5,
        frame: 42,
        velocity_enu: Some([1.0, 2.0, 3.0]),
        angular_rates_deg_s: None,
    };
    w.write(&p);
    match r.read() {
        ShmRead::New { pose, seq, .. } => {
            assert_eq!(pose, p);
            assert_eq!(seq, 2);
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(r.read(), ShmRead::Unchanged);
    // Raw bytes follow the documented layout.
    let raw = std::fs::read(&f.0).unwrap();
    assert_eq!(raw.len(), SHM_SIZE);
    assert_eq!(&raw[0..4], b"AEPS");
    assert_eq!(&raw[4..8], &[2, 0, 144, 0]);
    assert_eq!(&raw[16..20], &SHM_FLAG_VELOCITY.to_le_bytes());
    assert_eq!(&raw[24..32], &42u64.to_le_bytes());
    assert_eq!(&raw[40..48], &47.1f64.to_le_bytes());
    assert_eq!(
        &raw[136..140],
        &crc32fast::hash(&raw[16..136]).to_le_bytes()
    );
    // A truncated file is a shrink, reported without a fault; a regrown one is read again.
    let trunc = TempShm::new("trunc");
    let mut tw = ShmWriter::create(&trunc.0).unwrap();
    let mut tr = ShmReader::open(&trunc.0).unwrap();
    tw.write(&p);
    assert!(matches!(tr.read(), ShmRead::New { .. }));
    std::fs::OpenOptions::new()
        .write(true)
        .open(&trunc.0)
        .unwrap()
        .set_len(8)
        .unwrap();
    assert_eq!(
        tr.read(),
        ShmRead::Shrunk {
            len: 8,
            first: true
        }
    );
    assert_eq!(
        tr.read(),
        ShmRead::Shrunk {
            len: 8,
            first: false
        }
    );
    drop(tw);
    let mut tw = ShmWriter::create(&trunc.0).unwrap();
    assert_eq!(tr.read(), ShmRead::NotWritten);
    tw.write(&pose_k(9));
    assert!(matches!(tr.read(), ShmRead::New { pose, .. } if pose == pose_k(9)));
    // A reopened writer continues the sequence.
    drop(w);
    let mut w2 = ShmWriter::create(&f.0).unwrap();
    w2.write(&p);
    assert!(matches!(r.read(), ShmRead::New { seq: 4, .. }));
    // A version-1 file (136 bytes, no checksum) is refused by its version.
    let v1 = TempShm::new("v1");
    let mut old = vec![0u8; 136];
    old[..4].copy_from_slice(b"AEPS");
    old[4..8].copy_from_slice(&[1, 0, 136, 0]);
    std::fs::write(&v1.0, &old).unwrap();
    assert!(matches!(
        ShmReader::open(&v1.0),
        Err(ShmError::TooSmall { len: 136, .. })
    ));
    old.resize(SHM_SIZE, 0);
    std::fs::write(&v1.0, &old).unwrap();
    assert!(matches!(
        ShmReader::open(&v1.0),
        Err(ShmError::BadHeader {
            version: 1,
            size: 136,
            ..
        })
    ));
    // Bad files are refused with their name.
    let bad = TempShm::new("bad");
    std::fs::write(&bad.0, [0u8; 200]).unwrap();
    let e = ShmReader::open(&bad.0).err().unwrap();
    assert!(matches!(e, ShmError::BadHeader { .. }), "{e}");
    assert!(e.to_string().contains("aerie-test-bad"), "{e}");
    std::fs::write(&bad.0, [0u8; 10]).unwrap();
    assert!(matches!(
        ShmReader::open(&bad.0),
        Err(ShmError::TooSmall { len: 10, .. })
    ));
    assert!(matches!(
        ShmReader::open(Path::new("/nonexistent/aerie")),
        Err(ShmError::Io { .. })
    ));
}

/// Every field of pose `k` is derived from `k`; a torn read mixes two `k`s.
fn pose_k(k: u64) -> Pose {
    let x = k as f64;
    Pose {
        position: PosePosition::LocalEnu {
            x,
            y: 2.0 * x,
            z: 3.0 * x,
        },
        attitude_deg: [x, -((k % 80) as f64), 0.5 * x],
        sim_time_s: 0.25 * x,
        frame: k,
        velocity_enu: Some([x + 1.0, x + 2.0, x + 3.0]),
        angular_rates_deg_s: if k % 2 == 0 { Some([x; 3]) } else { None },
    }
}

#[test]
fn hammered_writer_never_yields_a_torn_pose() {
    let f = TempShm::new("torn");
    let mut w = ShmWriter::create(&f.0).unwrap();
    let mut r = ShmReader::open(&f.0).unwrap().with_max_retries(1_000);
    let stop = Arc::new(AtomicBool::new(false));
    let writer = {
        let stop = stop.clone();
        std::thread::spawn(move || {
            let mut k = 1u64;
            while !stop.load(Ordering::Relaxed) {
                w.write(&pose_k(k));
                // Back-to-back bursts of writes (reads overlap them and must retry), with a
                // pause of a microsecond or two after every eighth so that tear-free
                // windows exist too.
                if k % 8 == 0 {
                    for _ in 0..2000 {
                        std::hint::spin_loop();
                    }
                }
                k += 1;
            }
            k
        })
    };
    let t = Instant::now();
    let (mut reads, mut retried, mut last) = (0u64, 0u64, 0u64);
    // Until 2,000 consistent reads or 1.5 s (the machine may be busy with other work).
    while reads < 2_000 && t.elapsed() < Duration::from_millis(1500) {
        if let ShmRead::New { pose, retries, .. } = r.read() {
            assert_eq!(pose, pose_k(pose.frame), "torn pose");
            assert!(pose.frame > last, "went back: {} after {last}", pose.frame);
            last = pose.frame;
            reads += 1;
            retried += u64::from(retries);
        }
    }
    stop.store(true, Ordering::Relaxed);
    let written = writer.join().unwrap();
    assert!(reads >= 10, "only {reads} reads");
    eprintln!("{written} writes, {reads} consistent reads, {retried} torn reads retried");
}

#[test]
fn source_thread_feeds_the_reader() {
    let f = TempShm::new("src");
    // The source starts before the file exists and waits for it.
    let (src, mut reader) = ShmSource::spawn(ShmConfig {
        path: f.0.clone(),
        poll_interval: Duration::from_micros(200),
        ..ShmConfig::default()
    })
    .unwrap();
    std::thread::sleep(Duration::from_millis(30));
    let mut w = ShmWriter::create(&f.0).unwrap();
    let t = Instant::now();
    let mut k = 1;
    while t.elapsed() < Duration::from_secs(3) {
        w.write(&pose_k(k));
        std::thread::sleep(Duration::from_millis(2));
        if reader.latest().map(|s| s.latest.pose.frame) == Some(k) && k >= 5 {
            break;
        }
        k += 1;
    }
    let got = reader.pose_now().expect("a pose");
    assert_eq!(got.sample, reader.latest().unwrap().latest.sample);
    assert!(reader.latest().unwrap().latest.pose.frame >= 5);
    // An invalid pose (pitch 120°) is counted, the last good one kept.
    let before = reader.latest().unwrap().latest.pose;
    let mut bad = pose_k(k + 1);
    bad.attitude_deg[1] = 120.0;
    w.write(&bad);
    let t = Instant::now();
    while src.stats().dropped(DropReason::Invalid) == 0 && t.elapsed() < Duration::from_secs(2) {
        std::thread::sleep(Duration::from_millis(1));
    }
    assert_eq!(src.stats().dropped(DropReason::Invalid), 1);
    assert_eq!(reader.latest().unwrap().latest.pose, before);
    src.stop();
}

fn dropped(read: ShmRead) -> DropReason {
    match read {
        ShmRead::Dropped(e) => e.reason,
        other => panic!("expected a dropped record, got {other:?}"),
    }
}

#[test]
fn corrupted_checksum_is_dropped_once_and_the_next_good_pose_read() {
    let f = TempShm::new("crc");
    let mut w = ShmWriter::create(&f.0).unwrap();
    let mut r = ShmReader::open(&f.0).unwrap();
    w.write(&pose_k(1));
    assert!(matches!(r.read(), ShmRead::New { pose, .. } if pose == pose_k(1)));
    w.write_with_bad_checksum(&pose_k(2));
    assert_eq!(dropped(r.read()), DropReason::BadCrc);
    // Counted once, not once per poll.
    assert_eq!(r.read(), ShmRead::Unchanged);
    // One flipped bit in the payload of an otherwise good record.
    w.write(&pose_k(3));
    let mut b = std::fs::read(&f.0).unwrap();
    b[44] ^= 0x10;
    std::fs::write(&f.0, &b).unwrap();
    let ShmRead::Dropped(e) = r.read() else {
        panic!("a flipped bit was read")
    };
    assert!(e.detail.contains("offset 136"), "{}", e.detail);
    assert!(decode_snapshot(&b).unwrap_err().contains("checksum"));
    w.write(&pose_k(4));
    assert!(matches!(r.read(), ShmRead::New { pose, .. } if pose == pose_k(4)));
}

#[test]
fn the_header_is_checked_on_every_read() {
    let f = TempShm::new("hdr");
    let mut w = ShmWriter::create(&f.0).unwrap();
    let mut r = ShmReader::open(&f.0).unwrap();
    w.write(&pose_k(1));
    assert!(matches!(r.read(), ShmRead::New { .. }));
    // Magic, version and size overwritten after open: each is dropped by its reason.
    for (offset, byte, reason) in [
        (0, b'X', DropReason::Unknown),
        (4, 7, DropReason::BadVersion),
        (6, 200, DropReason::BadSize),
    ] {
        w.write(&pose_k(2 + offset as u64));
        let mut b = std::fs::read(&f.0).unwrap();
        let good = b[offset];
        b[offset] = byte;
        std::fs::write(&f.0, &b).unwrap();
        assert_eq!(dropped(r.read()), reason, "offset {offset}");
        assert_eq!(r.read(), ShmRead::Unchanged);
        b[offset] = good;
        std::fs::write(&f.0, &b).unwrap();
    }
}

#[test]
fn random_bytes_never_become_a_pose() {
    let f = TempShm::new("rand");
    let _w = ShmWriter::create(&f.0).unwrap();
    let mut r = ShmReader::open(&f.0).unwrap();
    // xorshift: reproducible noise. Half the files keep a good header (only the checksum
    // can catch them), half are noise throughout.
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let (mut by_reason, mut poses) = (std::collections::BTreeMap::new(), 0);
    for i in 0..2_000 {
        let mut b: Vec<u8> = (0..SHM_SIZE).map(|_| next() as u8).collect();
        if i % 2 == 0 {
            b[..8].copy_from_slice(&header_word().to_ne_bytes());
        }
        b[8] &= !1; // a stable seq, so the record is judged and not retried as mid-write
        std::fs::write(&f.0, &b).unwrap();
        match r.read() {
            ShmRead::New { pose, .. } => panic!("noise read as {pose:?}"),
            ShmRead::Dropped(e) => *by_reason.entry(e.reason).or_insert(0) += 1,
            ShmRead::NotWritten | ShmRead::Unchanged => {}
            other => panic!("{other:?}"),
        }
        poses += usize::from(decode_snapshot(&b).is_ok_and(|s| s.pose.is_some()));
    }
    assert_eq!(poses, 0);
    assert_eq!(by_reason.get(&DropReason::BadCrc), Some(&1_000));
    assert!(by_reason.get(&DropReason::Unknown).copied().unwrap_or(0) >= 990);
    eprintln!("2,000 noise records dropped: {by_reason:?}");
}
