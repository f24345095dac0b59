use std::cell::Cell;

use super::*;
use crate::ig::entities::EntityControlUpdate;

/// Ground at 100 m with a normal tilted 45° towards the east; line of sight hits where a
/// straight segment (in altitude) crosses 100 m; `pending` answers "pending" that many times.
struct Plane {
    pending: Cell<u32>,
    calls: Cell<u32>,
}

impl Plane {
    fn new(pending: u32) -> Self {
        Plane {
            pending: Cell::new(pending),
            calls: Cell::new(0),
        }
    }
    fn gate<T>(&self, t: Answer<T>) -> Answer<T> {
        self.calls.set(self.calls.get() + 1);
        if self.pending.get() > 0 {
            self.pending.set(self.pending.get() - 1);
            return Answer::Pending;
        }
        t
    }
}

const H: f64 = 100.0;
const N: [f64; 3] = [
    std::f64::consts::FRAC_1_SQRT_2,
    0.0,
    std::f64::consts::FRAC_1_SQRT_2,
];

fn geo(p: &PosePosition) -> Geodetic {
    match *p {
        PosePosition::Geodetic {
            lat_deg,
            lon_deg,
            alt_m,
        } => Geodetic::new(lat_deg, lon_deg, alt_m),
        PosePosition::LocalEnu { .. } => panic!("the session asks in geodetic"),
    }
}

impl TerrainQueries for Plane {
    fn height_of_terrain(&self, _: &PosePosition) -> Answer<Surface> {
        self.gate(Answer::Ready(Surface {
            height_m: H,
            normal_enu: N,
        }))
    }
    fn line_of_sight(&self, from: &PosePosition, to: &PosePosition) -> LosAnswer {
        let (a, b) = (geo(from), geo(to));
        let hit = (a.alt_m > H && b.alt_m < H).then(|| {
            let ltp = LocalTangentPlane::new(a);
            let d = ltp.geodetic_to_enu(b);
            let f = (a.alt_m - H) / (a.alt_m - b.alt_m);
            LosHit {
                range_m: d.length() * f,
                point: geodetic(ltp.enu_to_geodetic(d * f)),
                normal_enu: N,
            }
        });
        self.gate(Answer::Ready(hit))
    }
    fn line_of_sight_vector(
        &self,
        from: &PosePosition,
        azimuth_deg: f64,
        elevation_deg: f64,
        min_range_m: f64,
        max_range_m: f64,
    ) -> LosAnswer {
        let a = geo(from);
        let down = -elevation_deg.to_radians().sin();
        let range = (a.alt_m - H) / down;
        let hit = (down > 0.0 && range >= min_range_m && range <= max_range_m).then(|| LosHit {
            range_m: range,
            point: geodetic(along_ray(a, azimuth_deg, elevation_deg, range)),
            normal_enu: N,
        });
        self.gate(Answer::Ready(hit))
    }
}

use crate::query::LosAnswer;

fn at(lat: f64, lon: f64, alt: f64) -> RequestPoint {
    RequestPoint::Geodetic(Geodetic::new(lat, lon, alt))
}

fn hot(id: u16, kind: HotKind, period: u8) -> HostRequest {
    HostRequest::Hot(HotRequest {
        id,
        kind,
        at: at(47.0, 11.0, 350.0),
        period,
    })
}

/// Runs one frame: the answers given.
fn frame(
    t: &mut RequestTable,
    tick: u64,
    e: &EntityTable,
    terrain: &dyn TerrainQueries,
) -> Vec<Completion> {
    let (jobs, mut refused) = t.due(tick, e);
    let mut out: Vec<Completion> = refused
        .drain(..)
        .map(|response| Completion::Answer {
            response,
            latency_frames: Some(1),
            timed_out: false,
        })
        .collect();
    for j in jobs {
        let o = j.ask(terrain);
        out.push(t.complete(j.key, o, tick));
    }
    out
}

fn responses(c: &[Completion]) -> Vec<Response> {
    c.iter()
        .filter_map(|c| match c {
            Completion::Answer { response, .. } => Some(*response),
            _ => None,
        })
        .collect()
}

#[test]
fn one_shot_is_answered_once_in_the_next_frame() {
    let mut t = RequestTable::default();
    let e = EntityTable::default();
    let g = Plane::new(0);
    assert_eq!(t.add(hot(7, HotKind::Hat, 0), 10), Added::New);
    // Not before the frame after its arrival.
    assert!(frame(&mut t, 10, &e, &g).is_empty());
    let c = frame(&mut t, 11, &e, &g);
    assert_eq!(c.len(), 1);
    let Completion::Answer {
        response: Response::Hot(r),
        latency_frames,
        timed_out,
    } = c[0]
    else {
        panic!("{c:?}")
    };
    assert_eq!(latency_frames, Some(1));
    assert!(!timed_out);
    assert!(r.valid);
    assert_eq!((r.id, r.kind), (7, HotKind::Hat));
    assert_eq!(r.hot_m, H);
    assert_eq!(r.hat_m, 250.0);
    // The normal leans east by 45°: azimuth 90, elevation 45.
    assert!((r.normal_azimuth_deg - 90.0).abs() < 1e-4);
    assert!((r.normal_elevation_deg - 45.0).abs() < 1e-4);
    assert!(t.is_empty());
    assert!(frame(&mut t, 12, &e, &g).is_empty());
}

