//! Timing decisions, free of I/O and of the wall clock (every function takes the time as an
//! argument, so tests drive them with a fake clock):
//!
//! - [`SequenceTracker`]: accept newer sequence numbers, drop older and duplicate ones, count
//!   gaps, and resynchronise when the sender restarts;
//! - [`extrapolate`]: the pose at a frame's display time by dead reckoning from the sent
//!   velocity and rates, else from the last two poses, capped;
//! - [`StreamMonitor`]: live / lost / regained transitions of a stream.
//!
//! Times are seconds on one monotonic timeline ([`monotonic_s`] for real inputs).

use std::sync::OnceLock;
use std::time::Instant;

use crate::geodesy::{Geodetic, LocalTangentPlane};
use crate::pose::{Pose, PosePosition};
use crate::stats::DropReason;

fn epoch() -> Instant {
    static EPOCH: OnceLock<Instant> = OnceLock::new();
    *EPOCH.get_or_init(Instant::now)
}

/// Seconds since a process-wide epoch on the monotonic clock (the timeline of arrival stamps).
pub fn monotonic_s() -> f64 {
    instant_s(Instant::now())
}

/// `t` on the [`monotonic_s`] timeline (negative for instants before the epoch).
pub fn instant_s(t: Instant) -> f64 {
    let e = epoch();
    match t.checked_duration_since(e) {
        Some(d) => d.as_secs_f64(),
        None => -e.duration_since(t).as_secs_f64(),
    }
}

/// When the sequence tracker starts over instead of dropping.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SequenceParams {
    /// Accept any sequence number after this long without an accepted one (sender restarted
    /// while the stream was down), seconds.
    pub resync_after_s: f64,
    /// Accept after this many consecutive out-of-order drops (sender restarted mid-stream).
    pub resync_after_rejects: u32,
}

impl Default for SequenceParams {
    fn default() -> Self {
        Self {
            resync_after_s: 1.0,
            resync_after_rejects: 16,
        }
    }
}

/// What [`SequenceTracker::check`] decided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeqVerdict {
    /// The first sequence number seen: accepted.
    First,
    /// Exactly one more than the last: accepted.
    Next,
    /// Newer, with `missed` numbers skipped: accepted, counted as a gap.
    Gap {
        /// How many sequence numbers were skipped.
        missed: u32,
    },
    /// Older or equal but the tracker started over (restart detected): accepted.
    Resync,
    /// Same as the last accepted: dropped.
    Duplicate,
    /// Older than the last accepted: dropped.
    OutOfOrder,
}

impl SeqVerdict {
    /// Whether the packet is used.
    pub fn accepted(self) -> bool {
        self.drop_reason().is_none()
    }

    /// The counter a dropped packet goes to.
    pub fn drop_reason(self) -> Option<DropReason> {
        match self {
            SeqVerdict::Duplicate => Some(DropReason::Duplicate),
            SeqVerdict::OutOfOrder => Some(DropReason::OutOfOrder),
            _ => None,
        }
    }
}

/// Sequence-number acceptance with u32 wrap-around (serial-number arithmetic: `b` is newer
/// than `a` when `b − a` mod 2³² is in 1 … 2³¹ − 1).
#[derive(Clone, Debug)]
pub struct SequenceTracker {
    params: SequenceParams,
    last: Option<u32>,
    last_accept_s: f64,
    rejects: u32,
}

impl SequenceTracker {
    /// A tracker that has seen nothing yet.
    pub fn new(params: SequenceParams) -> Self {
        Self {
            params,
            last: None,
            last_accept_s: f64::NEG_INFINITY,
            rejects: 0,
        }
    }

    /// The last accepted sequence number.
    pub fn last(&self) -> Option<u32> {
        self.last
    }

