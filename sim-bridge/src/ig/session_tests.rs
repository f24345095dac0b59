use std::cell::Cell;
use std::net::SocketAddr;

use super::*;
use crate::codec::cigi::{
    self, decode_ig_message, AtmosphereControl, CelestialSphereControl, CigiResponse,
    CoordinateSystem, EntityControl, HatHotRequest, HatHotRequestType, IgControl, IgMessage,
    LosRequestType, LosSegmentRequest, LosVectorRequest,
};
use crate::geodesy::{Geodetic, LocalTangentPlane};
use crate::pose::PosePosition;
use crate::query::{Answer, LosAnswer, LosHit, NoTerrain, Surface};

const HOST: &str = "127.0.0.1:4000";
const H: f64 = 500.0;

fn host() -> SocketAddr {
    HOST.parse().unwrap()
}

/// Flat ground at 500 m; vectors pointing down hit it; segments ending below it hit it half
/// way (enough to tell answers apart). `pending` answers "pending" that many times first.
#[derive(Default)]
struct Ground {
    pending: Cell<u32>,
}

impl Ground {
    fn gate<T>(&self, t: Answer<T>) -> Answer<T> {
        if self.pending.get() > 0 {
            self.pending.set(self.pending.get() - 1);
            Answer::Pending
        } else {
            t
        }
    }
}

impl TerrainQueries for Ground {
    fn height_of_terrain(&self, _: &PosePosition) -> Answer<Surface> {
        self.gate(Answer::Ready(Surface {
            height_m: H,
            normal_enu: [0.0, 0.0, 1.0],
        }))
    }
    fn line_of_sight(&self, from: &PosePosition, to: &PosePosition) -> LosAnswer {
        let below = matches!(to, PosePosition::Geodetic { alt_m, .. } if *alt_m < H);
        self.gate(Answer::Ready(below.then_some(LosHit {
            range_m: 123.0,
            point: *from,
            normal_enu: [0.0, 0.0, 1.0],
        })))
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
            panic!("asked in geodetic")
        };
        self.gate(Answer::Ready((elevation_deg < -89.9).then_some(LosHit {
            range_m: alt_m - H,
            point: *from,
            normal_enu: [0.0, 0.0, 1.0],
        })))
    }
}

fn ig_control(frame: u32, mode: IgMode) -> IgControl {
    IgControl {
        ig_mode: mode.bits(),
        host_frame: frame,
        database: 0,
        ..IgControl::default()
    }
}

/// A host message of `version` in `order`: IG Control then `packets`.
fn message(
    control: IgControl,
    version: CigiVersion,
    order: ByteOrder,
    packets: &[Vec<u8>],
) -> CigiMessage {
    let mut b = control.encode_as(version, order);
    for p in packets {
        b.extend_from_slice(p);
    }
    cigi::decode(&b).unwrap_or_else(|e| panic!("{e}"))
}

fn operate(frame: u32, packets: &[Vec<u8>]) -> CigiMessage {
    message(
        ig_control(frame, IgMode::Operate),
        CigiVersion::V3_3,
        ByteOrder::Little,
        packets,
    )
}

fn hat_hot(id: u16, t: HatHotRequestType, period: u8) -> Vec<u8> {
    HatHotRequest {
        request_id: id,
        request_type: t,
        coordinate_system: CoordinateSystem::Geodetic,
        update_period: period,
        entity_id: 0,
        point: [47.0, 11.0, 1500.0],
    }
    .encode(CigiVersion::V3_3, ByteOrder::Little)
    .to_vec()
}

fn frame_n(n: u32) -> IgFrame {
    IgFrame {
        ig_frame: n,
        time_s: f64::from(n) / 60.0,
        database: DatabaseStatus::Ready(1),
    }
}

/// The CIGI message of a frame's answers, decoded as a host does.
fn cigi_of(a: &FrameAnswers) -> Option<IgMessage> {
    let d = a.datagrams.iter().find(|d| d.to == host())?;
    Some(decode_ig_message(&d.bytes).unwrap_or_else(|e| panic!("{e}")))
}

