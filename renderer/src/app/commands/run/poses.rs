//! The pose of every frame of `aerie run`: the built-in pass ([`StraightPassSource`]) without
//! input, else the simulator stream ([`RunPoses`] over a [`SimInput`]), with the figures of the
//! summary and the `--stats` rows. Shared by the window and the headless loops.

use std::time::Instant;

use aerie_config::Channel;
use aerie_sim_bridge::DropReason;

use crate::app::commands::run::args::RunArgs;
use crate::app::commands::run::ig::IgDriver;
use crate::app::commands::run::settings::RunSettings;
use crate::app::failure::{bad_input, runtime, Failure};
use crate::app::window::pose_source::PoseSource;
use crate::render::frame::{FrameStats, TerrainRenderer};
use crate::sim::channel::AircraftPose;
use crate::sim::flight::StraightPass;
use crate::sim::host_view::{HostViews, LiveChannel};
use crate::sim::pose_input::{counters_text, GeoMapping, SimInput};
use crate::tools::percentile::percentile;
use crate::tools::stats_csv::{FrameRow, PoseOrigin, StatsWriter};

/// The built-in straight pass as a pose source: the pass restarts at its beginning after
/// `period_s` seconds of wall time.
pub struct StraightPassSource {
    pub pass: StraightPass,
    pub period_s: f64,
}

impl PoseSource for StraightPassSource {
    fn pose(&mut self, _frame: u64, t_s: f64) -> AircraftPose {
        let t = if self.period_s > 0.0 {
            t_s.rem_euclid(self.period_s)
        } else {
            0.0
        };
        let (position, attitude) = self.pass.pose_at(t);
        AircraftPose { position, attitude }
    }
}

/// The pose of every frame of `aerie run`: the simulator stream when one is configured (the
/// built-in pass's first pose as a default view while none has arrived), else the built-in
/// pass. Keeps the figures of the summary and writes the `--stats` rows.
pub struct RunPoses {
    pub input: Option<SimInput>,
    pub builtin: StraightPassSource,
    /// From a frame's start to its display, seconds: what the pose is carried forward to.
    pub lead_s: f64,
    pub stats: Option<StatsWriter>,
    /// Pose ages of the frames drawn from the stream, milliseconds.
    pub ages_ms: Vec<f64>,
    /// Frames drawn from the stream, and how many of them extrapolated.
    pub input_frames: u64,
    pub extrapolated: u64,
    /// Frame-locked frames that drew exactly their target host frame.
    pub exact_sync: u64,
    /// Frames drawn with the default view while waiting.
    pub waiting_frames: u64,
    said_waiting: bool,
    got_first: bool,
    last_age_ms: Option<f64>,
    last_call: Option<Instant>,
    /// The last pose drawn from the stream: held if the stream has nothing to draw again (a
    /// frame-locked history restarting after a host restart).
    last_drawn: Option<AircraftPose>,
    /// Why the run must stop (set in the window path, where a pose source cannot return one).
    pub fail: Option<Failure>,
    /// The host's CIGI views over the channels (made on the first frame).
    pub views: Option<HostViews>,
    /// Window path: this frame's `--stats` row, written once the frame's triangles are known.
    pending: Option<FrameRow>,
    /// The image generator's side of a UDP input: answers and host state, once per frame.
    pub ig: Option<IgDriver>,
}

impl RunPoses {
    pub fn new(
        input: Option<SimInput>,
        builtin: StraightPassSource,
        lead_s: f64,
        stats: Option<StatsWriter>,
    ) -> Self {
        Self {
            input,
            builtin,
            lead_s,
            stats,
            ages_ms: Vec::new(),
            input_frames: 0,
            extrapolated: 0,
            exact_sync: 0,
            waiting_frames: 0,
            said_waiting: false,
            got_first: false,
            last_age_ms: None,
            last_call: None,
            last_drawn: None,
            fail: None,
            views: None,
            pending: None,
            ig: None,
        }
    }

