//! `aerie bench`: run time against measured image-space error, every LOD mode (× τ for
//! `bounded`) on the same frames of one flight, the baselines measured in the same run (issue 5).
//!
//! One renderer per configuration, all alive at once, so each keeps its own clipmap caches,
//! refined-tile pools and (for `distance`) hysteresis exactly as in a real flight. Every frame's
//! camera is rendered by every configuration before the next frame, in an order rotated by one
//! per frame so that no configuration always runs first or last; the first `--warmup` frames
//! are rendered and written to `results.csv` (marked) but left out of the summaries.
//!
//! Per frame and configuration: wall time of `TerrainRenderer::render` (select, upload, record,
//! submit, wait — the read-back copy is recorded in the same submission), its CPU stages and GPU
//! timestamps, the frame statistics, the image-space error of the frame against the
//! full-resolution terrain ([`crate::tools::image_error::measure`], holes against a `full` reference
//! render of the same camera), and the CPU oracle of the selection
//! ([`crate::tools::image_error::oracle_selection`]). Outputs in `--out`: `results.csv`,
//! `summary.csv`, `summary.md`, `time_vs_error.png`, `triangles_vs_error.png` and one error
//! heat map per configuration (its worst frame).

mod plot;
mod report;

use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use clap::Args;
use glam::DVec3;

use crate::app::args::{read_waypoints, PassArgs};
use crate::app::failure::{bad_input, runtime, Failure};
use crate::app::flight_plan::FlightPlan;
use crate::app::out_path::prepare_out_folder;
use crate::app::prepare::prepare_terrain;
use crate::app::progress::count_bar;
use crate::app::renderer_setup::{parse_view, patch_tiles, renderer_desc, RendererChoice, View};
use crate::render::frame::{FrameStats, RendererDesc, TerrainRenderer};
use crate::sim::flight::Waypoints;
use crate::tools::image_error::{
    heatmap_rgba, measure, oracle_selection, ImageError, MeasureParams, OracleResult,
};
use crate::tools::output::{write_png, write_text};
use aerie_terrain::camera::{Attitude, Camera};
use aerie_terrain::clipmap::{place_levels, ClipmapDesc};
use aerie_terrain::dataset::Dataset;
use aerie_terrain::select::{select_tiles, LodMode, Selection};

pub use report::{pareto_front, Quantiles};

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Elevation model (any format `render` reads); its bake is read from or written next to it.
    #[arg(long)]
    pub dem: PathBuf,
    /// Output folder (created, with the folders above it): results.csv, summary.csv, summary.md, time_vs_error.png, ...
    #[arg(long)]
    pub out: PathBuf,
    /// Timed waypoints (`t_s,x_m,y_m,z_m,heading,pitch,roll` per line) instead of the built-in
    /// straight pass through the dataset's centre.
    #[arg(long)]
    pub flight: Option<PathBuf>,
    /// Measured frames (every configuration renders each).
    #[arg(long, default_value_t = 60)]
    pub frames: u32,
    /// Frames rendered first and left out of the summaries (caches, pools, pipelines warm up).
    #[arg(long, default_value_t = 3)]
    pub warmup: u32,
    /// Simulated frame rate: frame k is the pose at k / fps seconds.
    #[arg(long, default_value_t = 30.0)]
    pub fps: f64,
    #[command(flatten)]
    pub pass: PassArgs,
    /// Output size, WxH pixels.
    #[arg(long, default_value = "1920x1080")]
    pub size: String,
    /// Horizontal field of view, degrees (0 < fov < 180).
    #[arg(long, default_value_t = 90.0)]
    pub fov: f64,
    /// LOD modes, comma-separated: bounded, clipmap, distance, full.
    #[arg(long, default_value = "bounded,clipmap,distance,full")]
    pub modes: String,
    /// τ values (px) for `bounded`, comma-separated; the other modes ignore τ and run once.
    #[arg(long, default_value = "0.5,1,2,5,10")]
    pub tau: String,
    /// Clipmap patch side n in vertices (129 or 257).
    #[arg(long, default_value_t = 129)]
    pub patch: u32,
    /// Draw a flat Earth (no curvature drop).
    #[arg(long)]
    pub no_curvature: bool,
    /// Nodes per frame the CPU oracle checks by brute force (0: no oracle).
    #[arg(long, default_value_t = 12)]
    pub oracle_nodes: u32,
    /// Skip the image-space error (and the `full` reference render it needs).
    #[arg(long)]
    pub no_image_error: bool,
    /// Use the first Vulkan device whose name contains this (case-insensitive).
    #[arg(long)]
    pub gpu: Option<String>,
    /// Enable the Khronos validation layer (always on in debug builds; slows every frame).
    #[arg(long)]
    pub validate: bool,
}

