//! What `aerie run` decides before anything opens: the arguments checked, the config read, the
//! settings resolved and the channels chosen. Bad input stops here (exit 2).

use aerie_config::{Channel, ChannelDisplay, RenderConfig};
use aerie_terrain::select::SelectParams;

use crate::app::commands::run::args::RunArgs;
use crate::app::commands::run::settings::{resolve_settings, RunSettings};
use crate::app::failure::{bad_input, Failure};
use crate::app::out_path::prepare_out_file;
use crate::render::frame::RendererDesc;
use crate::vk::DeviceDesc;
use aerie_config::parse_size;

/// Window size of a fullscreen channel shown with `--windowed` when it has no resolution.
const WINDOWED_DEFAULT: (u32, u32) = (960, 540);

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
        prepare_out_file("--json", j)?;
    }
    if let Some(p) = &a.stats {
        prepare_out_file("--stats", p)?;
    }
    if let Some(ms) = a.input.max_extrapolation_ms {
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
        parse_size(s).map_err(|e| bad_input(format!("--size: {e}")))?;
    }
    // Flag combinations that contradict each other (flags over config keys: resolve_settings).
    a.input.check(&[])?;
    Ok(())
}

/// Checks the arguments, reads the config, resolves the settings and picks the channels
/// (laid out side by side with `--windowed`).
/// The draped rasters of a run: the flags, and the config's `[landcover]` table (its raster
/// relative to the config's folder) where the flags leave it unset.
pub(crate) fn drape(
    a: &RunArgs,
    plan: &Plan,
) -> Result<Option<crate::render::drape_textures::SharedDrapeInput>, Failure> {
    let dir = a
        .config
        .as_deref()
        .and_then(std::path::Path::parent)
        .map(std::path::Path::to_path_buf)
        .unwrap_or_default();
    let landcover = plan.config.landcover.as_ref().map(|lc| (lc, dir.as_path()));
    crate::app::renderer_setup::drape_input_with(&a.drape, landcover)
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
            .map(parse_size)
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

/// The renderer `run` draws with, headless or windowed: validation, device, staging budget, tile
/// size and τ from the flags over the config; `size` is the first channel's. `presentation`:
/// the window system's instance extensions when drawing into windows (swapchains), `None`
/// headless.
pub(crate) fn renderer_desc(
    a: &RunArgs,
    plan: &Plan,
    size: (u32, u32),
    presentation: Option<Vec<std::ffi::CString>>,
) -> RendererDesc {
    let cfg = &plan.config.render;
    let defaults = RendererDesc::default();
    RendererDesc {
        validation: a.validate || cfg.validation || cfg!(debug_assertions),
        device: DeviceDesc {
            name_filter: a.gpu.clone().or_else(|| cfg.gpu.clone()),
            swapchain: presentation.is_some(),
        },
        instance_extensions: presentation.unwrap_or_default(),
        width: size.0,
        height: size.1,
        staging_budget: cfg.staging_budget_bytes(),
        tile_size: cfg.tile_size,
        // The host may turn the view anywhere after a load (`RendererDesc::warm_start`).
        warm_start: true,
        select: SelectParams {
            tau_px: cfg.tau_px,
            ..defaults.select
        },
        ..defaults
    }
}
