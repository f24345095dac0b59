//! `aerie run`: the image generator. Opens one window (or fullscreen display) per channel of a
//! config (`config/presets/*.toml`), all in one process on one device, or only the channels
//! named with `--channel` (one process per channel, e.g. one machine per projector, sharing the
//! config); or, with `--headless`, renders the same channels offscreen. Runs until Esc, a closed
//! window, `--frames` or `--seconds`; prints a summary (frames, frame times, per-channel
//! presentation, pose input, validation) and writes it as JSON with `--json`.
//!
//! The aircraft pose comes from a [`PoseSource`]: the built-in pass ([`StraightPassSource`])
//! without input, else the simulator stream ([`RunPoses`] over a
//! [`SimInput`](crate::sim::pose_input::SimInput)): with `--listen`, `--protocol`, `--multicast` or
//! `--shm-name`, each frame draws `PoseReader::pose_at(predicted display time)` (carried forward
//! at most `--max-extrapolation-ms`), or with `--sync-frames k` the pose of host frame
//! newest − k exactly (one process per channel on one stream). `--stats` writes the pose used
//! per frame ([`crate::tools::stats_csv`]).

use std::net::{IpAddr, Ipv4Addr, SocketAddr, SocketAddrV4};
use std::path::PathBuf;
use std::time::Instant;

use aerie_config::{Channel, ChannelDisplay, InputProtocolName, RenderConfig};
use aerie_sim_bridge::codec::ProtocolChoice;
use aerie_sim_bridge::shm::DEFAULT_SHM_NAME;
use aerie_sim_bridge::{DropReason, DEFAULT_PORT};
use clap::Args;
use winit::event_loop::EventLoop;

use super::check_out_folder;
use crate::app::failure::{bad_input, runtime, Failure};
use crate::app::prepare::prepare_terrain;
use crate::app::window::{
    new_event_loop, required_instance_extensions, run_channels, PoseSource, RunOptions, RunReport,
    WindowError,
};
use crate::render::frame::{FrameStats, RendererDesc, TerrainRenderer};
use crate::sim::channel::AircraftPose;
use crate::sim::flight::StraightPass;
use crate::sim::host_view::{HostViews, LiveChannel};
use crate::sim::pose_input::{counters_text, GeoMapping, InputProtocol, InputSpec, SimInput};
use crate::tools::output::write_text;
use crate::tools::percentile::percentile;
use crate::tools::stats_csv::{FrameRow, PoseOrigin, StatsWriter};
use crate::vk::DeviceDesc;
use aerie_terrain::camera::parse_size_arg;
use aerie_terrain::select::SelectParams;

/// Window size of a fullscreen channel shown with `--windowed` when it has no resolution.
const WINDOWED_DEFAULT: (u32, u32) = (960, 540);

