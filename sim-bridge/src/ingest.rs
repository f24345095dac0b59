//! The path from received bytes to the frame loop, without any I/O:
//! [`Ingest`] (transport thread side) decodes, checks the sequence, counts, and publishes the
//! newest accepted pose lock-free; [`PoseReader`] (frame loop side) takes the newest pose and
//! extrapolates it to the frame's display time, reporting lost/regained streams.

use std::sync::Arc;
use std::time::Instant;

use crate::codec::cigi::{CigiMessage, IgMode, ViewTable};
use crate::codec::{decode, DecodeError, Decoded, Protocol, ProtocolChoice};
use crate::handoff::{latest, Publisher, Subscriber};
use crate::pose::{Pose, PoseLimits};
use crate::stats::{Counters, DropReason, StatsSnapshot};
use crate::timing::{
    extrapolate, instant_s, monotonic_s, ExtrapolationParams, FramePose, SeqVerdict,
    SequenceParams, SequenceTracker, Stamped, StreamEvent, StreamMonitor, StreamState,
};

/// The newest accepted pose and the one accepted just before it (for motion estimates; `None`
/// after a sequence resync).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseSample {
    /// The newest accepted pose.
    pub latest: Stamped,
    /// The pose accepted just before it.
    pub previous: Option<Stamped>,
}

/// What happened to one datagram.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// A pose was accepted (with the sequence decision, if the protocol has sequence numbers).
    Accepted(Option<SeqVerdict>),
    /// A valid message without an ownship pose (e.g. CIGI views only).
    NoPose,
    /// Dropped, and why.
    Dropped(DropReason),
}

/// The result of [`Ingest::datagram`].
#[derive(Clone, Debug)]
pub struct Outcome {
    /// What happened.
    pub verdict: Verdict,
    /// The CIGI message when the datagram was a valid, in-order CIGI message (to answer it).
    pub cigi: Option<CigiMessage>,
}

/// Settings shared by every input.
#[derive(Clone, Debug)]
pub struct InputParams {
    /// Name used in log lines (e.g. `udp 127.0.0.1:47800`).
    pub name: String,
    /// Accepted protocol(s).
    pub protocol: ProtocolChoice,
    /// Sequence resync rules.
    pub sequence: SequenceParams,
    /// Extrapolation limits used by the reader.
    pub extrapolation: ExtrapolationParams,
    /// Plausibility limits every pose must meet before it is published.
    pub limits: PoseLimits,
}

impl Default for InputParams {
    fn default() -> Self {
        Self {
            name: "pose input".into(),
            protocol: ProtocolChoice::Auto,
            sequence: SequenceParams::default(),
            extrapolation: ExtrapolationParams::default(),
            limits: PoseLimits::default(),
        }
    }
}

/// Creates the two ends of one input.
pub fn input_channel(params: InputParams) -> (Ingest, PoseReader) {
    let counters = Arc::new(Counters::default());
    let name: Arc<str> = params.name.into();
    let (poses, poses_rx) = latest(None);
    let (views_out, views_rx) = latest(ViewTable::default());
    (
        Ingest {
            name: name.clone(),
            protocol: params.protocol,
            limits: params.limits,
            trackers: std::array::from_fn(|_| SequenceTracker::new(params.sequence)),
            counters: counters.clone(),
            last: None,
            accepted: 0,
            poses,
            views: ViewTable::default(),
            views_out,
            warned: [false; DropReason::ALL.len()],
        },
        PoseReader {
            name,
            poses: poses_rx,
            views: views_rx,
            counters,
            monitor: StreamMonitor::default(),
            params: params.extrapolation,
        },
    )
}

/// Transport side of an input: feed it datagrams (or shared-memory poses) as they arrive.
pub struct Ingest {
    name: Arc<str>,
    protocol: ProtocolChoice,
    limits: PoseLimits,
    /// One per protocol (indexed like [`Protocol::ALL`]): a port in auto mode may carry
    /// several senders' streams, each with its own numbering.
    trackers: [SequenceTracker; 4],
    counters: Arc<Counters>,
    last: Option<Stamped>,
    accepted: u64,
    poses: Publisher<Option<PoseSample>>,
    views: ViewTable,
    views_out: Publisher<ViewTable>,
    warned: [bool; DropReason::ALL.len()],
}