/// One configuration of the run: a mode, and τ for `bounded`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BenchConfig {
    pub mode: LodMode,
    /// τ (px) for `bounded`; None for the modes that do not use it.
    pub tau_px: Option<f64>,
}

impl BenchConfig {
    pub fn mode_name(&self) -> &'static str {
        mode_name(self.mode)
    }

    /// "bounded τ=0.5", "clipmap".
    pub fn label(&self) -> String {
        match self.tau_px {
            Some(t) => format!("{} τ={t}", self.mode_name()),
            None => self.mode_name().to_string(),
        }
    }

    /// ASCII key for CSV cells and file names: "bounded_tau0.5", "clipmap".
    pub fn key(&self) -> String {
        match self.tau_px {
            Some(t) => format!("{}_tau{t}", self.mode_name()),
            None => self.mode_name().to_string(),
        }
    }

    /// τ the image error's "fraction above τ" and heat map use: the configuration's own, 1 px
    /// for the modes without one.
    pub fn tau_for_error(&self) -> f64 {
        self.tau_px.unwrap_or(1.0)
    }
}

pub fn mode_name(mode: LodMode) -> &'static str {
    match mode {
        LodMode::Bounded => "bounded",
        LodMode::Clipmap => "clipmap",
        LodMode::Full => "full",
        LodMode::Distance => "distance",
    }
}

/// Parses `--modes`: a comma-separated list of mode names, duplicates dropped, order kept.
pub fn parse_modes(s: &str) -> Result<Vec<LodMode>, String> {
    let mut out = Vec::new();
    for part in s.split(',').map(str::trim) {
        let mode = match part {
            "bounded" => LodMode::Bounded,
            "clipmap" => LodMode::Clipmap,
            "distance" => LodMode::Distance,
            "full" => LodMode::Full,
            "" => return Err(format!("--modes {s:?}: empty mode name")),
            other => {
                return Err(format!(
                "--modes {s:?}: unknown mode {other:?} (expected bounded, clipmap, distance, full)"
            ))
            }
        };
        if !out.contains(&mode) {
            out.push(mode);
        }
    }
    Ok(out)
}

/// Parses `--tau`: comma-separated positive pixel values, duplicates dropped, order kept.
pub fn parse_taus(s: &str) -> Result<Vec<f64>, String> {
    let mut out: Vec<f64> = Vec::new();
    for part in s.split(',').map(str::trim) {
        let t: f64 = part
            .parse()
            .map_err(|_| format!("--tau {s:?}: {part:?} is not a number"))?;
        if !(t.is_finite() && t > 0.0) {
            return Err(format!(
                "--tau {s:?}: {part} must be a positive number of pixels"
            ));
        }
        if !out.contains(&t) {
            out.push(t);
        }
    }
    Ok(out)
}

