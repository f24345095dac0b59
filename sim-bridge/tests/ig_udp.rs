//! The IG session over real UDP on loopback: a synchronous CIGI host (one that sends its next
//! message only when a Start of Frame arrives) is paced by the IG's frame rate, and answers
//! arrive in the IG message after the request.

use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use aerie_sim_bridge::codec::cigi::{
    decode_ig_message, CigiResponse, CigiVersion, HatHotRequest, HatHotRequestType, IgControl,
    IgMessage, LosRequestType, LosVectorRequest,
};
use aerie_sim_bridge::codec::{native, ByteOrder};
use aerie_sim_bridge::ig::{DatabaseStatus, IgFrame, IgLink};
use aerie_sim_bridge::query::{
    Answer, LosAnswer, LosHit, NoTerrain, Surface, TerrainQueries, TerrainReply, TerrainRequest,
};
use aerie_sim_bridge::udp::{CigiReply, UdpConfig, UdpReceiver};
use aerie_sim_bridge::PosePosition;

const GROUND_M: f64 = 420.0;

/// Level ground at 420 m; a vector straight down hits it.
struct Level;

impl TerrainQueries for Level {
    fn height_of_terrain(&self, _: &PosePosition) -> Answer<Surface> {
        Answer::Ready(Surface {
            height_m: GROUND_M,
            normal_enu: [0.0, 0.0, 1.0],
        })
    }
    fn line_of_sight(&self, _: &PosePosition, _: &PosePosition) -> LosAnswer {
        Answer::Ready(None)
    }
    fn line_of_sight_vector(
        &self,
        from: &PosePosition,
        _: f64,
        elevation_deg: f64,
        _: f64,
        _: f64,
    ) -> LosAnswer {
        let PosePosition::Geodetic { alt_m, .. } = *from else {
            return Answer::NoTerrain;
        };
        Answer::Ready((elevation_deg < -89.0).then_some(LosHit {
            range_m: alt_m - GROUND_M,
            point: *from,
            normal_enu: [0.0, 0.0, 1.0],
        }))
    }
}

fn receiver() -> (UdpReceiver, IgLink) {
    let (rx, _reader) = UdpReceiver::spawn(UdpConfig {
        bind: "127.0.0.1:0".parse().unwrap(),
        cigi_reply: CigiReply::ToSender,
        ..UdpConfig::default()
    })
    .unwrap();
    let link = rx.ig_link();
    (rx, link)
}

fn host_message(frame: u32, version: CigiVersion, order: ByteOrder, extra: &[u8]) -> Vec<u8> {
    let mut b = IgControl {
        ig_mode: 1,
        host_frame: frame,
        ..IgControl::default()
    }
    .encode_as(version, order);
    b.extend_from_slice(extra);
    b
}

fn frame(n: u32) -> IgFrame {
    IgFrame {
        ig_frame: n,
        time_s: f64::from(n) / 60.0,
        database: DatabaseStatus::Ready(0),
    }
}

fn wait_for(what: &str, f: impl Fn() -> bool) {
    let t = Instant::now();
    while !f() {
        assert!(t.elapsed() < Duration::from_secs(10), "timed out: {what}");
        std::thread::sleep(Duration::from_millis(1));
    }
}

fn recv_message(host: &UdpSocket) -> IgMessage {
    let mut buf = [0u8; 65_536];
    let (n, _) = host.recv_from(&mut buf).expect("an IG message");
    decode_ig_message(&buf[..n]).unwrap_or_else(|e| panic!("{e}"))
}