#[derive(Debug, Args)]
pub struct RunArgs {
    /// Channel configuration (TOML, e.g. config/presets/wall3.toml). Without `[[channel]]`
    /// tables (or without --config) one window of the `[render]` size and field of view opens.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Open only this channel of the config (repeatable): one process per channel, e.g. one
    /// machine per projector sharing the config. Default: every channel, in this process.
    #[arg(long = "channel", value_name = "NAME")]
    pub channels: Vec<String>,
    /// Elevation model (as for `aerie render`); its bake is read from or written next to it.
    #[arg(long)]
    pub dem: PathBuf,
    /// Stop after this many frames (default: run until Esc or a window is closed).
    #[arg(long)]
    pub frames: Option<u64>,
    /// Stop after this many seconds.
    #[arg(long)]
    pub seconds: Option<f64>,
    /// Start with the statistics overlay shown (frame time, τ, tiles, late tiles, triangles,
    /// pose age); F1 or O toggles it in a window.
    #[arg(long)]
    pub overlay: bool,
    /// Also write the summary as JSON to this file.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Show fullscreen channels in windows (side by side) instead: try a wall or cockpit
    /// preset on a desktop.
    #[arg(long)]
    pub windowed: bool,
    /// With --windowed: the size of every channel's window, WxH (default: its resolution, or
    /// 960x540).
    #[arg(long, value_name = "WxH")]
    pub window_size: Option<String>,
    /// Use the first Vulkan device whose name contains this (overrides render.gpu).
    #[arg(long)]
    pub gpu: Option<String>,
    /// Enable the Khronos validation layer (also render.validation; always on in debug builds).
    #[arg(long)]
    pub validate: bool,
    /// Built-in pass: heading, degrees clockwise from north.
    #[arg(long, default_value_t = 70.0, allow_hyphen_values = true)]
    pub heading: f64,
    /// Built-in pass: aircraft pitch, degrees (negative: nose down; channel view offsets add).
    #[arg(long, default_value_t = -10.0, allow_hyphen_values = true)]
    pub pitch: f64,
    /// Built-in pass: ground speed, m/s.
    #[arg(long, default_value_t = 150.0)]
    pub speed: f64,
    /// Built-in pass: height above the highest sample of the DEM, metres.
    #[arg(long, default_value_t = 600.0)]
    pub agl: f64,
    /// Take the aircraft pose from a simulator on this UDP address (default 127.0.0.1:47800
    /// when --protocol is given; 0.0.0.0:47800 with --multicast).
    #[arg(long, value_name = "ADDR:PORT")]
    pub listen: Option<SocketAddr>,
    /// Pose protocol: auto (detected per datagram), native, cigi, xplane, fgfs, or shm (shared
    /// memory, see --shm-name). Any input flag turns the input on.
    #[arg(long, value_parser = parse_input_protocol)]
    pub protocol: Option<InputProtocol>,
    /// Shared-memory pose file: a name in /dev/shm or a path (implies --protocol shm).
    #[arg(long, value_name = "NAME")]
    pub shm_name: Option<String>,
    /// Join this IPv4 multicast group (several channel machines on one stream).
    #[arg(long, value_name = "GROUP")]
    pub multicast: Option<Ipv4Addr>,
    /// With --multicast: local interface address to join on (default: the kernel chooses;
    /// 127.0.0.1 for processes on one host without a multicast route).
    #[arg(long, value_name = "IPV4")]
    pub multicast_if: Option<Ipv4Addr>,
    /// Accept poses only from these source addresses (comma-separated).
    #[arg(long, value_delimiter = ',')]
    pub allow: Vec<IpAddr>,
    /// Carry a pose forward to the frame's display time by at most this much, milliseconds
    /// (0: draw poses as received). Default: input.max_extrapolation_ms, else 100.
    #[arg(long, value_name = "MS", allow_hyphen_values = true)]
    pub max_extrapolation_ms: Option<f64>,
    /// Frame-locked: draw host frame newest − K with its own pose (never extrapolated), so one
    /// process per channel on one stream draws the same host frame. K ≥ 1 absorbs network
    /// jitter between machines at the price of K host frames of latency.
    #[arg(long, value_name = "K")]
    pub sync_frames: Option<u32>,
    /// Headless: how long to wait for the first pose before giving up (exit 1), seconds.
    /// Default: input.wait_pose_s, else 10.
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub wait_pose_s: Option<f64>,
    /// Render offscreen, no window: every channel of the config (or one of --size).
    #[arg(long)]
    pub headless: bool,
    /// Headless: render size of every channel, WxH (default: each channel's resolution).
    #[arg(long, value_name = "WxH")]
    pub size: Option<String>,
    /// Write one CSV row per frame: the pose used, where it came from, frame cost.
    #[arg(long, value_name = "FILE.csv")]
    pub stats: Option<PathBuf>,
    /// Headless: frame rate to pace at. Default: render.fps, else 60.
    #[arg(long, allow_hyphen_values = true)]
    pub fps: Option<f64>,
    /// Headless: do not pace, render frames back to back.
    #[arg(long)]
    pub as_fast_as_possible: bool,
}

fn parse_input_protocol(s: &str) -> Result<InputProtocol, String> {
    s.parse()
}

/// Default `--max-extrapolation-ms` / `input.max_extrapolation_ms`.
pub const DEFAULT_MAX_EXTRAPOLATION_MS: f64 = 100.0;
/// Default `--wait-pose-s` / `input.wait_pose_s`.
pub const DEFAULT_WAIT_POSE_S: f64 = 10.0;
/// Default `--fps` / `render.fps`.
pub const DEFAULT_FPS: f64 = 60.0;

/// The run settings in effect: each command-line flag, else the config's key, else the default.
#[derive(Debug, Clone)]
pub struct RunSettings {
    /// The simulator input, if any flag or `[input]` key asks for one.
    pub input: Option<InputSpec>,
    pub max_extrapolation_ms: f64,
    pub wait_pose_s: f64,
    pub fps: f64,
}

fn config_protocol(p: InputProtocolName) -> InputProtocol {
    // The config names are a subset of what --protocol parses.
    p.as_str().parse().expect("config protocol names parse")
}

