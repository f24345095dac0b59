//! `aerie bench`: run time against measured image-space error, every LOD mode (× τ for
//! `bounded`) on the same frames of one flight, the baselines measured in the same run (issue 5).
//!
//! One renderer per configuration, all alive at once, so each keeps its own clipmap caches,
//! refined-tile pools and (for `distance`) hysteresis exactly as in a real flight. Every frame's
//! camera is rendered by every configuration before the next frame, in an order rotated by one
//! per frame so that no configuration always runs first or last (each replay in another order:
//! `replays::lane_order`); the first `--warmup` frames are rendered and written to
//! `results.csv` (marked) but left out of the summaries.
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
//!
//! Each baseline can be swept over its own knob (`--clipmap-n`, `--distance-scale`,
//! `--cdlod-range`), so that it is a curve like `bounded` over τ; `--suite` runs a TOML file of
//! datasets × flights and writes one combined report (`suite.rs`).

mod args;
mod config;
pub mod curves;
mod features;
mod flights;
mod lanes;
mod plot;
mod plot_labels;
mod replays;
mod report;
mod rows;
mod settle;
mod suite;
mod suite_config;
mod suite_report;
mod suite_resume;

use std::io::IsTerminal;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use crate::app::failure::{bad_input, runtime, Failure};
use crate::app::flight_plan::FlightPlan;
use crate::app::out_path::{prepare_run_folder, WriteFailures, BENCH_FILES};
use crate::app::prepare::{prepare_source, prepare_terrain, Terrain};
use crate::app::progress::count_bar;
use crate::render::frame::{FrameStats, RendererDesc};
use crate::tools::image_error::{
    heatmap_rgba, measure, oracle_selection, ImageError, MeasureParams,
};
use crate::tools::output::{write_png, write_text};
use aerie_terrain::bake::{BakeParams, ErrorBake};
use aerie_terrain::camera::Camera;
use aerie_terrain::clipmap::{place_levels, ClipmapDesc};
use aerie_terrain::dataset::Dataset;
use aerie_terrain::select::{select_tiles, LodMode};
use aerie_terrain::source::{InMemoryTerrain, TerrainSource};

pub use args::BenchArgs;
use args::{plan, Plan};
pub use config::{
    configurations, mode_name, parse_modes, parse_positive_list, parse_taus, BenchConfig, Sweeps,
};
use lanes::Lane;
use replays::{FrameReplays, ReplayTally};
pub use report::{pareto_front, Quantiles};
use rows::{FrameRow, ImageRow};

pub fn run(a: BenchArgs) -> Result<(), Failure> {
    if let Some(file) = &a.suite {
        let paths = suite::SuitePaths {
            file,
            data: a.data.as_deref(),
            out: &a.out,
            overwrite: a.overwrite,
            resume: a.resume,
            command_line: a.result_settings(),
            replays: a.replays,
        };
        return suite::run(&paths, &mut |job| suite_flight(&a, job));
    }
    let Some(dem) = a.dem.clone() else {
        return Err(bad_input("--dem: required without --suite"));
    };
    let mut p = plan(&a)?;
    let tile_size = RendererDesc::default().tile_size;
    let source_desc = RendererDesc {
        patch_tiles: p.patch_tiles,
        ..RendererDesc::default()
    };
    let terrain = prepare_source(&dem, &source_desc, &a.store)?;
    if terrain.dataset.is_none() && p.configs.iter().any(|c| c.tile_size.is_some()) {
        return Err(bad_input(format!(
            "--tile-sizes {}: a streamed store is drawn with the tiles it was imported with \
             ({tile_size}); bench other tile sizes on the dataset in memory",
            a.tile_sizes
        )));
    }
    // The truth the measurements need: the samples themselves, whole.
    let (ds, bake) = match &terrain.dataset {
        Some(ds) => (ds.clone(), terrain.bake.clone()),
        None => prepare_terrain(&dem, tile_size)?,
    };
    let total_frames = a.warmup + a.frames;
    let duration = total_frames as f64 / a.fps;
    let flight = FlightPlan::new(&terrain, &a.pass, p.waypoints.take(), duration)
        .map_err(|e| bad_input(format!("--flight: {e}")))?;
    let described = match &a.flight {
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
    };
    let input = FlightInput {
        dem: &dem,
        ds: &ds,
        bake: &bake,
        flight: &flight,
        described,
        source: terrain.source.clone(),
    };
    run_flight(&a, &p, &input, &a.out).map(|_| ())
}

