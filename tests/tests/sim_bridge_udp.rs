//! UDP pose input end to end on 127.0.0.1 with ephemeral ports: sender → receiver thread →
//! the frame loop's newest pose; allow-list; CIGI Start of Frame answers and views; every
//! protocol auto-detected on one port; a flood; record → replay (bytes and timing); the
//! `aerie listen` / `aerie replay` commands.

use std::net::{Ipv4Addr, SocketAddr, UdpSocket};
use std::path::Path;
use std::time::{Duration, Instant};

use aerie::app::commands::input_args::InputArgs;
use aerie::app::commands::listen::{self, ListenArgs};
use aerie::app::commands::replay::{self, ReplayArgs};
use aerie_sim_bridge::codec::cigi::{
    EntityControl, IgControl, StartOfFrame, ViewControl, ViewDefinition,
};
use aerie_sim_bridge::codec::{fgfs, native, xplane, ByteOrder, ProtocolChoice};
use aerie_sim_bridge::ig::{DatabaseStatus, IgFrame};
use aerie_sim_bridge::query::NoTerrain;
use aerie_sim_bridge::record::{
    read_recording, replay as replay_packets, write_recording, RecordedPacket, ReplayTiming,
};
use aerie_sim_bridge::udp::{CigiReply, UdpConfig, UdpReceiver};
use aerie_sim_bridge::{DropReason, Pose, PosePosition, PoseReader};

fn loopback_config() -> UdpConfig {
    UdpConfig {
        bind: "127.0.0.1:0".parse().unwrap(),
        ..UdpConfig::default()
    }
}

fn sender() -> UdpSocket {
    UdpSocket::bind("127.0.0.1:0").unwrap()
}

/// A pose with frame `frame` whose values stay in range for any frame.
fn pose_framed(frame: u64) -> Pose {
    Pose {
        frame,
        ..pose(frame % 1000)
    }
}

fn pose(i: u64) -> Pose {
    Pose {
        position: PosePosition::Geodetic {
            lat_deg: 47.0 + i as f64 * 1e-5,
            lon_deg: 11.0 + i as f64 * 2e-5,
            alt_m: 2000.0 + i as f64,
        },
        attitude_deg: [(i % 360) as f64, 2.0, -5.0],
        sim_time_s: i as f64 / 60.0,
        frame: i,
        velocity_enu: Some([100.0, 50.0, 1.0]),
        angular_rates_deg_s: None,
    }
}

