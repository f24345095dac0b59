//! `aerie run`: the image generator on screen. Opens one window (or fullscreen display) per
//! channel of a config (`config/presets/*.toml`), all in one process on one device, or only the
//! channels named with `--channel` (one process per channel, e.g. one machine per projector,
//! sharing the config). Flies the built-in straight pass until Esc, a closed window, `--frames`
//! or `--seconds`; prints a summary (frames, frame times, per-channel presentation, validation)
//! and writes it as JSON with `--json`.
//!
//! The aircraft pose comes from a [`PoseSource`]; the built-in pass is [`StraightPassSource`].
//! A simulator stream plugs in there without touching the presentation code.

use std::path::PathBuf;

use aerie_config::{Channel, ChannelDisplay, RenderConfig};
use clap::Args;
use winit::event_loop::EventLoop;

use super::check_out_folder;
use crate::camera::parse_size_arg;
use crate::channel::AircraftPose;
use crate::cli::{bad_input, prepare_terrain, runtime, Failure};
use crate::flight::StraightPass;
use crate::frame::{RendererDesc, TerrainRenderer};
use crate::output::write_text;
use crate::terrain::select::SelectParams;
use crate::vk::DeviceDesc;
use crate::window::{
    new_event_loop, required_instance_extensions, run_channels, PoseSource, RunOptions, RunReport,
    WindowError,
};

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

/// Everything decided from the arguments and the config before anything opens.
struct Plan {
    config: RenderConfig,
    source: String,
    channels: Vec<Channel>,
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
    Ok(())
}

fn plan(a: &RunArgs) -> Result<Plan, Failure> {
    check_args(a)?;
    let (config, source) = match &a.config {
        Some(p) => (
            aerie_config::load(p).map_err(bad_input)?,
            p.display().to_string(),
        ),
        None => (RenderConfig::default(), "(defaults)".to_owned()),
    };
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
    })
}

/// `aerie run`: opens the display, runs, exits.
pub fn run(a: RunArgs) -> Result<(), Failure> {
    // Arguments and config first: nothing opens when they are bad.
    plan(&a)?;
    let mut event_loop = new_event_loop(false).map_err(runtime)?;
    run_on(&mut event_loop, &a).map(|_| ())
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
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
    let mut source = StraightPassSource { pass, period_s };
    let mut renderer = TerrainRenderer::new(&desc).map_err(runtime)?;
    let start = source.pose(0, 0.0).position;
    renderer.load_terrain(ds, bake, start).map_err(runtime)?;
    let opts = RunOptions {
        max_frames: a.frames,
        max_seconds: a.seconds,
        actions: Vec::new(),
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
    let summary = summary_json(&report, &plan, a, &device, &desc, &counters);
    print_summary(&report, &device, &counters);
    if let Some(path) = &a.json {
        write_text(path, &format!("{summary:#}\n")).map_err(runtime)?;
    }
    if counters.errors() + counters.warnings() > 0 {
        return Err(runtime(format!(
            "validation reported {} errors and {} warnings; first: {}",
            counters.errors(),
            counters.warnings(),
            counters.messages().first().cloned().unwrap_or_default()
        )));
    }
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
