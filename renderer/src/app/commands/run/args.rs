//! The arguments of `aerie run`: what to show (config, channels, DEM), for how long, how
//! (window, fullscreen, headless), the built-in pass, and the pose input
//! ([`InputArgs`], shared with `aerie listen`).

use std::path::PathBuf;

use clap::Args;

use crate::app::commands::input_args::InputArgs;

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
    /// A tile store (`<name>.aerie`) is streamed.
    #[arg(long)]
    pub dem: PathBuf,
    #[command(flatten)]
    pub store: crate::app::args::StoreArgs,
    #[command(flatten)]
    pub drape: crate::app::args::DrapeArgs,
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
    // Last: the flattened input section's heading applies to the fields after it.
    #[command(flatten)]
    pub input: InputArgs,
    /// Frame-locked: draw host frame newest − K with its own pose (never extrapolated), so one
    /// process per channel on one stream draws the same host frame. K ≥ 1 absorbs network
    /// jitter between machines at the price of K host frames of latency.
    #[arg(long, value_name = "K", help_heading = "Pose input")]
    pub sync_frames: Option<u32>,
    /// The datum of the host's geodetic altitudes: msl (above mean sea level, as CIGI sends
    /// them and the terrain is) or ellipsoidal (above WGS84, GNSS heights: the EGM96 geoid
    /// undulation is taken off). Default: input.host_heights, else msl.
    #[arg(long, value_name = "DATUM", help_heading = "Pose input")]
    pub host_heights: Option<crate::sim::pose_input::HostHeights>,
    /// Headless: how long to wait for the first pose before giving up (exit 1), seconds.
    /// Default: input.wait_pose_s, else 10.
    #[arg(
        long,
        value_name = "S",
        allow_hyphen_values = true,
        help_heading = "Pose input"
    )]
    pub wait_pose_s: Option<f64>,
}
