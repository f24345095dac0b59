//! `aerie run --headless`: the image generator without a window. Every channel of the config (or
//! one channel of `--size`) is rendered offscreen each frame from one aircraft pose, with one
//! tile selection for all of them (as the window path does, via
//! [`TerrainRenderer::set_channels`]); frames are paced at `--fps` or rendered back to back
//! (`--as-fast-as-possible`). With a pose input it first waits for the first pose (at most
//! `--wait-pose-s`; then exit 1 naming the input and its counters) and fills the clipmap around
//! it. A progress line on stderr, a summary at the end (stdout, `--json`), `--stats` rows.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use aerie_config::Channel;

use crate::app::commands::run::args::RunArgs;
use crate::app::commands::run::ig::{ig_driver, IgDriver};
use crate::app::commands::run::plan::{plan, renderer_desc, Plan};
use crate::app::commands::run::poses::{open_input, open_stats, RunPoses, StraightPassSource};
use crate::app::failure::{bad_input, renderer_failure, runtime, Failure};
use crate::app::prepare::{prepare_source, Terrain};
use crate::app::window::pose_source::PoseSource;
use crate::render::frame::TerrainRenderer;
use crate::sim::channel::AircraftPose;
use crate::sim::flight::StraightPass;
use crate::sim::pose_input::{counters_text, GeoMapping, SimInput};
use crate::tools::output::write_text;
use crate::tools::overlay::{OverlayInfo, OverlayState};
use crate::tools::percentile::percentile;
use crate::tools::stats_csv::{FrameRow, TerrainColumns};
use aerie_config::parse_size;
use aerie_terrain::select::SelectParams;

/// How often the input is polled while a paced loop waits for the next frame: often enough that
/// frame-locked mode sees (nearly) every host frame of a 60-120 Hz host.
const POLL: Duration = Duration::from_millis(1);

/// The render size of each channel: `--size` for all, else the channel's resolution (or
/// window size), else the `[render]` size.
pub fn channel_sizes(
    channels: &[Channel],
    size: Option<(u32, u32)>,
    default: (u32, u32),
) -> Vec<(u32, u32)> {
    channels
        .iter()
        .map(|c| size.or(c.nominal_size()).unwrap_or(default))
        .collect()
}