fn session() -> IgSession {
    IgSession::new(IgConfig::default())
}

#[test]
fn one_start_of_frame_per_frame_however_many_messages_arrived() {
    let mut s = session();
    let g = Ground::default();
    // Nothing known about the host yet: no Start of Frame to send.
    assert!(s.begin_frame(&frame_n(1), &g).datagrams.is_empty());
    for f in 100..105 {
        s.receive(&operate(f, &[]), host());
    }
    let a = s.begin_frame(&frame_n(2), &g);
    assert_eq!(a.datagrams.len(), 1);
    let m = cigi_of(&a).unwrap();
    assert_eq!(m.start_of_frame.ig_frame, 2);
    assert_eq!(m.start_of_frame.last_host_frame, 104);
    assert_eq!(m.start_of_frame.ig_mode, IgMode::Operate.bits());
    assert_eq!(m.start_of_frame.timestamp, timestamp_ticks(2.0 / 60.0));
    assert!(m.responses.is_empty());
    // A frame without host messages still starts with a Start of Frame.
    for n in 3..10 {
        let m = cigi_of(&s.begin_frame(&frame_n(n), &g)).unwrap();
        assert_eq!(m.start_of_frame.ig_frame, n);
        assert_eq!(m.start_of_frame.last_host_frame, 104);
    }
    let st = s.stats();
    assert_eq!(st.start_of_frames, 8);
    assert_eq!(st.messages, 5);
    assert_eq!(st.packets.get(cigi::IG_CONTROL_ID), 5);
}

#[test]
fn answers_come_in_the_next_message_per_request_type() {
    let mut s = session();
    let g = Ground::default();
    s.begin_frame(&frame_n(1), &g);
    s.receive(
        &operate(
            7,
            &[
                hat_hot(1, HatHotRequestType::Hat, 0),
                hat_hot(2, HatHotRequestType::Hot, 0),
                hat_hot(3, HatHotRequestType::Extended, 0),
            ],
        ),
        host(),
    );
    let m = cigi_of(&s.begin_frame(&frame_n(2), &g)).unwrap();
    assert_eq!(m.responses.len(), 3, "{:?}", m.responses);
    let [CigiResponse::HatHot(hat), CigiResponse::HatHot(hot), CigiResponse::HatHotExtended(x)] =
        m.responses[..]
    else {
        panic!("{:?}", m.responses)
    };
    assert!(hat.valid && hot.valid && x.valid);
    assert_eq!(hat.height_m, 1000.0);
    assert_eq!(hot.height_m, H);
    assert_eq!((x.hat_m, x.hot_m, x.material_code), (1000.0, H, 0));
    assert_eq!(x.normal_elevation_deg, 90.0);
    // 3.3: the host frame's four low bits.
    assert_eq!(hat.host_frame_lsn, 7);
    // Answered once.
    let m = cigi_of(&s.begin_frame(&frame_n(3), &g)).unwrap();
    assert!(m.responses.is_empty());
    let st = s.stats();
    assert_eq!((st.requests_received, st.answered), (3, 3));
    assert_eq!(st.latency_frames[1], 3, "latency one frame: {st:?}");
    assert_eq!(st.latency_max_frames, 1);
}

