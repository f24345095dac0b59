//! `aerie fly`: a scripted flight over a DEM, headless. The built-in straight pass (or timed
//! waypoints) flown by one camera writes every `--every`-th frame as `<out>/frame_NNNN.png`, one
//! `frames.csv` row per frame and `summary.json`.
//!
//! With `--channels <preset.toml>` every display channel of a config is rendered offscreen from
//! one aircraft pose per frame (one tile selection for all of them, as on screen), each
//! channel's frames in `<out>/<channel>/frame_NNNN.png`, and a stitched review panorama
//! `<out>/panorama_NNNN.png` ([`crate::tools::panorama`]). `frames.csv` has one row per frame per
//! channel (first column `channel`); `summary.json` lists the channels and the panorama canvas.
//!
//! The output folder must be empty, or `--overwrite` removes what an earlier `fly` wrote there
//! ([`FLY_FILES`]). A PNG that cannot be written does not stop the flight: it is recorded, every
//! later frame is still tried, `frames.csv` and `summary.json` (`failed_frames`,
//! `failed_files`) are still written, and the command exits 1 naming the first failed file.

use std::path::{Path, PathBuf};
use std::time::Instant;

use aerie_config::{Channel, RenderConfig};
use clap::Args;

use crate::app::args::{read_waypoints, GpuArgs, PassArgs, StoreArgs};
use crate::app::commands::flight_files::{
    csv_row, frames_csv_header, median_max, median_p99_max, write_csv_and_summary,
};
use crate::app::commands::fly_no_draw::{fly_no_draw, NoDrawFlight};
use crate::app::commands::render::stream_json;
use crate::app::failure::{bad_input, renderer_failure, runtime, Failure};
use crate::app::flight_plan::FlightPlan;
use crate::app::out_path::{prepare_run_folder, WriteFailures, FLY_FILES};
use crate::app::prepare::prepare_source;
use crate::app::progress::count_bar;
use crate::app::renderer_setup::{setup, Setup};
use crate::render::frame::{FrameStats, Lighting, TerrainRenderer};
use crate::sim::channel::channel_camera;
use crate::sim::geo_mapping::GeoMapping;
use crate::sim::sun_clock::SunClock;
use crate::tools::output::write_png;
use crate::tools::overlay::{OverlayInfo, OverlayState};
use crate::tools::panorama::{canvas_for, PanoramaChannel, PanoramaMap, MAX_CANVAS};
use crate::tools::percentile::percentile;
use aerie_terrain::camera::Camera;

#[derive(Debug, Args)]
pub struct FlyArgs {
    /// Elevation model (any format `render` reads); its bake is read from or written next to it.
    /// A tile store (`<name>.aerie`) is streamed.
    #[arg(long)]
    pub dem: PathBuf,
    #[command(flatten)]
    pub store: StoreArgs,
    /// No drawing and no GPU: the frame thread's selection, streaming and clipmap/pool
    /// decisions alone, reporting RSS over time, late tiles, the longest terrain-data time per
    /// frame and the cache hit rate (`frames.csv`, `summary.json`; no PNGs).
    #[arg(long)]
    pub no_draw: bool,
    /// With --no-draw: frames follow the flight's clock sped up this many times (1 = real
    /// time; 0 = as fast as the frame thread goes, which leaves the page workers no time).
    #[arg(long, default_value_t = 1.0)]
    pub pace: f64,
    /// Number of frames.
    #[arg(long, default_value_t = 24)]
    pub frames: u32,
    /// Simulated frame rate (frames per second of flight time).
    #[arg(long, default_value_t = 30.0)]
    pub fps: f64,
    #[command(flatten)]
    pub pass: PassArgs,
    /// Timed waypoints instead of the built-in pass: lines `t_s,x_m,y_m,z_m,heading,pitch,roll`
    /// (local metres); a file whose first line is `geo` holds `t_s,lat,lon,alt,heading,pitch,roll`
    /// (degrees, metres above the data's datum) on a geo-referenced dataset.
    #[arg(long)]
    pub path: Option<PathBuf>,
    /// Light every frame by the sun where it stands over the aircraft at this UTC date and time
    /// plus the flight's clock (`2026-06-21T18:30:00Z`), on a geo-referenced dataset.
    #[arg(long)]
    pub time: Option<String>,
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
    /// Output folder (created, with the folders above it): frame_NNNN.png, frames.csv,
    /// summary.json. It must be empty unless --overwrite.
    #[arg(long)]
    pub out: PathBuf,
    /// Reuse a non-empty --out folder: first remove the files an earlier `aerie fly` wrote
    /// there (frame_NNNN.png, panorama_NNNN.png, channel folders' frames, frames.csv,
    /// summary.json); anything else in it is kept.
    #[arg(long)]
    pub overwrite: bool,
}

