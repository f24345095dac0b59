//! The `aerie` command line: argument types, commands, exit codes.
//! Exit 0 on success, 2 on bad input (arguments, DEM files), 1 on runtime failures (Vulkan, I/O).

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::{Args, Parser, Subcommand};
use glam::DVec3;

use crate::app::failure::{bad_input, runtime, Failure};
use crate::app::prepare::prepare_terrain;
use crate::render::frame::{FrameStats, RendererDesc, TerrainRenderer};
use crate::sim::flight::{StraightPass, Waypoints};
use crate::tools::output::{write_png, write_text};
use crate::tools::percentile::percentile;
use crate::vk::DeviceDesc;
use aerie_terrain::camera::{parse_camera_arg, parse_size_arg, Attitude, Camera, Frustum};
use aerie_terrain::select::{LodMode, SelectParams, MAX_REFINEMENT};

#[derive(Debug, Parser)]
#[command(
    name = "aerie",
    version,
    about = "Error-bounded Vulkan terrain renderer for flight simulators"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render one frame of a DEM from a fixed camera to a PNG (+ a JSON summary next to it).
    Render(RenderArgs),
    /// Fly a scripted straight-and-level pass over a DEM headless: PNGs + per-frame CSV.
    Fly(FlyArgs),
    /// Generate a deterministic synthetic DEM (raw f32 + JSON sidecar) for scale and stress tests.
    GenDem(crate::app::commands::gen_dem::GenDemArgs),
    /// Bake the per-tile error table of a dataset (file or folder of SRTM tiles).
    Bake(crate::app::commands::bake::BakeArgs),
    /// Time against measured image-space error: every LOD mode (× τ) on the same frames,
    /// results.csv, summary.csv/.md, time_vs_error.png in --out.
    Bench(crate::app::commands::bench::BenchArgs),
    /// Receive aircraft poses (UDP or shared memory) without rendering: progress, summary,
    /// optional recording.
    Listen(crate::app::commands::listen::ListenArgs),
    /// Send a recording's datagrams to a UDP address (original timing or --fast).
    Replay(crate::app::commands::replay::ReplayArgs),
    /// Show the terrain on screen: one window or fullscreen display per channel of a config
    /// (all in this process, or only --channel NAME), flying the built-in pass.
    Run(crate::app::commands::run::RunArgs),
}