    /// Decides about `seq` arriving at `now_s`; accepted numbers become the new last.
    pub fn check(&mut self, seq: u32, now_s: f64) -> SeqVerdict {
        let verdict = match self.last {
            None => SeqVerdict::First,
            Some(last) => {
                let d = seq.wrapping_sub(last) as i32;
                if d == 1 {
                    SeqVerdict::Next
                } else if d > 1 {
                    SeqVerdict::Gap {
                        missed: (d - 1) as u32,
                    }
                } else if now_s - self.last_accept_s > self.params.resync_after_s {
                    SeqVerdict::Resync
                } else if d == 0 {
                    SeqVerdict::Duplicate
                } else if self.rejects + 1 >= self.params.resync_after_rejects {
                    SeqVerdict::Resync
                } else {
                    SeqVerdict::OutOfOrder
                }
            }
        };
        match verdict {
            SeqVerdict::OutOfOrder => self.rejects += 1,
            SeqVerdict::Duplicate => {}
            _ => {
                self.last = Some(seq);
                self.last_accept_s = now_s;
                self.rejects = 0;
            }
        }
        verdict
    }
}

/// A pose with its arrival time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stamped {
    /// The pose as received.
    pub pose: Pose,
    /// Arrival, seconds on the monotonic timeline.
    pub arrival_s: f64,
    /// Running number of accepted poses on this input (1 = first).
    pub sample: u64,
}

/// Limits of extrapolation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExtrapolationParams {
    /// Never extrapolate further than this past the arrival; beyond it the pose is held and
    /// the stream reported stale, seconds.
    pub cap_s: f64,
    /// Two poses further apart than this are not used to estimate motion, seconds.
    pub max_pair_span_s: f64,
    /// Two poses closer than this are not used either (arrival jitter would dominate), seconds.
    pub min_pair_span_s: f64,
}

impl Default for ExtrapolationParams {
    fn default() -> Self {
        Self {
            cap_s: 0.1,
            max_pair_span_s: 0.5,
            min_pair_span_s: 0.004,
        }
    }
}

/// Where the motion used to extrapolate came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Motion {
    /// No motion known: the pose is used as received.
    Held,
    /// The velocity / rates the simulator sent.
    Sent,
    /// Estimated from the last two poses.
    LastTwo,
}

impl Motion {
    /// Short name for reports.
    pub fn name(self) -> &'static str {
        match self {
            Motion::Held => "held",
            Motion::Sent => "sent",
            Motion::LastTwo => "last_two",
        }
    }
}

/// The pose to draw a frame with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FramePose {
    /// The pose at the display time (extrapolated up to the cap).
    pub pose: Pose,
    /// The accepted sample it came from ([`Stamped::sample`]).
    pub sample: u64,
    /// Display time minus the sample's arrival, seconds (may exceed the cap).
    pub age_s: f64,
    /// How far the pose was carried forward: `age_s` clamped to [0, cap], seconds.
    pub ahead_s: f64,
    /// Source of the position's motion.
    pub position_motion: Motion,
    /// Source of the attitude's motion.
    pub attitude_motion: Motion,
    /// The sample is older than the cap: the pose is held and the stream is stale.
    pub stale: bool,
}

impl FramePose {
    /// Whether the pose differs from the received one.
    pub fn extrapolated(&self) -> bool {
        self.ahead_s > 0.0
            && (self.position_motion != Motion::Held || self.attitude_motion != Motion::Held)
    }
}

/// Angle difference `a − b` wrapped to (−180, 180] degrees.
pub fn wrap_deg(d: f64) -> f64 {
    let w = (d + 180.0).rem_euclid(360.0) - 180.0;
    if w == -180.0 {
        180.0
    } else {
        w
    }
}

/// The time between two poses to estimate motion over: their sim-time difference when it is
/// in [min, max], else their arrival difference when that is, else `None`.
fn pair_span(prev: &Stamped, latest: &Stamped, p: &ExtrapolationParams) -> Option<f64> {
    let ok = |s: f64| s >= p.min_pair_span_s && s <= p.max_pair_span_s;
    let sim = latest.pose.sim_time_s - prev.pose.sim_time_s;
    let arrival = latest.arrival_s - prev.arrival_s;
    if ok(sim) {
        Some(sim)
    } else if ok(arrival) {
        Some(arrival)
    } else {
        None
    }
}