#[test]
fn periodic_requests_every_n_frames_until_period_zero() {
    let mut s = session();
    let g = Ground::default();
    s.receive(
        &operate(1, &[hat_hot(9, HatHotRequestType::Hot, 2)]),
        host(),
    );
    let mut with_answer = Vec::new();
    for n in 1..=8 {
        let m = cigi_of(&s.begin_frame(&frame_n(n), &g)).unwrap();
        if !m.responses.is_empty() {
            with_answer.push(n);
        }
    }
    assert_eq!(with_answer, vec![1, 3, 5, 7]);
    assert_eq!(s.stats().periodic_live, 1);
    s.receive(
        &operate(2, &[hat_hot(9, HatHotRequestType::Hot, 0)]),
        host(),
    );
    let m = cigi_of(&s.begin_frame(&frame_n(9), &g)).unwrap();
    assert_eq!(
        m.responses.len(),
        1,
        "the cancelling request is answered once"
    );
    for n in 10..16 {
        assert!(cigi_of(&s.begin_frame(&frame_n(n), &g))
            .unwrap()
            .responses
            .is_empty());
    }
    let st = s.stats();
    assert_eq!(
        (st.requests_cancelled, st.periodic_live, st.requests_live),
        (1, 0, 0)
    );
}

#[test]
fn pending_terrain_is_asked_again_then_answered_invalid() {
    let mut s = session();
    let g = Ground::default();
    g.pending.set(u32::MAX);
    s.receive(
        &operate(1, &[hat_hot(4, HatHotRequestType::Hat, 0)]),
        host(),
    );
    for n in 1..MAX_PENDING_FRAMES {
        let m = cigi_of(&s.begin_frame(&frame_n(n), &g)).unwrap();
        assert!(m.responses.is_empty(), "frame {n}");
    }
    let m = cigi_of(&s.begin_frame(&frame_n(MAX_PENDING_FRAMES), &g)).unwrap();
    let [CigiResponse::HatHot(r)] = m.responses[..] else {
        panic!("{:?}", m.responses)
    };
    assert!(!r.valid);
    let st = s.stats();
    assert_eq!((st.timed_out, st.answered_invalid), (1, 1));
    assert_eq!(st.latency_max_frames, u64::from(MAX_PENDING_FRAMES));
}

#[test]
fn reset_clears_host_state_and_reports_standby_until_operate() {
    let mut s = session();
    let g = Ground::default();
    let entity = |id: u16| {
        EntityControl {
            entity_id: id,
            entity_state: 1,
            alpha: 255,
            lat_deg: 47.0,
            lon_deg: 11.0,
            alt_m: 2000.0,
            ..EntityControl::default()
        }
        .encode(ByteOrder::Little)
        .to_vec()
    };
    s.receive(
        &operate(
            1,
            &[
                entity(0),
                entity(5),
                entity(6),
                hat_hot(1, HatHotRequestType::Hat, 3),
            ],
        ),
        host(),
    );
    assert_eq!(s.state().entities, 3);
    assert_eq!(s.state().requests_live, 1);
    // The host resets the IG: requests dropped, entities but the ownship forgotten.
    let r = s.receive(
        &message(
            ig_control(2, IgMode::ResetOrStandby),
            CigiVersion::V3_3,
            ByteOrder::Little,
            &[entity(7), hat_hot(2, HatHotRequestType::Hat, 0)],
        ),
        host(),
    );
    assert!(r.reset);
    let st = s.state();
    assert_eq!((st.entities, st.requests_live, st.resets), (1, 0, 1));
    assert!(s.entities().get(0).is_some());
    assert_eq!(st.mode, IgMode::ResetOrStandby);
    // Standby in every Start of Frame until the host says Operate, and nothing answered.
    for n in 1..4 {
        let m = cigi_of(&s.begin_frame(&frame_n(n), &g)).unwrap();
        assert_eq!(m.start_of_frame.ig_mode, IgMode::ResetOrStandby.bits());
        assert!(m.responses.is_empty());
        let again = s.receive(
            &message(
                ig_control(2 + n, IgMode::ResetOrStandby),
                CigiVersion::V3_3,
                ByteOrder::Little,
                &[],
            ),
            host(),
        );
        assert!(!again.reset, "still the same reset");
    }
    assert_eq!(s.state().resets, 1);
    assert_eq!(s.stats().ignored_in_standby, 2);
    s.receive(&operate(10, &[entity(8)]), host());
    let m = cigi_of(&s.begin_frame(&frame_n(5), &g)).unwrap();
    assert_eq!(m.start_of_frame.ig_mode, IgMode::Operate.bits());
    assert_eq!(s.state().entities, 2);
    assert_eq!(s.state().mode, IgMode::Operate);
}

