//! The bench's replays (`--replays R`, the suite's `run.replays`): the measured frames flown R
//! times, each time by fresh renderers after the same start-up fill, and each frame timed by its
//! fastest flight that did the same work.
//!
//! Why: on a shared machine (two cores, a software rasteriser) one frame of fixed work takes
//! from 1× to 3× its least time from one flight to the next, and the worst-frame figure is then
//! the machine's, not the renderer's. The plans do not depend on timing (`render/plan.rs`, the
//! prefetch worker included), so a replay draws the same frames; the least of R times of the
//! same work is the renderer's cost with less of the machine's noise in it. A frame whose
//! replay did other work (another selection, other uploads) never takes that replay's time:
//! work that varies is measured, not averaged away.
//!
//! Each flight renders a frame's configurations in its own order ([`lane_order`]): what one
//! configuration renders just before another can slow it (on a software rasteriser, a frame of
//! half a million tessellated triangles left the next configuration's 22 k-triangle frame 30.7
//! against 21 ms without it, in each of three flights), so each flight puts another
//! configuration before each one, and the least time is not always taken after the same one.
//!
//! Tried and dropped: waiting, before each lane's timed frame, for every lane's view-ahead
//! selection (`render::ahead_select`'s worker, every fourth frame) to finish, so that no
//! lane's worker runs on the cores another's frame is timed on. On four flights (Inn follow
//! and approach, N40W074 follow and approach; every mode, three replays, one build flown with
//! and without) the worst ÷ median frame time was 1.76 / 1.43 / 1.38 / 1.66 with it against
//! 1.28 / 1.17 / 1.61 / 1.49 without: no pattern. The slow frames are single frames slower in
//! every replay's order for the same work (Inn approach τ = 10 px, frame 2: 14.1 ms in the
//! fastest of three flights, 7.5–9.0 ms for the other frames' same 1,282 triangles).
//!
//! Pure: the order, which timings a frame keeps, the tally and summary.md's line;
//! `lanes::replay` renders.

use crate::render::stats::FrameStats;

/// Whether two renderings of one frame did the same work: the same nodes at the same
/// refinements (the selection's digest), the same triangles, instances and draws, the same
/// bytes through the staging ring, the same tiles late.
pub(crate) fn same_work(a: &FrameStats, b: &FrameStats) -> bool {
    a.selection_digest == b.selection_digest
        && a.triangles == b.triangles
        && a.instances == b.instances
        && a.draw_calls == b.draw_calls
        && a.tiles_drawn == b.tiles_drawn
        && a.bytes_uploaded == b.bytes_uploaded
        && a.tiles_late == b.tiles_late
        && a.tiles_late_stream == b.tiles_late_stream
}

/// The order in which flight `flight` (0: the first, then each replay) renders frame `frame`'s
/// `m` configurations: position j renders configuration `(frame + j·s) mod m`, the stride `s`
/// 1 on the first flight (each frame's order rotated by one, as the bench always did), m − 1
/// (the reverse) on the second, then each stride in 2..m − 1 prime to m, in turn. Every order
/// is a permutation; a configuration not first in its frame follows configuration i − s, so
/// flights with different strides put different configurations before it.
pub(crate) fn lane_order(m: usize, flight: u32, frame: u32) -> Vec<usize> {
    if m == 0 {
        return Vec::new();
    }
    let gcd = |mut a: usize, mut b: usize| {
        while b != 0 {
            (a, b) = (b, a % b);
        }
        a
    };
    let mut strides = vec![1usize];
    if m > 2 {
        strides.push(m - 1);
        strides.extend((2..m - 1).filter(|&s| gcd(s, m) == 1));
    }
    let s = strides[flight as usize % strides.len()];
    let k = frame as usize % m;
    (0..m).map(|j| (k + j * s) % m).collect()
}

/// One frame's timings across its replays.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FrameReplays {
    /// The first flight's wall time (what a run without replays reports).
    pub first_ms: f64,
    /// Which flight's timings the frame keeps (0: the first).
    pub kept: u32,
    /// Flights that did the frame's work, the first included.
    pub same: u32,
    /// Flights that did other work (their times are not used).
    pub differed: u32,
}

impl FrameReplays {
    pub fn first(wall_ms: f64) -> Self {
        Self {
            first_ms: wall_ms,
            kept: 0,
            same: 1,
            differed: 0,
        }
    }
}

/// Takes replay `replay`'s rendering of a frame: when it did the same work as the frame's
/// first flight (`stats`, which keeps the work's counts) in less wall time than the time kept,
/// its wall time and statistics replace them. Returns whether they did.
pub(crate) fn take(
    kept_ms: &mut f64,
    stats: &mut FrameStats,
    replays: &mut FrameReplays,
    replay: u32,
    wall_ms: f64,
    replay_stats: &FrameStats,
) -> bool {
    if !same_work(stats, replay_stats) {
        replays.differed += 1;
        return false;
    }
    replays.same += 1;
    if wall_ms < *kept_ms {
        *kept_ms = wall_ms;
        *stats = *replay_stats;
        replays.kept = replay;
        true
    } else {
        false
    }
}

/// The flight's replays in numbers, for summary.md and the progress line.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct ReplayTally {
    pub replays: u32,
    pub frames: u32,
    /// Frames whose kept timings came from a replay after the first flight.
    pub from_replay: u32,
    /// Frames some replay of which did other work.
    pub differed: u32,
}

