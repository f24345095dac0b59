//! `aerie fly --channels <preset.toml>`: every display channel of a config rendered offscreen
//! from one aircraft pose per frame (one tile selection for all of them, as on screen), each
//! channel's frames in `<out>/<channel>/frame_NNNN.png`, and a stitched review panorama
//! `<out>/panorama_NNNN.png` ([`crate::tools::panorama`]). `frames.csv` has one row per frame per
//! channel (first column `channel`); `summary.json` lists the channels and the panorama canvas.

use std::path::{Path, PathBuf};
use std::time::Instant;

use aerie_config::{Channel, RenderConfig};
use glam::DVec3;

use crate::app::cli::{frames_csv_header, FlyArgs};
use crate::app::failure::{bad_input, runtime, Failure};
use crate::render::frame::{FrameStats, TerrainRenderer};
use crate::sim::channel::channel_camera;
use crate::tools::output::{write_png, write_text};
use crate::tools::overlay::{OverlayInfo, OverlayState};
use crate::tools::panorama::{canvas_for, PanoramaChannel, PanoramaMap, MAX_CANVAS};
use crate::tools::percentile::percentile;
use aerie_terrain::camera::{Attitude, Camera};

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
    pub pose_at: &'a dyn Fn(f64) -> (DVec3, Attitude),
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
    let bar = indicatif::ProgressBar::new(a.frames as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} frames, eta {eta}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_message(format!("flying {} channels", chans.len()));
    let mut csv = format!("channel,{}", frames_csv_header());
    let mut frame_ms = Vec::new();
    let mut per_channel_triangles: Vec<Vec<f64>> = vec![Vec::new(); chans.len()];
    let mut late = vec![0u64; chans.len()];
    let mut digests_equal = true;
    let mut pngs = 0u32;
    let mut panoramas = 0u32;
    let mut overlays: Vec<OverlayState> =
        chans.iter().map(|_| OverlayState::new(a.overlay)).collect();
    for f in 0..a.frames {
        let t = f as f64 / a.fps;
        let (pos, att) = (job.pose_at)(t);
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
            csv.push_str(&format!(
                "{},{:.4},{:.2},{:.2},{:.2},{:.3},{:.3},{:.3},{}\n",
                c.channel.name.replace([',', '\n'], "_"),
                t,
                cam.position.x,
                cam.position.y,
                cam.position.z,
                cam.attitude.heading.to_degrees(),
                cam.attitude.pitch.to_degrees(),
                cam.attitude.roll.to_degrees(),
                stats.csv_row()
            ));
            if write {
                let rgba = r.colour_rgba();
                let path = a.out.join(&c.folder).join(format!("frame_{f:04}.png"));
                write_png(&path, c.size.0, c.size.1, &rgba).map_err(runtime)?;
                pngs += 1;
                images.push(rgba);
            }
        }
        r.set_overlay(None);
        frame_ms.push(wall.elapsed().as_secs_f64() * 1e3);
        if write {
            let refs: Vec<&[u8]> = images.iter().map(|v| v.as_slice()).collect();
            let pano = map.compose(&refs, &sizes, !a.no_panorama_borders);
            let path = a.out.join(format!("panorama_{f:04}.png"));
            write_png(&path, canvas.width, canvas.height, &pano).map_err(runtime)?;
            panoramas += 1;
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let device = r.device_name().to_string();
    let counters = r.validation_counters();
    let validation = r.desc().validation;
    r.destroy();
    counters.verdict().map_err(runtime)?;
    write_text(&a.out.join("frames.csv"), &csv).map_err(runtime)?;
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
                "triangles": {"median": percentile(&tri, 0.5), "max": percentile(&tri, 1.0)},
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
        "frame_ms": {"median": percentile(&frame_ms, 0.5), "p99": percentile(&frame_ms, 0.99), "max": percentile(&frame_ms, 1.0)},
        "validation": {"enabled": validation, "errors": counters.errors(), "warnings": counters.warnings()},
    });
    write_text(&a.out.join("summary.json"), &format!("{summary:#}\n")).map_err(runtime)?;
    println!(
        "{} frames × {} channels ({} PNGs, {} panoramas {}x{}) in {}: frame median {:.1} ms, max {:.1} ms (all channels); validation clean",
        a.frames,
        chans.len(),
        pngs,
        panoramas,
        canvas.width,
        canvas.height,
        a.out.display(),
        percentile(&frame_ms, 0.5),
        percentile(&frame_ms, 1.0),
    );
    Ok(())
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