    /// The channels as drawn this frame: `configured` with the host's latest CIGI views
    /// applied (as configured without an input or without views).
    pub fn live_channels(&mut self, configured: &[Channel]) -> &[LiveChannel] {
        let views = self.views.get_or_insert_with(|| HostViews::new(configured));
        match &mut self.input {
            Some(input) => views.update(input.views()),
            None => views.live(),
        }
    }

    /// Writes the window path's pending `--stats` row (without triangles if the frame was
    /// never reported drawn).
    fn flush_pending(&mut self) -> Result<(), Failure> {
        match self.pending.take() {
            Some(row) => self.record(&row),
            None => Ok(()),
        }
    }

    /// The default view while no pose has arrived: the start of the built-in pass.
    pub fn default_view(&self) -> AircraftPose {
        let (position, attitude) = self.builtin.pass.pose_at(0.0);
        AircraftPose { position, attitude }
    }

    /// The pose of display frame `frame`, `t_s` seconds after the first frame began. `Err`
    /// (bad input, exit 2) when a pose cannot be placed on this dataset.
    pub fn next(&mut self, frame: u64, t_s: f64) -> Result<(AircraftPose, PoseOrigin), Failure> {
        let Some(input) = &mut self.input else {
            return Ok((self.builtin.pose(frame, t_s), PoseOrigin::Builtin));
        };
        match input.sample_now(self.lead_s).map_err(bad_input)? {
            Some((pose, info)) => {
                if !self.got_first {
                    self.got_first = true;
                    eprintln!(
                        "first pose from {} (host frame {})",
                        input.what, info.host_frame
                    );
                }
                self.last_age_ms = Some(info.age_s * 1e3);
                self.ages_ms.push(info.age_s * 1e3);
                self.input_frames += 1;
                self.extrapolated += u64::from(info.extrapolated);
                self.exact_sync += u64::from(info.sync_target == Some(info.host_frame));
                self.last_drawn = Some(pose);
                Ok((pose, PoseOrigin::Input(info)))
            }
            None => {
                if !self.said_waiting {
                    self.said_waiting = true;
                    eprintln!(
                        "waiting for poses on {}; holding the default view",
                        input.what
                    );
                }
                self.last_age_ms = None;
                self.waiting_frames += 1;
                Ok((
                    self.last_drawn.unwrap_or_else(|| self.default_view()),
                    PoseOrigin::Waiting,
                ))
            }
        }
    }

    /// Writes a `--stats` row (no-op without --stats).
    pub fn record(&mut self, row: &FrameRow) -> Result<(), Failure> {
        match &mut self.stats {
            Some(w) => w.row(row).map_err(runtime),
            None => Ok(()),
        }
    }

    /// Flushes the stats file.
    pub fn finish(&mut self) -> Result<(), Failure> {
        if let Some(i) = &mut self.input {
            i.stop();
        }
        self.flush_pending()?;
        match &mut self.stats {
            Some(w) => w.flush().map_err(runtime),
            None => Ok(()),
        }
    }

    /// The input part of the summary (`null` without input).
    pub fn summary_json(&self) -> serde_json::Value {
        let Some(input) = &self.input else {
            return serde_json::Value::Null;
        };
        let s = input.stats();
        let mut dropped = serde_json::Map::new();
        for r in DropReason::ALL {
            dropped.insert(r.name().to_string(), s.dropped(r).into());
        }
        let mut ages = self.ages_ms.clone();
        ages.sort_by(f64::total_cmp);
        serde_json::json!({
            "source": input.what,
            "received": s.received,
            "accepted": s.accepted,
            "without_pose": s.no_pose,
            "dropped_total": s.dropped_total(),
            "dropped": dropped,
            "gaps": s.gaps,
            "frames_from_stream": self.input_frames,
            "frames_waiting": self.waiting_frames,
            "pose_age_ms": {
                "median": (!ages.is_empty()).then(|| percentile(&ages, 0.5)),
                "max": ages.last(),
            },
            "extrapolated_pct": pct(self.extrapolated, self.input_frames),
            "sync_frames": input_sync(input),
            "sync_exact_pct": input_sync(input).map(|_| pct(self.exact_sync, self.input_frames)),
            "views": self.views.as_ref().map(HostViews::to_json),
        })
    }