#[derive(Debug, Args)]
pub struct GpuArgs {
    /// Use the first Vulkan device whose name contains this (case-insensitive).
    #[arg(long)]
    pub gpu: Option<String>,
    /// Enable the Khronos validation layer (always on in debug builds).
    #[arg(long)]
    pub validate: bool,
    /// Horizontal field of view, degrees (0 < fov < 180).
    #[arg(long, default_value_t = 90.0)]
    pub fov: f64,
    /// Output size, WxH pixels.
    #[arg(long, default_value = "1920x1080")]
    pub size: String,
    /// Screen-space error bound τ, pixels.
    #[arg(long, default_value_t = 1.0)]
    pub tau: f64,
    /// Level-of-detail decision: bounded (ours), clipmap (no refinement), full (brute force),
    /// distance (discrete LOD by distance with 10 % hysteresis).
    #[arg(long, value_enum, default_value_t = LodArg::Bounded)]
    pub lod: LodArg,
    /// Clipmap patch side n in vertices (129 or 257; n = P(m−1)+1).
    #[arg(long, default_value_t = 129)]
    pub patch: u32,
    /// Colour tiles by clipmap level and refinement.
    #[arg(long)]
    pub debug_tiles: bool,
    /// Draw a flat Earth (no curvature drop).
    #[arg(long)]
    pub no_curvature: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum LodArg {
    Bounded,
    Clipmap,
    Full,
    Distance,
}

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Elevation model: .hgt, .hgt.zip, a folder of SRTM tiles, GeoTIFF, 16-bit .png,
    /// raw .f32/.u16 with a .json sidecar, .npy/.npz. Its error bake is read from (or written
    /// to) `<name>.aerie-bake` next to it.
    #[arg(long)]
    pub dem: PathBuf,
    /// Camera as x,y,z,heading,pitch,roll: metres from the DEM's south-west sample (z above sea
    /// level), degrees (heading clockwise from north, pitch nose-up, roll right-wing-down).
    #[arg(long, allow_hyphen_values = true)]
    pub camera: String,
    #[command(flatten)]
    pub gpu: GpuArgs,
    /// Output PNG; a JSON summary is written next to it (same name, .json).
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Debug, Args)]
pub struct FlyArgs {
    #[arg(long)]
    pub dem: PathBuf,
    /// Number of frames.
    #[arg(long, default_value_t = 24)]
    pub frames: u32,
    /// Simulated frame rate (frames per second of flight time).
    #[arg(long, default_value_t = 30.0)]
    pub fps: f64,
    /// Ground speed, m/s.
    #[arg(long, default_value_t = 340.0)]
    pub speed: f64,
    /// Height above the highest sample of the DEM, metres (with --follow-terrain: above the
    /// ground under the aircraft).
    #[arg(long, default_value_t = 600.0)]
    pub agl: f64,
    /// Fly --agl metres above the ground under the aircraft instead of above the highest sample.
    #[arg(long)]
    pub follow_terrain: bool,
    /// Timed waypoints instead of the built-in pass: lines `t_s,x_m,y_m,z_m,heading,pitch,roll`.
    #[arg(long)]
    pub path: Option<PathBuf>,
    /// Heading of the pass, degrees clockwise from north.
    #[arg(long, default_value_t = 70.0, allow_hyphen_values = true)]
    pub heading: f64,
    /// Camera pitch, degrees (negative looks down).
    #[arg(long, default_value_t = -12.0, allow_hyphen_values = true)]
    pub pitch: f64,
    /// Write every k-th frame as PNG (stats are written for every frame).
    #[arg(long, default_value_t = 1)]
    pub every: u32,
    #[command(flatten)]
    pub gpu: GpuArgs,
    /// Render every `[[channel]]` of this config (e.g. config/presets/wall3.toml) offscreen from
    /// the one aircraft pose: `<out>/<channel>/frame_NNNN.png` and a stitched
    /// `<out>/panorama_NNNN.png`. Sizes, views, frusta and τ come from the config.
    #[arg(long)]
    pub channels: Option<PathBuf>,
    /// With --channels: multiply every channel's resolution by this (e.g. 0.1 for quick runs).
    #[arg(long, default_value_t = 1.0)]
    pub channel_scale: f64,
    /// With --channels: no line along the borders between channels in the panorama.
    #[arg(long)]
    pub no_panorama_borders: bool,
    /// Draw the statistics overlay (frame time, τ, tiles, late tiles, triangles, pose age)
    /// into the top-left corner of every frame.
    #[arg(long)]
    pub overlay: bool,
    /// Output folder (created): frame_NNNN.png, frames.csv, summary.json.
    #[arg(long)]
    pub out: PathBuf,
}

pub fn run(cli: Cli) -> Result<(), Failure> {
    match cli.command {
        Command::Render(a) => cmd_render(a),
        Command::Fly(a) => cmd_fly(a),
        Command::GenDem(a) => crate::app::commands::gen_dem::run(a),
        Command::Bake(a) => crate::app::commands::bake::run(a),
        Command::Bench(a) => crate::app::commands::bench::run(a),
        Command::Listen(a) => crate::app::commands::listen::run(a),
        Command::Replay(a) => crate::app::commands::replay::run(a),
        Command::Run(a) => crate::app::commands::run::run(a),
    }
}

struct Setup {
    width: u32,
    height: u32,
    frustum: Frustum,
    desc: RendererDesc,
}