/// Waits for the first pose: `Ok` once one arrived, bad input (exit 2) if it cannot be placed,
/// runtime (exit 1) after `wait_s` naming the input and its counters.
fn wait_first_pose(
    input: &mut SimInput,
    wait_s: f64,
    mut ig: Option<&mut IgDriver>,
    fps: f64,
) -> Result<AircraftPose, Failure> {
    let start = Instant::now();
    let period = Duration::from_secs_f64(1.0 / fps);
    let mut next_tick = start;
    eprintln!(
        "waiting up to {wait_s} s for the first pose on {}",
        input.what
    );
    loop {
        if let Some((pose, _)) = input.sample_now(0.0).map_err(bad_input)? {
            return Ok(pose);
        }
        // A synchronous CIGI host waits for Start of Frame before it sends again: the IG
        // keeps its frame rate while there is nothing to draw yet.
        if let Some(ig) = ig.as_deref_mut() {
            let now = Instant::now();
            if now >= next_tick {
                ig.idle_frame();
                // After a stall, one Start of Frame, not a burst catching up.
                next_tick = (next_tick + period).max(now);
            }
        }
        if start.elapsed().as_secs_f64() >= wait_s {
            return Err(runtime(format!(
                "no pose within {wait_s} s on {}: {} (check the simulator's destination address and protocol)",
                input.what,
                counters_text(&input.stats())
            )));
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Runs `aerie run --headless`; returns the JSON summary.
pub fn run(a: &RunArgs) -> Result<serde_json::Value, Failure> {
    let plan = plan(a)?;
    let cfg = &plan.config.render;
    let size = a
        .size
        .as_deref()
        .map(parse_size)
        .transpose()
        .map_err(|e| bad_input(format!("--size: {e}")))?;
    let sizes = channel_sizes(&plan.channels, size, (cfg.width, cfg.height));
    let mut desc = renderer_desc(a, &plan, sizes[0], None);
    desc.drape = super::plan::drape(a, &plan)?;
    desc.drape_budget_bytes = crate::app::renderer_setup::drape_budget(&a.drape)?;
    let terrain = prepare_source(&a.dem, &desc, &a.store)?;
    let period_s = a
        .seconds
        .or(a.frames.map(|n| n as f64 / plan.settings.fps))
        .unwrap_or(60.0)
        .max(1.0);
    let pass = straight_pass(&terrain, a, period_s);
    // The port is bound before the (slow) device creation, so a sender may start right away.
    let input = open_input(&plan.settings, terrain.grid())?;
    let geo = GeoMapping::of_source(terrain.grid()).ok();
    let ig = ig_driver(a, &plan, input.as_ref(), &terrain, &desc)?;
    let mut poses = RunPoses::new(
        input,
        StraightPassSource { pass, period_s },
        0.0,
        open_stats(a, geo)?,
    );
    poses.ig = ig;
    let mut renderer = TerrainRenderer::new(&desc).map_err(runtime)?;
    let result = (|| {
        let start = match &mut poses.input {
            Some(input) => wait_first_pose(
                input,
                plan.settings.wait_pose_s,
                poses.ig.as_mut(),
                plan.settings.fps,
            )?,
            None => poses.default_view(),
        };
        renderer
            .load_source(terrain.source.clone(), terrain.bake.clone(), start.position)
            .map_err(renderer_failure)?;
        frame_loop(a, &plan, &sizes, &mut renderer, &mut poses)
    })();
    let device = renderer.device_name().to_string();
    let drape = crate::app::renderer_setup::drape_json(&renderer);
    let counters = renderer.validation_counters();
    renderer.destroy();
    let finished = poses.finish();
    let report = result?;
    finished?;

    let mut ms = report.frame_ms.clone();
    ms.sort_by(f64::total_cmp);
    let mut tri = report.triangles.clone();
    tri.sort_by(f64::total_cmp);
    let channels: Vec<serde_json::Value> = plan
        .channels
        .iter()
        .zip(&sizes)
        .map(|(c, s)| serde_json::json!({"name": c.name, "render_size": [s.0, s.1]}))
        .collect();
    let summary = serde_json::json!({
        "device": device,
        "config": plan.source,
        "dem": a.dem.display().to_string(),
        "headless": true,
        "frames": report.frames,
        "seconds": report.seconds,
        "fps": if report.seconds > 0.0 { report.frames as f64 / report.seconds } else { 0.0 },
        "paced_fps": (!a.as_fast_as_possible).then_some(plan.settings.fps),
        "frame_ms": {
            "median": percentile(&ms, 0.5),
            "p99": percentile(&ms, 0.99),
            "max": percentile(&ms, 1.0),
        },
        "triangles": {"median": percentile(&tri, 0.5), "max": percentile(&tri, 1.0)},
        "overlay_frames": report.overlay_frames,
        "channels": channels,
        "input": poses.summary_json(),
        "ig": poses.ig.as_ref().map(IgDriver::summary_json),
        "stats": a.stats.as_ref().map(|p| p.display().to_string()),
        "drape": drape,
        "validation": {
            "enabled": desc.validation,
            "errors": counters.errors(),
            "warnings": counters.warnings(),
        },
    });
    println!(
        "{} frames of {} channel(s) in {:.1} s headless on {device}: frame median {:.1} ms, p99 {:.1} ms, max {:.1} ms; triangles median {:.0}; validation: {} errors, {} warnings",
        report.frames,
        plan.channels.len(),
        report.seconds,
        percentile(&ms, 0.5),
        percentile(&ms, 0.99),
        percentile(&ms, 1.0),
        percentile(&tri, 0.5),
        counters.errors(),
        counters.warnings()
    );
    if let Some(line) = poses.summary_line() {
        println!("{line}");
    }
    if let Some(ig) = &poses.ig {
        println!("{}", ig.summary_line());
    }
    if let Some(w) = &poses.stats {
        println!("stats: {} rows in {}", w.rows(), w.path().display());
    }
    if let Some(path) = &a.json {
        write_text(path, &format!("{summary:#}\n")).map_err(runtime)?;
    }
    counters.verdict().map_err(runtime)?;
    Ok(summary)
}

struct LoopReport {
    frames: u64,
    seconds: f64,
    frame_ms: Vec<f64>,
    triangles: Vec<f64>,
    /// Channel frames drawn with the statistics overlay.
    overlay_frames: u64,
}

fn frame_loop(
    a: &RunArgs,
    plan: &Plan,
    sizes: &[(u32, u32)],
    renderer: &mut TerrainRenderer,
    poses: &mut RunPoses,
) -> Result<LoopReport, Failure> {
    let tty = std::io::stderr().is_terminal();
    let fps = plan.settings.fps;
    let channels = &plan.channels;
    let period = Duration::from_secs_f64(1.0 / fps);
    let t0 = Instant::now();
    let mut next_at = t0;
    let mut last_line = t0;
    let mut frame_ms = Vec::new();
    let mut triangles = Vec::new();
    let mut frame = 0u64;
    let base = renderer.desc().select;
    // --overlay: the statistics panel drawn into every channel's frame (as `aerie fly` does).
    let mut overlays: Vec<OverlayState> = channels
        .iter()
        .map(|_| OverlayState::new(a.overlay))
        .collect();
    let mut overlay_frames = 0u64;
    loop {
        if a.frames.is_some_and(|n| frame >= n)
            || a.seconds.is_some_and(|s| t0.elapsed().as_secs_f64() >= s)
        {
            break;
        }
        if !a.as_fast_as_possible {
            // Wait for the frame's slot, polling the input so frame-locked mode sees every
            // host frame; a late frame starts at once and the schedule restarts from it.
            loop {
                if let Some(i) = &mut poses.input {
                    i.poll();
                }
                let now = Instant::now();
                if now >= next_at {
                    break;
                }
                std::thread::sleep(POLL.min(next_at - now));
            }
            next_at = (next_at + period).max(Instant::now());
        }
        let started = Instant::now();
        let t_s = if a.as_fast_as_possible {
            frame as f64 / fps
        } else {
            (started - t0).as_secs_f64()
        };
        poses.begin_frame(frame, renderer).map_err(runtime)?;
        let (pose, origin) = poses.next(frame, t_s)?;
        // The host's CIGI views replace the channels' view, eye and frustum before selection.
        let views: Vec<_> = poses
            .live_channels(channels)
            .iter()
            .zip(sizes)
            .map(|(live, &(w, h))| {
                let cam = live.camera(&pose, w as f64 / h as f64);
                (cam, (w, h), live.channel.tau_px)
            })
            .collect();
        // One selection for all channels, as in the window path.
        renderer.set_channels(if views.len() > 1 {
            views.clone()
        } else {
            Vec::new()
        });
        let mut tri = 0u64;
        let mut terrain = TerrainColumns::default();
        for (k, (camera, (w, h), tau)) in views.iter().enumerate() {
            renderer.resize(*w, *h).map_err(runtime)?;
            if renderer.desc().select.tau_px != *tau {
                renderer.set_select_params(SelectParams {
                    tau_px: *tau,
                    ..base
                });
            }
            let panel = overlays[k].panel((*w, *h), poses.pose_age_ms());
            overlay_frames += u64::from(panel.is_some());
            renderer.set_overlay(panel);
            let channel_wall = Instant::now();
            let stats = renderer.render(camera).map_err(runtime)?;
            overlays[k].record(
                channel_wall.elapsed().as_secs_f64() * 1e3,
                OverlayInfo::from_stats(&stats, *tau),
            );
            tri += stats.triangles;
            terrain.add(&stats);
        }
        renderer.set_overlay(None);
        let ms = started.elapsed().as_secs_f64() * 1e3;
        frame_ms.push(ms);
        triangles.push(tri as f64);
        poses.record(&FrameRow {
            frame,
            wall_s: t_s,
            pose,
            origin,
            triangles: Some(tri),
            frame_ms: Some(ms),
            terrain: Some(terrain),
        })?;
        frame += 1;
        if last_line.elapsed() >= Duration::from_secs(if tty { 1 } else { 5 }) {
            last_line = Instant::now();
            let line = format!(
                "frame {frame}{}: {:.1} fps, last {:.1} ms, {} triangles{}",
                a.frames.map(|n| format!("/{n}")).unwrap_or_default(),
                frame as f64 / t0.elapsed().as_secs_f64(),
                ms,
                tri,
                poses
                    .input
                    .as_ref()
                    .map(|i| format!("; {}", counters_text(&i.stats())))
                    .unwrap_or_default()
            );
            if tty {
                eprint!("\r{line}\x1b[K");
            } else {
                eprintln!("{line}");
            }
        }
    }
    if tty {
        eprintln!();
    }
    Ok(LoopReport {
        frames: frame,
        seconds: t0.elapsed().as_secs_f64(),
        frame_ms,
        triangles,
        overlay_frames,
    })
}

/// The built-in pass over `terrain` (its highest sample from memory, else from the bake).
pub(crate) fn straight_pass(terrain: &Terrain, a: &RunArgs, period_s: f64) -> StraightPass {
    match &terrain.dataset {
        Some(ds) => StraightPass::over(ds, a.heading, a.pitch, a.speed, a.agl, period_s),
        None => {
            let g = terrain.grid();
            let extent = [
                (g.valid_width - 1) as f64 * g.spacing_x,
                (g.valid_height - 1) as f64 * g.spacing_y,
            ];
            let top = terrain.top_height();
            StraightPass::over_extent(extent, top, a.heading, a.pitch, a.speed, a.agl, period_s)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn size_flag_overrides_every_channel() {
        let chans = vec![
            Channel::window("a", 640, 360, 60.0, 1.0),
            Channel::window("b", 320, 180, 60.0, 1.0),
        ];
        assert_eq!(
            channel_sizes(&chans, None, (1920, 1080)),
            [(640, 360), (320, 180)]
        );
        assert_eq!(
            channel_sizes(&chans, Some((160, 90)), (1920, 1080)),
            [(160, 90), (160, 90)]
        );
    }
}