    /// One line for the end of the run.
    pub fn summary_line(&self) -> Option<String> {
        let input = self.input.as_ref()?;
        let mut ages = self.ages_ms.clone();
        ages.sort_by(f64::total_cmp);
        Some(format!(
            "poses from {}: {}; {} frames from the stream ({} waiting), pose age median {:.1} ms, max {:.1} ms, {:.0} % extrapolated{}",
            input.what,
            counters_text(&input.stats()),
            self.input_frames,
            self.waiting_frames,
            percentile(&ages, 0.5),
            ages.last().copied().unwrap_or(0.0),
            pct(self.extrapolated, self.input_frames),
            match input_sync(input) {
                Some(k) => format!(
                    ", frame-locked newest−{k}: {:.0} % exact",
                    pct(self.exact_sync, self.input_frames)
                ),
                None => String::new(),
            }
        ))
    }
}

fn input_sync(i: &SimInput) -> Option<u32> {
    i.sync_frames()
}

fn pct(n: u64, of: u64) -> f64 {
    if of == 0 {
        0.0
    } else {
        100.0 * n as f64 / of as f64
    }
}

impl PoseSource for RunPoses {
    fn begin_frame(&mut self, _frame: u64, renderer: &mut TerrainRenderer) -> Result<(), String> {
        let eye = self
            .last_drawn
            .unwrap_or_else(|| self.default_view())
            .position;
        match &mut self.ig {
            Some(ig) => ig.begin_frame(renderer, self.input.as_mut(), eye),
            None => Ok(()),
        }
    }

    fn pose(&mut self, frame: u64, t_s: f64) -> AircraftPose {
        let now = Instant::now();
        let frame_ms = self.last_call.map(|l| (now - l).as_secs_f64() * 1e3);
        self.last_call = Some(now);
        // The row waits for frame_drawn (the triangles); a frame never reported drawn is
        // written without them when the next one starts.
        let got = self.flush_pending().and_then(|_| {
            self.next(frame, t_s).map(|(pose, origin)| {
                self.pending = Some(FrameRow {
                    frame,
                    wall_s: t_s,
                    pose,
                    origin,
                    triangles: None,
                    frame_ms,
                    terrain: None,
                });
                pose
            })
        });
        match got {
            Ok(pose) => pose,
            Err(f) => {
                self.fail.get_or_insert(f);
                self.default_view()
            }
        }
    }

    fn pose_age_ms(&self) -> Option<f64> {
        self.last_age_ms
    }

    fn failure(&mut self) -> Option<String> {
        self.fail.as_ref().map(|f| f.message.clone())
    }

    fn channels(&mut self, configured: &[Channel]) -> Vec<LiveChannel> {
        self.live_channels(configured).to_vec()
    }

    fn frame_drawn(&mut self, frame: u64, stats: &[FrameStats]) {
        if let Some(row) = self.pending.as_mut().filter(|r| r.frame == frame) {
            row.triangles = Some(stats.iter().map(|s| s.triangles).sum());
        }
        if let Err(f) = self.flush_pending() {
            self.fail.get_or_insert(f);
        }
    }
}

/// Opens the simulator input of the arguments (if any) for dataset `ds`.
pub fn open_input(
    settings: &RunSettings,
    grid: &aerie_terrain::source::SourceGrid,
) -> Result<Option<SimInput>, Failure> {
    let Some(spec) = &settings.input else {
        return Ok(None);
    };
    let input = SimInput::open(spec, GeoMapping::of_source(grid)).map_err(runtime)?;
    eprintln!(
        "pose input: {}{}",
        input.what,
        match spec.sync_frames {
            Some(k) => format!(", frame-locked to host frame newest−{k}"),
            None => format!(
                ", extrapolated at most {} ms",
                settings.max_extrapolation_ms
            ),
        }
    );
    Ok(Some(input))
}

/// The `--stats` file, if asked for.
pub fn open_stats(a: &RunArgs, geo: Option<GeoMapping>) -> Result<Option<StatsWriter>, Failure> {
    a.stats
        .as_ref()
        .map(|p| StatsWriter::create(p, geo).map_err(runtime))
        .transpose()
}