#[test]
fn periodic_every_n_frames_until_cancelled_by_period_zero() {
    let mut t = RequestTable::default();
    let e = EntityTable::default();
    let g = Plane::new(0);
    t.add(hot(3, HotKind::Extended, 3), 0);
    let mut answered = Vec::new();
    for tick in 1..=10 {
        let c = frame(&mut t, tick, &e, &g);
        if !c.is_empty() {
            answered.push(tick);
        }
    }
    assert_eq!(answered, vec![1, 4, 7, 10]);
    assert_eq!(t.periodic(), 1);
    // The same ID with period 0: answered once more, then no more.
    assert_eq!(
        t.add(hot(3, HotKind::Extended, 0), 10),
        Added::Replaced { was_periodic: true }
    );
    let c = frame(&mut t, 11, &e, &g);
    assert_eq!(responses(&c).len(), 1);
    for tick in 12..20 {
        assert!(frame(&mut t, tick, &e, &g).is_empty(), "tick {tick}");
    }
    assert!(t.is_empty());
}

#[test]
fn pending_is_retried_then_answered_invalid() {
    let e = EntityTable::default();
    // Pending twice, then ready: answered in the third frame, latency 3.
    let mut t = RequestTable::default();
    let g = Plane::new(2);
    t.add(hot(1, HotKind::Hot, 0), 0);
    assert_eq!(frame(&mut t, 1, &e, &g), vec![Completion::Retry]);
    assert_eq!(frame(&mut t, 2, &e, &g), vec![Completion::Retry]);
    let c = frame(&mut t, 3, &e, &g);
    assert!(
        matches!(c[..], [Completion::Answer { response: Response::Hot(r), latency_frames: Some(3), timed_out: false }] if r.valid && r.hot_m == H),
        "{c:?}"
    );
    // Never ready: invalid after MAX_PENDING_FRAMES frames, and gone.
    let mut t = RequestTable::default();
    let g = Plane::new(u32::MAX);
    t.add(hot(2, HotKind::Hat, 0), 0);
    for tick in 1..u64::from(MAX_PENDING_FRAMES) {
        assert_eq!(
            frame(&mut t, tick, &e, &g),
            vec![Completion::Retry],
            "tick {tick}"
        );
    }
    let c = frame(&mut t, u64::from(MAX_PENDING_FRAMES), &e, &g);
    let [Completion::Answer {
        response: Response::Hot(r),
        latency_frames,
        timed_out: true,
    }] = c[..]
    else {
        panic!("{c:?}")
    };
    assert!(!r.valid);
    assert_eq!(latency_frames, Some(u64::from(MAX_PENDING_FRAMES)));
    assert!(t.is_empty());
    assert_eq!(g.calls.get(), MAX_PENDING_FRAMES);
}

#[test]
fn a_replacement_while_asking_makes_the_outcome_stale() {
    let mut t = RequestTable::default();
    let e = EntityTable::default();
    let g = Plane::new(0);
    t.add(hot(5, HotKind::Hot, 0), 0);
    let (jobs, _) = t.due(1, &e);
    let outcome = jobs[0].ask(&g);
    // The host re-sent ID 5 while the terrain was being asked.
    t.add(hot(5, HotKind::Hat, 0), 1);
    assert_eq!(t.complete(jobs[0].key, outcome, 1), Completion::Stale);
    let c = frame(&mut t, 2, &e, &g);
    assert!(matches!(responses(&c)[..], [Response::Hot(r)] if r.kind == HotKind::Hat));
}