#[test]
fn database_request_is_exposed_and_loading_reports_minus_n() {
    let mut s = session();
    let g = Ground::default();
    let mut c = ig_control(1, IgMode::Operate);
    c.database = 3;
    s.receive(
        &message(c, CigiVersion::V3_3, ByteOrder::Little, &[]),
        host(),
    );
    // 0 means "no change": the request stays.
    s.receive(&operate(2, &[]), host());
    assert_eq!(s.state().database_request, Some(3));
    let loading = IgFrame {
        database: DatabaseStatus::Loading(3),
        ..frame_n(1)
    };
    let m = cigi_of(&s.begin_frame(&loading, &g)).unwrap();
    assert_eq!(m.start_of_frame.database, -3);
    let ready = IgFrame {
        database: DatabaseStatus::Ready(3),
        ..frame_n(2)
    };
    let m = cigi_of(&s.begin_frame(&ready, &g)).unwrap();
    assert_eq!(m.start_of_frame.database, 3);
    assert_eq!(DatabaseStatus::Unavailable.wire(), -128);
    assert_eq!(DatabaseStatus::Loading(-128).wire(), -128);
}

#[test]
fn answers_go_out_in_the_hosts_version_and_byte_order() {
    for version in CigiVersion::ALL {
        for order in [ByteOrder::Big, ByteOrder::Little] {
            let mut s = session();
            let req = HatHotRequest {
                request_id: 11,
                request_type: HatHotRequestType::Hot,
                point: [47.0, 11.0, 0.0],
                ..HatHotRequest::default()
            }
            .encode(version, order)
            .to_vec();
            s.receive(
                &message(ig_control(0x25, IgMode::Operate), version, order, &[req]),
                host(),
            );
            let a = s.begin_frame(&frame_n(1), &Ground::default());
            let bytes = &a.datagrams[0].bytes;
            // 3.0 and 3.1 hosts get the 16-byte Start of Frame.
            let sof_size = if version.is_3_2_or_later() { 24 } else { 16 };
            assert_eq!(bytes[1], sof_size, "{version}");
            let m = cigi_of(&a).unwrap();
            assert_eq!(m.byte_order, order, "{version}");
            if version.is_3_2_or_later() {
                assert_eq!(m.version, version);
            }
            let [CigiResponse::HatHot(r)] = m.responses[..] else {
                panic!("{version} {order:?}: {:?}", m.responses)
            };
            assert_eq!((r.request_id, r.height_m), (11, H));
            let lsn = if version.is_3_2_or_later() { 5 } else { 0 };
            assert_eq!(r.host_frame_lsn, lsn, "{version}");
        }
    }
}

#[test]
fn line_of_sight_segments_and_vectors() {
    let mut s = session();
    let g = Ground::default();
    let seg = |id: u16, to_alt: f64, t: LosRequestType| {
        LosSegmentRequest {
            request_id: id,
            request_type: t,
            source: [47.0, 11.0, 1000.0],
            destination: [47.01, 11.0, to_alt],
            ..LosSegmentRequest::default()
        }
        .encode(CigiVersion::V3_3, ByteOrder::Little)
        .to_vec()
    };
    let down = LosVectorRequest {
        request_id: 3,
        request_type: LosRequestType::Extended,
        elevation_deg: -90.0,
        max_range_m: 5000.0,
        source: [47.0, 11.0, 800.0],
        ..LosVectorRequest::default()
    }
    .encode(CigiVersion::V3_3, ByteOrder::Little)
    .to_vec();
    s.receive(
        &operate(
            1,
            &[
                seg(1, 900.0, LosRequestType::Basic),
                seg(2, 100.0, LosRequestType::Basic),
                down,
            ],
        ),
        host(),
    );
    let m = cigi_of(&s.begin_frame(&frame_n(1), &g)).unwrap();
    let [CigiResponse::Los(clear), CigiResponse::Los(hit), CigiResponse::LosExtended(v)] =
        m.responses[..]
    else {
        panic!("{:?}", m.responses)
    };
    assert!(!clear.valid && clear.visible && !clear.entity_id_valid);
    assert!(hit.valid && !hit.visible && hit.range_m == 123.0);
    assert!(v.valid && v.range_valid && !v.entity_id_valid);
    assert_eq!(v.range_m, 300.0);
    assert_eq!(v.point, [47.0, 11.0, 800.0]);
    assert_eq!(v.point_coordinate_system, CoordinateSystem::Geodetic);
    assert_eq!(v.response_count, 1);
}