/// Polls `cond` for up to 3 s.
fn wait_for(what: &str, mut cond: impl FnMut() -> bool) {
    let t = Instant::now();
    while !cond() {
        assert!(
            t.elapsed() < Duration::from_secs(3),
            "timed out waiting for {what}"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
}

/// Waits until `n` datagrams were received *and* decided (accepted, no pose, or dropped): the
/// receiver counts a datagram on arrival and its verdict a moment later, and the tests read
/// the verdict counters next.
fn wait_received(rx: &UdpReceiver, n: u64) {
    wait_for(&format!("{n} datagrams"), || {
        let s = rx.stats();
        s.received >= n && s.accepted + s.no_pose + s.dropped_total() >= n
    });
}

#[test]
fn newest_pose_reaches_the_frame_loop_and_bad_packets_are_counted() {
    let (rx, mut reader) = UdpReceiver::spawn(loopback_config()).unwrap();
    let to = rx.local_addr();
    let tx = sender();
    let sent = std::thread::spawn(move || {
        for i in 1..=50u64 {
            tx.send_to(&native::encode(&pose(i), i as u32), to).unwrap();
            if i == 25 {
                // A corrupted copy, a duplicate, an old one and garbage in the middle.
                let mut bad = native::encode(&pose(99), 26);
                bad[50] ^= 0x10;
                tx.send_to(&bad, to).unwrap();
                tx.send_to(&native::encode(&pose(25), 25), to).unwrap();
                tx.send_to(&native::encode(&pose(3), 3), to).unwrap();
                tx.send_to(b"not a pose", to).unwrap();
            }
            std::thread::sleep(Duration::from_micros(500));
        }
        // Skip 51..53: a gap of three.
        tx.send_to(&native::encode(&pose(54), 54), to).unwrap();
    });
    sent.join().unwrap();
    wait_received(&rx, 55);
    let f = reader.pose_now().expect("a pose");
    assert_eq!(f.pose.frame, 54, "the newest pose");
    let latest = reader.latest().unwrap().latest.pose;
    assert_eq!(latest, pose(54));
    let s = reader.stats();
    assert_eq!(s.received, 55);
    assert_eq!(s.accepted, 51);
    assert_eq!(s.dropped(DropReason::BadCrc), 1);
    assert_eq!(s.dropped(DropReason::Duplicate), 1);
    assert_eq!(s.dropped(DropReason::OutOfOrder), 1);
    assert_eq!(s.dropped(DropReason::Unknown), 1);
    assert_eq!((s.gaps, s.missed), (1, 3));
    rx.stop().unwrap();
}

#[test]
fn allow_list_drops_and_counts_other_senders() {
    let (rx, mut reader) = UdpReceiver::spawn(UdpConfig {
        allow: vec!["10.9.8.7".parse().unwrap()],
        ..loopback_config()
    })
    .unwrap();
    let tx = sender();
    for i in 1..=5u64 {
        tx.send_to(&native::encode(&pose(i), i as u32), rx.local_addr())
            .unwrap();
    }
    wait_received(&rx, 5);
    let s = reader.stats();
    assert_eq!(s.dropped(DropReason::NotAllowed), 5);
    assert_eq!(s.accepted, 0);
    assert!(reader.latest().is_none());
    drop(rx);

    // The same sender on the list is accepted.
    let (rx, mut reader) = UdpReceiver::spawn(UdpConfig {
        allow: vec!["10.9.8.7".parse().unwrap(), "127.0.0.1".parse().unwrap()],
        ..loopback_config()
    })
    .unwrap();
    tx.send_to(&native::encode(&pose(1), 1), rx.local_addr())
        .unwrap();
    wait_received(&rx, 1);
    assert_eq!(reader.stats().accepted, 1);
    assert!(reader.latest().is_some());
}

fn cigi_message(frame: u32, order: ByteOrder, lat: f64) -> Vec<u8> {
    let mut b = IgControl {
        ig_mode: 1,
        minor_version: 3,
        database: 3,
        host_frame: frame,
        ..IgControl::default()
    }
    .encode(order)
    .to_vec();
    b.extend(
        EntityControl {
            entity_state: 1,
            roll_deg: 10.0,
            pitch_deg: -2.0,
            yaw_deg: 135.0,
            lat_deg: lat,
            lon_deg: 11.5,
            alt_m: 3000.0,
            ..EntityControl::default()
        }
        .encode(order),
    );
    b
}

#[test]
fn cigi_host_gets_start_of_frame_and_views_reach_the_reader() {
    let (rx, mut reader) = UdpReceiver::spawn(loopback_config()).unwrap();
    let host = sender();
    host.set_read_timeout(Some(Duration::from_secs(3))).unwrap();
    let mut buf = [0u8; 256];
    for (frame, order) in [(500u32, ByteOrder::Big), (501, ByteOrder::Little)] {
        let mut msg = cigi_message(frame, order, 46.5);
        msg.extend(
            ViewControl {
                view_id: 1,
                enable: 0x20,
                roll_pitch_yaw_deg: [0.0, 0.0, -60.0],
                ..ViewControl::default()
            }
            .encode(order),
        );
        msg.extend(
            ViewDefinition {
                view_id: 1,
                enable: 0x3C,
                left_deg: -30.0,
                right_deg: 30.0,
                top_deg: 20.0,
                bottom_deg: -20.0,
                ..ViewDefinition::default()
            }
            .encode(order),
        );
        host.send_to(&msg, rx.local_addr()).unwrap();
        // The IG answers once per IG frame: begin one once the message is in.
        let link = rx.ig_link();
        wait_for("the message reaches the IG session", || {
            link.state().last_host_frame == Some(frame)
        });
        let ig_frame = IgFrame {
            ig_frame: frame - 499,
            time_s: 1.0,
            database: DatabaseStatus::Ready(3),
        };
        link.begin_frame(&ig_frame, &NoTerrain);
        let (n, from) = host.recv_from(&mut buf).expect("Start of Frame answer");
        assert_eq!(from, rx.local_addr());
        let (sof, got_order) = StartOfFrame::decode(&buf[..n]).unwrap();
        assert_eq!(got_order, order, "answered in the host's byte order");
        assert_eq!(sof.last_host_frame, frame);
        assert_eq!(sof.ig_frame, frame - 499);
        assert_eq!(sof.ig_mode, 1);
        assert_eq!(sof.database, 3);
        assert_eq!(rx.ig_link().state().database_request, Some(3));
    }
    let p = reader.latest().unwrap().latest.pose;
    assert_eq!(p.frame, 501);
    assert_eq!(p.attitude_deg, [135.0, -2.0, 10.0]);
    let v = *reader.views().get(1).unwrap();
    assert_eq!(v.roll_pitch_yaw_deg[2], Some(-60.0));
    assert_eq!(v.half_angles_deg(), Some([-30.0, 30.0, 20.0, -20.0]));
    // The counter is bumped just after the send the host already saw.
    wait_for("two answers counted", || rx.stats().replies == 2);

    // Replies can be switched off.
    let (rx, _reader) = UdpReceiver::spawn(UdpConfig {
        cigi_reply: CigiReply::Off,
        ..loopback_config()
    })
    .unwrap();
    host.send_to(&cigi_message(1, ByteOrder::Big, 46.0), rx.local_addr())
        .unwrap();
    wait_received(&rx, 1);
    let link = rx.ig_link();
    wait_for("the message reaches the IG session", || {
        link.state().last_host_frame == Some(1)
    });
    link.begin_frame(&IgFrame::default(), &NoTerrain);
    host.set_read_timeout(Some(Duration::from_millis(100)))
        .unwrap();
    assert!(host.recv_from(&mut buf).is_err(), "no answer expected");
    assert_eq!(rx.stats().replies, 0);
}

#[test]
fn every_protocol_is_detected_on_one_port_and_forced_ports_refuse_others() {
    let (rx, mut reader) = UdpReceiver::spawn(loopback_config()).unwrap();
    let tx = sender();
    let rpos = xplane::encode(&xplane::Rpos::from_pose(&pose(7), 100.0)).to_vec();
    let fdm = fgfs::encode(&fgfs::FdmPose::from_pose(&pose(8))).to_vec();
    let datagrams = [
        native::encode(&pose(6), 1).to_vec(),
        rpos.clone(),
        fdm.clone(),
        cigi_message(10, ByteOrder::Big, 47.25),
    ];
    let mut lat_seen = Vec::new();
    for (i, d) in datagrams.iter().enumerate() {
        tx.send_to(d, rx.local_addr()).unwrap();
        wait_received(&rx, i as u64 + 1);
        let PosePosition::Geodetic { lat_deg, .. } = reader.latest().unwrap().latest.pose.position
        else {
            panic!("geodetic expected")
        };
        lat_seen.push(lat_deg);
    }
    assert_eq!(reader.stats().accepted, 4);
    let want = [47.00006, 47.00007, 47.00008, 47.25];
    for (got, want) in lat_seen.iter().zip(want) {
        assert!((got - want).abs() < 1e-9, "{lat_seen:?}");
    }

    let (rx, reader) = UdpReceiver::spawn(UdpConfig {
        protocol: "xplane".parse::<ProtocolChoice>().unwrap(),
        ..loopback_config()
    })
    .unwrap();
    tx.send_to(&fdm, rx.local_addr()).unwrap();
    tx.send_to(&rpos, rx.local_addr()).unwrap();
    wait_received(&rx, 2);
    let s = reader.stats();
    assert_eq!((s.accepted, s.dropped(DropReason::Unknown)), (1, 1));
}

/// Flood: a sender thread paced at 100,000 native datagrams/s on loopback for 2 s while a
/// "frame loop" polls the reader at ~60 Hz. Per frame k, with A_k = the receiver's accepted
/// count read just before the poll: the pose the frame gets is the A_k-th accepted pose or a
/// newer one (`sample ≥ A_k`; exact, not timing-dependent: the count is released after the
/// pose is published, and read with acquire), its sequence never goes back, and every poll
/// returns a pose (the reader is wait-free by construction: a triple buffer, no locks, so a
/// receiver thread busy with 100k datagrams/s cannot hold a frame up). The achieved send rate
/// and the kernel's drop count (receive buffer full) are printed, not asserted.
#[test]
fn flood_keeps_the_frame_loop_on_the_newest_pose() {
    const RATE: f64 = 100_000.0;
    const SECONDS: f64 = 2.0;
    let (rx, mut reader) = UdpReceiver::spawn(UdpConfig {
        // 4 MiB asked (the kernel caps it at net.core.rmem_max): fewer kernel drops.
        recv_buffer_bytes: Some(4 << 20),
        ..loopback_config()
    })
    .unwrap();
    let to = rx.local_addr();
    let flood = std::thread::spawn(move || {
        let tx = sender();
        let t = Instant::now();
        let (mut i, mut errors) = (0u64, 0u64);
        loop {
            let el = t.elapsed().as_secs_f64();
            if el >= SECONDS {
                return (i, errors, el);
            }
            // Send what is due by now, then give the CPU away briefly (2 shared cores).
            let due = (el * RATE) as u64;
            while i < due {
                i += 1;
                if tx
                    .send_to(&native::encode(&pose_framed(i), i as u32), to)
                    .is_err()
                {
                    errors += 1;
                }
            }
            std::thread::sleep(Duration::from_micros(200));
        }
    });
    // The frame loop.
    let (mut frames, mut polled, mut last_sample, mut last_frame) = (0u64, 0u64, 0u64, 0u64);
    while !flood.is_finished() {
        let accepted = rx.stats().accepted;
        let got = reader.pose_now();
        frames += 1;
        if accepted > 0 {
            let f = got.unwrap_or_else(|| panic!("frame {frames}: no pose after {accepted}"));
            polled += 1;
            assert!(
                f.sample >= accepted,
                "frame {frames}: pose sample {} older than the {accepted} accepted before the poll",
                f.sample
            );
            // Sequence k is at least the k-th accepted (numbering starts at 1, never repeats).
            assert!(f.pose.frame >= f.sample, "{f:?}");
            assert!(
                f.sample >= last_sample && f.pose.frame >= last_frame,
                "frame {frames} went back: sample {} after {last_sample}",
                f.sample
            );
            (last_sample, last_frame) = (f.sample, f.pose.frame);
        }
        std::thread::sleep(Duration::from_micros(16_667));
    }
    let (sent, send_errors, elapsed) = flood.join().unwrap();
    // After the flood, one more pose arrives and is the one the frame loop gets. (It is
    // repeated until seen: while the flood's backlog fills the socket buffer the kernel drops
    // new datagrams; the repeats are then dropped as duplicates.)
    let tx = sender();
    let last = native::encode(&pose_framed(sent + 1000), (sent + 1000) as u32);
    wait_for("the post-flood pose", || {
        tx.send_to(&last, to).unwrap();
        std::thread::sleep(Duration::from_millis(5));
        reader.latest().map(|s| s.latest.pose.frame) == Some(sent + 1000)
    });
    assert_eq!(reader.pose_now().unwrap().pose.frame, sent + 1000);
    let s = rx.stats();
    let kernel =
        aerie_sim_bridge::udp::kernel_drops(to.port()).map_or("n/a".to_string(), |d| d.to_string());
    eprintln!(
        "flood: {sent} sent in {elapsed:.2} s ({:.0}/s, {send_errors} send errors), {} received, \
         {} accepted, {} gaps ({} missed), kernel drops {kernel}; {frames} frames, {polled} with a pose",
        sent as f64 / elapsed,
        s.received,
        s.accepted,
        s.gaps,
        s.missed
    );
    assert!(s.accepted > 100, "{s:?}");
    assert!(
        polled >= 2,
        "the frame loop ran {frames} frames, {polled} with a pose"
    );
    // Nothing was dropped for a reason other than the flood itself (old/duplicate poses).
    assert_eq!(s.dropped_total(), s.dropped(DropReason::Duplicate), "{s:?}");
}

/// Several receivers on one host share a multicast group's port (SO_REUSEADDR/SO_REUSEPORT on
/// multicast binds) and each gets every datagram; loopback only (IP_MULTICAST_IF 127.0.0.1,
/// IP_MULTICAST_LOOP on), so no multicast route is needed. A unicast port stays exclusive.
#[test]
fn two_receivers_share_a_multicast_group_and_port() {
    let group = Ipv4Addr::new(239, 255, 47, 81);
    let cfg = |port: u16| UdpConfig {
        bind: SocketAddr::from((Ipv4Addr::UNSPECIFIED, port)),
        multicast: Some(group),
        multicast_interface: Ipv4Addr::LOCALHOST,
        ..UdpConfig::default()
    };
    let (rx1, mut r1) = UdpReceiver::spawn(cfg(0)).unwrap();
    let port = rx1.local_addr().port();
    let (rx2, mut r2) = UdpReceiver::spawn(cfg(port)).expect("second receiver on the same port");
    let tx = aerie_sim_bridge::udp::multicast_sender(Ipv4Addr::LOCALHOST).unwrap();
    for i in 1..=3u64 {
        tx.send_to(&native::encode(&pose(i), i as u32), (group, port))
            .unwrap();
    }
    wait_for("both receivers", || {
        rx1.stats().accepted >= 3 && rx2.stats().accepted >= 3
    });
    assert_eq!(r1.latest().unwrap().latest.pose.frame, 3);
    assert_eq!(r2.latest().unwrap().latest.pose.frame, 3);
    // Unicast binds are not shared: a second aerie on the same port fails loudly.
    let (u1, _) = UdpReceiver::spawn(loopback_config()).unwrap();
    let e = UdpReceiver::spawn(UdpConfig {
        bind: u1.local_addr(),
        ..UdpConfig::default()
    })
    .err()
    .expect("unicast port shared");
    assert!(e.to_string().contains(&u1.local_addr().to_string()), "{e}");
}

fn assorted_datagrams() -> Vec<Vec<u8>> {
    let mut v = Vec::new();
    for i in 1..=30u64 {
        v.push(native::encode(&pose(i), i as u32).to_vec());
        if i % 10 == 0 {
            v.push(cigi_message(i as u32, ByteOrder::Little, 45.0));
            v.push(b"\x00\x01garbage".to_vec());
            v.push(Vec::new());
        }
    }
    v
}

fn record_datagrams(path: &Path, datagrams: &[Vec<u8>], spacing: Duration) -> Vec<RecordedPacket> {
    let (rx, _reader) = UdpReceiver::spawn(UdpConfig {
        record: Some(path.to_path_buf()),
        cigi_reply: CigiReply::Off,
        ..loopback_config()
    })
    .unwrap();
    let tx = sender();
    for d in datagrams {
        tx.send_to(d, rx.local_addr()).unwrap();
        std::thread::sleep(spacing);
    }
    wait_received(&rx, datagrams.len() as u64);
    rx.stop().unwrap();
    read_recording(path).unwrap()
}

#[test]
fn record_then_fast_replay_reproduces_the_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let datagrams = assorted_datagrams();
    let first = record_datagrams(
        &dir.path().join("a.aerie-rec"),
        &datagrams,
        Duration::from_millis(1),
    );
    let bytes: Vec<Vec<u8>> = first.iter().map(|p| p.bytes.clone()).collect();
    assert_eq!(
        bytes, datagrams,
        "the recording holds exactly what was sent"
    );
    assert!(first.windows(2).all(|w| w[0].t_ns <= w[1].t_ns));
    // Sent ≥ 1 ms apart: the recorded span is at least (n − 1) ms.
    let span_ms = (first.last().unwrap().t_ns - first[0].t_ns) as f64 / 1e6;
    assert!(
        span_ms >= (datagrams.len() - 1) as f64 * 0.9,
        "span {span_ms} ms"
    );

    // Replay it (fast) into a second recording receiver: same bytes, same order.
    let path_b = dir.path().join("b.aerie-rec");
    let (rx, reader) = UdpReceiver::spawn(UdpConfig {
        record: Some(path_b.clone()),
        cigi_reply: CigiReply::Off,
        ..loopback_config()
    })
    .unwrap();
    let report = replay_packets(
        &first,
        &sender(),
        rx.local_addr(),
        ReplayTiming::Fast,
        |_| {},
    )
    .unwrap();
    assert_eq!(report.packets, datagrams.len());
    wait_received(&rx, datagrams.len() as u64);
    let s = reader.stats();
    rx.stop().unwrap();
    let second = read_recording(&path_b).unwrap();
    assert_eq!(
        second.iter().map(|p| &p.bytes).collect::<Vec<_>>(),
        first.iter().map(|p| &p.bytes).collect::<Vec<_>>()
    );
    // And the replayed input is judged the same way: 33 poses, 3 garbage, 3 empty.
    assert_eq!((s.accepted, s.dropped_total()), (33, 6), "{s:?}");
}

#[test]
fn original_timing_replay_keeps_the_spacing() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("three.aerie-rec");
    let times_ms = [0u64, 80, 200];
    let packets: Vec<RecordedPacket> = times_ms
        .iter()
        .enumerate()
        .map(|(i, t)| RecordedPacket {
            t_ns: 5_000_000_000 + t * 1_000_000,
            bytes: native::encode(&pose(i as u64 + 1), i as u32 + 1).to_vec(),
        })
        .collect();
    write_recording(&path, &packets).unwrap();

    let path_out = dir.path().join("out.aerie-rec");
    let (rx, _reader) = UdpReceiver::spawn(UdpConfig {
        record: Some(path_out.clone()),
        ..loopback_config()
    })
    .unwrap();
    let report = replay_packets(
        &read_recording(&path).unwrap(),
        &sender(),
        rx.local_addr(),
        ReplayTiming::Original,
        |_| {},
    )
    .unwrap();
    wait_received(&rx, 3);
    rx.stop().unwrap();
    let got = read_recording(&path_out).unwrap();
    assert_eq!(got.len(), 3);
    for (i, want) in times_ms.iter().enumerate() {
        let rel = (got[i].t_ns - got[0].t_ns) as f64 / 1e6;
        // Within a loaded machine's scheduling jitter (on either side: the first arrival
        // may be stamped late too).
        assert!(
            (rel - *want as f64).abs() <= 40.0,
            "packet {i} arrived {rel:.1} ms after the first, recorded {want} ms"
        );
        assert_eq!(got[i].bytes, packets[i].bytes);
    }
    assert!((report.recorded_span_s - 0.2).abs() < 1e-9);
    assert!(report.elapsed_s >= 0.198, "{report:?}");
}