/// Merges the input flags over the config's `[input]` (and `render.fps`): a flag given wins,
/// a key the file gives comes next, then the defaults. A flag that picks the transport
/// (`--protocol`, `--shm-name` for shared memory, `--listen`/`--multicast`/`--allow` for UDP)
/// also drops the config keys of the other transport. Pure: no socket, no file.
pub fn resolve_settings(a: &RunArgs, config: &RenderConfig) -> Result<RunSettings, Failure> {
    let c = &config.input;
    let max_extrapolation_ms = a
        .max_extrapolation_ms
        .or(c.max_extrapolation_ms)
        .unwrap_or(DEFAULT_MAX_EXTRAPOLATION_MS);
    let wait_pose_s = a
        .wait_pose_s
        .or(c.wait_pose_s)
        .unwrap_or(DEFAULT_WAIT_POSE_S);
    let fps = a.fps.or(config.render.fps).unwrap_or(DEFAULT_FPS);
    let sync_frames = a.sync_frames.or(c.sync_frames);
    let cli_udp = a.listen.is_some() || a.multicast.is_some() || !a.allow.is_empty();
    let wanted = cli_udp || a.protocol.is_some() || a.shm_name.is_some() || c.wants_input();
    if let Some(k) = sync_frames.filter(|&k| k > aerie_config::MAX_SYNC_FRAMES) {
        return Err(bad_input(format!(
            "--sync-frames: {k} is more than the {} host frames kept (0..={})",
            aerie_config::MAX_SYNC_FRAMES + 1,
            aerie_config::MAX_SYNC_FRAMES
        )));
    }
    if !wanted {
        if sync_frames.is_some() {
            return Err(bad_input(
                "--sync-frames: needs a pose input (--listen, --protocol, --multicast or --shm-name, or an [input] protocol in the config)",
            ));
        }
        return Ok(RunSettings {
            input: None,
            max_extrapolation_ms,
            wait_pose_s,
            fps,
        });
    }
    let cli_protocol = a
        .protocol
        .or(a.shm_name.is_some().then_some(InputProtocol::Shm));
    let config_protocol = c
        .protocol
        .map(config_protocol)
        .or(c.shm_name.is_some().then_some(InputProtocol::Shm));
    let protocol = cli_protocol
        .or(config_protocol.filter(|p| !(cli_udp && *p == InputProtocol::Shm)))
        .unwrap_or(InputProtocol::Udp(ProtocolChoice::Auto));
    let shm = protocol == InputProtocol::Shm;
    // Keys of the other transport do not apply (the config itself refuses mixing them).
    let (cfg_listen, cfg_multicast, cfg_if, cfg_allow, cfg_shm) = if shm {
        (None, None, None, Vec::new(), c.shm_name.clone())
    } else {
        (c.listen, c.multicast, c.multicast_if, c.allow.clone(), None)
    };
    let multicast = a.multicast.or(cfg_multicast);
    let multicast_if = a.multicast_if.or(cfg_if);
    if multicast_if.is_some() && multicast.is_none() {
        return Err(bad_input(
            "--multicast-if: only with --multicast (or input.multicast)",
        ));
    }
    let host = if multicast.is_some() {
        Ipv4Addr::UNSPECIFIED
    } else {
        Ipv4Addr::LOCALHOST
    };
    Ok(RunSettings {
        input: Some(InputSpec {
            protocol,
            listen: a
                .listen
                .or(cfg_listen)
                .unwrap_or(SocketAddr::V4(SocketAddrV4::new(host, DEFAULT_PORT))),
            multicast,
            multicast_interface: multicast_if.unwrap_or(Ipv4Addr::UNSPECIFIED),
            allow: if a.allow.is_empty() {
                cfg_allow
            } else {
                a.allow.clone()
            },
            shm_name: a
                .shm_name
                .clone()
                .or(cfg_shm)
                .unwrap_or_else(|| DEFAULT_SHM_NAME.to_string()),
            cap_s: max_extrapolation_ms / 1e3,
            sync_frames,
        }),
        max_extrapolation_ms,
        wait_pose_s,
        fps,
    })
}

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
    ds: &aerie_terrain::dataset::Dataset,
) -> Result<Option<SimInput>, Failure> {
    let Some(spec) = &settings.input else {
        return Ok(None);
    };
    let input = SimInput::open(spec, GeoMapping::of_dataset(ds)).map_err(runtime)?;
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

/// Everything decided from the arguments and the config before anything opens.
pub(crate) struct Plan {
    pub config: RenderConfig,
    pub source: String,
    pub channels: Vec<Channel>,
    /// Flags over the config's `[input]` and `render.fps`.
    pub settings: RunSettings,
}

fn check_args(a: &RunArgs) -> Result<(), Failure> {
    if a.frames == Some(0) {
        return Err(bad_input("--frames: must be at least 1"));
    }
    if let Some(s) = a.seconds {
        if !(s.is_finite() && s > 0.0) {
            return Err(bad_input(format!(
                "--seconds: {s} must be a finite positive number"
            )));
        }
    }
    for (name, v) in [("--speed", a.speed), ("--agl", a.agl)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(bad_input(format!(
                "{name}: {v} must be a finite number ≥ 0"
            )));
        }
    }
    for (name, v) in [("--heading", a.heading), ("--pitch", a.pitch)] {
        if !v.is_finite() {
            return Err(bad_input(format!("{name}: {v} is not finite")));
        }
    }
    if a.window_size.is_some() && !a.windowed {
        return Err(bad_input("--window-size: only with --windowed"));
    }
    if let Some(j) = &a.json {
        check_out_folder("--json", j)?;
    }
    if let Some(p) = &a.stats {
        check_out_folder("--stats", p)?;
    }
    if let Some(ms) = a.max_extrapolation_ms {
        if !(ms.is_finite() && ms >= 0.0) {
            return Err(bad_input(format!(
                "--max-extrapolation-ms: {ms} must be a finite number ≥ 0"
            )));
        }
    }
    for (name, v) in [("--wait-pose-s", a.wait_pose_s), ("--fps", a.fps)] {
        let Some(v) = v else { continue };
        if !(v.is_finite() && v > 0.0) {
            return Err(bad_input(format!(
                "{name}: {v} must be a finite positive number"
            )));
        }
    }
    if a.headless {
        if a.windowed {
            return Err(bad_input("--windowed and --headless exclude each other"));
        }
        if a.frames.is_none() && a.seconds.is_none() {
            return Err(bad_input(
                "--headless: give --frames N or --seconds S (there is no window to close)",
            ));
        }
    } else {
        for (flag, set) in [
            ("--size", a.size.is_some()),
            ("--as-fast-as-possible", a.as_fast_as_possible),
        ] {
            if set {
                return Err(bad_input(format!("{flag}: only with --headless")));
            }
        }
    }
    if let Some(s) = &a.size {
        parse_size_arg(s).map_err(|e| bad_input(format!("--size: {e}")))?;
    }
    // Flag combinations that contradict each other (flags over config keys: resolve_settings).
    let cli_shm = match a.protocol {
        Some(p) => p == InputProtocol::Shm,
        None => a.shm_name.is_some(),
    };
    if cli_shm && (a.listen.is_some() || a.multicast.is_some() || !a.allow.is_empty()) {
        return Err(bad_input(
            "--protocol shm reads shared memory: --listen, --multicast and --allow apply to UDP only",
        ));
    }
    if !cli_shm && a.shm_name.is_some() {
        return Err(bad_input("--shm-name: only with --protocol shm"));
    }
    Ok(())
}