#[test]
fn entity_relative_requests_use_the_entity_pose() {
    let mut s = session();
    let g = Ground::default();
    let origin = Geodetic::new(46.5, 7.5, 1200.0);
    let ship = EntityControl {
        entity_id: 0,
        entity_state: 1,
        alpha: 255,
        yaw_deg: 90.0,
        lat_deg: origin.lat_deg,
        lon_deg: origin.lon_deg,
        alt_m: origin.alt_m,
        ..EntityControl::default()
    }
    .encode(ByteOrder::Little)
    .to_vec();
    // 30 m ahead and 10 m below the ownship, facing east.
    let req = HatHotRequest {
        request_id: 1,
        request_type: HatHotRequestType::Extended,
        coordinate_system: CoordinateSystem::Entity,
        entity_id: 0,
        point: [30.0, 0.0, 10.0],
        ..HatHotRequest::default()
    }
    .encode(CigiVersion::V3_3, ByteOrder::Little)
    .to_vec();
    s.receive(&operate(1, &[ship, req]), host());
    let m = cigi_of(&s.begin_frame(&frame_n(1), &g)).unwrap();
    let [CigiResponse::HatHotExtended(x)] = m.responses[..] else {
        panic!("{:?}", m.responses)
    };
    // The point's altitude, from the geodesy: 30 m east and 10 m down in the tangent plane.
    let p = LocalTangentPlane::new(origin).enu_to_geodetic(glam::DVec3::new(30.0, 0.0, -10.0));
    assert!(
        (x.hat_m - (p.alt_m - H)).abs() < 1e-9,
        "{} vs {}",
        x.hat_m,
        p.alt_m - H
    );
    assert!((x.hat_m - 690.0).abs() < 0.01);
}

#[test]
fn native_queries_are_answered_to_their_sender_in_the_frame() {
    let mut s = session();
    let g = Ground::default();
    let sender: SocketAddr = "127.0.0.1:5000".parse().unwrap();
    let at = PosePosition::Geodetic {
        lat_deg: 47.0,
        lon_deg: 11.0,
        alt_m: 0.0,
    };
    s.receive_native(77, TerrainRequest::HeightOfTerrain { at }, sender);
    g.pending.set(1);
    let a = s.begin_frame(&frame_n(1), &g);
    assert!(a.datagrams.is_empty(), "pending: asked again next frame");
    let a = s.begin_frame(&frame_n(2), &g);
    assert_eq!(a.native, 1);
    assert_eq!(a.datagrams[0].to, sender);
    let (id, reply) = native::decode_reply(&a.datagrams[0].bytes).unwrap();
    assert_eq!(id, 77);
    assert!(
        matches!(reply, TerrainReply::HeightOfTerrain(Answer::Ready(s)) if s.height_m == H),
        "{reply:?}"
    );
    // Never ready: answered "pending" (timed out) after the bound.
    s.receive_native(78, TerrainRequest::HeightOfTerrain { at }, sender);
    g.pending.set(u32::MAX);
    let mut answers = 0;
    for n in 0..MAX_PENDING_FRAMES {
        let a = s.begin_frame(&frame_n(3 + n), &g);
        answers += a.native;
        if a.native == 1 {
            let (_, reply) = native::decode_reply(&a.datagrams[0].bytes).unwrap();
            assert!(TerrainRequest::is_pending(&reply), "{reply:?}");
            assert_eq!(n, MAX_PENDING_FRAMES - 1);
        }
    }
    assert_eq!(answers, 1);
    assert_eq!(s.stats().native_timed_out, 1);
}