#[test]
fn entity_relative_requests_follow_the_entity_and_end_with_it() {
    let mut t = RequestTable::default();
    let mut e = EntityTable::default();
    let g = Plane::new(0);
    let origin = Geodetic::new(47.0, 11.0, 600.0);
    e.apply_control(
        &EntityControlUpdate {
            id: 9,
            state: 1,
            attached: false,
            parent: 0,
            entity_type: 0,
            alpha: 255,
            lat_or_x: origin.lat_deg,
            lon_or_y: origin.lon_deg,
            alt_or_z: origin.alt_m,
            attitude_deg: [0.0, 0.0, 0.0],
        },
        1,
    );
    // 20 m below the entity: HAT = 600 − 20 − 100.
    t.add(
        HostRequest::Hot(HotRequest {
            id: 1,
            kind: HotKind::Hat,
            at: RequestPoint::Entity {
                entity: 9,
                offset_m: [0.0, 0.0, 20.0],
            },
            period: 1,
        }),
        0,
    );
    // A vector straight down the entity's body z axis (elevation −90 in body axes).
    t.add(
        HostRequest::Los(LosRequest {
            id: 2,
            extended: true,
            shape: LosShape::Vector {
                from: RequestPoint::Entity {
                    entity: 9,
                    offset_m: [0.0; 3],
                },
                azimuth_deg: 0.0,
                elevation_deg: -90.0,
                min_range_m: 0.0,
                max_range_m: 10_000.0,
            },
            period: 1,
        }),
        0,
    );
    let r = responses(&frame(&mut t, 1, &e, &g));
    let [Response::Hot(h), Response::Los(l)] = r[..] else {
        panic!("{r:?}")
    };
    assert!(h.valid);
    assert!((h.hat_m - 480.0).abs() < 1e-6, "{}", h.hat_m);
    assert!(l.valid && !l.visible);
    assert!((l.range_m - 500.0).abs() < 1e-6, "{}", l.range_m);
    assert!((l.point.alt_m - H).abs() < 1e-6);
    // The entity is destroyed: its periodic requests end.
    assert_eq!(t.cancel_for_entity(9), 2);
    assert!(t.is_empty());
    // A one-shot for an unknown entity is answered invalid, not retried.
    t.add(
        HostRequest::Hot(HotRequest {
            id: 4,
            kind: HotKind::Hot,
            at: RequestPoint::Entity {
                entity: 99,
                offset_m: [0.0; 3],
            },
            period: 0,
        }),
        1,
    );
    let r = responses(&frame(&mut t, 2, &e, &g));
    assert!(matches!(r[..], [Response::Hot(h)] if !h.valid));
}

#[test]
fn segments_say_visible_only_when_clear() {
    let mut t = RequestTable::default();
    let e = EntityTable::default();
    let g = Plane::new(0);
    let seg = |id, to_alt| {
        HostRequest::Los(LosRequest {
            id,
            extended: false,
            shape: LosShape::Segment {
                from: at(47.0, 11.0, 300.0),
                to: at(47.01, 11.0, to_alt),
            },
            period: 0,
        })
    };
    t.add(seg(1, 200.0), 0);
    t.add(seg(2, -100.0), 0);
    let r = responses(&frame(&mut t, 1, &e, &g));
    let [Response::Los(clear), Response::Los(hit)] = r[..] else {
        panic!("{r:?}")
    };
    assert!(!clear.valid && clear.visible);
    assert!(hit.valid && !hit.visible);
    // Crosses 100 m half way down from 300 to −100.
    let len = LocalTangentPlane::new(Geodetic::new(47.0, 11.0, 300.0))
        .geodetic_to_enu(Geodetic::new(47.01, 11.0, -100.0))
        .length();
    assert!((hit.range_m - len / 2.0).abs() < 1e-6);
    // (The plane's point lies on the chord, 2 cm below the geodetic altitude line.)
    assert!((hit.point.alt_m - H).abs() < 0.1, "{}", hit.point.alt_m);
    // No terrain: neither valid nor visible.
    t.add(seg(3, 200.0), 1);
    let r = responses(&frame(&mut t, 2, &e, &crate::query::NoTerrain));
    assert!(matches!(r[..], [Response::Los(l)] if !l.valid && !l.visible));
}

#[test]
fn a_full_table_answers_invalid_and_reset_drops_everything() {
    let mut t = RequestTable::default();
    let e = EntityTable::default();
    let g = Plane::new(0);
    for id in 0..MAX_REQUESTS as u16 {
        assert_eq!(t.add(hot(id, HotKind::Hot, 5), 0), Added::New);
    }
    assert_eq!(t.add(hot(60_000, HotKind::Hot, 5), 0), Added::Full);
    let c = frame(&mut t, 1, &e, &g);
    let r = responses(&c);
    assert_eq!(r.len(), MAX_REQUESTS + 1);
    assert_eq!(
        r.iter()
            .filter(|r| matches!(r, Response::Hot(h) if !h.valid && h.id == 60_000))
            .count(),
        1
    );
    assert_eq!(t.len(), (MAX_REQUESTS, 0));
    assert_eq!(t.clear(), MAX_REQUESTS);
    assert!(t.is_empty());
}

#[test]
fn azimuth_and_elevation_of_directions() {
    assert_eq!(azimuth_elevation_deg(DVec3::Y), (0.0, 0.0));
    assert_eq!(azimuth_elevation_deg(DVec3::X), (90.0, 0.0));
    assert_eq!(azimuth_elevation_deg(DVec3::Z).1, 90.0);
    let (az, el) = azimuth_elevation_deg(DVec3::new(-1.0, -1.0, 0.0));
    assert!((az + 135.0).abs() < 1e-12 && el == 0.0);
}