/// ENU velocity (m/s, in the tangent plane at `latest`) from two positions `span` s apart.
fn pair_velocity(prev: &PosePosition, latest: &PosePosition, span: f64) -> Option<[f64; 3]> {
    match (*prev, *latest) {
        (
            PosePosition::Geodetic {
                lat_deg: la0,
                lon_deg: lo0,
                alt_m: al0,
            },
            PosePosition::Geodetic {
                lat_deg,
                lon_deg,
                alt_m,
            },
        ) => {
            let ltp = LocalTangentPlane::new(Geodetic::new(lat_deg, lon_deg, alt_m));
            let d = ltp.geodetic_to_enu(Geodetic::new(la0, lo0, al0));
            Some((-d / span).to_array())
        }
        (
            PosePosition::LocalEnu {
                x: x0,
                y: y0,
                z: z0,
            },
            PosePosition::LocalEnu { x, y, z },
        ) => Some([(x - x0) / span, (y - y0) / span, (z - z0) / span]),
        _ => None,
    }
}

/// `position` moved by ENU velocity `v` for `dt` seconds. Geodetic positions move along the
/// tangent plane at the position (exact to ≪ 1 mm over the capped distances) and keep their
/// longitude convention (a longitude given in [180, 360) stays there).
pub fn advance_position(position: &PosePosition, v: [f64; 3], dt: f64) -> PosePosition {
    match *position {
        PosePosition::Geodetic {
            lat_deg,
            lon_deg,
            alt_m,
        } => {
            let ltp = LocalTangentPlane::new(Geodetic::new(lat_deg, lon_deg, alt_m));
            let g = ltp.enu_to_geodetic(glam::DVec3::from_array(v) * dt);
            let mut lon = g.lon_deg;
            if lon_deg >= 180.0 && lon < 0.0 {
                lon += 360.0;
            }
            PosePosition::Geodetic {
                lat_deg: g.lat_deg,
                lon_deg: lon,
                alt_m: g.alt_m,
            }
        }
        PosePosition::LocalEnu { x, y, z } => PosePosition::LocalEnu {
            x: x + v[0] * dt,
            y: y + v[1] * dt,
            z: z + v[2] * dt,
        },
    }
}

/// The pose at `display_s`: `latest` carried forward by `min(display_s − arrival, cap)`
/// seconds (never backwards), with the position moved by the sent velocity (else the velocity
/// between `previous` and `latest`) and the attitude turned by the sent rates (else the rates
/// between the two). Heading and roll differences are taken the short way round; pitch stays in
/// [−90, 90]. Beyond the cap the pose is held at the cap and marked stale.
pub fn extrapolate(
    latest: &Stamped,
    previous: Option<&Stamped>,
    display_s: f64,
    p: &ExtrapolationParams,
) -> FramePose {
    let age_s = display_s - latest.arrival_s;
    let stale = age_s.is_nan() || age_s > p.cap_s;
    let ahead_s = if age_s.is_nan() {
        0.0
    } else {
        age_s.clamp(0.0, p.cap_s)
    };
    let pair = previous.and_then(|prev| pair_span(prev, latest, p).map(|span| (prev, span)));
    let pose = latest.pose;

    let (velocity, position_motion) = match (pose.velocity_enu, pair) {
        (Some(v), _) => (Some(v), Motion::Sent),
        (None, Some((prev, span))) => {
            match pair_velocity(&prev.pose.position, &pose.position, span) {
                Some(v) => (Some(v), Motion::LastTwo),
                None => (None, Motion::Held),
            }
        }
        (None, None) => (None, Motion::Held),
    };
    let (rates, attitude_motion) = match (pose.angular_rates_deg_s, pair) {
        (Some(r), _) => (Some(r), Motion::Sent),
        (None, Some((prev, span))) => {
            let [h0, p0, r0] = prev.pose.attitude_deg;
            let [h1, p1, r1] = pose.attitude_deg;
            (
                Some([
                    wrap_deg(h1 - h0) / span,
                    (p1 - p0) / span,
                    wrap_deg(r1 - r0) / span,
                ]),
                Motion::LastTwo,
            )
        }
        (None, None) => (None, Motion::Held),
    };

    let mut out = pose;
    if ahead_s > 0.0 {
        if let Some(v) = velocity {
            out.position = advance_position(&pose.position, v, ahead_s);
        }
        if let Some([hr, pr, rr]) = rates {
            let [h, pi, r] = pose.attitude_deg;
            out.attitude_deg = [
                h + hr * ahead_s,
                (pi + pr * ahead_s).clamp(-90.0, 90.0),
                r + rr * ahead_s,
            ];
        }
        if velocity.is_some() || rates.is_some() {
            out.sim_time_s = pose.sim_time_s + ahead_s;
        }
    }
    FramePose {
        pose: out,
        sample: latest.sample,
        age_s,
        ahead_s,
        position_motion,
        attitude_motion,
        stale,
    }
}