pub fn run(a: FlyArgs) -> Result<(), Failure> {
    let mut s = setup(&a.gpu)?;
    // A flight's next frames may look anywhere (`RendererDesc::warm_start`).
    s.desc.warm_start = true;
    if a.frames == 0 {
        return Err(bad_input("--frames: must be at least 1"));
    }
    if a.every == 0 {
        return Err(bad_input("--every: must be at least 1"));
    }
    a.pass.check(a.fps)?;
    // The channel config is checked before any data is loaded.
    let channel_plan = match &a.channels {
        Some(p) => Some(plan_channels(p, a.channel_scale)?),
        None => None,
    };
    let waypoints = read_waypoints("--path", a.path.as_ref())?;
    let clock = match &a.time {
        Some(t) => Some(SunClock::parse(t).map_err(|e| bad_input(format!("--time: {e}")))?),
        None => None,
    };
    let removed = prepare_run_folder("--out", &a.out, a.overwrite, &FLY_FILES)?;
    if removed > 0 {
        eprintln!(
            "--overwrite: removed {removed} files of an earlier fly from {}",
            a.out.display()
        );
    }
    let terrain = prepare_source(&a.dem, &s.desc, &a.store)?;
    let flight = FlightPlan::new(&terrain, &a.pass, waypoints, a.frames as f64 / a.fps)
        .map_err(|e| bad_input(format!("--path: {e}")))?;
    let light = match clock {
        Some(clock) => Some(FlightLight {
            clock,
            mapping: GeoMapping::of_source(terrain.grid())
                .map_err(|e| bad_input(format!("--time: the sun's place needs latitudes: {e}")))?,
        }),
        None => None,
    };
    if a.no_draw {
        let job = NoDrawFlight {
            dem: &a.dem,
            out: &a.out,
            frames: a.frames,
            fps: a.fps,
            pace: a.pace,
        };
        return fly_no_draw(&job, &s, &terrain, &flight);
    }
    let mut desc = s.desc.clone();
    if let Some((_, chans)) = &channel_plan {
        (desc.width, desc.height) = chans[0].size;
    }
    let mut r = TerrainRenderer::new(&desc).map_err(runtime)?;
    let t_upload = Instant::now();
    let up = r
        .load_source(
            terrain.source.clone(),
            terrain.bake.clone(),
            flight.pose_at(0.0).0,
        )
        .map_err(renderer_failure)?;
    eprintln!(
        "{} clipmap levels filled: {:.1} MB in {} submissions ({:.2} s) on {}",
        up.levels,
        up.bytes as f64 / 1e6,
        up.submissions,
        t_upload.elapsed().as_secs_f64(),
        r.device_name()
    );
    match channel_plan {
        Some((_, channels)) => {
            let job = ChannelFlight {
                args: &a,
                config_path: a.channels.clone().unwrap_or_default(),
                channels,
                flight: &flight,
                light: light.as_ref(),
            };
            fly_channels(&mut r, job)
        }
        None => fly_one_camera(&mut r, &a, &s, &flight, light.as_ref()),
    }
}

/// `--time`: the sun over the aircraft as the flight's clock runs.
pub struct FlightLight {
    pub clock: SunClock,
    pub mapping: GeoMapping,
}

impl FlightLight {
    /// The light `t_s` seconds into the flight for an eye at world point `eye`.
    pub fn at(&self, t_s: f64, eye: glam::DVec3) -> Lighting {
        Lighting::from_host(self.clock.sun_world(t_s, &self.mapping, eye), None)
    }
}