impl ReplayTally {
    pub fn of<'a>(replays: u32, frames: impl IntoIterator<Item = &'a FrameReplays>) -> Self {
        let mut t = Self {
            replays,
            ..Self::default()
        };
        for f in frames {
            t.frames += 1;
            t.from_replay += u32::from(f.kept > 0);
            t.differed += u32::from(f.differed > 0);
        }
        t
    }

    /// summary.md's line; none without replays.
    pub fn describe(&self) -> Option<String> {
        (self.replays > 1).then(|| {
            format!(
                "replays: the measured frames flown {} times, each by fresh renderers after the \
                 same start-up fill; a frame's timings are those of its fastest flight that did \
                 the same work (selection, triangles, instances, draws, bytes uploaded, late \
                 tiles) — {} of {} frames timed by a replay after the first, {} with a replay \
                 that did other work (its time not used)",
                self.replays, self.from_replay, self.frames, self.differed
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stats(triangles: u64, digest: u64, gpu_ms: f64) -> FrameStats {
        FrameStats {
            triangles,
            selection_digest: digest,
            instances: 7,
            bytes_uploaded: 4096,
            gpu_terrain_ms: gpu_ms,
            ..FrameStats::default()
        }
    }

    #[test]
    fn each_flight_renders_every_configuration_once_after_another_predecessor() {
        for m in [1usize, 2, 3, 4, 6, 23, 24] {
            for frame in 0..30 {
                // The first flight's order is the rotation by one per frame.
                let first = lane_order(m, 0, frame);
                assert_eq!(
                    first,
                    (0..m).map(|j| (j + frame as usize) % m).collect::<Vec<_>>()
                );
                let flights: Vec<Vec<usize>> = (0..3).map(|f| lane_order(m, f, frame)).collect();
                for order in &flights {
                    let mut sorted = order.clone();
                    sorted.sort_unstable();
                    assert_eq!(sorted, (0..m).collect::<Vec<_>>(), "m {m}: a permutation");
                }
                if m < 3 {
                    continue;
                }
                // Three strides where one in 2..m − 1 is prime to m (m = 23, 24), else the
                // reverse comes back (m = 4, 6: strides 1 and m − 1 only).
                let third = matches!(m, 23 | 24);
                assert_ne!(flights[0], flights[1]);
                assert_eq!(flights[2] == flights[0], !third, "m {m}");
                // Each configuration not first in its frame has another predecessor in each
                // flight of another order.
                for lane in 0..m {
                    let before: Vec<Option<usize>> = flights
                        .iter()
                        .map(|o| {
                            let at = o.iter().position(|&x| x == lane).unwrap();
                            (at > 0).then(|| o[at - 1])
                        })
                        .collect();
                    for a in 0..3 {
                        for b in a + 1..3 {
                            if flights[a] == flights[b] {
                                continue;
                            }
                            if let (Some(x), Some(y)) = (before[a], before[b]) {
                                assert_ne!(x, y, "m {m} frame {frame} lane {lane}");
                            }
                        }
                    }
                }
            }
        }
        assert!(lane_order(0, 1, 3).is_empty());
    }

    #[test]
    fn a_faster_replay_of_the_same_work_replaces_the_timings() {
        let mut ms = 150.0;
        let mut s = stats(1000, 9, 149.0);
        let mut r = FrameReplays::first(ms);
        assert!(take(
            &mut ms,
            &mut s,
            &mut r,
            1,
            120.0,
            &stats(1000, 9, 119.0)
        ));
        assert_eq!((ms, s.gpu_terrain_ms, r.kept, r.same), (120.0, 119.0, 1, 2));
        // A slower one later keeps the fastest.
        assert!(!take(
            &mut ms,
            &mut s,
            &mut r,
            2,
            130.0,
            &stats(1000, 9, 129.0)
        ));
        assert_eq!((ms, r.kept, r.same, r.differed), (120.0, 1, 3, 0));
        assert_eq!(r.first_ms, 150.0, "the first flight's time is kept apart");
    }

    #[test]
    fn a_replay_that_did_other_work_is_never_taken_however_fast() {
        for other in [stats(999, 9, 1.0), stats(1000, 8, 1.0), {
            let mut s = stats(1000, 9, 1.0);
            s.bytes_uploaded += 1;
            s
        }] {
            let mut ms = 150.0;
            let mut s = stats(1000, 9, 149.0);
            let mut r = FrameReplays::first(ms);
            assert!(!take(&mut ms, &mut s, &mut r, 1, 1.0, &other));
            assert_eq!(
                (ms, s.gpu_terrain_ms, r.kept, r.same, r.differed),
                (150.0, 149.0, 0, 1, 1)
            );
        }
    }

    #[test]
    fn the_tally_counts_frames_timed_by_replays_and_frames_that_differed() {
        let frames = [
            FrameReplays {
                first_ms: 1.0,
                kept: 0,
                same: 3,
                differed: 0,
            },
            FrameReplays {
                first_ms: 1.0,
                kept: 2,
                same: 3,
                differed: 0,
            },
            FrameReplays {
                first_ms: 1.0,
                kept: 1,
                same: 2,
                differed: 1,
            },
        ];
        let t = ReplayTally::of(3, &frames);
        assert_eq!((t.frames, t.from_replay, t.differed), (3, 2, 1));
        let line = t.describe().expect("a line with replays");
        assert!(
            line.contains("flown 3 times") && line.contains("2 of 3 frames"),
            "{line}"
        );
        assert_eq!(ReplayTally::of(1, &frames[..1]).describe(), None);
    }
}
