//! `aerie bake <dataset>`: the exact error bake ([`aerie_terrain::bake`]) written next to the
//! dataset (or to `--out`), with a progress bar and a one-line summary; `--report` adds the
//! per-level ε distribution, printed and written as CSV next to the bake file.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use crate::app::failure::{bad_input, runtime, Failure};
use crate::app::out_path::{prepare_out_file, with_suffix};
use crate::app::progress::{human_bytes, progress_bar};
use aerie_terrain::bake::{
    bake, bake_path_for, check_existing, report_csv, write_bake, BakeError, BakeParams, ErrorBake,
    Existing,
};
use aerie_terrain::dataset::{load_dataset, Dataset};

#[derive(Debug, Args)]
pub struct BakeArgs {
    /// Dataset: a DEM file (.hgt, .hgt.zip, .tif, .png, raw .f32/.u16 with sidecar, .npy, .npz)
    /// or a folder of adjacent SRTM .hgt/.hgt.zip tiles (stitched).
    pub dataset: PathBuf,
    /// Tile side in vertices, 2^j + 1 (3 ..= 257).
    #[arg(long, default_value_t = 17)]
    pub tile_size: u32,
    /// Number of levels (0 = as many as fit the dataset).
    #[arg(long, default_value_t = 0)]
    pub levels: u32,
    /// Print the ε distribution per level (max, p99, median) and write it as CSV next to the
    /// bake file (`<bake file>.csv`).
    #[arg(long)]
    pub report: bool,
    /// Overwrite whatever is at the output path, and re-bake an up-to-date bake.
    #[arg(long)]
    pub force: bool,
    /// Bake file (default: `<dataset>.aerie-bake` next to the dataset file or folder); its
    /// folder is created.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

fn bake_failure(e: BakeError) -> Failure {
    match e {
        BakeError::Write { .. } => runtime(format!("{e} (use --out to write the bake elsewhere)")),
        BakeError::Io { .. } => runtime(e),
        _ => bad_input(e),
    }
}

pub fn run(a: BakeArgs) -> Result<(), Failure> {
    let params = BakeParams {
        tile_size: a.tile_size,
        levels: a.levels,
    };
    params
        .log2_quads()
        .map_err(|e| bad_input(format!("--tile-size: {e}")))?;
    let t = Instant::now();
    let ds = load_dataset(&a.dataset).map_err(bad_input)?;
    let out = a.out.clone().unwrap_or_else(|| bake_path_for(&a.dataset));
    prepare_out_file("--out", &out)?;
    eprintln!(
        "loaded {}: {}, {} voids filled; {} ({:.2} s)",
        ds.source,
        ds.summary(),
        ds.hf.voids_filled,
        ds.hf.spacing_note,
        t.elapsed().as_secs_f64()
    );
    let levels = params.resolve_levels(&ds).map_err(|e| match a.levels {
        0 => bad_input(format!("--tile-size: {e}")),
        _ => bad_input(format!("--levels: {e}")),
    })?;
    let params = BakeParams { levels, ..params };
    let b = match check_existing(&ds, &out, params, a.force).map_err(bake_failure)? {
        Existing::UpToDate(b) => {
            println!(
                "{}: up to date (m = {}, {} levels, source checksum {:#010x}, {}); use --force to re-bake",
                out.display(),
                b.params.tile_size,
                b.params.levels,
                b.source_checksum,
                human_bytes(b.file_size())
            );
            *b
        }
        existing => {
            if let Existing::Replace(why) = &existing {
                eprintln!("replacing the existing file: {why}");
            }
            bake_and_write(&ds, params, &out)?
        }
    };
    if a.report {
        report(&b, &out)?;
    }
    Ok(())
}

fn bake_and_write(
    ds: &Dataset,
    params: BakeParams,
    out: &std::path::Path,
) -> Result<ErrorBake, Failure> {
    let samples = (ds.hf.width * ds.hf.height) as u64;
    let bar = progress_bar(samples, &format!("baking {} levels", params.levels));
    let t = Instant::now();
    let b = bake(ds, params, &|done, _| bar.set_position(done));
    let bake_s = t.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let tw = Instant::now();
    write_bake(out, &b).map_err(bake_failure)?;
    let write_s = tw.elapsed().as_secs_f64();
    let real = (ds.valid_width * ds.valid_height) as f64;
    let size = b.file_size();
    let f32_bytes = real * 4.0;
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    let per_level: Vec<String> = b
        .levels
        .iter()
        .map(|t| {
            let m = t
                .eps
                .iter()
                .zip(&t.terrain)
                .filter(|(_, &k)| k)
                .fold(0f32, |a, (&e, _)| a.max(e));
            format!("L{} {}", t.level, trim(m))
        })
        .collect();
    println!(
        "baked {}: {}×{} samples ({}×{} real), m = {}, {} levels in {bake_s:.2} s on {threads} threads: {:.1} M samples/s ({:.1} M real samples/s); wrote {} ({}, {:.2} % of the f32 dataset) in {write_s:.2} s; max ε per level (m): {}",
        out.display(),
        ds.hf.width,
        ds.hf.height,
        ds.valid_width,
        ds.valid_height,
        b.params.tile_size,
        b.params.levels,
        samples as f64 / bake_s / 1e6,
        real / bake_s / 1e6,
        out.display(),
        human_bytes(size),
        size as f64 / f32_bytes * 100.0,
        per_level.join(", ")
    );
    Ok(b)
}

/// Up to 3 decimals without trailing zeros.
fn trim(v: f32) -> String {
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

fn report(b: &ErrorBake, out: &std::path::Path) -> Result<(), Failure> {
    let stats = b.level_stats();
    println!(
        "{:>5} {:>6} {:>9} {:>9} {:>21} {:>10} {:>10} {:>10}",
        "level", "step", "tiles", "terrain", "tile extent (m)", "max ε", "p99 ε", "median ε"
    );
    for l in &stats {
        println!(
            "{:>5} {:>6} {:>9} {:>9} {:>21} {:>10} {:>10} {:>10}",
            l.level,
            1u64 << l.level,
            l.tiles,
            l.terrain_tiles,
            format!("{:.0} × {:.0}", l.tile_extent_x_m, l.tile_extent_y_m),
            trim(l.max),
            trim(l.p99),
            trim(l.median)
        );
    }
    let csv = with_suffix(out, ".csv");
    aerie_io::write_atomic(&csv, report_csv(&stats).as_bytes()).map_err(runtime)?;
    println!("report: {}", csv.display());
    Ok(())
}