/// Flies the one camera of `s`: `r` has its terrain loaded. Writes the PNGs, `frames.csv` and
/// `summary.json`, prints a one-line summary; destroys the renderer and fails on any
/// validation message.
fn fly_one_camera(
    r: &mut TerrainRenderer,
    a: &FlyArgs,
    s: &Setup,
    flight: &FlightPlan,
    light: Option<&FlightLight>,
) -> Result<(), Failure> {
    let (width, height) = (s.view.width, s.view.height);
    let mut overlay = OverlayState::new(a.overlay);
    let bar = count_bar(a.frames as u64, "frames", "flying");
    let mut csv = frames_csv_header();
    let mut late = 0u64;
    let mut late_stream = 0u64;
    let mut drawn = 0u64;
    let mut data_us = 0f64;
    let mut last = FrameStats::default();
    let mut refined = 0u64;
    let mut gpu_ms = Vec::new();
    let mut frame_ms = Vec::new();
    let mut thread_us = Vec::new();
    let mut after_plan_us = Vec::new();
    let mut triangles = Vec::new();
    let mut pngs = 0u32;
    let mut failures = WriteFailures::default();
    for f in 0..a.frames {
        let t = f as f64 / a.fps;
        let (pos, att) = flight.pose_at(t);
        let camera = Camera::new(pos, att, s.view.frustum);
        if let Some(l) = light {
            r.set_lighting(l.at(t, pos));
        }
        r.set_overlay(overlay.panel((width, height), None));
        let wall = Instant::now();
        let stats = r.render(&camera).map_err(runtime)?;
        frame_ms.push(wall.elapsed().as_secs_f64() * 1e3);
        overlay.record(
            wall.elapsed().as_secs_f64() * 1e3,
            OverlayInfo::from_stats(&stats, s.desc.select.tau_px),
        );
        gpu_ms.push(stats.gpu_upload_ms + stats.gpu_terrain_ms);
        thread_us.push(stats.cpu_thread_us);
        after_plan_us.push(stats.cpu_thread_us - stats.cpu_thread_plan_us);
        triangles.push(stats.triangles as f64);
        late += stats.tiles_late as u64;
        late_stream += stats.tiles_late_stream as u64;
        drawn += stats.tiles_drawn as u64;
        data_us = data_us.max(stats.cpu_terrain_data_us);
        last = stats;
        refined += stats.tiles_drawn as u64 - stats.tiles_by_refinement[0] as u64;
        csv.push_str(&csv_row(&stats, t, pos, att));
        if f % a.every == 0 {
            let path = a.out.join(format!("frame_{f:04}.png"));
            let written = write_png(&path, width, height, &r.colour_rgba());
            pngs += failures.check(Some(f), &path, written) as u32;
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let device = r.device_name().to_string();
    let drape = crate::app::renderer_setup::drape_json(r);
    r.destroy();
    r.validation_counters().verdict().map_err(runtime)?;
    for v in [
        &mut gpu_ms,
        &mut frame_ms,
        &mut thread_us,
        &mut after_plan_us,
        &mut triangles,
    ] {
        v.sort_by(f64::total_cmp);
    }
    let summary = serde_json::json!({
        "device": device,
        "dem": a.dem.display().to_string(),
        "frames": a.frames,
        "pngs": pngs,
        "size": [width, height],
        "gpu_ms": median_p99_max(&gpu_ms),
        "frame_ms": median_p99_max(&frame_ms),
        "frame_thread_cpu_us": median_p99_max(&thread_us),
        "stage_record_submit_thread_cpu_us": median_p99_max(&after_plan_us),
        "triangles": median_max(&triangles),
        "lod": s.desc.select.mode,
        "tau_px": s.desc.select.tau_px,
        "tiles_refined": refined,
        "tiles_late": late,
        "tiles_late_stream": late_stream,
        "tiles_drawn": drawn,
        "max_terrain_data_us": data_us,
        "stream": stream_json(&last),
        "drape": drape,
        "validation": {
            "enabled": s.desc.validation,
            "errors": r.validation_counters().errors(),
            "warnings": r.validation_counters().warnings(),
        },
    });
    let done = write_csv_and_summary(&a.out, &csv, summary, &mut failures);
    println!(
        "{} frames ({} PNGs) in {}: frame median {:.1} ms, p99 {:.1} ms, max {:.1} ms (GPU median {:.1} ms; the frame thread's CPU median {:.0} µs, p99 {:.0} µs, of which staging, recording and submission {:.0} / {:.0} µs); triangles median {:.0}; {} tiles refined, {} late; validation clean{}",
        a.frames,
        pngs,
        a.out.display(),
        percentile(&frame_ms, 0.5),
        percentile(&frame_ms, 0.99),
        percentile(&frame_ms, 1.0),
        percentile(&gpu_ms, 0.5),
        percentile(&thread_us, 0.5),
        percentile(&thread_us, 0.99),
        percentile(&after_plan_us, 0.5),
        percentile(&after_plan_us, 0.99),
        percentile(&triangles, 0.5),
        refined,
        late,
        not_written_note(&done),
    );
    done
}

/// Said at the end of the one-line summary when some files were not written, so the line does
/// not read like a success before the error that follows it.
fn not_written_note(done: &Result<(), Failure>) -> &'static str {
    if done.is_err() {
        "; some files were NOT written (below)"
    } else {
        ""
    }
}

/// One channel as flown: its config, render size and output folder name.
#[derive(Debug, Clone)]
pub struct FlyChannel {
    pub channel: Channel,
    pub size: (u32, u32),
    pub folder: String,
}

/// The render size of a channel: its `resolution`, else its window's size, else the config's
/// `[render]` size, times `scale` (rounded, at least 1 pixel). Presets are 1920×1080; tests and
/// CI fly them at e.g. 1/12 scale.
pub fn channel_render_size(ch: &Channel, cfg: &RenderConfig, scale: f64) -> (u32, u32) {
    let (w, h) = ch
        .nominal_size()
        .unwrap_or((cfg.render.width, cfg.render.height));
    let s = |v: u32| ((v as f64 * scale).round() as u32).max(1);
    (s(w), s(h))
}

/// A folder name for a channel: its name with anything but ASCII letters, digits, `-`, `_` and
/// `.` replaced by `_` (names are free text in the config).
pub fn channel_folder(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() || s.chars().all(|c| c == '.') {
        format!("_{s}")
    } else {
        s
    }
}

/// Reads the channel config and decides every channel's size and folder: bad input (unknown
/// file, config errors with file:line:key, a config without channels, a bad scale) is reported
/// before anything is loaded.
pub fn plan_channels(path: &Path, scale: f64) -> Result<(RenderConfig, Vec<FlyChannel>), Failure> {
    if !(scale.is_finite() && scale > 0.0 && scale <= 4.0) {
        return Err(bad_input(format!(
            "--channel-scale: {scale} must be in (0, 4]"
        )));
    }
    let cfg = aerie_config::load(path).map_err(bad_input)?;
    if cfg.channels.is_empty() {
        return Err(bad_input(format!(
            "--channels {}: the config has no [[channel]] table",
            path.display()
        )));
    }
    let mut out: Vec<FlyChannel> = Vec::new();
    for ch in &cfg.channels {
        let mut folder = channel_folder(&ch.name);
        if out.iter().any(|c| c.folder == folder) {
            folder = format!("{folder}-{}", out.len());
        }
        out.push(FlyChannel {
            channel: ch.clone(),
            size: channel_render_size(ch, &cfg, scale),
            folder,
        });
    }
    Ok((cfg, out))
}

/// Everything `fly_channels` needs besides the renderer.
pub struct ChannelFlight<'a> {
    pub args: &'a FlyArgs,
    pub config_path: PathBuf,
    pub channels: Vec<FlyChannel>,
    pub flight: &'a FlightPlan,
    /// `--time`: the sun over the aircraft.
    pub light: Option<&'a FlightLight>,
}