/// One flight of a suite: the command's arguments with the suite's settings, its waypoints.
fn suite_flight(
    a: &BenchArgs,
    job: &suite::FlightJob,
) -> Result<(String, Vec<report::Summary>), Failure> {
    let r = job.run;
    let join = |v: &[f64]| v.iter().map(f64::to_string).collect::<Vec<_>>().join(",");
    let mut args = a.clone();
    args.size = r.size.clone();
    args.fov = r.fov;
    args.frames = r.frames;
    args.warmup = r.warmup;
    args.settle = r.settle;
    args.replays = Some(r.replays);
    args.fps = r.fps;
    args.modes = r.modes.clone();
    args.tau = join(&r.tau);
    let clipmap_n: Vec<f64> = r.sweeps.clipmap_n.iter().map(|&n| n as f64).collect();
    args.clipmap_n = join(&clipmap_n);
    args.distance_scale = join(&r.sweeps.distance_scale);
    args.cdlod_range = join(&r.sweeps.cdlod_range);
    args.tess_density = join(&r.sweeps.tess_density);
    let tile_sizes: Vec<f64> = r.sweeps.tile_sizes.iter().map(|&m| m as f64).collect();
    args.tile_sizes = join(&tile_sizes);
    args.oracle_nodes = r.oracle_nodes;
    args.flight = None;
    // A flight flown again under --resume replaces what an interrupted run left in its folder.
    args.overwrite = a.overwrite || a.resume;
    let p = plan(&args)?;
    let duration = (r.warmup + r.frames) as f64 / r.fps;
    let terrain = Terrain::in_memory(job.ds.clone(), job.bake.clone());
    let flight = FlightPlan::new(&terrain, &args.pass, Some(job.waypoints.clone()), duration)
        .map_err(|e| runtime(format!("{}: {e}", job.described)))?;
    let input = FlightInput {
        dem: job.dem,
        ds: job.ds,
        bake: job.bake,
        flight: &flight,
        described: job.described.clone(),
        source: terrain.source.clone(),
    };
    let outcome = run_flight(&args, &p, &input, &job.out)?;
    Ok((outcome.device, outcome.summaries))
}

/// What one benched flight flies over and along.
pub(crate) struct FlightInput<'a> {
    pub dem: &'a Path,
    pub ds: &'a Arc<Dataset>,
    pub bake: &'a Arc<aerie_terrain::bake::ErrorBake>,
    pub flight: &'a FlightPlan,
    /// The flight in words, for summary.md.
    pub described: String,
    /// What the measured configurations draw from (a streamed store, or the dataset).
    pub source: Arc<dyn TerrainSource>,
}

/// What one benched flight gives the suite: the device and every configuration's summary.
pub(crate) struct FlightOutcome {
    pub device: String,
    pub summaries: Vec<report::Summary>,
}