pub(crate) fn plan(a: &RunArgs) -> Result<Plan, Failure> {
    check_args(a)?;
    let (config, source) = match &a.config {
        Some(p) => (
            aerie_config::load(p).map_err(bad_input)?,
            p.display().to_string(),
        ),
        None => (RenderConfig::default(), "(defaults)".to_owned()),
    };
    let settings = resolve_settings(a, &config)?;
    let r = &config.render;
    let mut channels = if config.channels.is_empty() {
        vec![Channel::window(
            "main", r.width, r.height, r.fov_deg, r.tau_px,
        )]
    } else {
        config.channels.clone()
    };
    if !a.channels.is_empty() {
        let names: Vec<&str> = channels.iter().map(|c| c.name.as_str()).collect();
        for n in &a.channels {
            if !names.contains(&n.as_str()) {
                return Err(bad_input(format!(
                    "--channel {n}: no such channel in {source}; channels: {}",
                    names.join(", ")
                )));
            }
        }
        channels.retain(|c| a.channels.contains(&c.name));
    }
    if a.windowed {
        let size = a
            .window_size
            .as_deref()
            .map(parse_size_arg)
            .transpose()
            .map_err(|e| bad_input(format!("--window-size: {e}")))?;
        let mut x = 0i32;
        for c in &mut channels {
            let (w, h) = size.or(c.nominal_size()).unwrap_or(WINDOWED_DEFAULT);
            if c.is_fullscreen() || size.is_some() {
                c.display = ChannelDisplay::Window {
                    x: Some(x),
                    y: Some(0),
                    width: w,
                    height: h,
                };
                c.monitor = None;
                // The window's size is the render size: what a desktop trial wants to see.
                if size.is_some() {
                    c.resolution = None;
                }
            }
            x += w as i32 + 8;
        }
    }
    Ok(Plan {
        config,
        source,
        channels,
        settings,
    })
}

/// `aerie run`: opens the display, runs, exits.
pub fn run(a: RunArgs) -> Result<(), Failure> {
    // Arguments and config first: nothing opens when they are bad.
    plan(&a)?;
    if a.headless {
        return crate::app::headless::run(&a).map(|_| ());
    }
    let mut event_loop = new_event_loop(false).map_err(runtime)?;
    run_on(&mut event_loop, &a).map(|_| ())
}