fn setup(g: &GpuArgs) -> Result<Setup, Failure> {
    let (width, height) = parse_size_arg(&g.size).map_err(|e| bad_input(format!("--size: {e}")))?;
    if !(g.fov.is_finite() && g.fov > 0.0 && g.fov < 180.0) {
        return Err(bad_input(format!(
            "--fov: {} is outside (0, 180) degrees",
            g.fov
        )));
    }
    let frustum = Frustum::try_symmetric(g.fov.to_radians(), width, height)
        .map_err(|e| bad_input(format!("--fov: {e}")))?;
    if !(g.tau.is_finite() && g.tau > 0.0) {
        return Err(bad_input(format!(
            "--tau: {} must be a positive number of pixels",
            g.tau
        )));
    }
    let defaults = RendererDesc::default();
    let q = defaults.tile_size - 1;
    if g.patch < 8 * q + 1 || !(g.patch - 1).is_multiple_of(2 * q) {
        return Err(bad_input(format!(
            "--patch: {} must be P·{q}+1 with P even and ≥ 8 (e.g. 129 or 257)",
            g.patch
        )));
    }
    let mode = match g.lod {
        LodArg::Bounded => LodMode::Bounded,
        LodArg::Clipmap => LodMode::Clipmap,
        LodArg::Full => LodMode::Full,
        LodArg::Distance => LodMode::Distance,
    };
    let mut pool_capacity = defaults.pool_capacity;
    if mode == LodMode::Full {
        // Brute force draws every visible tile at full resolution: room for all of them.
        pool_capacity = [1024, 512, 256, 128, 48, 16];
    }
    let desc = RendererDesc {
        validation: g.validate || cfg!(debug_assertions),
        device: DeviceDesc {
            name_filter: g.gpu.clone(),
            swapchain: false,
        },
        width,
        height,
        patch_tiles: (g.patch - 1) / q,
        pool_capacity,
        debug_tiles: g.debug_tiles,
        select: SelectParams {
            mode,
            tau_px: g.tau,
            curvature: !g.no_curvature,
            max_refinement: if mode == LodMode::Full {
                MAX_REFINEMENT
            } else {
                SelectParams::default().max_refinement
            },
            ..SelectParams::default()
        },
        ..defaults
    };
    Ok(Setup {
        width,
        height,
        frustum,
        desc,
    })
}

fn check_validation(r: &TerrainRenderer) -> Result<(), Failure> {
    r.validation_counters().verdict().map_err(runtime)
}

fn cmd_render(a: RenderArgs) -> Result<(), Failure> {
    let s = setup(&a.gpu)?;
    let (position, attitude) =
        parse_camera_arg(&a.camera).map_err(|e| bad_input(format!("--camera: {e}")))?;
    check_out_file(&a.out)?;
    let (ds, b) = prepare_terrain(&a.dem, s.desc.tile_size)?;
    let mut r = TerrainRenderer::new(&s.desc).map_err(runtime)?;
    r.load_terrain(ds, b, position).map_err(runtime)?;
    let camera = Camera::new(position, attitude, s.frustum);
    let stats = r.render(&camera).map_err(runtime)?;
    let rgba = r.colour_rgba();
    let device = r.device_name().to_string();
    r.destroy();
    check_validation(&r)?;
    write_png(&a.out, s.width, s.height, &rgba).map_err(runtime)?;
    let summary = serde_json::json!({
        "device": device,
        "dem": a.dem.display().to_string(),
        "size": [s.width, s.height],
        "lod": s.desc.select.mode,
        "tau_px": s.desc.select.tau_px,
        "triangles": stats.triangles,
        "tiles_drawn": stats.tiles_drawn,
        "tiles_culled": stats.tiles_culled,
        "tiles_by_refinement": stats.tiles_by_refinement,
        "tiles_late": stats.tiles_late,
        "instances": stats.instances,
        "draw_calls": stats.draw_calls,
        "gpu_ms": stats.gpu_upload_ms + stats.gpu_terrain_ms,
        "cpu_select_us": stats.cpu_select_us,
        "out": a.out.display().to_string(),
    });
    let line = summary.to_string();
    write_text(&a.out.with_extension("json"), &format!("{line}\n")).map_err(runtime)?;
    println!("{line}");
    Ok(())
}

