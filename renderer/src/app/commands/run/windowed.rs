//! `aerie run` in windows: one window (or fullscreen display) per channel, all drawn by one
//! renderer from one pose per frame ([`run_channels`]), then the summary (stdout, `--json`).

use winit::event_loop::EventLoop;

use crate::app::commands::run::args::RunArgs;
use crate::app::commands::run::headless::straight_pass;
use crate::app::commands::run::ig::{ig_driver, IgDriver};
use crate::app::commands::run::plan::{plan, renderer_desc, Plan};
use crate::app::commands::run::poses::{open_input, open_stats, RunPoses, StraightPassSource};
use crate::app::failure::{bad_input, renderer_failure, runtime, Failure};
use crate::app::prepare::prepare_source;
use crate::app::window::display::required_instance_extensions;
use crate::app::window::report::{RunOptions, RunReport, WindowError};
use crate::app::window::session::run_channels;
use crate::render::frame::{RendererDesc, TerrainRenderer};
use crate::sim::pose_input::GeoMapping;
use crate::tools::output::write_text;
use crate::tools::percentile::percentile;

/// `aerie run` in windows on an existing event loop (winit allows one per process; tests run several
/// sessions on theirs). Returns the JSON summary.
pub fn run_on(event_loop: &mut EventLoop<()>, a: &RunArgs) -> Result<serde_json::Value, Failure> {
    let plan = plan(a)?;
    let cfg = &plan.config.render;
    let extensions = required_instance_extensions(&*event_loop).map_err(runtime)?;
    let (width, height) = plan.channels[0]
        .nominal_size()
        .unwrap_or((cfg.width, cfg.height));
    let mut desc = renderer_desc(a, &plan, (width, height), Some(extensions));
    desc.drape = super::plan::drape(a, &plan)?;
    desc.drape_budget_bytes = crate::app::renderer_setup::drape_budget(&a.drape)?;
    let terrain = prepare_source(&a.dem, &desc, &a.store)?;
    let period_s = a
        .seconds
        .or(a.frames.map(|n| n as f64 / 60.0))
        .unwrap_or(60.0)
        .max(1.0);
    let pass = straight_pass(&terrain, a, period_s);
    let input = open_input(&plan.settings, terrain.grid())?;
    let geo = GeoMapping::of_source(terrain.grid()).ok();
    let ig = ig_driver(a, &plan, input.as_ref(), &terrain, &desc)?;
    // Predicted display: one frame after the frame starts (FIFO, frames in flight).
    let lead_s = 1.0 / 60.0;
    let mut source = RunPoses::new(
        input,
        StraightPassSource { pass, period_s },
        lead_s,
        open_stats(a, geo)?,
    );
    source.ig = ig;
    let mut renderer = TerrainRenderer::new(&desc).map_err(runtime)?;
    let start = source.default_view().position;
    renderer
        .load_source(terrain.source.clone(), terrain.bake.clone(), start)
        .map_err(renderer_failure)?;
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
    summary["ig"] = source.ig.as_ref().map(IgDriver::summary_json).into();
    summary["stats"] = a.stats.as_ref().map(|p| p.display().to_string()).into();
    print_summary(&report, &device, &counters);
    if let Some(line) = source.summary_line() {
        println!("{line}");
    }
    if let Some(ig) = &source.ig {
        println!("{}", ig.summary_line());
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