/// [`run`] on an existing event loop (winit allows one per process; tests run several
/// sessions on theirs). Returns the JSON summary.
pub fn run_on(event_loop: &mut EventLoop<()>, a: &RunArgs) -> Result<serde_json::Value, Failure> {
    let plan = plan(a)?;
    let cfg = &plan.config.render;
    let (ds, bake) = prepare_terrain(&a.dem, cfg.tile_size)?;
    let extensions = required_instance_extensions(&*event_loop).map_err(runtime)?;
    let (width, height) = plan.channels[0]
        .nominal_size()
        .unwrap_or((cfg.width, cfg.height));
    let defaults = RendererDesc::default();
    let desc = RendererDesc {
        validation: a.validate || cfg.validation || cfg!(debug_assertions),
        instance_extensions: extensions,
        device: DeviceDesc {
            name_filter: a.gpu.clone().or_else(|| cfg.gpu.clone()),
            swapchain: true,
        },
        width,
        height,
        staging_budget: cfg.staging_budget_bytes(),
        tile_size: cfg.tile_size,
        select: SelectParams {
            tau_px: cfg.tau_px,
            ..defaults.select
        },
        ..defaults
    };
    let period_s = a
        .seconds
        .or(a.frames.map(|n| n as f64 / 60.0))
        .unwrap_or(60.0)
        .max(1.0);
    let pass = StraightPass::over(&ds, a.heading, a.pitch, a.speed, a.agl, period_s);
    let input = open_input(&plan.settings, &ds)?;
    let geo = GeoMapping::of_dataset(&ds).ok();
    // Predicted display: one frame after the frame starts (FIFO, frames in flight).
    let lead_s = 1.0 / 60.0;
    let mut source = RunPoses::new(
        input,
        StraightPassSource { pass, period_s },
        lead_s,
        open_stats(a, geo)?,
    );
    let mut renderer = TerrainRenderer::new(&desc).map_err(runtime)?;
    let start = source.default_view().position;
    renderer.load_terrain(ds, bake, start).map_err(runtime)?;
    let opts = RunOptions {
        max_frames: a.frames,
        max_seconds: a.seconds,
        actions: Vec::new(),
        overlay: a.overlay,
    };
    let result = run_channels(
        event_loop,
        &mut renderer,
        &plan.channels,
        &mut source,
        &opts,
    );
    let device = renderer.device_name().to_string();
    let counters = renderer.validation_counters();
    renderer.destroy();
    let finished = source.finish();
    if let Some(f) = source.fail.take() {
        return Err(f);
    }
    finished?;
    let report = result.map_err(|e| match e {
        WindowError::Channel { channel, key, .. } => {
            // Name the file, the line and column of the key, the key and the reason.
            let at = a
                .config
                .as_ref()
                .and_then(|p| std::fs::read_to_string(p).ok())
                .and_then(|text| {
                    aerie_config::key_location(&text, &format!("channel[{channel}].{key}")).or_else(
                        || aerie_config::key_location(&text, &format!("channel[{channel}]")),
                    )
                })
                .map(|l| format!(":{l}"))
                .unwrap_or_default();
            bad_input(format!("{}{at}: {e}", plan.source))
        }
        e => runtime(e),
    })?;
    let mut summary = summary_json(&report, &plan, a, &device, &desc, &counters);
    summary["input"] = source.summary_json();
    summary["stats"] = a.stats.as_ref().map(|p| p.display().to_string()).into();
    print_summary(&report, &device, &counters);
    if let Some(line) = source.summary_line() {
        println!("{line}");
    }
    if let Some(path) = &a.json {
        write_text(path, &format!("{summary:#}\n")).map_err(runtime)?;
    }
    counters.verdict().map_err(runtime)?;
    Ok(summary)
}

fn summary_json(
    report: &RunReport,
    plan: &Plan,
    a: &RunArgs,
    device: &str,
    desc: &RendererDesc,
    counters: &crate::vk::ValidationCounters,
) -> serde_json::Value {
    let mut ms = report.frame_ms.clone();
    ms.sort_by(f64::total_cmp);
    serde_json::json!({
        "device": device,
        "config": plan.source,
        "dem": a.dem.display().to_string(),
        "frames": report.frames,
        "seconds": report.seconds,
        "exit": report.exit,
        "idle_waits": report.idle_waits,
        "frame_ms": {
            "median": percentile(&ms, 0.5),
            "p99": percentile(&ms, 0.99),
            "max": percentile(&ms, 1.0),
        },
        "channels": report.channels,
        "validation": {
            "enabled": desc.validation,
            "errors": counters.errors(),
            "warnings": counters.warnings(),
        },
    })
}

