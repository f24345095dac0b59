//! `aerie import <files or folders…> --out <name>.aerie`: a tile store
//! ([`aerie_terrain::store`]) built once from any DEM the loaders read — one file of any
//! format, or SRTM tiles (files and folders of them, stitched) — with the error bake of every
//! level written into its pages. A raw grid is read a band of rows at a time, so its size is
//! not bounded by memory; other inputs are loaded whole. Progress bars, throughput and a
//! one-line summary; `--json` writes the summary as JSON.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;

use crate::app::commands::import_imagery;
use crate::app::failure::{bad_input, runtime, Failure};
use crate::app::out_path::prepare_out_file;
use crate::app::progress::{count_bar, human_bytes, progress_bar};
use crate::tools::output::write_text;
use aerie_terrain::bake::{bake, BakeParams};
use aerie_terrain::dataset::{load_dataset, load_dataset_tiles, Dataset};
use aerie_terrain::drape::GeoRaster;
use aerie_terrain::load::stitch::tile_files;
use aerie_terrain::load::RawRows;
use aerie_terrain::store::{
    bake_rows, write_store, write_store_rows, ImportParams, StoreError, StoreSummary,
    DEFAULT_PAGE_TILES, STORE_EXTENSION,
};

#[derive(Debug, Args)]
pub struct ImportArgs {
    /// DEM files (.hgt, .hgt.zip, .tif, .png, raw .f32/.u16 with sidecar, .npy, .npz) or
    /// folders of SRTM tiles. Several inputs must all be SRTM tiles (stitched into one grid);
    /// any other format is imported on its own. None with --imagery: the imagery is added to
    /// the existing store at --out.
    #[arg(required_unless_present = "imagery")]
    pub inputs: Vec<PathBuf>,
    /// The store to write (`<name>.aerie`); its folder is created.
    #[arg(long)]
    pub out: PathBuf,
    /// Tile side in vertices, 2^j + 1 (3 ..= 257).
    #[arg(long, default_value_t = 17)]
    pub tile_size: u32,
    /// Page side in tiles (a power of two).
    #[arg(long, default_value_t = DEFAULT_PAGE_TILES)]
    pub page_tiles: u32,
    /// zstd level, 1 (fastest) ..= 19 (smallest). 3 is within 1 % of 9's size at half its
    /// time on SRTM; 19 saves 5 % more at 15× the time.
    #[arg(long, default_value_t = 3)]
    pub zstd_level: i32,
    /// 8-bit RGB or RGBA GeoTIFFs (geographic or UTM) draped onto every level of the store,
    /// later files on top: written beside it as `<name>.aerie-imagery` and streamed with the
    /// heights by `run`, `fly` and `bench`.
    #[arg(long, num_args = 1..)]
    pub imagery: Vec<PathBuf>,
    /// Imagery texels per terrain sample per axis (1, 2 or 4); by default the finest
    /// raster's resolution, rounded up to a power of two.
    #[arg(long, requires = "imagery")]
    pub imagery_texels: Option<u32>,
    /// Replace an existing store (or, adding imagery to a store, its imagery layer) at --out.
    #[arg(long)]
    pub overwrite: bool,
    /// Also write the summary as JSON to this file.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// How the inputs are loaded.
#[derive(Debug, Clone, PartialEq)]
pub enum Inputs {
    /// One DEM file, any format (or one folder of SRTM tiles).
    One(PathBuf),
    /// SRTM tiles, stitched.
    Tiles(Vec<PathBuf>),
}

fn is_srtm_tile(p: &Path) -> bool {
    let n = p
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    n.ends_with(".hgt") || n.ends_with(".hgt.zip")
}

/// The loading plan for the inputs: `folders[i]` is the tile list of input i when it is a
/// folder. Pure: refuses (naming the file and the reason) a mix that cannot make one grid.
pub fn plan_inputs(inputs: &[PathBuf], folders: &[Option<Vec<PathBuf>>]) -> Result<Inputs, String> {
    if let ([one], [_]) = (inputs, folders) {
        return Ok(Inputs::One(one.clone()));
    }
    let mut tiles = Vec::new();
    for (p, f) in inputs.iter().zip(folders) {
        match f {
            Some(list) => tiles.extend(list.iter().cloned()),
            None if is_srtm_tile(p) => tiles.push(p.clone()),
            None => {
                return Err(format!(
                    "{}: only SRTM tiles (.hgt, .hgt.zip) are stitched together; import this file on its own",
                    p.display()
                ))
            }
        }
    }
    tiles.sort();
    if let Some(w) = tiles.windows(2).find(|w| w[0] == w[1]) {
        return Err(format!("{}: given twice", w[0].display()));
    }
    Ok(Inputs::Tiles(tiles))
}

fn load(inputs: &Inputs) -> Result<Dataset, Failure> {
    match inputs {
        Inputs::One(p) => load_dataset(p).map_err(bad_input),
        Inputs::Tiles(t) => load_dataset_tiles(t).map_err(bad_input),
    }
}

pub fn run(a: ImportArgs) -> Result<(), Failure> {
    let params = BakeParams {
        tile_size: a.tile_size,
        levels: 0,
    };
    params
        .log2_quads()
        .map_err(|e| bad_input(format!("--tile-size: {e}")))?;
    if a.page_tiles == 0 || !a.page_tiles.is_power_of_two() || a.page_tiles > 1024 {
        return Err(bad_input(format!(
            "--page-tiles {}: not a power of two in 1..=1024",
            a.page_tiles
        )));
    }
    if !(1..=19).contains(&a.zstd_level) {
        return Err(bad_input(format!(
            "--zstd-level {}: not in 1..=19",
            a.zstd_level
        )));
    }
    if a.out.extension().and_then(|e| e.to_str()) != Some(STORE_EXTENSION) {
        return Err(bad_input(format!(
            "--out {}: a store's name ends in .{STORE_EXTENSION}",
            a.out.display()
        )));
    }
    import_imagery::check_texels(a.imagery_texels)?;
    let rasters = import_imagery::read_imagery(&a.imagery)?;
    if a.inputs.is_empty() {
        return add_imagery(&a, &rasters);
    }
    if a.out.exists() && !a.overwrite {
        return Err(bad_input(format!(
            "--out {}: exists; use --overwrite to replace it",
            a.out.display()
        )));
    }
    prepare_out_file("--out", &a.out)?;
    let mut folders = Vec::with_capacity(a.inputs.len());
    for p in &a.inputs {
        folders.push(if p.is_dir() {
            Some(tile_files(p).map_err(bad_input)?)
        } else {
            None
        });
    }
    let inputs = plan_inputs(&a.inputs, &folders).map_err(bad_input)?;
    let sources = match &inputs {
        Inputs::One(p) => vec![p.display().to_string()],
        Inputs::Tiles(t) => t.iter().map(|p| p.display().to_string()).collect(),
    };
    let ip = ImportParams {
        sources,
        page_tiles: a.page_tiles,
        zstd_level: a.zstd_level,
    };
    let t = Instant::now();
    // A raw grid is read a band of rows at a time (it may be larger than memory); any other
    // input is loaded whole (SRTM mosaics are stitched and void-filled over the whole grid).
    let rows = match &inputs {
        Inputs::One(p) => RawRows::open(p).map_err(bad_input)?,
        Inputs::Tiles(_) => None,
    };
    let (streamed, (s, load_s, bake_s, write_s)) = match rows {
        Some(rows) => (true, import_streamed(&a, &rows, params, &ip)?),
        None => (false, import_whole(&a, &inputs, params, &ip)?),
    };
    let imagery = if rasters.is_empty() {
        import_imagery::remove_stale_layer(&a.out)?;
        None
    } else {
        Some(import_imagery::write_layer(
            &a.out,
            &rasters,
            a.imagery_texels,
            a.zstd_level,
        )?)
    };
    let total_s = t.elapsed().as_secs_f64();
    println!(
        "{}",
        summary_line(&a.out, &s, load_s, bake_s, write_s, total_s)
    );
    if let Some(i) = &imagery {
        println!("{}", import_imagery::summary_line(i));
    }
    if let Some(j) = &a.json {
        prepare_out_file("--json", j)?;
        let mut v = summary_json(&a.out, &s, load_s, bake_s, write_s, total_s);
        v["streamed"] = serde_json::json!(streamed);
        v["imagery"] = imagery
            .as_ref()
            .map_or(serde_json::Value::Null, import_imagery::summary_json);
        write_text(j, &format!("{v:#}\n")).map_err(runtime)?;
    }
    Ok(())
}

/// `aerie import --imagery … --out <existing store>`: the layer added to a store as it is.
fn add_imagery(a: &ImportArgs, rasters: &[GeoRaster]) -> Result<(), Failure> {
    if !a.out.is_file() {
        return Err(bad_input(format!(
            "--out {}: no store there to add imagery to; give DEM inputs to make one",
            a.out.display()
        )));
    }
    let layer = aerie_terrain::store::imagery_path(&a.out);
    if layer.exists() && !a.overwrite {
        return Err(bad_input(format!(
            "{}: the store has an imagery layer; use --overwrite to replace it",
            layer.display()
        )));
    }
    let i = import_imagery::write_layer(&a.out, rasters, a.imagery_texels, a.zstd_level)?;
    println!("{}", import_imagery::summary_line(&i));
    if let Some(j) = &a.json {
        prepare_out_file("--json", j)?;
        let mut v = serde_json::json!({ "store": a.out.display().to_string() });
        v["imagery"] = import_imagery::summary_json(&i);
        write_text(j, &format!("{v:#}\n")).map_err(runtime)?;
    }
    Ok(())
}

/// A store error as a failure: writing and reading are runtime, the rest bad input.
fn store_failure(e: StoreError) -> Failure {
    match e {
        StoreError::Write(_) | StoreError::Io { .. } => runtime(e),
        _ => bad_input(e),
    }
}

/// (summary, load s, bake s, pages s) of a raw grid imported a band of rows at a time: nothing
/// is loaded (load 0 s); the bake and the pages each read the file once.
#[allow(clippy::type_complexity)]
fn import_streamed(
    a: &ImportArgs,
    rows: &RawRows,
    params: BakeParams,
    ip: &ImportParams,
) -> Result<(StoreSummary, f64, f64, f64), Failure> {
    let (vw, vh) = rows.valid_size();
    let (w, h) = rows.padded_size();
    eprintln!(
        "reading {} by rows: {vw}×{vh} samples (padded to {w}×{h}), {}",
        rows.path().display(),
        rows.spacing_note()
    );
    let levels = params
        .resolve_levels_for(w, h)
        .map_err(|e| bad_input(format!("--tile-size: {e}")))?;
    let params = BakeParams { levels, ..params };
    let bar = progress_bar((w * h) as u64, &format!("baking {levels} levels"));
    let tb = Instant::now();
    let b = bake_rows(rows, params, &|done, _| bar.set_position(done)).map_err(bad_input)?;
    let bake_s = tb.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let bar = count_bar(u64::from(page_count(&b, a)), "pages", "compressing");
    let tw = Instant::now();
    let s = write_store_rows(&a.out, rows, &b, ip, &|done, _| bar.set_position(done))
        .map_err(store_failure)?;
    bar.finish_and_clear();
    Ok((s, 0.0, bake_s, tw.elapsed().as_secs_f64()))
}

fn page_count(b: &aerie_terrain::bake::ErrorBake, a: &ImportArgs) -> u32 {
    aerie_terrain::store::Layout::new(
        b.width,
        b.height,
        a.tile_size - 1,
        b.levels.len() as u32,
        a.page_tiles,
    )
    .map(|l| l.page_count())
    .unwrap_or(0)
}

/// (summary, load s, bake s, pages s) of inputs loaded whole.
#[allow(clippy::type_complexity)]
fn import_whole(
    a: &ImportArgs,
    inputs: &Inputs,
    params: BakeParams,
    ip: &ImportParams,
) -> Result<(StoreSummary, f64, f64, f64), Failure> {
    let t = Instant::now();
    let ds = load(inputs)?;
    let load_s = t.elapsed().as_secs_f64();
    eprintln!(
        "loaded {}: {}, {} voids filled; {} ({load_s:.2} s)",
        ds.source,
        ds.summary(),
        ds.hf.voids_filled,
        ds.hf.spacing_note
    );
    let levels = params
        .resolve_levels(&ds)
        .map_err(|e| bad_input(format!("--tile-size: {e}")))?;
    let params = BakeParams { levels, ..params };
    let samples = (ds.hf.width * ds.hf.height) as u64;
    let bar = progress_bar(samples, &format!("baking {levels} levels"));
    let tb = Instant::now();
    let b = bake(&ds, params, &|done, _| bar.set_position(done));
    let bake_s = tb.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let bar = count_bar(u64::from(page_count(&b, a)), "pages", "compressing");
    let tw = Instant::now();
    let s = write_store(&a.out, &ds, &b, ip, &|done, _| bar.set_position(done))
        .map_err(store_failure)?;
    bar.finish_and_clear();
    Ok((s, load_s, bake_s, tw.elapsed().as_secs_f64()))
}

fn max_eps_text(s: &StoreSummary) -> String {
    s.max_eps
        .iter()
        .enumerate()
        .map(|(l, e)| format!("L{l} {e}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn summary_line(
    out: &Path,
    s: &StoreSummary,
    load_s: f64,
    bake_s: f64,
    write_s: f64,
    total_s: f64,
) -> String {
    let h = &s.header;
    format!(
        "imported {}: {}×{} samples ({} real), m = {}, {} levels, {} pages ({} i16, {} i16 + exceptions, {} f32) of {}×{} tiles; {} ({} of samples as f32, ratio {:.2}; bake section {}); load {load_s:.2} s, bake {bake_s:.2} s, pages {write_s:.2} s: {:.1} M real samples/s overall; max ε per level (m): {}",
        out.display(),
        h.width,
        h.height,
        s.real_samples,
        h.tile_size,
        h.levels,
        s.pages,
        s.i16_pages,
        s.exception_pages,
        s.f32_pages,
        h.page_tiles,
        h.page_tiles,
        human_bytes(s.file_bytes),
        human_bytes(h.raw_sample_bytes),
        s.ratio(),
        human_bytes(s.bake_bytes),
        s.real_samples as f64 / total_s.max(1e-9) / 1e6,
        max_eps_text(s)
    )
}

fn summary_json(
    out: &Path,
    s: &StoreSummary,
    load_s: f64,
    bake_s: f64,
    write_s: f64,
    total_s: f64,
) -> serde_json::Value {
    let h = &s.header;
    serde_json::json!({
        "store": out.display().to_string(),
        "format_version": h.version,
        "width": h.width,
        "height": h.height,
        "valid_width": h.valid_width,
        "valid_height": h.valid_height,
        "real_samples": s.real_samples,
        "page_samples": s.page_samples,
        "tile_size": h.tile_size,
        "page_tiles": h.page_tiles,
        "levels": h.levels,
        "pages": s.pages,
        "i16_pages": s.i16_pages,
        "i16_exception_pages": s.exception_pages,
        "f32_pages": s.f32_pages,
        "file_bytes": s.file_bytes,
        "page_bytes": s.page_bytes,
        "bake_bytes": s.bake_bytes,
        "raw_sample_bytes": h.raw_sample_bytes,
        "compression_ratio": s.ratio(),
        "max_eps_m": s.max_eps,
        "sources": h.sources,
        "load_s": load_s,
        "bake_s": bake_s,
        "pages_s": write_s,
        "total_s": total_s,
        "real_samples_per_s": s.real_samples as f64 / total_s.max(1e-9),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(s: &str) -> PathBuf {
        PathBuf::from(s)
    }

    #[test]
    fn inputs_are_one_file_or_srtm_tiles() {
        assert_eq!(
            plan_inputs(&[p("a.tif")], &[None]),
            Ok(Inputs::One(p("a.tif")))
        );
        assert_eq!(
            plan_inputs(&[p("dir")], &[Some(vec![p("dir/N1E1.hgt")])]),
            Ok(Inputs::One(p("dir")))
        );
        assert_eq!(
            plan_inputs(
                &[p("b/N02E003.hgt.zip"), p("dir")],
                &[None, Some(vec![p("dir/N01E003.hgt")])]
            ),
            Ok(Inputs::Tiles(vec![
                p("b/N02E003.hgt.zip"),
                p("dir/N01E003.hgt")
            ]))
        );
        let e = plan_inputs(&[p("N01E003.hgt"), p("x.tif")], &[None, None]).unwrap_err();
        assert!(e.contains("x.tif") && e.contains("only SRTM tiles"), "{e}");
        let e = plan_inputs(
            &[p("dir/N01E003.hgt"), p("dir")],
            &[None, Some(vec![p("dir/N01E003.hgt")])],
        )
        .unwrap_err();
        assert!(e.contains("N01E003.hgt: given twice"), "{e}");
    }
}