/// Benches every configuration of `p` along one flight into `out` (a `bench` run folder).
fn run_flight(
    a: &BenchArgs,
    p: &Plan,
    input: &FlightInput,
    out: &Path,
) -> Result<FlightOutcome, Failure> {
    let removed = prepare_run_folder("--out", out, a.overwrite, &BENCH_FILES)?;
    if removed > 0 {
        eprintln!(
            "--overwrite: removed {removed} files of an earlier bench from {}",
            out.display()
        );
    }
    let (ds, bake, flight) = (input.ds, input.bake, input.flight);
    let tile_size = RendererDesc::default().tile_size;
    let total_frames = a.warmup + a.frames;
    let in_memory: Arc<dyn TerrainSource> = Arc::new(InMemoryTerrain::with_checksum(
        ds.clone(),
        bake.source_checksum,
    ));
    let image_error = !a.no_image_error;
    let mut lane_configs: Vec<(BenchConfig, bool)> = p.configs.iter().map(|&c| (c, true)).collect();
    let has_full = p.configs.iter().any(|c| c.mode == LodMode::Full);
    if image_error && !has_full && !a.no_holes {
        lane_configs.push((
            BenchConfig {
                mode: LodMode::Full,
                tau_px: None,
                knob: None,
                tile_size: None,
            },
            false,
        ));
    }
    let eye0 = flight.pose_at(0.0).0;
    let bakes = bakes_for_tile_sizes(ds, bake, &p.configs)?;
    let t_setup = Instant::now();
    let mut lanes: Vec<Lane> = Vec::new();
    let drape = crate::app::renderer_setup::drape_input(&a.drape)?;
    // `--drape-mb` also bounds a store's imagery layer (what is held whole, what streams).
    let drape_budget = crate::app::renderer_setup::drape_budget(&a.drape)?;
    let inputs = lanes::LaneInputs {
        a,
        p,
        drape,
        drape_budget,
        bakes: &bakes,
        eye0,
    };
    for &(config, reported) in &lane_configs {
        // Measured configurations draw from the source given; the reference from memory.
        let source = if reported {
            input.source.clone()
        } else {
            in_memory.clone()
        };
        let renderer = inputs.open(config, source, |_| {})?;
        lanes.push(Lane::new(config, renderer, reported, None));
    }
    if lanes.is_empty() {
        return Err(bad_input(format!(
            "--modes: no configuration runs on {}",
            input.dem.display()
        )));
    }
    let mut costs = None;
    if a.feature_costs {
        let base = lanes[0].config;
        let r = &lanes[0].renderer;
        let features = features::features_on(r.desc(), r.draped().0.is_some());
        for (v, f) in features.iter().enumerate() {
            let renderer = inputs.open(base, input.source.clone(), |d| f.apply(d))?;
            lanes.push(Lane::new(base, renderer, false, Some(v)));
        }
        costs = Some(features::FeatureCosts::new(base.label(), &features));
    }
    let device = lanes[0].renderer.device_name().to_string();
    eprintln!(
        "{} renderers on {device} ({:.1} s): {}",
        lanes.len(),
        t_setup.elapsed().as_secs_f64(),
        lanes
            .iter()
            .map(|l| match (l.reported, l.variant) {
                (true, _) => l.config.label(),
                (false, Some(_)) => format!("{} with a feature off", l.config.label()),
                (false, None) => "full (reference only)".to_string(),
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
        .position(|l| l.config.mode == LodMode::Full && l.variant.is_none())
        .filter(|_| image_error);
    let startup = lanes::settle_lanes(&mut lanes, flight, p, a.settle, false)?;
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
        for i in replays::lane_order(n, 0, k) {
            let lane = &mut lanes[i];
            let t0 = Instant::now();
            let stats = lane
                .renderer
                .render(&camera)
                .map_err(|e| runtime(format!("{} frame {k}: {e}", lane.config.label())))?;
            let wall_ms = t0.elapsed().as_secs_f64() * 1e3;
            if image_error && lane.variant.is_none() {
                lane.depth = lane.renderer.depth();
            }
            results[i] = Some((wall_ms, stats));
            bar.inc(1);
        }
        let viewer = [pos.x / ds.hf.spacing_x, pos.y / ds.hf.spacing_y];
        let reference_depth = reference.map(|r| std::mem::take(&mut lanes[r].depth));
        for (i, lane) in lanes.iter_mut().enumerate() {
            let (wall_ms, stats) = results[i].expect("rendered");
            if let (Some(c), false) = (costs.as_mut(), warmup) {
                if lane.variant.is_some() || i == 0 {
                    c.push(lane.variant, &stats);
                }
            }
            if lane.variant.is_some() {
                continue;
            }
            let image = if image_error {
                let own = std::mem::take(&mut lane.depth);
                let depth = if Some(i) == reference {
                    reference_depth.as_deref().expect("reference depth")
                } else {
                    &own
                };
                Some(measure_lane(
                    ds,
                    &camera,
                    size,
                    depth,
                    reference_depth.as_deref(),
                    a,
                    lane,
                    k,
                    warmup,
                ))
            } else {
                None
            };
            // The oracle checks tile selections; the tessellation baseline draws none.
            let tiles = lane.config.mode != LodMode::Tessellation;
            let oracle = if a.oracle_nodes > 0 && tiles {
                let desc = lane.renderer.desc();
                // Each lane's own patch (a swept clipmap has its own) and tiles.
                let clip = ClipmapDesc {
                    patch_tiles: desc.patch_tiles,
                    tile_quads: desc.tile_size - 1,
                    ..clip
                };
                let placements = place_levels(&clip, viewer);
                select_tiles(
                    lanes::bake_for(&bakes, desc.tile_size)?,
                    &clip,
                    &placements,
                    &camera,
                    size,
                    &desc.select,
                    &mut lane.selection,
                );
                Some(oracle_selection(
                    ds,
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
                    replays: FrameReplays::first(wall_ms),
                });
            }
        }
    }
    bar.finish_and_clear();

    let mut validation = Vec::new();
    lanes::replay(
        &mut lanes,
        &inputs,
        &input.source,
        flight,
        &mut rows,
        &mut validation,
    )?;
    let replayed = ReplayTally::of(
        a.replays(),
        rows.iter().filter(|r| !r.warmup).map(|r| &r.replays),
    );
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
        dem: input.dem.display().to_string(),
        dataset: ds.summary(),
        size,
        fov_deg: a.fov,
        frames: a.frames,
        warmup: a.warmup,
        flight: input.described.clone(),
        validation: lanes[0].renderer.desc().validation,
        image_error,
        oracle_nodes: a.oracle_nodes,
        startup,
        replays: replayed.describe(),
    };
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
    if a.no_holes && !p.configs.iter().any(|c| c.mode == LodMode::Full) {
        md.push_str("\nHoles not measured (`--no-holes`: no `full` reference was drawn); the holes column is 0.\n");
    }
    if let Some(c) = &costs {
        md.push_str(&c.markdown());
        let path = out.join("features.csv");
        failures.check(None, &path, write_text(&path, &c.csv()));
        for (f, median, _, cost) in c.rows() {
            eprintln!(
                "feature cost, {}: {} off {median:.3} GPU terrain ms, the feature {cost:+.3} ms",
                c.base_label,
                f.name()
            );
        }
    }
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
    failures.verdict(md_written.then_some(path.as_path()))?;
    Ok(FlightOutcome {
        device: meta.device,
        summaries,
    })
}

/// The given bake (of the default tile size) and one more, made in memory, for each other
/// tile size among `configs` (`--tile-sizes`).
fn bakes_for_tile_sizes(
    ds: &Arc<Dataset>,
    bake: &Arc<ErrorBake>,
    configs: &[BenchConfig],
) -> Result<Vec<Arc<ErrorBake>>, Failure> {
    let mut bakes = vec![bake.clone()];
    for c in configs {
        let m = c.tile_size_or_default();
        if bakes.iter().any(|b| b.params.tile_size == m) {
            continue;
        }
        let params = BakeParams {
            tile_size: m,
            levels: 0,
        };
        params
            .resolve_levels(ds)
            .map_err(|e| bad_input(format!("--tile-sizes: tiles of {m}: {e}")))?;
        let t = Instant::now();
        let b = aerie_terrain::bake::bake(ds, params, &|_: u64, _: u64| {});
        eprintln!(
            "baked tiles of {m} in memory ({} levels, {:.2} s)",
            b.levels.len(),
            t.elapsed().as_secs_f64()
        );
        bakes.push(Arc::new(b));
    }
    Ok(bakes)
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