impl Ingest {
    /// The input's counters.
    pub fn counters(&self) -> &Arc<Counters> {
        &self.counters
    }

    fn drop_with(&mut self, reason: DropReason, detail: &dyn std::fmt::Display) {
        self.counters.dropped(reason);
        let i = DropReason::ALL
            .iter()
            .position(|r| *r == reason)
            .unwrap_or(0);
        if self.warned[i] {
            tracing::debug!("{}: dropped ({reason}): {detail}", self.name);
        } else {
            self.warned[i] = true;
            tracing::warn!(
                "{}: dropped a packet ({reason}): {detail} (further drops for this reason are logged at debug level)",
                self.name
            );
        }
    }

    /// Counts a datagram from a sender that is not on the allow-list.
    pub fn not_allowed(&mut self, from: &dyn std::fmt::Display) {
        self.counters.received();
        self.drop_with(DropReason::NotAllowed, &format_args!("sender {from}"));
    }

    /// Decodes and, when valid and in order, publishes one datagram that arrived at `arrival_s`.
    pub fn datagram(&mut self, bytes: &[u8], arrival_s: f64) -> Outcome {
        self.counters.received();
        match decode(self.protocol, bytes).and_then(|d| within(&self.limits, d)) {
            Err(e) => {
                let reason = e.reason();
                self.drop_with(reason, &e);
                Outcome {
                    verdict: Verdict::Dropped(reason),
                    cigi: None,
                }
            }
            Ok(d) => {
                if let Some(m) = &d.cigi {
                    self.counters.cigi_packets(&m.packet_counts);
                }
                let mut seq_verdict = None;
                if let Some(seq) = d.sequence {
                    let k = Protocol::ALL
                        .iter()
                        .position(|p| *p == d.protocol)
                        .unwrap_or(0);
                    let tracker = &mut self.trackers[k];
                    let v = tracker.check(seq, arrival_s);
                    let last = tracker.last().unwrap_or(0);
                    match v {
                        SeqVerdict::Gap { missed } => {
                            self.counters.gap(missed.into());
                            tracing::debug!(
                                "{}: sequence gap, {missed} missed before {seq}",
                                self.name
                            );
                        }
                        SeqVerdict::Resync => {
                            self.counters.resync();
                            self.last = None;
                            tracing::info!("{}: sequence restarted at {seq}", self.name);
                        }
                        _ => {}
                    }
                    if let Some(reason) = v.drop_reason() {
                        self.drop_with(
                            reason,
                            &format_args!("{} sequence {seq} after {last}", d.protocol),
                        );
                        return Outcome {
                            verdict: Verdict::Dropped(reason),
                            cigi: None,
                        };
                    }
                    seq_verdict = Some(v);
                }
                if let Some(m) = &d.cigi {
                    if self.host_views(m) {
                        self.views_out.publish(self.views.clone());
                    }
                }
                let verdict = match d.pose {
                    Some(pose) => {
                        self.accept(pose, arrival_s);
                        Verdict::Accepted(seq_verdict)
                    }
                    None => {
                        self.counters.no_pose();
                        Verdict::NoPose
                    }
                };
                Outcome {
                    verdict,
                    cigi: d.cigi,
                }
            }
        }
    }

    /// Applies a message's views; a message in Reset/Standby puts the views back to the
    /// configuration (an empty table) and applies none (the IG session ignores every packet
    /// but IG Control while the host holds it in Reset). Returns whether the table changed.
    fn host_views(&mut self, m: &CigiMessage) -> bool {
        if m.ig_control.mode() == IgMode::ResetOrStandby {
            let had = !self.views.views().is_empty();
            self.views = ViewTable::default();
            had
        } else {
            self.views.apply(m)
        }
    }

    /// Counts a datagram that was a valid native terrain query (no pose; the IG session
    /// answers it).
    pub fn native_query(&mut self) {
        self.counters.received();
        self.counters.no_pose();
    }