/// Flies every channel: `r` has its terrain loaded. Writes the PNGs, `frames.csv` and
/// `summary.json`, prints a one-line summary; destroys the renderer and fails on any
/// validation message.
pub fn fly_channels(r: &mut TerrainRenderer, job: ChannelFlight) -> Result<(), Failure> {
    let a = job.args;
    let chans = &job.channels;
    for c in chans {
        let dir = a.out.join(&c.folder);
        std::fs::create_dir_all(&dir)
            .map_err(|e| runtime(format!("{}: cannot create folder: {e}", dir.display())))?;
    }
    let pano_chans: Vec<PanoramaChannel> = chans
        .iter()
        .map(|c| PanoramaChannel::new(&c.channel, c.size))
        .collect();
    let t_map = Instant::now();
    let canvas = canvas_for(&pano_chans, MAX_CANVAS);
    let map = PanoramaMap::new(&pano_chans, canvas);
    let coverage = map.coverage(chans.len());
    eprintln!(
        "panorama {}x{}: azimuth {:.1}°..{:.1}°, elevation {:.1}°..{:.1}° ({:.2} s to map)",
        canvas.width,
        canvas.height,
        canvas.az0_deg,
        canvas.az0_deg + canvas.az_span_deg,
        canvas.el0_deg,
        canvas.el1_deg,
        t_map.elapsed().as_secs_f64()
    );
    let sizes: Vec<(u32, u32)> = chans.iter().map(|c| c.size).collect();
    let bar = count_bar(
        a.frames as u64,
        "frames",
        &format!("flying {} channels", chans.len()),
    );
    let mut csv = format!("channel,{}", frames_csv_header());
    let mut frame_ms = Vec::new();
    let mut per_channel_triangles: Vec<Vec<f64>> = vec![Vec::new(); chans.len()];
    let mut late = vec![0u64; chans.len()];
    let mut digests_equal = true;
    let mut pngs = 0u32;
    let mut panoramas = 0u32;
    let mut failures = WriteFailures::default();
    let mut overlays: Vec<OverlayState> =
        chans.iter().map(|_| OverlayState::new(a.overlay)).collect();
    for f in 0..a.frames {
        let t = f as f64 / a.fps;
        let (pos, att) = job.flight.pose_at(t);
        if let Some(l) = job.light {
            r.set_lighting(l.at(t, pos));
        }
        let cams: Vec<Camera> = chans
            .iter()
            .map(|c| channel_camera((pos, att), &c.channel, c.size.0 as f64 / c.size.1 as f64))
            .collect();
        // One selection for every channel, exactly as the window path does.
        r.set_channels(if chans.len() > 1 {
            cams.iter()
                .zip(chans)
                .map(|(cam, c)| (*cam, c.size, c.channel.tau_px))
                .collect()
        } else {
            Vec::new()
        });
        let write = f % a.every == 0;
        let mut images: Vec<Vec<u8>> = Vec::new();
        let wall = Instant::now();
        let mut digest = None;
        for (k, (c, cam)) in chans.iter().zip(&cams).enumerate() {
            r.resize(c.size.0, c.size.1).map_err(runtime)?;
            let mut params = r.desc().select;
            if params.tau_px != c.channel.tau_px {
                params.tau_px = c.channel.tau_px;
                r.set_select_params(params);
            }
            r.set_overlay(overlays[k].panel(c.size, None));
            let channel_wall = Instant::now();
            let stats: FrameStats = r.render(cam).map_err(runtime)?;
            overlays[k].record(
                channel_wall.elapsed().as_secs_f64() * 1e3,
                OverlayInfo::from_stats(&stats, c.channel.tau_px),
            );
            if *digest.get_or_insert(stats.selection_digest) != stats.selection_digest {
                digests_equal = false;
            }
            per_channel_triangles[k].push(stats.triangles as f64);
            late[k] += stats.tiles_late as u64;
            csv.push_str(&c.channel.name.replace([',', '\n'], "_"));
            csv.push(',');
            csv.push_str(&csv_row(&stats, t, cam.position, cam.attitude));
            if write {
                let rgba = r.colour_rgba();
                let path = a.out.join(&c.folder).join(format!("frame_{f:04}.png"));
                let written = write_png(&path, c.size.0, c.size.1, &rgba);
                pngs += failures.check(Some(f), &path, written) as u32;
                images.push(rgba);
            }
        }
        r.set_overlay(None);
        frame_ms.push(wall.elapsed().as_secs_f64() * 1e3);
        if write {
            let refs: Vec<&[u8]> = images.iter().map(|v| v.as_slice()).collect();
            let pano = map.compose(&refs, &sizes, !a.no_panorama_borders);
            let path = a.out.join(format!("panorama_{f:04}.png"));
            let written = write_png(&path, canvas.width, canvas.height, &pano);
            panoramas += failures.check(Some(f), &path, written) as u32;
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let device = r.device_name().to_string();
    let counters = r.validation_counters();
    let validation = r.desc().validation;
    let drape = crate::app::renderer_setup::drape_json(r);
    r.destroy();
    counters.verdict().map_err(runtime)?;
    frame_ms.sort_by(f64::total_cmp);
    let channels_json: Vec<serde_json::Value> = chans
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let mut tri = per_channel_triangles[k].clone();
            tri.sort_by(f64::total_cmp);
            serde_json::json!({
                "name": c.channel.name,
                "folder": c.folder,
                "size": [c.size.0, c.size.1],
                "tau_px": c.channel.tau_px,
                "view_deg": [c.channel.view.heading_deg, c.channel.view.pitch_deg, c.channel.view.roll_deg],
                "frustum_deg": frustum_json(&pano_chans[k]),
                "triangles": median_max(&tri),
                "tiles_late": late[k],
                "panorama_pixels": coverage[k],
            })
        })
        .collect();
    let uncovered = map.sources.iter().filter(|s| s.is_none()).count();
    let summary = serde_json::json!({
        "device": device,
        "dem": a.dem.display().to_string(),
        "config": job.config_path.display().to_string(),
        "frames": a.frames,
        "pngs": pngs,
        "channel_scale": a.channel_scale,
        "channels": channels_json,
        "one_selection_for_all_channels": digests_equal,
        "panorama": {
            "pngs": panoramas,
            "canvas": canvas,
            "borders": !a.no_panorama_borders,
            "uncovered_pixels": uncovered,
        },
        "overlay": a.overlay,
        "frame_ms": median_p99_max(&frame_ms),
        "drape": drape,
        "validation": {"enabled": validation, "errors": counters.errors(), "warnings": counters.warnings()},
    });
    let done = write_csv_and_summary(&a.out, &csv, summary, &mut failures);
    println!(
        "{} frames × {} channels ({} PNGs, {} panoramas {}x{}) in {}: frame median {:.1} ms, max {:.1} ms (all channels); validation clean{}",
        a.frames,
        chans.len(),
        pngs,
        panoramas,
        canvas.width,
        canvas.height,
        a.out.display(),
        percentile(&frame_ms, 0.5),
        percentile(&frame_ms, 1.0),
        not_written_note(&done),
    );
    done
}

/// The channel's frustum edge angles (left, right, down, up), degrees from its view axis.
fn frustum_json(c: &PanoramaChannel) -> [f64; 4] {
    let f = &c.camera.frustum;
    [f.tan_left, f.tan_right, f.tan_down, f.tan_up].map(|t| t.atan().to_degrees())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channel_sizes_scale_from_the_preset() {
        let text = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../config/presets/wall3.toml"),
        )
        .unwrap();
        let cfg = aerie_config::parse(&text, "wall3.toml").unwrap();
        let ch = &cfg.channels[0];
        assert_eq!(channel_render_size(ch, &cfg, 1.0), (1920, 1080));
        assert_eq!(channel_render_size(ch, &cfg, 1.0 / 12.0), (160, 90));
        assert_eq!(channel_render_size(ch, &cfg, 1e-6), (1, 1));
    }

    #[test]
    fn folders_are_safe_names() {
        assert_eq!(channel_folder("left"), "left");
        assert_eq!(channel_folder("chin-left"), "chin-left");
        assert_eq!(channel_folder("a/b c"), "a_b_c");
        assert_eq!(channel_folder(".."), "_..");
    }
}