#[test]
fn multicast_group_is_joined_when_the_host_supports_it() {
    let group = Ipv4Addr::new(239, 255, 47, 80);
    let spawned = UdpReceiver::spawn(UdpConfig {
        bind: "0.0.0.0:0".parse().unwrap(),
        multicast: Some(group),
        ..UdpConfig::default()
    });
    let (rx, mut reader) = match spawned {
        Ok(x) => x,
        Err(e) => {
            eprintln!("skipped: cannot join {group} here: {e}");
            return;
        }
    };
    // Not bound to 127.0.0.1: the group is routed like any other destination (the default
    // route) and a loopback source address would not leave the host's stack.
    let tx = UdpSocket::bind("0.0.0.0:0").unwrap();
    tx.set_multicast_loop_v4(true).unwrap();
    let to = SocketAddr::from((group, rx.local_addr().port()));
    let t = Instant::now();
    while reader.latest().is_none() && t.elapsed() < Duration::from_millis(500) {
        if let Err(e) = tx.send_to(&native::encode(&pose(1), 1), to) {
            eprintln!("skipped: cannot send to {to} here: {e}");
            return;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    match reader.latest() {
        Some(s) => assert_eq!(s.latest.pose.frame, 1),
        None => eprintln!("skipped: multicast loopback delivers nothing on this host"),
    }
}

#[test]
fn xplane_is_asked_for_rpos_and_answers_to_our_port() {
    // A stand-in for X-Plane: waits for the RPOS request, then streams RPOS to its sender.
    let xplane = UdpSocket::bind("127.0.0.1:0").unwrap();
    xplane
        .set_read_timeout(Some(Duration::from_secs(3)))
        .unwrap();
    let (rx, mut reader) = UdpReceiver::spawn(UdpConfig {
        xplane_rpos: Some(aerie_sim_bridge::RposRequest {
            xplane: xplane.local_addr().unwrap(),
            rate_hz: 30,
        }),
        ..loopback_config()
    })
    .unwrap();
    let mut buf = [0u8; 64];
    let (n, from) = xplane.recv_from(&mut buf).expect("an RPOS request");
    assert_eq!(&buf[..n], b"RPOS\x0030\x00");
    assert_eq!(from, rx.local_addr(), "requested from the listening port");
    let rpos = xplane::encode(&xplane::Rpos::from_pose(&pose(3), 50.0));
    xplane.send_to(&rpos, from).unwrap();
    wait_received(&rx, 1);
    assert_eq!(reader.stats().accepted, 1);
    assert_eq!(
        reader.latest().unwrap().latest.pose.position,
        pose(3).position
    );
}

fn free_port() -> u16 {
    UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

#[test]
fn listen_and_replay_commands() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("flight.aerie-rec");
    let datagrams: Vec<RecordedPacket> = (1..=40u64)
        .map(|i| RecordedPacket {
            t_ns: i * 1_000_000,
            bytes: if i == 20 {
                b"junk".to_vec()
            } else {
                native::encode(&pose(i), i as u32).to_vec()
            },
        })
        .collect();
    write_recording(&rec, &datagrams).unwrap();

    let port = free_port();
    let json = dir.path().join("listen.json");
    let listen_rec = dir.path().join("heard.aerie-rec");
    let args = ListenArgs {
        input: InputArgs {
            listen: Some(SocketAddr::from(([127, 0, 0, 1], port))),
            max_extrapolation_ms: Some(100.0),
            ..InputArgs::default()
        },
        record: Some(listen_rec.clone()),
        seconds: Some(1.2),
        json: Some(json.clone()),
        no_cigi_reply: false,
        ig_rate: listen::DEFAULT_IG_RATE_HZ,
    };
    let listener = std::thread::spawn(move || listen::run(args));
    std::thread::sleep(Duration::from_millis(300));
    replay::run(ReplayArgs {
        file: rec.clone(),
        to: SocketAddr::from(([127, 0, 0, 1], port)),
        fast: true,
    })
    .map_err(|f| f.message)
    .unwrap();
    listener.join().unwrap().map_err(|f| f.message).unwrap();

    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(summary["packets"], 40, "{summary:#}");
    assert_eq!(summary["accepted"], 39);
    assert_eq!(summary["dropped"]["unknown"], 1);
    assert_eq!(summary["gaps"], 1, "seq 20 never came");
    assert_eq!(summary["last_pose"]["frame"], 40);
    assert!(summary["pose_rate_hz"].as_f64().unwrap() > 0.0);
    // The command's own recording holds the replayed bytes.
    let heard = read_recording(&listen_rec).unwrap();
    assert_eq!(
        heard.iter().map(|p| &p.bytes).collect::<Vec<_>>(),
        datagrams.iter().map(|p| &p.bytes).collect::<Vec<_>>()
    );

    // A truncated recording is refused with the byte offset.
    let full = std::fs::read(&rec).unwrap();
    let cut = dir.path().join("cut.aerie-rec");
    std::fs::write(&cut, &full[..full.len() - 3]).unwrap();
    let err = replay::run(ReplayArgs {
        file: cut,
        to: SocketAddr::from(([127, 0, 0, 1], port)),
        fast: true,
    })
    .unwrap_err();
    assert_eq!(err.code, 2);
    assert!(err.message.contains("byte offset"), "{}", err.message);
}

/// The reader side can be moved to another thread (the frame loop's).
#[test]
fn reader_is_send() {
    fn is_send<T: Send>() {}
    is_send::<PoseReader>();
    is_send::<UdpReceiver>();
}