/// A stream's state for [`StreamMonitor`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StreamState {
    /// Nothing received yet.
    Waiting,
    /// The newest sample is within the cap.
    Live,
    /// The newest sample is older than the cap.
    Lost,
}

/// A transition reported by [`StreamMonitor::update`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StreamEvent {
    /// The first fresh sample arrived.
    Started,
    /// No sample for longer than the cap.
    Lost {
        /// Seconds since the last arrival when the loss was noticed.
        silent_s: f64,
    },
    /// A fresh sample after a loss.
    Regained {
        /// Seconds between the last arrival before the loss and the first one after it.
        outage_s: f64,
    },
}

/// Live / lost / regained state machine over the newest arrival time.
#[derive(Clone, Debug)]
pub struct StreamMonitor {
    state: StreamState,
    arrival_before_loss: f64,
}

impl Default for StreamMonitor {
    fn default() -> Self {
        Self {
            state: StreamState::Waiting,
            arrival_before_loss: 0.0,
        }
    }
}

impl StreamMonitor {
    /// The current state.
    pub fn state(&self) -> StreamState {
        self.state
    }

    /// Updates the state from the newest arrival (if any) seen at `now_s`.
    pub fn update(
        &mut self,
        last_arrival_s: Option<f64>,
        now_s: f64,
        cap_s: f64,
    ) -> Option<StreamEvent> {
        let a = last_arrival_s?;
        let fresh = now_s - a <= cap_s;
        match (self.state, fresh) {
            (StreamState::Waiting, true) => {
                self.state = StreamState::Live;
                Some(StreamEvent::Started)
            }
            (StreamState::Waiting | StreamState::Live, false) => {
                self.state = StreamState::Lost;
                self.arrival_before_loss = a;
                Some(StreamEvent::Lost {
                    silent_s: now_s - a,
                })
            }
            (StreamState::Lost, true) => {
                self.state = StreamState::Live;
                Some(StreamEvent::Regained {
                    outage_s: a - self.arrival_before_loss,
                })
            }
            (StreamState::Live, true) | (StreamState::Lost, false) => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tracker() -> SequenceTracker {
        SequenceTracker::new(SequenceParams::default())
    }

    #[test]
    fn sequence_old_and_duplicate_dropped_gaps_counted() {
        let mut t = tracker();
        let mut now = 0.0;
        let mut step = |t: &mut SequenceTracker, s: u32| {
            now += 0.01;
            t.check(s, now)
        };
        assert_eq!(step(&mut t, 10), SeqVerdict::First);
        assert_eq!(step(&mut t, 11), SeqVerdict::Next);
        assert_eq!(step(&mut t, 11), SeqVerdict::Duplicate);
        assert_eq!(step(&mut t, 9), SeqVerdict::OutOfOrder);
        assert_eq!(step(&mut t, 15), SeqVerdict::Gap { missed: 3 });
        assert_eq!(step(&mut t, 14), SeqVerdict::OutOfOrder);
        assert_eq!(step(&mut t, 16), SeqVerdict::Next);
        assert_eq!(t.last(), Some(16));
        assert!(!SeqVerdict::Duplicate.accepted());
        assert_eq!(
            SeqVerdict::OutOfOrder.drop_reason(),
            Some(DropReason::OutOfOrder)
        );
        assert!(SeqVerdict::Gap { missed: 1 }.accepted());
    }

    #[test]
    fn sequence_wraps_around() {
        let mut t = tracker();
        t.check(u32::MAX - 1, 0.0);
        assert_eq!(t.check(u32::MAX, 0.01), SeqVerdict::Next);
        assert_eq!(t.check(0, 0.02), SeqVerdict::Next);
        assert_eq!(t.check(2, 0.03), SeqVerdict::Gap { missed: 1 });
        assert_eq!(t.check(u32::MAX, 0.04), SeqVerdict::OutOfOrder);
    }

    #[test]
    fn sequence_resyncs_after_restart() {
        let mut t = tracker();
        t.check(5000, 0.0);
        // Restart mid-stream: 16 consecutive older numbers and the tracker follows.
        for i in 0..15 {
            assert_eq!(t.check(i, 0.01 * (i + 1) as f64), SeqVerdict::OutOfOrder);
        }
        assert_eq!(t.check(15, 0.2), SeqVerdict::Resync);
        assert_eq!(t.check(16, 0.21), SeqVerdict::Next);
        // Restart after a silence longer than resync_after_s: accepted at once.
        assert_eq!(t.check(3, 1.5), SeqVerdict::Resync);
        // Duplicates alone do not count towards the reject resync.
        for _ in 0..40 {
            assert_eq!(t.check(3, 1.6), SeqVerdict::Duplicate);
        }
    }

    fn pose_at(lat: f64, lon: f64, alt: f64, att: [f64; 3], t: f64) -> Pose {
        Pose {
            position: PosePosition::Geodetic {
                lat_deg: lat,
                lon_deg: lon,
                alt_m: alt,
            },
            attitude_deg: att,
            sim_time_s: t,
            frame: 0,
            velocity_enu: None,
            angular_rates_deg_s: None,
        }
    }

    fn local(x: f64, y: f64, z: f64, att: [f64; 3], t: f64) -> Pose {
        Pose {
            position: PosePosition::LocalEnu { x, y, z },
            ..pose_at(0.0, 0.0, 0.0, att, t)
        }
    }

    fn stamped(pose: Pose, arrival_s: f64) -> Stamped {
        Stamped {
            pose,
            arrival_s,
            sample: 1,
        }
    }

    fn xyz(p: &PosePosition) -> [f64; 3] {
        match *p {
            PosePosition::LocalEnu { x, y, z } => [x, y, z],
            PosePosition::Geodetic { .. } => panic!("local expected"),
        }
    }

    #[test]
    fn extrapolates_with_sent_velocity_and_rates() {
        let mut p = local(100.0, 200.0, 1000.0, [350.0, 5.0, -20.0], 7.0);
        p.velocity_enu = Some([50.0, -10.0, 2.0]);
        p.angular_rates_deg_s = Some([30.0, -2.0, 10.0]);
        let f = extrapolate(
            &stamped(p, 10.0),
            None,
            10.04,
            &ExtrapolationParams::default(),
        );
        // 40 ms: x 100 + 50·0.04 = 102, y 200 − 0.4, z 1000 + 0.08;
        // heading 350 + 1.2, pitch 5 − 0.08, roll −20 + 0.4.
        let [x, y, z] = xyz(&f.pose.position);
        assert!((x - 102.0).abs() < 1e-9 && (y - 199.6).abs() < 1e-9 && (z - 1000.08).abs() < 1e-9);
        let [h, pi, r] = f.pose.attitude_deg;
        assert!((h - 351.2).abs() < 1e-9 && (pi - 4.92).abs() < 1e-9 && (r + 19.6).abs() < 1e-9);
        assert!((f.ahead_s - 0.04).abs() < 1e-12 && (f.age_s - 0.04).abs() < 1e-12);
        assert_eq!(
            (f.position_motion, f.attitude_motion),
            (Motion::Sent, Motion::Sent)
        );
        assert!(f.extrapolated() && !f.stale);
        assert!((f.pose.sim_time_s - 7.04).abs() < 1e-12);
    }

    #[test]
    fn extrapolates_from_the_last_two_poses() {
        // Sim times 1/60 s apart; heading crosses north (359 → 1: +2° per frame = 120°/s),
        // roll crosses 180 (179 → −179: +2° per frame).
        let prev = stamped(local(0.0, 0.0, 500.0, [359.0, 1.0, 179.0], 1.0), 5.0);
        let latest = stamped(
            local(5.0, -1.0, 500.5, [1.0, 2.0, -179.0], 1.0 + 1.0 / 60.0),
            5.02,
        );
        let f = extrapolate(&latest, Some(&prev), 5.07, &ExtrapolationParams::default());
        // dt 50 ms, velocity per sim time: (300, −60, 30) m/s → +15, −3, +1.5 m.
        let [x, y, z] = xyz(&f.pose.position);
        assert!((x - 20.0).abs() < 1e-9 && (y + 4.0).abs() < 1e-9 && (z - 502.0).abs() < 1e-9);
        // Rates 120°/s, 60°/s, 120°/s → +6, +3, +6.
        let [h, pi, r] = f.pose.attitude_deg;
        assert!((h - 7.0).abs() < 1e-9 && (pi - 5.0).abs() < 1e-9 && (r + 173.0).abs() < 1e-9);
        assert_eq!(f.position_motion, Motion::LastTwo);
        // Sim times equal (protocol without sim time): the arrival times are used instead.
        let prev0 = Stamped {
            pose: Pose {
                sim_time_s: 0.0,
                ..prev.pose
            },
            ..prev
        };
        let latest0 = Stamped {
            pose: Pose {
                sim_time_s: 0.0,
                ..latest.pose
            },
            ..latest
        };
        let f = extrapolate(
            &latest0,
            Some(&prev0),
            5.07,
            &ExtrapolationParams::default(),
        );
        // Arrival span 20 ms: velocity (250, −50, 25) → +12.5, −2.5, +1.25 over 50 ms.
        let [x, y, _] = xyz(&f.pose.position);
        assert!((x - 17.5).abs() < 1e-9 && (y + 3.5).abs() < 1e-9, "{x} {y}");
        // Too far apart (> 0.5 s) or too close: held.
        let old = Stamped {
            arrival_s: 4.0,
            pose: Pose {
                sim_time_s: 0.0,
                ..prev.pose
            },
            ..prev
        };
        let f = extrapolate(&latest0, Some(&old), 5.07, &ExtrapolationParams::default());
        assert_eq!(
            (f.position_motion, f.attitude_motion),
            (Motion::Held, Motion::Held)
        );
        assert_eq!(f.pose, latest0.pose);
        assert!(!f.extrapolated());
    }

    #[test]
    fn geodetic_velocity_moves_along_the_ellipsoid() {
        let mut p = pose_at(45.0, 7.0, 1000.0, [90.0, 0.0, 0.0], 0.0);
        p.velocity_enu = Some([200.0, 100.0, -5.0]);
        let f = extrapolate(
            &stamped(p, 0.0),
            None,
            0.05,
            &ExtrapolationParams::default(),
        );
        let PosePosition::Geodetic {
            lat_deg,
            lon_deg,
            alt_m,
        } = f.pose.position
        else {
            panic!()
        };
        // Hand computation: 10 m east, 5 m north at 45°, h = 1000 m.
        // N = a/√(1−e² sin²φ), M = a(1−e²)/(1−e² sin²φ)^{3/2};
        // Δλ = 10/((N+h) cos φ), Δφ = 5/(M+h); Δh = −0.25 m (+ the tangent-plane rise ≈ 1e-5 m).
        let (a, e2) = (6_378_137.0f64, 0.006_694_379_990_14f64);
        let s2 = 0.5f64;
        let n = a / (1.0 - e2 * s2).sqrt();
        let m = a * (1.0 - e2) / (1.0 - e2 * s2).powf(1.5);
        let dlon = (10.0 / ((n + 1000.0) * 45f64.to_radians().cos())).to_degrees();
        let dlat = (5.0 / (m + 1000.0)).to_degrees();
        assert!((lon_deg - (7.0 + dlon)).abs() < 1e-9, "{lon_deg}");
        assert!((lat_deg - (45.0 + dlat)).abs() < 1e-9, "{lat_deg}");
        assert!((alt_m - 999.75).abs() < 1e-4, "{alt_m}");
        // Longitudes given in [180, 360) stay there across the antimeridian.
        let q = advance_position(
            &PosePosition::Geodetic {
                lat_deg: 0.0,
                lon_deg: 359.9999999,
                alt_m: 0.0,
            },
            [100.0, 0.0, 0.0],
            0.1,
        );
        let PosePosition::Geodetic { lon_deg, .. } = q else {
            panic!()
        };
        assert!(
            (0.0..360.0).contains(&lon_deg) && lon_deg < 1.0,
            "{lon_deg}"
        );
    }

    #[test]
    fn staleness_cap_holds_the_pose() {
        let mut p = local(0.0, 0.0, 0.0, [0.0, 89.0, 0.0], 0.0);
        p.velocity_enu = Some([100.0, 0.0, 0.0]);
        p.angular_rates_deg_s = Some([0.0, 50.0, 0.0]);
        // A cap exact in binary, so that "age == cap" is exact too.
        let params = ExtrapolationParams {
            cap_s: 0.125,
            ..ExtrapolationParams::default()
        };
        let s = stamped(p, 1.0);
        let at_cap = extrapolate(&s, None, 1.125, &params);
        assert!(!at_cap.stale);
        let late = extrapolate(&s, None, 1.5, &params);
        assert!(late.stale);
        assert_eq!((late.age_s, late.ahead_s), (0.5, 0.125));
        // Held at the cap: 12.5 m, not 50 m; pitch 89 + 6.25 clamped at 90.
        assert_eq!(xyz(&late.pose.position)[0], 12.5);
        assert_eq!(late.pose.attitude_deg[1], 90.0);
        assert_eq!(late.pose, at_cap.pose);
        // The default cap is 100 ms.
        assert_eq!(ExtrapolationParams::default().cap_s, 0.1);
        assert!(extrapolate(&s, None, 1.2, &ExtrapolationParams::default()).stale);
        assert!(!extrapolate(&s, None, 1.09, &ExtrapolationParams::default()).stale);
        // A display time before the arrival never extrapolates backwards.
        let early = extrapolate(&s, None, 0.99, &params);
        assert_eq!(early.ahead_s, 0.0);
        assert_eq!(early.pose, p);
    }

    #[test]
    fn stream_monitor_transitions() {
        let mut m = StreamMonitor::default();
        assert_eq!(m.update(None, 1.0, 0.1), None);
        assert_eq!(m.state(), StreamState::Waiting);
        assert_eq!(m.update(Some(1.0), 1.01, 0.125), Some(StreamEvent::Started));
        assert_eq!(m.update(Some(1.0), 1.125, 0.125), None);
        match m.update(Some(1.0), 1.15, 0.125) {
            Some(StreamEvent::Lost { silent_s }) => assert!((silent_s - 0.15).abs() < 1e-12),
            e => panic!("{e:?}"),
        }
        assert_eq!(m.state(), StreamState::Lost);
        assert_eq!(m.update(Some(1.0), 3.0, 0.125), None);
        match m.update(Some(3.5), 3.5, 0.125) {
            Some(StreamEvent::Regained { outage_s }) => assert!((outage_s - 2.5).abs() < 1e-12),
            e => panic!("{e:?}"),
        }
        assert_eq!(m.state(), StreamState::Live);
    }

    #[test]
    fn wrap_is_short_way_round() {
        assert_eq!(wrap_deg(2.0), 2.0);
        assert_eq!(wrap_deg(-358.0), 2.0);
        assert_eq!(wrap_deg(358.0), -2.0);
        assert_eq!(wrap_deg(180.0), 180.0);
        assert_eq!(wrap_deg(-180.0), 180.0);
    }

    #[test]
    fn monotonic_timeline() {
        let a = monotonic_s();
        let b = instant_s(Instant::now());
        assert!(b >= a);
        assert!(instant_s(epoch()) == 0.0);
    }
}
