//! `aerie bench --suite <file>`: every (dataset, flight) pair of a suite file benched as one
//! `bench` run into `<out>/<dataset>-<flight>/`, its waypoints in `<out>/flights/`, then one
//! combined report (`suite_report.rs`).
//!
//! Inputs are never touched where they lie: a dataset given by path is copied (the file, its
//! raw sidecar, or the regular files of its folder) into a temporary folder, where its bake is
//! written; a generated one is generated there. The folder is removed at the end.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::flights::waypoints_csv;
use super::report::Summary;
use super::suite_config::{parse_suite, DatasetSource, DatasetSpec, RunSettings, Suite};
use super::suite_report::{write_report, FlightResult, SuiteInfo};
use super::suite_resume::{
    fingerprint, read_record, remove_record, write_record, FlightRecord, Resume,
};
use crate::app::failure::{bad_input, runtime, Failure};
use crate::app::prepare::prepare_terrain;
use crate::render::frame::RendererDesc;
use crate::sim::flight::Waypoints;
use crate::tools::output::write_text;
use aerie_terrain::bake::ErrorBake;
use aerie_terrain::dataset::Dataset;

/// One (dataset, flight) for the command's flight runner.
pub(crate) struct FlightJob<'a> {
    pub run: &'a RunSettings,
    pub dem: &'a Path,
    pub ds: &'a Arc<Dataset>,
    pub bake: &'a Arc<ErrorBake>,
    pub waypoints: Waypoints,
    /// The flight in words, for its summary.md.
    pub described: String,
    /// Its `bench` run folder.
    pub out: PathBuf,
}

/// What a benched flight gives back: the device's name and every configuration's summary.
pub(crate) type FlightRunner<'r> =
    dyn FnMut(&FlightJob) -> Result<(String, Vec<Summary>), Failure> + 'r;

/// Where a suite's inputs and outputs are.
pub(crate) struct SuitePaths<'a> {
    pub file: &'a Path,
    /// `--data`: the root of relative dataset paths (default: the suite file's folder).
    pub data: Option<&'a Path>,
    pub out: &'a Path,
    pub overwrite: bool,
    /// `--resume`: flights whose record matches are taken from it (`suite_resume.rs`).
    pub resume: bool,
    /// The command line's options that change a flight's results
    /// (`BenchArgs::result_settings`): part of each flight's fingerprint, so `--resume` never
    /// takes a flight run with other ones.
    pub command_line: String,
    /// `--replays`: replaces the suite's `run.replays` (in its flights' records too).
    pub replays: Option<u32>,
}

/// Largest suite file read.
const MAX_SUITE_BYTES: u64 = 1 << 20;

/// Runs the suite file: every pair through `flight`, then the combined report.
pub(super) fn run(paths: &SuitePaths, flight: &mut FlightRunner) -> Result<(), Failure> {
    let file = paths.file;
    let name = file.display().to_string();
    let meta = std::fs::metadata(file).map_err(|e| bad_input(format!("--suite {name}: {e}")))?;
    if meta.len() > MAX_SUITE_BYTES {
        return Err(bad_input(format!(
            "--suite {name}: {} bytes, more than the {MAX_SUITE_BYTES}-byte limit",
            meta.len()
        )));
    }
    let text =
        std::fs::read_to_string(file).map_err(|e| bad_input(format!("--suite {name}: {e}")))?;
    let mut suite = parse_suite(&text, &name).map_err(bad_input)?;
    suite.run.replays = paths.replays.unwrap_or(suite.run.replays);
    let root = match paths.data {
        Some(d) => d.to_path_buf(),
        None => file.parent().map(Path::to_path_buf).unwrap_or_default(),
    };
    check_out(paths.out, paths.overwrite || paths.resume)?;
    let work = std::env::temp_dir().join(format!("aerie-suite-{}", std::process::id()));
    let result = run_pairs(paths, &suite, &root, &work, &name, flight);
    // Best effort: the temporary copies and bakes are of no use afterwards.
    let _ = std::fs::remove_dir_all(&work);
    result
}

/// `--out` must be empty unless `--overwrite` (each flight's folder is then replaced as
/// `bench --overwrite` does, the combined report rewritten).
fn check_out(out: &Path, overwrite: bool) -> Result<(), Failure> {
    if out.exists() && !out.is_dir() {
        return Err(bad_input(format!(
            "--out {}: is a file, expected a folder",
            out.display()
        )));
    }
    let used = std::fs::read_dir(out).is_ok_and(|mut d| d.next().is_some());
    if used && !overwrite {
        return Err(bad_input(format!(
            "--out {}: folder is not empty; pass --overwrite to replace an earlier suite's \
             results, --resume to go on with an interrupted one, or choose an empty folder",
            out.display()
        )));
    }
    std::fs::create_dir_all(out.join("flights"))
        .map_err(|e| runtime(format!("--out {}: {e}", out.display())))
}

