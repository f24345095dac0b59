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
//! heat map per configuration (its worst frame). The folder must be empty, or `--overwrite`
//! removes what an earlier `bench` wrote there ([`BENCH_FILES`]). A file that cannot be written
//! does not stop the others: every output is tried, `summary.md` lists the ones that failed
//! before it, and the command exits 1 naming the first.

mod config;
mod plot;
mod report;
mod rows;

use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use clap::Args;

use crate::app::args::{read_waypoints, PassArgs};
use crate::app::failure::{bad_input, runtime, Failure};
use crate::app::flight_plan::FlightPlan;
use crate::app::out_path::{prepare_run_folder, WriteFailures, BENCH_FILES};
use crate::app::prepare::prepare_terrain;
use crate::app::progress::count_bar;
use crate::app::renderer_setup::{parse_view, patch_tiles, renderer_desc, RendererChoice, View};
use crate::render::frame::{FrameStats, RendererDesc, TerrainRenderer};
use crate::sim::flight::Waypoints;
use crate::tools::image_error::{
    heatmap_rgba, measure, oracle_selection, ImageError, MeasureParams,
};
use crate::tools::output::{write_png, write_text};
use aerie_terrain::camera::Camera;
use aerie_terrain::clipmap::{place_levels, ClipmapDesc};
use aerie_terrain::dataset::Dataset;
use aerie_terrain::select::{select_tiles, LodMode, Selection};

pub use config::{configurations, mode_name, parse_modes, parse_taus, BenchConfig};
pub use report::{pareto_front, Quantiles};
use rows::{FrameRow, ImageRow};

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Elevation model (any format `render` reads); its bake is read from or written next to it.
    #[arg(long)]
    pub dem: PathBuf,
    /// Output folder (created, with the folders above it): results.csv, summary.csv, summary.md, time_vs_error.png, ...
    /// It must be empty unless --overwrite.
    #[arg(long)]
    pub out: PathBuf,
    /// Reuse a non-empty --out folder: first remove the files an earlier `aerie bench` wrote
    /// there (results.csv, summary.csv, summary.md, the charts, heatmap_*.png); anything else in
    /// it is kept.
    #[arg(long)]
    pub overwrite: bool,
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
    let removed = prepare_run_folder("--out", &a.out, a.overwrite, &BENCH_FILES)?;
    if removed > 0 {
        eprintln!(
            "--overwrite: removed {removed} files of an earlier bench from {}",
            a.out.display()
        );
    }
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
    // Every output is tried even when one fails; the charts and heat maps go first so that
    // summary.md can list what is missing.
    let mut failures = WriteFailures::default();
    let path = out.join("time_vs_error.png");
    failures.check(None, &path, plot::time_vs_error(&path, &summaries));
    let path = out.join("triangles_vs_error.png");
    failures.check(None, &path, plot::triangles_vs_error(&path, &summaries));
    let mut heatmaps = 0;
    for lane in &reported {
        if let Some((frame, _)) = lane.worst {
            let scale = 2.0 * lane.config.tau_for_error();
            let path = out.join(format!("heatmap_{}_frame{frame:04}.png", lane.config.key()));
            let rgba = heatmap_rgba(&lane.worst_heat, scale);
            let written = write_png(&path, p.view.width, p.view.height, &rgba);
            heatmaps += failures.check(None, &path, written) as u32;
        }
    }
    let path = out.join("results.csv");
    failures.check(
        None,
        &path,
        write_text(&path, &report::results_csv(&configs, &rows)),
    );
    let path = out.join("summary.csv");
    failures.check(
        None,
        &path,
        write_text(&path, &report::summary_csv(&summaries)),
    );
    let mut md = report::summary_md(&meta, &summaries);
    if !failures.failed.is_empty() {
        md.push_str("\n## Files not written\n\n");
        for f in &failures.failed {
            md.push_str(&format!("- {}\n", f.error));
        }
    }
    let path = out.join("summary.md");
    let written = write_text(&path, &md);
    let md_written = failures.check(None, &path, written);
    println!("{}", report::summary_table(&summaries));
    println!(
        "{} configurations × {} frames ({} warm-up) on {}: {}/results.csv, summary.csv, summary.md, time_vs_error.png, triangles_vs_error.png, {heatmaps} heat maps",
        configs.len(),
        a.frames,
        a.warmup,
        meta.device,
        out.display()
    );
    failures.verdict(md_written.then_some(path.as_path()))
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