    /// Publishes a pose read from shared memory (validated here) that was new at `arrival_s`.
    pub fn pose(&mut self, pose: Pose, arrival_s: f64) -> Verdict {
        self.counters.received();
        match pose.validate_within(&self.limits) {
            Ok(()) => {
                self.accept(pose, arrival_s);
                Verdict::Accepted(None)
            }
            Err(e) => {
                let reason = e.reason();
                self.drop_with(reason, &e);
                Verdict::Dropped(reason)
            }
        }
    }

    /// Counts an input error that is not a datagram (e.g. a shared-memory record with a bad
    /// header or checksum) under `reason`.
    pub fn count_drop(&mut self, reason: DropReason, detail: &dyn std::fmt::Display) {
        self.counters.received();
        self.drop_with(reason, detail);
    }

    fn accept(&mut self, pose: Pose, arrival_s: f64) {
        self.accepted += 1;
        let latest = Stamped {
            pose,
            arrival_s,
            sample: self.accepted,
        };
        let previous = self.last.replace(latest);
        self.poses.publish(Some(PoseSample { latest, previous }));
        self.counters.accepted(arrival_s);
    }
}

/// `d` when its pose (if any) is within the input's configured limits; the decoders checked
/// only the widest configurable ones.
fn within(limits: &PoseLimits, d: Decoded) -> Result<Decoded, DecodeError> {
    if let Some(pose) = &d.pose {
        pose.validate_within(limits)
            .map_err(|error| DecodeError::Invalid {
                protocol: d.protocol,
                error,
            })?;
    }
    Ok(d)
}

/// Frame-loop side of an input. Never blocks: every call is a handful of atomic operations plus
/// the extrapolation arithmetic.
pub struct PoseReader {
    name: Arc<str>,
    poses: Subscriber<Option<PoseSample>>,
    views: Subscriber<ViewTable>,
    counters: Arc<Counters>,
    monitor: StreamMonitor,
    params: ExtrapolationParams,
}

impl PoseReader {
    /// The newest accepted pose, if any.
    pub fn latest(&mut self) -> Option<PoseSample> {
        self.poses.update();
        *self.poses.get()
    }

    /// The pose at `display_s` (seconds on the [`monotonic_s`] timeline): the newest pose
    /// extrapolated (see [`extrapolate`]). Updates the stream state and logs lost/regained.
    /// `None` until the first pose arrives.
    pub fn pose_at(&mut self, display_s: f64) -> Option<FramePose> {
        self.poses.update();
        let sample = *self.poses.get();
        let arrival = sample.map(|s| s.latest.arrival_s);
        match self.monitor.update(arrival, display_s, self.params.cap_s) {
            Some(StreamEvent::Started) => tracing::info!("{}: pose stream started", self.name),
            Some(StreamEvent::Lost { silent_s }) => tracing::warn!(
                "{}: pose stream lost: no pose for {:.0} ms (cap {:.0} ms); holding the last pose",
                self.name,
                silent_s * 1e3,
                self.params.cap_s * 1e3
            ),
            Some(StreamEvent::Regained { outage_s }) => tracing::info!(
                "{}: pose stream regained after {:.0} ms",
                self.name,
                outage_s * 1e3
            ),
            None => {}
        }
        sample.map(|s| extrapolate(&s.latest, s.previous.as_ref(), display_s, &self.params))
    }

    /// [`pose_at`](Self::pose_at) for a display time given as an [`Instant`].
    pub fn pose_at_instant(&mut self, display: Instant) -> Option<FramePose> {
        self.pose_at(instant_s(display))
    }

    /// [`pose_at`](Self::pose_at) now.
    pub fn pose_now(&mut self) -> Option<FramePose> {
        self.pose_at(monotonic_s())
    }

    /// The per-view records set by CIGI View Control / View Definition packets.
    pub fn views(&mut self) -> &ViewTable {
        self.views.update();
        self.views.get()
    }

    /// The input's counters now.
    pub fn stats(&self) -> StatsSnapshot {
        self.counters.snapshot()
    }

    /// Live / lost / waiting, as of the last [`pose_at`](Self::pose_at).
    pub fn state(&self) -> StreamState {
        self.monitor.state()
    }