fn check_out_file(out: &Path) -> Result<(), Failure> {
    let parent = out.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(p) = parent {
        if !p.is_dir() {
            return Err(bad_input(format!(
                "--out {}: folder {} does not exist",
                out.display(),
                p.display()
            )));
        }
    }
    Ok(())
}

/// One CSV row per frame: the pose, then every frame statistic.
fn csv_row(s: &FrameStats, t: f64, pos: DVec3, att: Attitude) -> String {
    format!(
        "{:.4},{:.2},{:.2},{:.2},{:.3},{:.3},{:.3},{}\n",
        t,
        pos.x,
        pos.y,
        pos.z,
        att.heading.to_degrees(),
        att.pitch.to_degrees(),
        att.roll.to_degrees(),
        s.csv_row()
    )
}

/// Header of `frames.csv`.
pub fn frames_csv_header() -> String {
    format!(
        "time_s,x_m,y_m,z_m,heading_deg,pitch_deg,roll_deg,{}\n",
        FrameStats::CSV_HEADER
    )
}

fn cmd_fly(a: FlyArgs) -> Result<(), Failure> {
    let s = setup(&a.gpu)?;
    if a.frames == 0 {
        return Err(bad_input("--frames: must be at least 1"));
    }
    if a.every == 0 {
        return Err(bad_input("--every: must be at least 1"));
    }
    for (name, v) in [("--fps", a.fps), ("--speed", a.speed), ("--agl", a.agl)] {
        if !v.is_finite() || v < 0.0 || (name == "--fps" && v == 0.0) {
            return Err(bad_input(format!(
                "{name}: {v} must be a finite positive number"
            )));
        }
    }
    for (name, v) in [("--heading", a.heading), ("--pitch", a.pitch)] {
        if !v.is_finite() {
            return Err(bad_input(format!("{name}: {v} is not finite")));
        }
    }
    // The channel config is checked before any data is loaded.
    let channel_plan = match &a.channels {
        Some(p) => Some(crate::app::commands::fly::plan_channels(
            p,
            a.channel_scale,
        )?),
        None => None,
    };
    std::fs::create_dir_all(&a.out).map_err(|e| {
        bad_input(format!(
            "--out {}: cannot create folder: {e}",
            a.out.display()
        ))
    })?;
    let (ds, b) = prepare_terrain(&a.dem, s.desc.tile_size)?;
    let waypoints = match &a.path {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .map_err(|e| bad_input(format!("--path {}: {e}", p.display())))?;
            Some(Waypoints::parse(&text, &p.display().to_string()).map_err(bad_input)?)
        }
        None => None,
    };
    let duration = a.frames as f64 / a.fps;
    let pass = StraightPass::over(&ds, a.heading, a.pitch, a.speed, a.agl, duration);
    let terrain = ds.clone();
    let pose_at = |t: f64| -> (DVec3, Attitude) {
        if let Some(w) = &waypoints {
            return w.pose_at(t);
        }
        let (mut p, att) = pass.pose_at(t);
        if a.follow_terrain {
            p.z = terrain.hf.height_at_m(p.x, p.y) + a.agl;
        }
        (p, att)
    };
    let mut desc = s.desc.clone();
    if let Some((_, chans)) = &channel_plan {
        (desc.width, desc.height) = chans[0].size;
    }
    let mut r = TerrainRenderer::new(&desc).map_err(runtime)?;
    let t_upload = Instant::now();
    let up = r.load_terrain(ds, b, pose_at(0.0).0).map_err(runtime)?;
    eprintln!(
        "{} clipmap levels filled: {:.1} MB in {} submissions ({:.2} s) on {}",
        up.levels,
        up.bytes as f64 / 1e6,
        up.submissions,
        t_upload.elapsed().as_secs_f64(),
        r.device_name()
    );
    if let Some((_, channels)) = channel_plan {
        let job = crate::app::commands::fly::ChannelFlight {
            args: &a,
            config_path: a.channels.clone().unwrap_or_default(),
            channels,
            pose_at: &pose_at,
        };
        return crate::app::commands::fly::fly_channels(&mut r, job);
    }
    let mut overlay = crate::tools::overlay::OverlayState::new(a.overlay);
    let bar = indicatif::ProgressBar::new(a.frames as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} frames, eta {eta}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_message("flying");
    let mut csv = frames_csv_header();
    let mut late = 0u64;
    let mut refined = 0u64;
    let mut gpu_ms = Vec::new();
    let mut frame_ms = Vec::new();
    let mut triangles = Vec::new();
    let mut pngs = 0u32;
    for f in 0..a.frames {
        let t = f as f64 / a.fps;
        let (pos, att) = pose_at(t);
        let camera = Camera::new(pos, att, s.frustum);
        r.set_overlay(overlay.panel((s.width, s.height), None));
        let wall = Instant::now();
        let stats = r.render(&camera).map_err(runtime)?;
        frame_ms.push(wall.elapsed().as_secs_f64() * 1e3);
        overlay.record(
            wall.elapsed().as_secs_f64() * 1e3,
            crate::tools::overlay::OverlayInfo::from_stats(&stats, s.desc.select.tau_px),
        );
        gpu_ms.push(stats.gpu_upload_ms + stats.gpu_terrain_ms);
        triangles.push(stats.triangles as f64);
        late += stats.tiles_late as u64;
        refined += stats.tiles_drawn as u64 - stats.tiles_by_refinement[0] as u64;
        csv.push_str(&csv_row(&stats, t, pos, att));
        if f % a.every == 0 {
            let path = a.out.join(format!("frame_{f:04}.png"));
            write_png(&path, s.width, s.height, &r.colour_rgba()).map_err(runtime)?;
            pngs += 1;
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let device = r.device_name().to_string();
    r.destroy();
    check_validation(&r)?;
    write_text(&a.out.join("frames.csv"), &csv).map_err(runtime)?;
    for v in [&mut gpu_ms, &mut frame_ms, &mut triangles] {
        v.sort_by(f64::total_cmp);
    }
    let summary = serde_json::json!({
        "device": device,
        "dem": a.dem.display().to_string(),
        "frames": a.frames,
        "pngs": pngs,
        "size": [s.width, s.height],
        "gpu_ms": {"median": percentile(&gpu_ms, 0.5), "p99": percentile(&gpu_ms, 0.99), "max": percentile(&gpu_ms, 1.0)},
        "frame_ms": {"median": percentile(&frame_ms, 0.5), "p99": percentile(&frame_ms, 0.99), "max": percentile(&frame_ms, 1.0)},
        "triangles": {"median": percentile(&triangles, 0.5), "max": percentile(&triangles, 1.0)},
        "lod": s.desc.select.mode,
        "tau_px": s.desc.select.tau_px,
        "tiles_refined": refined,
        "tiles_late": late,
        "validation": {
            "enabled": s.desc.validation,
            "errors": r.validation_counters().errors(),
            "warnings": r.validation_counters().warnings(),
        },
    });
    write_text(&a.out.join("summary.json"), &format!("{summary:#}\n")).map_err(runtime)?;
    println!(
        "{} frames ({} PNGs) in {}: frame median {:.1} ms, p99 {:.1} ms, max {:.1} ms (GPU median {:.1} ms); triangles median {:.0}; {} tiles refined, {} late; validation clean",
        a.frames,
        pngs,
        a.out.display(),
        percentile(&frame_ms, 0.5),
        percentile(&frame_ms, 0.99),
        percentile(&frame_ms, 1.0),
        percentile(&gpu_ms, 0.5),
        percentile(&triangles, 0.5),
        refined,
        late
    );
    Ok(())
}