/// The IG ticks at 100 Hz for a fixed number of frames; the host answers every Start of Frame
/// at once, as the CCL's MiniHost does. Counted, not timed: the host gets exactly one Start
/// of Frame per IG frame and so sends at most one message per frame (it ran away at ~580
/// messages per frame when every host message was answered with a Start of Frame).
#[test]
fn synchronous_host_is_paced_by_the_ig_frame_rate() {
    let (rx, link) = receiver();
    let to = rx.local_addr();
    let host = UdpSocket::bind("127.0.0.1:0").unwrap();
    host.set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let sent = Arc::new(AtomicU64::new(0));
    let sofs = Arc::new(AtomicU64::new(0));
    let host_thread = {
        let (stop, sent, sofs) = (stop.clone(), sent.clone(), sofs.clone());
        std::thread::spawn(move || {
            let mut frame = 1u32;
            host.send_to(
                &host_message(frame, CigiVersion::V3_3, ByteOrder::Big, &[]),
                to,
            )
            .unwrap();
            sent.fetch_add(1, Ordering::Relaxed);
            let mut buf = [0u8; 2048];
            let mut last_ig_frame = 0;
            while !stop.load(Ordering::Relaxed) {
                let Ok((n, _)) = host.recv_from(&mut buf) else {
                    continue;
                };
                let m = decode_ig_message(&buf[..n]).unwrap();
                assert!(
                    m.start_of_frame.ig_frame > last_ig_frame,
                    "IG frames increase"
                );
                last_ig_frame = m.start_of_frame.ig_frame;
                sofs.fetch_add(1, Ordering::Relaxed);
                frame += 1;
                host.send_to(
                    &host_message(frame, CigiVersion::V3_3, ByteOrder::Big, &[]),
                    to,
                )
                .unwrap();
                sent.fetch_add(1, Ordering::Relaxed);
            }
        })
    };
    // Wait for the host's first message, then tick a fixed number of frames at 100 Hz.
    wait_for("the host's first message", || link.stats().messages >= 1);
    let frames = 60u32;
    let start = Instant::now();
    for n in 1..=frames {
        let due = start + Duration::from_millis(10) * n;
        std::thread::sleep(due.saturating_duration_since(Instant::now()));
        let a = link.begin_frame(&frame(n), &NoTerrain);
        assert!(a.start_of_frame, "frame {n}");
    }
    wait_for("the last Start of Frame", || {
        sofs.load(Ordering::Relaxed) >= u64::from(frames)
    });
    stop.store(true, Ordering::Relaxed);
    host_thread.join().unwrap();
    let (sofs, sent) = (sofs.load(Ordering::Relaxed), sent.load(Ordering::Relaxed));
    let st = link.stats();
    assert_eq!(st.start_of_frames, u64::from(frames));
    assert_eq!(sofs, u64::from(frames), "one Start of Frame per IG frame");
    // The host sent its first message, then one per Start of Frame.
    assert_eq!(sent, sofs + 1);
    assert!(st.messages <= sent);
    assert_eq!(rx.stats().replies, u64::from(frames));
    println!(
        "synchronous host: {frames} IG frames in {:.2} s, {sofs} Start of Frames, {sent} host messages",
        start.elapsed().as_secs_f64()
    );
}