#[test]
fn reply_destinations() {
    let g = NoTerrain;
    let fixed: SocketAddr = "127.0.0.1:6000".parse().unwrap();
    // A fixed address gets Start of Frame from the first frame, before the host spoke.
    let mut s = IgSession::new(IgConfig {
        reply: CigiReply::To(fixed),
    });
    let a = s.begin_frame(&frame_n(1), &g);
    assert_eq!(a.datagrams.len(), 1);
    assert_eq!(a.datagrams[0].to, fixed);
    s.receive(&operate(3, &[]), host());
    assert_eq!(s.begin_frame(&frame_n(2), &g).datagrams[0].to, fixed);
    // Off: nothing, ever.
    let mut s = IgSession::new(IgConfig {
        reply: CigiReply::Off,
    });
    s.receive(
        &operate(3, &[hat_hot(1, HatHotRequestType::Hat, 0)]),
        host(),
    );
    assert!(s.begin_frame(&frame_n(1), &g).datagrams.is_empty());
    assert_eq!(s.stats().responses_unsent, 1);
}

#[test]
fn a_full_message_defers_the_rest_to_the_next() {
    let mut s = session();
    let g = Ground::default();
    // Extended responses are 40 bytes: 1000 of them do not fit one message.
    let n = 1000u16;
    let reqs: Vec<Vec<u8>> = (0..n)
        .map(|id| hat_hot(id, HatHotRequestType::Extended, 0))
        .collect();
    for chunk in reqs.chunks(100) {
        s.receive(&operate(1, chunk), host());
    }
    let mut got = 0;
    let mut frames = 0;
    while got < usize::from(n) {
        frames += 1;
        let a = s.begin_frame(&frame_n(frames), &g);
        assert!(a.datagrams[0].bytes.len() <= MAX_MESSAGE_BYTES);
        got += cigi_of(&a).unwrap().responses.len();
        assert!(frames < 10);
    }
    assert_eq!(got, usize::from(n));
    assert_eq!(frames, 3);
    assert!(s.stats().deferred > 0);
}

#[test]
fn environment_and_rejected_requests() {
    let mut s = session();
    let g = Ground::default();
    s.begin_frame(
        &IgFrame {
            time_s: 50.0,
            ..frame_n(1)
        },
        &g,
    );
    let celestial = CelestialSphereControl {
        hour: 12,
        minute: 30,
        ephemeris_enabled: true,
        sun_enabled: true,
        date_valid: true,
        month: 6,
        day: 21,
        year: 2024,
        ..CelestialSphereControl::default()
    }
    .encode(ByteOrder::Little)
    .to_vec();
    let atmosphere = AtmosphereControl {
        visibility_m: 8000.0,
        ..AtmosphereControl::default()
    }
    .encode(ByteOrder::Little)
    .to_vec();
    // HAT/HOT requests with a latitude of 95°: rejected by the codec, answered invalid in
    // the response their type asks for.
    let bad = |id, t| {
        HatHotRequest {
            request_id: id,
            request_type: t,
            point: [95.0, 0.0, 0.0],
            ..HatHotRequest::default()
        }
        .encode(CigiVersion::V3_3, ByteOrder::Little)
        .to_vec()
    };
    let m = operate(
        1,
        &[
            celestial,
            atmosphere,
            bad(40, HatHotRequestType::Hat),
            bad(41, HatHotRequestType::Extended),
        ],
    );
    assert_eq!(m.rejected.len(), 2, "{:?}", m.rejected);
    s.receive(&m, host());
    let env = s.state().environment;
    let c = env.celestial.unwrap();
    assert_eq!(c.date, Some((2024, 6, 21)));
    assert_eq!((c.seconds_utc, c.set_at_s), (45_000.0, 50.0));
    assert_eq!(env.visibility_m(), Some(8000.0));
    // Solstice noon-ish over Greenwich: the sun high in the south.
    let sun = env.sun_direction_enu(50.0, 51.48, 0.0).unwrap();
    assert!(sun[2] > 0.85 && sun[1] < 0.0, "{sun:?}");
    let m = cigi_of(&s.begin_frame(&frame_n(2), &g)).unwrap();
    assert!(
        matches!(m.responses[..], [CigiResponse::HatHot(r), CigiResponse::HatHotExtended(x)]
            if r.request_id == 40 && !r.valid && x.request_id == 41 && !x.valid),
        "{:?}",
        m.responses
    );
    assert_eq!(s.stats().requests_rejected, 2);
}