fn run_pairs(
    paths: &SuitePaths,
    suite: &Suite,
    root: &Path,
    work: &Path,
    source: &str,
    run_flight: &mut FlightRunner,
) -> Result<(), Failure> {
    let (out, r) = (paths.out, &suite.run);
    let tile_size = RendererDesc::default().tile_size;
    let total = r.warmup + r.frames;
    let pairs = suite.pairs();
    let mut results: Vec<FlightResult> = Vec::new();
    let mut devices: Vec<String> = Vec::new();
    for d in &suite.datasets {
        let mine: Vec<_> = pairs.iter().filter(|(pd, _)| pd.name == d.name).collect();
        if mine.is_empty() {
            continue;
        }
        // Copied (or generated) and baked only when one of its flights is flown.
        let mut prepared: Option<(PathBuf, Arc<Dataset>, Arc<ErrorBake>)> = None;
        for (_, f) in mine {
            let key = format!("{}-{}", d.name, f.spec.name);
            eprintln!("suite: {key} ({}/{})", results.len() + 1, pairs.len());
            let dir = out.join(&key);
            let print = fingerprint(r, d, f, &paths.command_line);
            if paths.resume {
                match read_record(&dir, &print) {
                    Resume::Record(rec) => {
                        eprintln!("suite: {key} taken from {} (--resume)", dir.display());
                        devices.push(rec.device);
                        results.push(FlightResult {
                            dataset: d.name.clone(),
                            flight: f.spec.name.clone(),
                            dataset_summary: rec.dataset_summary,
                            summaries: rec.summaries,
                        });
                        continue;
                    }
                    Resume::Run(why) => eprintln!("suite: {key} is flown: {why}"),
                }
            }
            remove_record(&dir).map_err(runtime)?;
            if prepared.is_none() {
                let dem = materialise(d, root, work)?;
                let (ds, bake) = prepare_terrain(&dem, tile_size)?;
                prepared = Some((dem, ds, bake));
            }
            let Some((dem, ds, bake)) = prepared.as_ref() else {
                unreachable!("prepared just above");
            };
            let csv = waypoints_csv(ds, &f.spec, total, r.fps);
            let csv_path = out.join("flights").join(format!("{key}.csv"));
            write_text(&csv_path, &csv)
                .map_err(|e| runtime(format!("{}: {e}", csv_path.display())))?;
            let waypoints = Waypoints::parse(&csv, &csv_path.display().to_string())
                .map_err(|e| runtime(format!("generated flight {key}: {e}")))?;
            let job = FlightJob {
                run: r,
                dem,
                ds,
                bake,
                waypoints,
                described: format!(
                    "suite {source}, flight {:?}: {:?}, waypoints flights/{key}.csv",
                    f.spec.name, f.spec.kind
                ),
                out: dir.clone(),
            };
            let (dev, summaries) = run_flight(&job)?;
            let record = FlightRecord::new(print, dev.clone(), ds.summary(), summaries.clone());
            if let Err(e) = write_record(&dir, &record) {
                // The flight's own report is written; only resuming it later is lost.
                eprintln!(
                    "suite: {key}: its record could not be written ({e}); --resume flies it again"
                );
            }
            devices.push(dev);
            results.push(FlightResult {
                dataset: d.name.clone(),
                flight: f.spec.name.clone(),
                dataset_summary: ds.summary(),
                summaries,
            });
        }
    }
    let info = SuiteInfo {
        source: source.to_string(),
        device: distinct(devices).join("; "),
        size: r.size.clone(),
        fov: r.fov,
        frames: r.frames,
        warmup: r.warmup,
        fps: r.fps,
        replays: r.replays,
    };
    write_report(out, &info, &results)
}

/// The devices the flights ran on, each once, in the order first met (a resumed suite may have
/// run on several).
fn distinct(devices: Vec<String>) -> Vec<String> {
    let mut seen: Vec<String> = Vec::new();
    for d in devices {
        if !seen.contains(&d) {
            seen.push(d);
        }
    }
    seen
}

/// The dataset's path in `work`: copied from under `root`, or generated.
fn materialise(d: &DatasetSpec, root: &Path, work: &Path) -> Result<PathBuf, Failure> {
    let dir = work.join(&d.name);
    std::fs::create_dir_all(&dir).map_err(|e| runtime(format!("{}: {e}", dir.display())))?;
    match &d.source {
        DatasetSource::Generate {
            kind,
            size,
            spacing,
            seed,
        } => {
            let out = dir.join(format!("{}.f32", d.name));
            crate::app::commands::gen_dem::run(crate::app::commands::gen_dem::GenDemArgs {
                size: *size,
                spacing: *spacing,
                kind: kind.clone(),
                seed: *seed,
                out: out.clone(),
            })?;
            Ok(out)
        }
        DatasetSource::Path(p) => {
            let from = root.join(p);
            let what = |e: std::io::Error| {
                bad_input(format!("dataset {:?}: {}: {e}", d.name, from.display()))
            };
            if from.is_dir() {
                let mut n = 0;
                for entry in std::fs::read_dir(&from).map_err(what)? {
                    let path = entry.map_err(what)?.path();
                    let name = path.file_name().unwrap_or_default().to_string_lossy();
                    if path.is_file() && !name.ends_with(".aerie-bake") {
                        copy(&path, &dir.join(path.file_name().unwrap_or_default()))?;
                        n += 1;
                    }
                }
                if n == 0 {
                    return Err(bad_input(format!(
                        "dataset {:?}: {}: no files",
                        d.name,
                        from.display()
                    )));
                }
                Ok(dir)
            } else {
                let name = from.file_name().unwrap_or_default();
                let to = dir.join(name);
                copy(&from, &to)?;
                let sidecar = PathBuf::from(format!("{}.json", from.display()));
                if sidecar.is_file() {
                    copy(&sidecar, &PathBuf::from(format!("{}.json", to.display())))?;
                }
                Ok(to)
            }
        }
    }
}

fn copy(from: &Path, to: &Path) -> Result<(), Failure> {
    let bytes = std::fs::read(from).map_err(|e| bad_input(format!("{}: {e}", from.display())))?;
    aerie_io::write_atomic(to, &bytes).map_err(|e| runtime(format!("{}: {e}", to.display())))
}