    /// The extrapolation limits in use.
    pub fn params(&self) -> ExtrapolationParams {
        self.params
    }

    /// The input's name.
    pub fn name(&self) -> &str {
        &self.name
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codec::cigi::{EntityControl, IgControl, ViewControl};
    use crate::codec::{native, ByteOrder};
    use crate::pose::PosePosition;

    fn pose(i: u64) -> Pose {
        Pose {
            position: PosePosition::LocalEnu {
                x: i as f64,
                y: 2.0 * i as f64,
                z: 1000.0,
            },
            attitude_deg: [i as f64, 0.0, 0.0],
            sim_time_s: i as f64 / 60.0,
            frame: i,
            velocity_enu: None,
            angular_rates_deg_s: None,
        }
    }

    #[test]
    fn order_gaps_and_counts() {
        let (mut ing, mut rd) = input_channel(InputParams::default());
        assert!(rd.pose_at(0.0).is_none());
        let t = |i: u32| f64::from(i) * 0.01;
        for (seq, want) in [
            (1u32, Verdict::Accepted(Some(SeqVerdict::First))),
            (2, Verdict::Accepted(Some(SeqVerdict::Next))),
            (2, Verdict::Dropped(DropReason::Duplicate)),
            (1, Verdict::Dropped(DropReason::OutOfOrder)),
            (6, Verdict::Accepted(Some(SeqVerdict::Gap { missed: 3 }))),
        ] {
            let got = ing
                .datagram(&native::encode(&pose(seq.into()), seq), t(seq))
                .verdict;
            assert_eq!(got, want, "seq {seq}");
        }
        let mut bad = native::encode(&pose(7), 7);
        bad[40] ^= 1;
        assert_eq!(
            ing.datagram(&bad, 0.07).verdict,
            Verdict::Dropped(DropReason::BadCrc)
        );
        assert_eq!(
            ing.datagram(b"junk", 0.08).verdict,
            Verdict::Dropped(DropReason::Unknown)
        );
        ing.not_allowed(&"10.0.0.9:5000");
        let s = rd.stats();
        assert_eq!((s.received, s.accepted, s.gaps, s.missed), (8, 3, 1, 3));
        assert_eq!(s.dropped(DropReason::Duplicate), 1);
        assert_eq!(s.dropped(DropReason::OutOfOrder), 1);
        assert_eq!(s.dropped(DropReason::BadCrc), 1);
        assert_eq!(s.dropped(DropReason::NotAllowed), 1);
        assert_eq!(s.received, s.accepted + s.no_pose + s.dropped_total());
        // The newest valid pose is kept despite the bad packets after it.
        let latest = rd.latest().unwrap();
        assert_eq!(latest.latest.pose, pose(6));
        assert_eq!(latest.previous.unwrap().pose, pose(2));
        assert_eq!(latest.latest.sample, 3);
    }

    #[test]
    fn each_protocol_has_its_own_sequence() {
        let (mut ing, rd) = input_channel(InputParams::default());
        ing.datagram(&native::encode(&pose(1), 10), 0.0);
        let cigi = IgControl {
            host_frame: 10,
            ..IgControl::default()
        }
        .encode(ByteOrder::Big);
        assert_eq!(ing.datagram(&cigi, 0.01).verdict, Verdict::NoPose);
        assert_eq!(
            ing.datagram(&native::encode(&pose(1), 10), 0.02).verdict,
            Verdict::Dropped(DropReason::Duplicate)
        );
        assert_eq!(rd.stats().dropped_total(), 1);
    }

    #[test]
    fn reader_reports_stale_and_extrapolates_from_two() {
        let (mut ing, mut rd) = input_channel(InputParams::default());
        ing.datagram(&native::encode(&pose(60), 1), 1.0);
        ing.datagram(&native::encode(&pose(61), 2), 1.0 + 1.0 / 60.0);
        // 1 m/s east per 1/60 s = 60 m/s: 20 ms later → x = 61 + 1.2.
        let f = rd.pose_at(1.0 + 1.0 / 60.0 + 0.02).unwrap();
        let PosePosition::LocalEnu { x, .. } = f.pose.position else {
            panic!()
        };
        assert!((x - 62.2).abs() < 1e-9, "{x}");
        assert_eq!(rd.state(), StreamState::Live);
        let f = rd.pose_at(2.0).unwrap();
        assert!(f.stale);
        assert_eq!(rd.state(), StreamState::Lost);
        ing.datagram(&native::encode(&pose(62), 3), 2.01);
        assert!(!rd.pose_at(2.02).unwrap().stale);
        assert_eq!(rd.state(), StreamState::Live);
    }

    #[test]
    fn cigi_views_reach_the_reader_and_resync_breaks_the_pair() {
        let (mut ing, mut rd) = input_channel(InputParams::default());
        let msg = |frame: u32, with_entity: bool| {
            let mut b = IgControl {
                ig_mode: 1,
                host_frame: frame,
                ..IgControl::default()
            }
            .encode(ByteOrder::Little)
            .to_vec();
            if with_entity {
                b.extend(
                    EntityControl {
                        lat_deg: 47.0,
                        lon_deg: 11.0,
                        alt_m: 2000.0,
                        ..EntityControl::default()
                    }
                    .encode(ByteOrder::Little),
                );
            }
            b.extend(
                ViewControl {
                    view_id: 3,
                    enable: 0x20,
                    roll_pitch_yaw_deg: [0.0, 0.0, frame as f32],
                    ..ViewControl::default()
                }
                .encode(ByteOrder::Little),
            );
            b
        };
        let o = ing.datagram(&msg(100, false), 0.0);
        assert_eq!(o.verdict, Verdict::NoPose);
        assert!(o.cigi.is_some());
        assert_eq!(
            rd.views().get(3).unwrap().roll_pitch_yaw_deg[2],
            Some(100.0)
        );
        ing.datagram(&msg(101, true), 0.01);
        ing.datagram(&msg(102, true), 0.02);
        assert!(rd.latest().unwrap().previous.is_some());
        // Host restarted after a long silence: frame 1 is accepted, and the previous pose is
        // not used as a motion reference across the restart.
        let o = ing.datagram(&msg(1, true), 5.0);
        assert_eq!(o.verdict, Verdict::Accepted(Some(SeqVerdict::Resync)));
        assert!(rd.latest().unwrap().previous.is_none());
        assert_eq!(rd.views().get(3).unwrap().roll_pitch_yaw_deg[2], Some(1.0));
        let s = rd.stats();
        assert_eq!((s.received, s.accepted, s.no_pose, s.resyncs), (4, 3, 1, 1));
    }

    #[test]
    fn a_reset_puts_views_back_and_packets_are_tallied() {
        let (mut ing, mut rd) = input_channel(InputParams::default());
        let msg = |frame: u32, mode: u8| {
            let mut b = IgControl {
                ig_mode: mode,
                host_frame: frame,
                ..IgControl::default()
            }
            .encode(ByteOrder::Big)
            .to_vec();
            b.extend(
                ViewControl {
                    view_id: 2,
                    enable: 0x20,
                    roll_pitch_yaw_deg: [0.0, 0.0, 45.0],
                    ..ViewControl::default()
                }
                .encode(ByteOrder::Big),
            );
            b
        };
        ing.datagram(&msg(1, 1), 0.0);
        assert!(rd.views().get(2).is_some());
        // Reset: the table empties (channels fall back to their configured views) and the
        // message's own View Control is not applied.
        assert_eq!(ing.datagram(&msg(2, 0), 0.01).verdict, Verdict::NoPose);
        assert!(rd.views().views().is_empty());
        ing.datagram(&msg(3, 0), 0.02);
        assert!(rd.views().views().is_empty());
        ing.datagram(&msg(4, 1), 0.03);
        assert_eq!(rd.views().get(2).unwrap().roll_pitch_yaw_deg[2], Some(45.0));
        let t = rd.stats().cigi_packets;
        assert_eq!((t.get(1), t.get(16)), (4, 4));
        // A native query is counted as a valid packet without a pose.
        ing.native_query();
        let s = rd.stats();
        assert_eq!(s.received, s.accepted + s.no_pose + s.dropped_total());
        assert_eq!(s.no_pose, 5);
    }
}
