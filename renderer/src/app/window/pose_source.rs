//! The seam between the window loop and where the aircraft is: the built-in flight, a
//! recording or the simulator's stream.

use aerie_config::Channel;

use crate::render::frame::{FrameStats, TerrainRenderer};
use crate::sim::channel::AircraftPose;
use crate::sim::host_view::LiveChannel;

/// Where the aircraft is for each frame: the seam where the built-in flight, a recording or the
/// simulator's UDP stream plugs in. Called once per frame; every channel of that frame uses the
/// same pose.
pub trait PoseSource {
    /// The start of display frame `frame`, before [`PoseSource::pose`]: where an image
    /// generator answers its host (one CIGI Start of Frame per frame, the queries since the
    /// last one) and applies what the host changed (database, sun, visibility). An `Err` ends
    /// the session with that error.
    fn begin_frame(&mut self, _frame: u64, _renderer: &mut TerrainRenderer) -> Result<(), String> {
        Ok(())
    }

    /// The pose to draw for display frame `frame` (0-based), `t_s` seconds after the first
    /// frame began.
    fn pose(&mut self, frame: u64, t_s: f64) -> AircraftPose;

    /// Age of the pose last returned (its packet's arrival to the frame's predicted display
    /// time), milliseconds, for the overlay; `None` when the source is not a stream.
    fn pose_age_ms(&self) -> Option<f64> {
        None
    }

    /// Set when the source cannot go on (e.g. geodetic poses on a dataset without a
    /// geo-reference): checked after every pose, the session then ends with this error.
    fn failure(&mut self) -> Option<String> {
        None
    }

    /// The channels to draw this frame, called once per frame after [`PoseSource::pose`] and
    /// before selection: the configured ones, with the host's CIGI views applied when the
    /// source has any ([`crate::sim::host_view`]).
    fn channels(&mut self, configured: &[Channel]) -> Vec<LiveChannel> {
        configured.iter().map(LiveChannel::configured).collect()
    }

    /// The frame just drawn: the statistics of every channel drawn (empty when none was), so
    /// the source can complete its per-frame records (e.g. the `--stats` triangles).
    fn frame_drawn(&mut self, _frame: u64, _stats: &[FrameStats]) {}
}

impl<F: FnMut(u64, f64) -> AircraftPose> PoseSource for F {
    fn pose(&mut self, frame: u64, t_s: f64) -> AircraftPose {
        self(frame, t_s)
    }
}