fn print_summary(report: &RunReport, device: &str, counters: &crate::vk::ValidationCounters) {
    let mut ms = report.frame_ms.clone();
    ms.sort_by(f64::total_cmp);
    let channels: Vec<String> = report
        .channels
        .iter()
        .map(|c| {
            format!(
                "{} {}x{} {} ({} presented, {} skipped, {} swapchain builds)",
                c.name,
                c.render_size[0],
                c.render_size[1],
                c.present_mode,
                c.presented,
                c.skipped,
                c.swapchain_builds
            )
        })
        .collect();
    println!(
        "{} frames in {:.1} s on {device} (exit: {:?}): frame median {:.1} ms, p99 {:.1} ms, max {:.1} ms; channels: {}; validation: {} errors, {} warnings",
        report.frames,
        report.seconds,
        report.exit,
        percentile(&ms, 0.5),
        percentile(&ms, 0.99),
        percentile(&ms, 1.0),
        channels.join("; "),
        counters.errors(),
        counters.warnings()
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use aerie_sim_bridge::codec::native;
    use aerie_sim_bridge::{Pose, PosePosition};
    use aerie_terrain::dataset::Dataset;
    use aerie_terrain::Heightfield;
    use glam::DVec3;
    use std::time::Duration;

    fn flat() -> Dataset {
        let n = 65;
        Dataset::from_heightfield(
            Heightfield {
                width: n,
                height: n,
                spacing_x: 30.0,
                spacing_y: 30.0,
                heights: vec![500.0; n * n],
                geo: None,
                voids_filled: 0,
                spacing_note: String::new(),
            },
            "flat".into(),
        )
    }

    fn pose(seq: u64, position: PosePosition) -> Pose {
        Pose {
            position,
            attitude_deg: [45.0, -3.0, 7.0],
            sim_time_s: seq as f64 / 60.0,
            frame: seq,
            velocity_enu: Some([100.0, 0.0, 0.0]),
            angular_rates_deg_s: None,
        }
    }

    #[derive(clap::Parser)]
    struct Cli {
        #[command(flatten)]
        args: RunArgs,
    }

    fn plan_of(extra: &[&str]) -> Result<Plan, Failure> {
        use clap::Parser;
        let argv = ["run", "--dem", "x.hgt"].iter().chain(extra);
        plan(&Cli::try_parse_from(argv).expect("parses").args)
    }

    #[test]
    fn bad_input_flag_combinations_stop_before_anything_opens() {
        for (args, says) in [
            (
                &["--sync-frames", "1"][..],
                "--sync-frames: needs a pose input",
            ),
            (
                &["--headless"],
                "--headless: give --frames N or --seconds S",
            ),
            (&["--size", "160x90"], "--size: only with --headless"),
            (&["--as-fast-as-possible"], "only with --headless"),
            (&["--headless", "--frames", "2", "--size", "0x9"], "--size:"),
            (
                &["--headless", "--frames", "2", "--windowed"],
                "exclude each other",
            ),
            (&["--max-extrapolation-ms=-1"], "--max-extrapolation-ms: -1"),
            (&["--fps", "0"], "--fps: 0"),
            (
                &["--protocol", "shm", "--listen", "127.0.0.1:9"],
                "UDP only",
            ),
            (
                &["--protocol", "cigi", "--shm-name", "x"],
                "--shm-name: only with",
            ),
            (
                &["--multicast-if", "127.0.0.1", "--protocol", "native"],
                "only with --multicast",
            ),
            (
                &["--stats", "/nonexistent-dir/s.csv"],
                "--stats /nonexistent-dir/s.csv",
            ),
        ] {
            let Err(f) = plan_of(args) else {
                panic!("{args:?} accepted")
            };
            assert_eq!(f.code, 2, "{args:?}: {}", f.message);
            assert!(f.message.contains(says), "{args:?}: {}", f.message);
        }
        // Input flags: defaults and what turns the input on.
        let spec = |extra: &[&str]| {
            use clap::Parser;
            let argv = ["run", "--dem", "x"].iter().chain(extra);
            let args = Cli::try_parse_from(argv).unwrap().args;
            resolve_settings(&args, &RenderConfig::default())
                .unwrap()
                .input
        };
        assert!(spec(&[]).is_none());
        let s = spec(&["--protocol", "cigi"]).unwrap();
        assert_eq!(s.listen, "127.0.0.1:47800".parse().unwrap());
        assert_eq!(s.cap_s, 0.1);
        let s = spec(&["--multicast", "239.1.2.3", "--sync-frames", "2"]).unwrap();
        assert_eq!(s.listen, "0.0.0.0:47800".parse().unwrap());
        assert_eq!(s.protocol, InputProtocol::Udp(ProtocolChoice::Auto));
        assert_eq!(s.sync_frames, Some(2));
        let s = spec(&["--shm-name", "sim"]).unwrap();
        assert_eq!(
            (s.protocol, s.shm_name.as_str()),
            (InputProtocol::Shm, "sim")
        );
        assert!(plan_of(&[
            "--headless",
            "--frames",
            "3",
            "--size",
            "160x90",
            "--protocol",
            "shm"
        ])
        .is_ok());
    }

    fn settings_of(config: &str, extra: &[&str]) -> Result<RunSettings, Failure> {
        use clap::Parser;
        let cfg = aerie_config::parse(config, "ig.toml").unwrap();
        let argv = ["run", "--dem", "x"].iter().chain(extra);
        resolve_settings(&Cli::try_parse_from(argv).unwrap().args, &cfg)
    }

    /// `[input]` of the config is used; each flag given overrides its key; a flag choosing the
    /// other transport drops the config's keys of the first.
    #[test]
    fn config_input_is_used_and_flags_override_it() {
        let cfg = "[render]\nfps = 30\n[input]\nprotocol = \"cigi\"\nlisten = \"127.0.0.1:47999\"\nallow = [\"127.0.0.2\"]\nmax_extrapolation_ms = 40\nsync_frames = 2\nwait_pose_s = 3\n";
        let s = settings_of(cfg, &[]).unwrap();
        let i = s.input.as_ref().expect("the config turns the input on");
        assert_eq!(
            i.protocol,
            InputProtocol::Udp(ProtocolChoice::Only(
                aerie_sim_bridge::codec::Protocol::Cigi
            ))
        );
        assert_eq!(i.listen, "127.0.0.1:47999".parse().unwrap());
        assert_eq!(i.allow, ["127.0.0.2".parse::<IpAddr>().unwrap()]);
        assert_eq!((i.cap_s, i.sync_frames), (0.04, Some(2)));
        assert_eq!(
            (s.max_extrapolation_ms, s.wait_pose_s, s.fps),
            (40.0, 3.0, 30.0)
        );

        let s = settings_of(
            cfg,
            &[
                "--protocol",
                "native",
                "--listen",
                "127.0.0.1:5000",
                "--allow",
                "127.0.0.3",
                "--max-extrapolation-ms",
                "0",
                "--sync-frames",
                "0",
                "--wait-pose-s",
                "1",
                "--fps",
                "90",
            ],
        )
        .unwrap();
        let i = s.input.as_ref().unwrap();
        assert_eq!(
            i.protocol,
            InputProtocol::Udp(ProtocolChoice::Only(
                aerie_sim_bridge::codec::Protocol::Aerie
            ))
        );
        assert_eq!(i.listen, "127.0.0.1:5000".parse().unwrap());
        assert_eq!(i.allow, ["127.0.0.3".parse::<IpAddr>().unwrap()]);
        assert_eq!((i.cap_s, i.sync_frames), (0.0, Some(0)));
        assert_eq!(
            (s.max_extrapolation_ms, s.wait_pose_s, s.fps),
            (0.0, 1.0, 90.0)
        );

        // --shm-name switches to shared memory: the config's UDP keys no longer apply.
        let i = settings_of(cfg, &["--shm-name", "sim"])
            .unwrap()
            .input
            .unwrap();
        assert_eq!(
            (i.protocol, i.shm_name.as_str()),
            (InputProtocol::Shm, "sim")
        );
        // A config on shared memory and --listen on the command line: UDP.
        let i = settings_of(
            "[input]\nshm_name = \"sim\"\n",
            &["--listen", "127.0.0.1:7"],
        )
        .unwrap()
        .input
        .unwrap();
        assert_eq!(i.protocol, InputProtocol::Udp(ProtocolChoice::Auto));
        assert_eq!(i.listen, "127.0.0.1:7".parse().unwrap());
        // Multicast from the config: bound on all interfaces; interface from the flag.
        let i = settings_of(
            "[input]\nmulticast = \"239.1.2.3\"\n",
            &["--multicast-if", "127.0.0.1"],
        )
        .unwrap()
        .input
        .unwrap();
        assert_eq!(i.listen, "0.0.0.0:47800".parse().unwrap());
        assert_eq!(i.multicast_interface, Ipv4Addr::LOCALHOST);
        // Tuning keys alone do not turn the input on; defaults without anything.
        let s = settings_of("[input]\nmax_extrapolation_ms = 5\n", &[]).unwrap();
        assert!(s.input.is_none());
        assert_eq!(
            (s.max_extrapolation_ms, s.wait_pose_s, s.fps),
            (5.0, 10.0, 60.0)
        );
        // Sync frames beyond the history, from a flag: refused naming the flag.
        let f =
            settings_of("[input]\nprotocol = \"cigi\"\n", &["--sync-frames", "64"]).unwrap_err();
        assert_eq!(f.code, 2);
        assert!(f.message.starts_with("--sync-frames: 64"), "{}", f.message);
    }

    /// Window path: a frame's `--stats` row waits for the frame's statistics (the triangles of
    /// every channel drawn, summed); a frame never reported drawn keeps the column empty.
    #[test]
    fn window_frames_get_their_triangles_in_the_stats_rows() {
        let ds = flat();
        let dir = tempfile::tempdir().unwrap();
        let csv = dir.path().join("s.csv");
        let pass = StraightPass::over(&ds, 70.0, -10.0, 150.0, 600.0, 10.0);
        let mut src = RunPoses::new(
            None,
            StraightPassSource {
                pass,
                period_s: 10.0,
            },
            0.0,
            Some(StatsWriter::create(&csv, None).unwrap()),
        );
        let stats = |triangles| FrameStats {
            triangles,
            ..FrameStats::default()
        };
        let _ = PoseSource::pose(&mut src, 0, 0.0);
        src.frame_drawn(0, &[stats(1200), stats(34)]);
        let _ = PoseSource::pose(&mut src, 1, 0.1);
        // Frame 1 is never reported drawn (e.g. every window minimised).
        let _ = PoseSource::pose(&mut src, 2, 0.2);
        src.frame_drawn(2, &[stats(7)]);
        src.finish().unwrap();
        let text = std::fs::read_to_string(&csv).unwrap();
        let col = crate::tools::stats_csv::HEADER
            .split(',')
            .position(|h| h == "triangles")
            .unwrap();
        let tri: Vec<String> = text
            .lines()
            .skip(1)
            .map(|l| l.split(',').nth(col).unwrap().to_string())
            .collect();
        assert_eq!(tri, ["1234", "", "7"]);
    }

    /// The window path's pose source: default view and a "waiting" row until the first pose,
    /// then the pose as sent (cap 0), and a bad-input failure for a geodetic pose on a dataset
    /// without geo-reference (the window loop ends the session on it).
    #[test]
    fn stream_source_waits_then_follows_then_fails_on_unplaceable_poses() {
        let ds = flat();
        let spec = InputSpec {
            protocol: InputProtocol::Udp(ProtocolChoice::Auto),
            listen: "127.0.0.1:0".parse().unwrap(),
            multicast: None,
            multicast_interface: Ipv4Addr::UNSPECIFIED,
            allow: Vec::new(),
            shm_name: String::new(),
            cap_s: 0.0,
            sync_frames: None,
        };
        let input = SimInput::open(&spec, GeoMapping::of_dataset(&ds)).unwrap();
        let to = input.local_addr().unwrap();
        let dir = tempfile::tempdir().unwrap();
        let csv = dir.path().join("s.csv");
        let pass = StraightPass::over(&ds, 70.0, -10.0, 150.0, 600.0, 10.0);
        let mut src = RunPoses::new(
            Some(input),
            StraightPassSource {
                pass,
                period_s: 10.0,
            },
            0.0,
            Some(StatsWriter::create(&csv, None).unwrap()),
        );
        let held = PoseSource::pose(&mut src, 0, 0.0);
        assert_eq!(held, src.default_view());
        assert_eq!((src.waiting_frames, src.input_frames), (1, 0));
        assert!(src.failure().is_none());

        let socket = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
        let local = PosePosition::LocalEnu {
            x: 1000.0,
            y: 900.0,
            z: 1500.0,
        };
        socket
            .send_to(&native::encode(&pose(1, local), 1), to)
            .unwrap();
        let mut frame = 1;
        let got = loop {
            let p = PoseSource::pose(&mut src, frame, 0.0);
            frame += 1;
            if src.input_frames > 0 {
                break p;
            }
            assert!(frame < 2000, "no pose arrived");
            std::thread::sleep(Duration::from_millis(1));
        };
        assert_eq!(got.position, DVec3::new(1000.0, 900.0, 1500.0));
        assert!((got.attitude.roll.to_degrees() - 7.0).abs() < 1e-12);
        assert!(src.pose_age_ms().is_some());

        let geodetic = PosePosition::Geodetic {
            lat_deg: 47.0,
            lon_deg: 11.0,
            alt_m: 1500.0,
        };
        socket
            .send_to(&native::encode(&pose(2, geodetic), 2), to)
            .unwrap();
        let why = loop {
            let _ = PoseSource::pose(&mut src, frame, 0.0);
            frame += 1;
            if let Some(w) = src.failure() {
                break w;
            }
            assert!(frame < 4000, "the geodetic pose never failed");
            std::thread::sleep(Duration::from_millis(1));
        };
        assert!(
            why.contains("geodetic") && why.contains("flat: no geo-reference"),
            "{why}"
        );
        assert_eq!(src.fail.as_ref().unwrap().code, 2);
        src.finish().unwrap();
        let text = std::fs::read_to_string(&csv).unwrap();
        let rows: Vec<&str> = text.lines().skip(1).collect();
        assert!(rows[0].contains(",waiting,"), "{}", rows[0]);
        assert!(rows.iter().any(|r| r.contains(",1000,900,1500,")), "{text}");
    }
}