mod random_hosts {
    use super::*;
    use crate::codec::cigi::{ConformalClampedEntityControl, RateControl};
    use proptest::prelude::*;

    /// Answers drawn from a seed: ready (with a hit or not), no terrain, or pending.
    struct Dice(Cell<u64>);

    impl Dice {
        fn roll(&self) -> u64 {
            let x = self
                .0
                .get()
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            self.0.set(x);
            x >> 33
        }
        fn pick<T>(&self, t: T) -> Answer<T> {
            match self.roll() % 4 {
                0 => Answer::NoTerrain,
                1 => Answer::Pending,
                _ => Answer::Ready(t),
            }
        }
    }

    impl TerrainQueries for Dice {
        fn height_of_terrain(&self, _: &PosePosition) -> Answer<Surface> {
            self.pick(Surface {
                height_m: (self.roll() % 3000) as f64,
                normal_enu: [0.0, 0.6, 0.8],
            })
        }
        fn line_of_sight(&self, from: &PosePosition, _: &PosePosition) -> LosAnswer {
            let hit = self.roll() % 2 == 0;
            self.pick(hit.then_some(LosHit {
                range_m: 10.0,
                point: *from,
                normal_enu: [0.0, 0.0, 1.0],
            }))
        }
        fn line_of_sight_vector(
            &self,
            f: &PosePosition,
            _: f64,
            _: f64,
            _: f64,
            _: f64,
        ) -> LosAnswer {
            self.line_of_sight(f, f)
        }
    }

    fn value() -> impl Strategy<Value = f64> {
        prop_oneof![
            -90.0..90.0f64,
            -1e7..1e7f64,
            Just(0.0),
            Just(1e300),
            Just(-1e300),
        ]
    }

    fn packet() -> impl Strategy<Value = (u8, u16, u8, bool, [f64; 3], u16)> {
        (
            0u8..7,
            0u16..6,
            0u8..4,
            any::<bool>(),
            [value(), value(), value()],
            0u16..6,
        )
    }