/// Every mode × τ for `bounded`, each other mode once, in the order of `modes`.
pub fn configurations(modes: &[LodMode], taus: &[f64]) -> Vec<BenchConfig> {
    let mut out = Vec::new();
    for &mode in modes {
        if mode == LodMode::Bounded {
            out.extend(taus.iter().map(|&t| BenchConfig {
                mode,
                tau_px: Some(t),
            }));
        } else {
            out.push(BenchConfig { mode, tau_px: None });
        }
    }
    out
}

/// Validated arguments.
struct Plan {
    view: View,
    configs: Vec<BenchConfig>,
    patch_tiles: u32,
    waypoints: Option<Waypoints>,
}

fn plan(a: &BenchArgs) -> Result<Plan, Failure> {
    let view = parse_view(&a.size, a.fov)?;
    let modes = parse_modes(&a.modes).map_err(bad_input)?;
    let taus = parse_taus(&a.tau).map_err(bad_input)?;
    if a.frames == 0 {
        return Err(bad_input("--frames: must be at least 1"));
    }
    if a.oracle_nodes > 4096 {
        return Err(bad_input(format!(
            "--oracle-nodes: {} is more than 4096",
            a.oracle_nodes
        )));
    }
    a.pass.check(a.fps)?;
    let patch_tiles = patch_tiles(a.patch)?;
    let waypoints = read_waypoints("--flight", a.flight.as_ref())?;
    Ok(Plan {
        view,
        configs: configurations(&modes, &taus),
        patch_tiles,
        waypoints,
    })
}

/// The renderer of one configuration: `full` gets pools large enough to draw every visible
/// tile at full resolution (as `aerie render --lod full`).
fn lane_desc(a: &BenchArgs, p: &Plan, config: BenchConfig) -> RendererDesc {
    renderer_desc(&RendererChoice {
        gpu: a.gpu.clone(),
        validate: a.validate,
        width: p.view.width,
        height: p.view.height,
        patch_tiles: p.patch_tiles,
        mode: config.mode,
        tau_px: config.tau_px.unwrap_or(1.0),
        curvature: !a.no_curvature,
        debug_tiles: false,
    })
}

/// One frame of one configuration, as written to `results.csv`.
#[derive(Debug, Clone)]
pub(crate) struct FrameRow {
    pub frame: u32,
    pub warmup: bool,
    pub time_s: f64,
    pub position: DVec3,
    pub attitude: Attitude,
    pub config: usize,
    pub wall_ms: f64,
    pub stats: FrameStats,
    pub image: Option<ImageRow>,
    pub oracle: Option<OracleResult>,
}

/// The image error of one frame, reduced to what a CSV row holds.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ImageRow {
    pub max_px: f64,
    /// Largest error confirmed by a neighbouring pixel ([`ImageError::confirmed`]).
    pub confirmed_max_px: f64,
    pub p99_px: f64,
    pub mean_px: f64,
    pub fraction_over_tau: f64,
    pub measured_px: u64,
    pub holes_px: u64,
    pub hole_max_px: f64,
    pub extra_px: u64,
    pub max_at: Option<(u32, u32)>,
}

impl ImageRow {
    fn of(e: &ImageError) -> Self {
        Self {
            max_px: e.max_px(),
            confirmed_max_px: e.confirmed_max_px(),
            p99_px: e.p99_px(),
            mean_px: e.mean_px(),
            fraction_over_tau: e.fraction_over_tau(),
            measured_px: e.hist.count(),
            holes_px: e.holes_px,
            hole_max_px: e.hole_max_px,
            extra_px: e.extra_px,
            max_at: e.max_at,
        }
    }
}

/// A configuration's renderer with its CPU mirror of the selection (for the oracle) and its
/// worst frame so far.
struct Lane {
    config: BenchConfig,
    renderer: TerrainRenderer,
    /// Reported in the summaries (false for a `full` renderer made only as the reference).
    reported: bool,
    selection: Selection,
    depth: Vec<f32>,
    heat: Vec<f32>,
    worst_heat: Vec<f32>,
    worst: Option<(u32, f64)>,
    image_total: ImageError,
}