/// Lockstep: the host sends a request; once the IG has it, the IG begins a frame; the
/// frame's message carries the answer. One-shot, periodic (every 2 frames) and cancelled
/// HAT/HOT, a LOS vector, a 3.0 big-endian host, and a native query answered to its sender.
#[test]
fn answers_arrive_in_the_message_after_the_request() {
    let (rx, link) = receiver();
    let to = rx.local_addr();
    let host = UdpSocket::bind("127.0.0.1:0").unwrap();
    host.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let v = CigiVersion::V3_3;
    let o = ByteOrder::Little;
    let hot = |id: u16, t: HatHotRequestType, period: u8| {
        HatHotRequest {
            request_id: id,
            request_type: t,
            update_period: period,
            point: [47.1, 11.2, 1000.0],
            ..HatHotRequest::default()
        }
        .encode(v, o)
        .to_vec()
    };
    let mut n = 0u32;
    let mut exchange = |host_frame: u32, extra: Vec<u8>| -> IgMessage {
        let before = link.stats().messages;
        host.send_to(&host_message(host_frame, v, o, &extra), to)
            .unwrap();
        wait_for("the IG takes the message", || {
            link.stats().messages > before
        });
        n += 1;
        link.begin_frame(&frame(n), &Level);
        recv_message(&host)
    };
    let m = exchange(1, hot(1, HatHotRequestType::Hat, 0));
    assert_eq!(m.start_of_frame.last_host_frame, 1);
    let [CigiResponse::HatHot(r)] = m.responses[..] else {
        panic!("{:?}", m.responses)
    };
    assert!(r.valid && r.request_id == 1 && r.height_m == 1000.0 - GROUND_M);
    // Periodic every 2 frames: answered in the next message, then every other one.
    let m = exchange(2, hot(2, HatHotRequestType::Hot, 2));
    assert!(
        matches!(m.responses[..], [CigiResponse::HatHot(r)] if r.request_id == 2 && r.height_m == GROUND_M)
    );
    let mut answered = Vec::new();
    for f in 3..9 {
        let m = exchange(f, Vec::new());
        answered.push(!m.responses.is_empty());
    }
    assert_eq!(answered, [false, true, false, true, false, true]);
    // Cancelled by period 0: one last answer, then none.
    let m = exchange(9, hot(2, HatHotRequestType::Extended, 0));
    assert!(matches!(m.responses[..], [CigiResponse::HatHotExtended(x)] if x.hot_m == GROUND_M));
    for f in 10..14 {
        assert!(exchange(f, Vec::new()).responses.is_empty());
    }
    // A LOS vector straight down from 1,500 m.
    let los = LosVectorRequest {
        request_id: 5,
        request_type: LosRequestType::Basic,
        elevation_deg: -90.0,
        max_range_m: 10_000.0,
        source: [47.1, 11.2, 1500.0],
        ..LosVectorRequest::default()
    }
    .encode(v, o)
    .to_vec();
    let m = exchange(14, los);
    assert!(
        matches!(m.responses[..], [CigiResponse::Los(l)] if l.valid && l.range_m == 1500.0 - GROUND_M),
        "{:?}",
        m.responses
    );
    let st = link.stats();
    assert_eq!(st.latency_max_frames, 1, "{st:?}");
    assert_eq!(st.start_of_frames, u64::from(n));

    // A CIGI 3.0 host in big-endian: a 16-byte Start of Frame in its order, and its answer.
    let old = HatHotRequest {
        request_id: 8,
        request_type: HatHotRequestType::Hot,
        point: [47.1, 11.2, 0.0],
        ..HatHotRequest::default()
    }
    .encode(CigiVersion::V3_0, ByteOrder::Big)
    .to_vec();
    host.send_to(
        &host_message(100, CigiVersion::V3_0, ByteOrder::Big, &old),
        to,
    )
    .unwrap();
    wait_for("the 3.0 message", || {
        link.state().last_host_frame == Some(100)
    });
    link.begin_frame(&frame(100), &Level);
    let mut buf = [0u8; 2048];
    let (len, _) = host.recv_from(&mut buf).unwrap();
    assert_eq!(buf[1], 16, "3.0 Start of Frame size");
    let m = decode_ig_message(&buf[..len]).unwrap();
    assert_eq!(m.byte_order, ByteOrder::Big);
    assert!(
        matches!(m.responses[..], [CigiResponse::HatHot(r)] if r.request_id == 8 && r.height_m == GROUND_M)
    );

    // A native query, answered to its own sender in the next frame.
    let asker = UdpSocket::bind("127.0.0.1:0").unwrap();
    asker
        .set_read_timeout(Some(Duration::from_secs(5)))
        .unwrap();
    let q = native::encode_query(
        4242,
        &TerrainRequest::HeightOfTerrain {
            at: PosePosition::Geodetic {
                lat_deg: 47.1,
                lon_deg: 11.2,
                alt_m: 0.0,
            },
        },
    );
    asker.send_to(&q, to).unwrap();
    wait_for("the native query", || link.stats().native_received == 1);
    link.begin_frame(&frame(101), &Level);
    let (len, from): (usize, SocketAddr) = asker.recv_from(&mut buf).unwrap();
    assert_eq!(from, to);
    let (id, reply) = native::decode_reply(&buf[..len]).unwrap();
    assert_eq!(id, 4242);
    assert!(
        matches!(reply, TerrainReply::HeightOfTerrain(Answer::Ready(s)) if s.height_m == GROUND_M),
        "{reply:?}"
    );
    // The CIGI host got its Start of Frame of that frame too, and nothing else.
    let m = recv_message(&host);
    assert!(m.responses.is_empty());
    let s = rx.stats();
    assert_eq!(s.received, s.accepted + s.no_pose + s.dropped_total());
    assert!(s.cigi_packets.get(24) >= 4, "{:?}", s.cigi_packets);
}
