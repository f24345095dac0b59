//! The bench's start-up fill (`--settle`, the suite's `run.settle`): before the first frame each
//! configuration renders the flight's first pose until a frame leaves nothing late and nothing
//! pending, as an IG fills its caches while the host waits for the database to load. Without it
//! every configuration starts from empty pools and level textures, and the first measured frames
//! count the start-up's uploads as late tiles: that is the cost of loading, not of flying.
//!
//! Pure: the stop rule and the words summary.md says; the frames are rendered by `bench.rs`.

use crate::render::stats::FrameStats;

/// Whether a start-up frame left the configuration filled: no tile drawn coarser than its
/// bound asked for lack of samples (`tiles_late`, streaming's share included) and no level
/// texture cell waiting for its samples (`cells_pending`).
pub(crate) fn filled(stats: &FrameStats) -> bool {
    stats.tiles_late == 0 && stats.tiles_late_stream == 0 && stats.cells_pending == 0
}

/// How one configuration's start-up went: the frames it rendered, and whether the last of them
/// was filled (false: it was still late after the most `--settle` allows).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Fill {
    pub frames: u32,
    pub filled: bool,
}

/// Follows one configuration's start-up frame by frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Settler {
    max: u32,
    fill: Fill,
}

impl Settler {
    pub fn new(max: u32) -> Self {
        Self {
            max,
            fill: Fill {
                frames: 0,
                filled: max == 0,
            },
        }
    }

    /// Whether another start-up frame is to be rendered.
    pub fn wants_frame(&self) -> bool {
        !self.fill.filled && self.fill.frames < self.max
    }

    /// Takes the statistics of the start-up frame just rendered.
    pub fn rendered(&mut self, stats: &FrameStats) {
        debug_assert!(self.wants_frame(), "a start-up frame past the end");
        self.fill.frames += 1;
        self.fill.filled = filled(stats);
    }

    pub fn fill(&self) -> Fill {
        self.fill
    }
}

/// summary.md's line on the start-up fill, `None` when there was none (`--settle 0`).
/// `fills` pairs each configuration's label with how its start-up went.
pub(crate) fn describe(max: u32, fills: &[(String, Fill)]) -> Option<String> {
    if max == 0 {
        return None;
    }
    let parts: Vec<String> = fills
        .iter()
        .map(|(label, f)| {
            if f.filled {
                format!("{label} {}", f.frames)
            } else {
                format!("{label} **still late after {}**", f.frames)
            }
        })
        .collect();
    Some(format!(
        "start-up fill (at most {max} frames at the first pose, not measured) — frames until nothing was late or pending: {}",
        parts.join(", ")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(late: u32, late_stream: u32, pending: u32) -> FrameStats {
        FrameStats {
            tiles_late: late,
            tiles_late_stream: late_stream,
            cells_pending: pending,
            ..FrameStats::default()
        }
    }

    #[test]
    fn a_frame_is_filled_only_with_nothing_late_and_nothing_pending() {
        assert!(filled(&frame(0, 0, 0)));
        assert!(!filled(&frame(1, 0, 0)));
        assert!(!filled(&frame(0, 1, 0)));
        assert!(!filled(&frame(0, 0, 3)));
    }

    #[test]
    fn the_settler_stops_at_the_first_filled_frame_or_at_the_most_allowed() {
        let mut s = Settler::new(5);
        let mut late = [frame(19, 0, 4), frame(5, 0, 0), frame(0, 0, 0)].into_iter();
        while s.wants_frame() {
            s.rendered(&late.next().expect("stops at the filled frame"));
        }
        assert_eq!(
            s.fill(),
            Fill {
                frames: 3,
                filled: true
            }
        );

        let mut s = Settler::new(2);
        while s.wants_frame() {
            s.rendered(&frame(7, 7, 0));
        }
        assert_eq!(
            s.fill(),
            Fill {
                frames: 2,
                filled: false
            }
        );

        let s = Settler::new(0);
        assert!(!s.wants_frame(), "--settle 0 renders no start-up frame");
    }

    #[test]
    fn summary_md_names_each_configuration_and_one_still_late() {
        assert_eq!(describe(0, &[]), None);
        let fills = [
            (
                "bounded τ=0.5".to_string(),
                Fill {
                    frames: 3,
                    filled: true,
                },
            ),
            (
                "clipmap n=513".to_string(),
                Fill {
                    frames: 30,
                    filled: false,
                },
            ),
        ];
        let line = describe(30, &fills).expect("a line");
        assert!(line.contains("at most 30 frames"), "{line}");
        assert!(line.contains("bounded τ=0.5 3"), "{line}");
        assert!(
            line.contains("clipmap n=513 **still late after 30**"),
            "{line}"
        );
    }
}
