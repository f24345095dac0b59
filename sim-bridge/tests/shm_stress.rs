//! Shared-memory stress (issue #6): a writer thread at 10 kHz for 2 s, a reader polling the
//! file the whole time. Every pose is built from one counter k, so a pose mixing two writes
//! (a torn read the seqlock failed to catch) is detected field by field.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use aerie_sim_bridge::shm::{ShmRead, ShmReader, ShmWriter};
use aerie_sim_bridge::{Pose, PosePosition};

/// Every field a different function of k (including the flag-carried options).
fn pose_k(k: u64) -> Pose {
    let x = k as f64;
    Pose {
        position: PosePosition::LocalEnu {
            x,
            y: -2.0 * x,
            z: 1000.0 + 0.5 * x,
        },
        attitude_deg: [(k % 360) as f64, ((k % 170) as f64) - 85.0, -x / 1e4],
        sim_time_s: x * 1e-4,
        frame: k,
        velocity_enu: Some([x + 1.0, x + 2.0, x + 3.0]),
        angular_rates_deg_s: if k % 3 == 0 { None } else { Some([x; 3]) },
    }
}

#[test]
fn writer_at_10_khz_for_2_s_never_tears_a_read() {
    const RATE_HZ: f64 = 10_000.0;
    const SECONDS: f64 = 2.0;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("aerie-pose-stress");
    let mut w = ShmWriter::create(&path).unwrap();
    let mut r = ShmReader::open(&path).unwrap();
    let done = Arc::new(AtomicBool::new(false));
    let writer = {
        let done = done.clone();
        std::thread::spawn(move || {
            let t = Instant::now();
            let mut k = 0u64;
            // Write k at k/RATE s; sleep (not spin) while waiting, the box has 2 shared
            // cores. When late (descheduled), write the due ones back to back.
            loop {
                let el = t.elapsed().as_secs_f64();
                if el >= SECONDS {
                    break;
                }
                let due = (el * RATE_HZ) as u64 + 1;
                while k < due {
                    k += 1;
                    w.write(&pose_k(k));
                }
                std::thread::sleep(Duration::from_micros(50));
            }
            done.store(true, Ordering::Release);
            (k, t.elapsed().as_secs_f64())
        })
    };
    let (mut reads, mut retried, mut busy, mut polls) = (0u64, 0u64, 0u64, 0u64);
    let (mut last_seq, mut last_k) = (0u64, 0u64);
    let mut torn = Vec::new();
    loop {
        // Checked before the read: the last poll happens after the last write.
        let finished = done.load(Ordering::Acquire);
        polls += 1;
        match r.read() {
            ShmRead::New { pose, seq, retries } => {
                if pose != pose_k(pose.frame) {
                    torn.push(pose);
                }
                assert!(seq % 2 == 0 && seq > last_seq, "seq {seq} after {last_seq}");
                assert!(pose.frame > last_k, "k {} after {last_k}", pose.frame);
                (last_seq, last_k) = (seq, pose.frame);
                reads += 1;
                retried += u64::from(retries);
            }
            ShmRead::Busy { .. } => busy += 1,
            ShmRead::Unchanged | ShmRead::NotWritten => {}
            other => panic!("unexpected {other:?}"),
        }
        if finished {
            break;
        }
        std::thread::yield_now();
    }
    let (written, elapsed) = writer.join().unwrap();
    eprintln!(
        "shm stress: {written} writes in {elapsed:.2} s ({:.0}/s), {polls} polls, {reads} new \
         poses read ({:.0} %), {retried} torn attempts retried, {busy} busy polls",
        written as f64 / elapsed,
        100.0 * reads as f64 / written.max(1) as f64
    );
    assert!(
        torn.is_empty(),
        "{} torn poses, first {:?}",
        torn.len(),
        torn[0]
    );
    // The final poll follows the last write: the reader ends on it.
    assert_eq!(last_k, written, "the last write was not read");
    // A reader that stopped seeing new poses (a seqlock stuck odd or at an old value) would
    // read a handful; 1 % of 20,000 survives a reader descheduled most of the time.
    assert!(
        reads * 100 >= written,
        "only {reads} of {written} writes seen"
    );
}