pub fn run(a: BenchArgs) -> Result<(), Failure> {
    let mut p = plan(&a)?;
    prepare_out_folder("--out", &a.out)?;
    let tile_size = RendererDesc::default().tile_size;
    let (ds, bake) = prepare_terrain(&a.dem, tile_size)?;
    let total_frames = a.warmup + a.frames;
    let duration = total_frames as f64 / a.fps;
    let flight = FlightPlan::new(&ds, &a.pass, p.waypoints.take(), duration);
    let image_error = !a.no_image_error;
    let mut lane_configs: Vec<(BenchConfig, bool)> = p.configs.iter().map(|&c| (c, true)).collect();
    let has_full = p.configs.iter().any(|c| c.mode == LodMode::Full);
    if image_error && !has_full {
        lane_configs.push((
            BenchConfig {
                mode: LodMode::Full,
                tau_px: None,
            },
            false,
        ));
    }
    let eye0 = flight.pose_at(0.0).0;
    let t_setup = Instant::now();
    let mut lanes: Vec<Lane> = Vec::new();
    for &(config, reported) in &lane_configs {
        let desc = lane_desc(&a, &p, config);
        let mut renderer = TerrainRenderer::new(&desc).map_err(runtime)?;
        renderer
            .load_terrain(ds.clone(), bake.clone(), eye0)
            .map_err(|e| runtime(format!("{}: {e}", config.label())))?;
        lanes.push(Lane {
            config,
            renderer,
            reported,
            selection: Selection::default(),
            depth: Vec::new(),
            heat: Vec::new(),
            worst_heat: Vec::new(),
            worst: None,
            image_total: ImageError {
                tau_px: config.tau_for_error(),
                ..Default::default()
            },
        });
    }
    let device = lanes[0].renderer.device_name().to_string();
    eprintln!(
        "{} renderers on {device} ({:.1} s): {}",
        lanes.len(),
        t_setup.elapsed().as_secs_f64(),
        lanes
            .iter()
            .map(|l| if l.reported {
                l.config.label()
            } else {
                "full (reference only)".to_string()
            })
            .collect::<Vec<_>>()
            .join(", ")
    );
    let clip = ClipmapDesc {
        tile_quads: tile_size - 1,
        patch_tiles: p.patch_tiles,
        margin_tiles: RendererDesc::default().margin_tiles,
        width: ds.hf.width as u32,
        height: ds.hf.height as u32,
    };
    let reference = lanes
        .iter()
        .position(|l| l.config.mode == LodMode::Full)
        .filter(|_| image_error);
    let bar = count_bar(total_frames as u64 * lanes.len() as u64, "renders", "");
    let mut rows: Vec<FrameRow> = Vec::new();
    let size = (p.view.width, p.view.height);
    let n = lanes.len();
    // indicatif draws nothing when stderr is not a terminal (CI logs, nohup): print a plain
    // line per ~10 % of the frames there instead.
    let plain_progress = !std::io::stderr().is_terminal();
    let started = Instant::now();
    let every = (total_frames / 10).max(1);
    for k in 0..total_frames {
        if plain_progress && k > 0 && k % every == 0 {
            let elapsed = started.elapsed().as_secs_f64();
            eprintln!(
                "bench: {k}/{total_frames} frames × {n} configurations, {elapsed:.0} s elapsed, eta {:.0} s",
                elapsed / k as f64 * (total_frames - k) as f64
            );
        }
        let warmup = k < a.warmup;
        bar.set_message(if warmup {
            format!("warm-up {}/{}", k + 1, a.warmup)
        } else {
            format!("frame {}/{}", k - a.warmup + 1, a.frames)
        });
        let t = k as f64 / a.fps;
        let (pos, att) = flight.pose_at(t);
        let camera = Camera::new(pos, att, p.view.frustum);
        let mut results: Vec<Option<(f64, FrameStats)>> = vec![None; n];
        for j in 0..n {
            let i = (j + k as usize) % n;
            let lane = &mut lanes[i];
            let t0 = Instant::now();
            let stats = lane
                .renderer
                .render(&camera)
                .map_err(|e| runtime(format!("{} frame {k}: {e}", lane.config.label())))?;
            let wall_ms = t0.elapsed().as_secs_f64() * 1e3;
            if image_error {
                lane.depth = lane.renderer.depth();
            }
            results[i] = Some((wall_ms, stats));
            bar.inc(1);
        }
        let viewer = [pos.x / ds.hf.spacing_x, pos.y / ds.hf.spacing_y];
        let placements = place_levels(&clip, viewer);
        let reference_depth = reference.map(|r| std::mem::take(&mut lanes[r].depth));
        for (i, lane) in lanes.iter_mut().enumerate() {
            let (wall_ms, stats) = results[i].expect("rendered");
            let image = if image_error {
                let own = std::mem::take(&mut lane.depth);
                let depth = if Some(i) == reference {
                    reference_depth.as_deref().expect("reference depth")
                } else {
                    &own
                };
                Some(measure_lane(
                    &ds,
                    &camera,
                    size,
                    depth,
                    reference_depth.as_deref(),
                    &a,
                    lane,
                    k,
                    warmup,
                ))
            } else {
                None
            };
            let oracle = if a.oracle_nodes > 0 {
                let desc = lane.renderer.desc();
                select_tiles(
                    &bake,
                    &clip,
                    &placements,
                    &camera,
                    size,
                    &desc.select,
                    &mut lane.selection,
                );
                Some(oracle_selection(
                    &ds,
                    &camera,
                    size,
                    clip.tile_quads,
                    &lane.selection.items,
                    desc.select.curvature,
                    a.oracle_nodes as usize,
                    k as u64 * 131 + i as u64,
                ))
            } else {
                None
            };
            if lane.reported {
                rows.push(FrameRow {
                    frame: k,
                    warmup,
                    time_s: t,
                    position: pos,
                    attitude: att,
                    config: i,
                    wall_ms,
                    stats,
                    image,
                    oracle,
                });
            }
        }
    }
    bar.finish_and_clear();

    let mut validation = Vec::new();
    for lane in &mut lanes {
        let counters = lane.renderer.validation_counters();
        lane.renderer.destroy();
        if let Err(e) = counters.verdict() {
            validation.push(format!("{}: {e}", lane.config.label()));
        }
    }
    if let Some(first) = validation.first() {
        return Err(runtime(first));
    }

    let reported: Vec<&Lane> = lanes.iter().filter(|l| l.reported).collect();
    let configs: Vec<BenchConfig> = reported.iter().map(|l| l.config).collect();
    let totals: Vec<Option<&ImageError>> = reported
        .iter()
        .map(|l| image_error.then_some(&l.image_total))
        .collect();
    let summaries = report::summarize(&configs, &rows, &totals);
    let meta = report::RunInfo {
        device,
        dem: a.dem.display().to_string(),
        dataset: ds.summary(),
        size,
        fov_deg: a.fov,
        frames: a.frames,
        warmup: a.warmup,
        flight: match &a.flight {
            Some(f) => format!("waypoints {}", f.display()),
            None => format!(
                "built-in straight pass, heading {}°, pitch {}°, {} m/s, {} m {}, {} fps",
                a.pass.heading,
                a.pass.pitch,
                a.pass.speed,
                a.pass.agl,
                if a.pass.follow_terrain {
                    "above the ground"
                } else {
                    "above the highest sample"
                },
                a.fps
            ),
        },
        validation: lanes[0].renderer.desc().validation,
        image_error,
        oracle_nodes: a.oracle_nodes,
    };
    let out = &a.out;
    write_text(
        &out.join("results.csv"),
        &report::results_csv(&configs, &rows),
    )
    .map_err(runtime)?;
    write_text(&out.join("summary.csv"), &report::summary_csv(&summaries)).map_err(runtime)?;
    let md = report::summary_md(&meta, &summaries);
    write_text(&out.join("summary.md"), &md).map_err(runtime)?;
    plot::time_vs_error(&out.join("time_vs_error.png"), &summaries).map_err(runtime)?;
    plot::triangles_vs_error(&out.join("triangles_vs_error.png"), &summaries).map_err(runtime)?;
    let mut heatmaps = 0;
    for lane in &reported {
        if let Some((frame, _)) = lane.worst {
            let scale = 2.0 * lane.config.tau_for_error();
            let path = out.join(format!("heatmap_{}_frame{frame:04}.png", lane.config.key()));
            write_png(
                &path,
                p.view.width,
                p.view.height,
                &heatmap_rgba(&lane.worst_heat, scale),
            )
            .map_err(runtime)?;
            heatmaps += 1;
        }
    }
    println!("{}", report::summary_table(&summaries));
    println!(
        "{} configurations × {} frames ({} warm-up) on {}: {}/results.csv, summary.csv, summary.md, time_vs_error.png, triangles_vs_error.png, {heatmaps} heat maps",
        configs.len(),
        a.frames,
        a.warmup,
        meta.device,
        out.display()
    );
    Ok(())
}