    fn encode(p: &(u8, u16, u8, bool, [f64; 3], u16), v: CigiVersion, o: ByteOrder) -> Vec<u8> {
        let &(kind, id, small, flag, point, other) = p;
        let cs = if flag {
            CoordinateSystem::Entity
        } else {
            CoordinateSystem::Geodetic
        };
        match kind {
            0 => HatHotRequest {
                request_id: id,
                request_type: match small % 3 {
                    0 => HatHotRequestType::Hat,
                    1 => HatHotRequestType::Hot,
                    _ => HatHotRequestType::Extended,
                },
                coordinate_system: cs,
                update_period: small,
                entity_id: other,
                point,
            }
            .encode(v, o)
            .to_vec(),
            1 => LosSegmentRequest {
                request_id: id,
                source_coordinate_system: cs,
                destination_coordinate_system: cs,
                destination_entity_id_valid: small % 2 == 0,
                destination_entity_id: other,
                entity_id: other,
                update_period: small,
                source: point,
                destination: [point[1], point[0], point[2] - 100.0],
                ..LosSegmentRequest::default()
            }
            .encode(v, o)
            .to_vec(),
            2 => LosVectorRequest {
                request_id: id,
                source_coordinate_system: cs,
                entity_id: other,
                azimuth_deg: (point[0] as f32).clamp(-180.0, 180.0),
                elevation_deg: (point[1] as f32).clamp(-90.0, 90.0),
                max_range_m: 1000.0,
                update_period: small,
                source: point,
                ..LosVectorRequest::default()
            }
            .encode(v, o)
            .to_vec(),
            3 | 4 => EntityControl {
                entity_id: id,
                entity_state: small % 3,
                attached: flag,
                parent_id: other,
                alpha: 255,
                yaw_deg: point[0] as f32,
                lat_deg: point[0],
                lon_deg: point[1],
                alt_m: point[2],
                ..EntityControl::default()
            }
            .encode(o)
            .to_vec(),
            5 => ConformalClampedEntityControl {
                entity_id: id,
                yaw_deg: 10.0,
                lat_deg: point[0],
                lon_deg: point[1],
            }
            .encode(o)
            .to_vec(),
            _ => RateControl {
                entity_id: id,
                apply_to_articulated_part: flag,
                linear_m_s: [1.0, 2.0, 3.0],
                ..RateControl::default()
            }
            .encode(v, o)
            .to_vec(),
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(128))]

        /// Any sequence of host messages and frames: never a panic, one decodable message per
        /// frame once the host is known (under the size bound), the mode it reports the last
        /// message's, and nothing pending beyond the bound.
        #[test]
        fn any_host_gets_one_message_per_frame(
            seed in any::<u64>(),
            steps in prop::collection::vec(
                (0u8..5, 0usize..4, any::<bool>(), prop::collection::vec(packet(), 0..6)),
                1..40,
            ),
        ) {
            let mut s = session();
            let dice = Dice(Cell::new(seed));
            let mut host_frame = 0u32;
            let mut frame = 0u32;
            let mut known = false;
            let mut standby = false;
            for (what, version, big, packets) in steps {
                if what == 0 {
                    frame += 1;
                    let a = s.begin_frame(&frame_n(frame), &dice);
                    let cigi: Vec<_> = a.datagrams.iter().filter(|d| d.to == host()).collect();
                    prop_assert_eq!(cigi.len(), usize::from(known));
                    if let Some(d) = cigi.first() {
                        prop_assert!(d.bytes.len() <= MAX_MESSAGE_BYTES);
                        let m = decode_ig_message(&d.bytes).unwrap();
                        prop_assert_eq!(m.start_of_frame.ig_frame, frame);
                        prop_assert_eq!(m.start_of_frame.ig_mode == 0, standby);
                        prop_assert_eq!(m.responses.len(), a.responses);
                    }
                    continue;
                }
                let v = CigiVersion::ALL[version];
                let o = if big { ByteOrder::Big } else { ByteOrder::Little };
                let mode = if what == 1 { IgMode::ResetOrStandby } else { IgMode::Operate };
                host_frame += 1;
                let mut b = ig_control(host_frame, mode).encode_as(v, o);
                for p in &packets {
                    b.extend(encode(p, v, o));
                }
                if let Ok(m) = cigi::decode(&b) {
                    s.receive(&m, host());
                    known = true;
                    standby = mode == IgMode::ResetOrStandby;
                }
            }
            // However the dice fell, nothing waits longer than the pending bound.
            for _ in 0..MAX_PENDING_FRAMES + 1 {
                frame += 1;
                s.begin_frame(&frame_n(frame), &NoTerrain);
            }
            let st = s.stats();
            prop_assert_eq!(st.periodic_live, st.requests_live);
            prop_assert!(st.latency_max_frames <= u64::from(MAX_PENDING_FRAMES));
        }
    }
}