/// Measures one lane's frame, accumulates it (outside warm-up) and keeps its worst heat map.
#[allow(clippy::too_many_arguments)]
fn measure_lane(
    ds: &Arc<Dataset>,
    camera: &Camera,
    size: (u32, u32),
    depth: &[f32],
    reference: Option<&[f32]>,
    a: &BenchArgs,
    lane: &mut Lane,
    frame: u32,
    warmup: bool,
) -> ImageRow {
    let params = MeasureParams {
        tau_px: lane.config.tau_for_error(),
        curvature: !a.no_curvature,
        ..MeasureParams::default()
    };
    let pixels = size.0 as usize * size.1 as usize;
    lane.heat.resize(pixels, 0.0);
    let e = measure(
        ds,
        camera,
        size,
        depth,
        reference,
        &params,
        Some(&mut lane.heat),
    );
    if !warmup {
        lane.image_total.merge(&e);
        let worse = match lane.worst {
            None => true,
            Some((_, m)) => e.confirmed_max_px() > m,
        };
        if worse {
            lane.worst = Some((frame, e.confirmed_max_px()));
            std::mem::swap(&mut lane.heat, &mut lane.worst_heat);
        }
    }
    ImageRow::of(&e)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn modes_and_taus_parse_and_expand() {
        let modes = parse_modes("bounded, clipmap,full,bounded").unwrap();
        assert_eq!(
            modes,
            vec![LodMode::Bounded, LodMode::Clipmap, LodMode::Full]
        );
        let taus = parse_taus("0.5,1,2,1").unwrap();
        assert_eq!(taus, vec![0.5, 1.0, 2.0]);
        let c = configurations(&modes, &taus);
        assert_eq!(c.len(), 5);
        assert_eq!(c[0].label(), "bounded τ=0.5");
        assert_eq!(c[0].key(), "bounded_tau0.5");
        assert_eq!(c[3].key(), "clipmap");
        assert_eq!(c[4].tau_for_error(), 1.0);
        for (bad, word) in [("bounded,fast", "fast"), ("", "empty"), ("full,,", "empty")] {
            let e = parse_modes(bad).unwrap_err();
            assert!(e.contains(word) && e.contains("--modes"), "{e}");
        }
        for (bad, word) in [
            ("1,x", "\"x\""),
            ("0", "positive"),
            ("-1", "positive"),
            ("nan", "positive"),
        ] {
            let e = parse_taus(bad).unwrap_err();
            assert!(e.contains(word) && e.contains("--tau"), "{e}");
        }
    }
}
