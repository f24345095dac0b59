//! `aerie import … --imagery <GeoTIFF…>`: a store's imagery layer (`<name>.aerie-imagery`,
//! [`aerie_terrain::store::imagery`]) draped from 8-bit RGB/RGBA GeoTIFFs onto every level of
//! the store, so the renderer streams it with the heights. Written after the store when DEM
//! inputs are given, or added to an existing store (`aerie import --imagery x.tif --out
//! store.aerie`, no DEM inputs). The rasters are read before anything is written, and a
//! layer that would cover nothing is refused; a store replaced without `--imagery` loses the
//! old layer beside it (it belongs to the old store and would be refused at open).

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::app::failure::{bad_input, runtime, Failure};
use crate::app::progress::{count_bar, human_bytes};
use aerie_terrain::drape::{
    read_raster, store_texels_per_sample, GeoRaster, LevelDraper, MAX_STORE_TEXELS_PER_SAMPLE,
};
use aerie_terrain::store::{
    imagery_path, store_grid, write_imagery_in, ImagerySummary, Store, StoreError,
};

/// The rasters of `--imagery`, read (and their georeference checked) before any work.
pub fn read_imagery(paths: &[PathBuf]) -> Result<Vec<GeoRaster>, Failure> {
    paths
        .iter()
        .map(|p| read_raster(p).map_err(|e| bad_input(format!("--imagery: {e}"))))
        .collect()
}

/// `--imagery-texels`: a power of two up to the store's limit, or bad input naming it.
pub fn check_texels(k: Option<u32>) -> Result<(), Failure> {
    match k {
        Some(k) if k == 0 || !k.is_power_of_two() || k > MAX_STORE_TEXELS_PER_SAMPLE => {
            Err(bad_input(format!(
                "--imagery-texels {k}: texels per sample are 1, 2 or {MAX_STORE_TEXELS_PER_SAMPLE}"
            )))
        }
        _ => Ok(()),
    }
}

/// What writing the layer did, for the summary line and the JSON.
pub struct ImageryImport {
    pub path: PathBuf,
    pub summary: ImagerySummary,
    pub seconds: f64,
}

/// Drapes `rasters` onto every level of the store at `store_path` and writes its imagery
/// layer (replacing one there: the caller has checked `--overwrite`).
pub fn write_layer(
    store_path: &Path,
    rasters: &[GeoRaster],
    texels: Option<u32>,
    zstd_level: i32,
) -> Result<ImageryImport, Failure> {
    let t = Instant::now();
    let store = Store::open(store_path).map_err(bad_input)?;
    let grid = store_grid(&store).map_err(|e| bad_input(format!("--imagery: {e}")))?;
    let k = texels.unwrap_or_else(|| store_texels_per_sample(&grid, rasters));
    let levels = store.header().levels;
    let draper = LevelDraper::new(&grid, rasters, k, levels).map_err(bad_input)?;
    if draper.coarse_coverage(levels) == 0 {
        let names: Vec<&str> = rasters.iter().map(|r| r.path.as_str()).collect();
        return Err(bad_input(format!(
            "--imagery {}: no overlap with the terrain of {}",
            names.join(", "),
            store_path.display()
        )));
    }
    let pages = u64::from(store.header().page_count);
    let bar = count_bar(
        pages,
        "pages",
        &format!("draping imagery, {k} texels/sample"),
    );
    let sources = rasters.iter().map(|r| r.path.clone()).collect();
    let summary = write_imagery_in(
        aerie_io::real(),
        &store,
        &draper,
        sources,
        zstd_level,
        &|done, _| bar.set_position(done),
    )
    .map_err(|e| match e {
        StoreError::Write(_) | StoreError::Io { .. } => runtime(e),
        _ => bad_input(e),
    })?;
    bar.finish_and_clear();
    Ok(ImageryImport {
        path: imagery_path(store_path),
        summary,
        seconds: t.elapsed().as_secs_f64(),
    })
}

/// Removes the imagery layer of a store that was just replaced (it names the old store's
/// checksum, so the new store would refuse it); says so on stderr.
pub fn remove_stale_layer(store_path: &Path) -> Result<(), Failure> {
    let at = imagery_path(store_path);
    if at.exists() {
        std::fs::remove_file(&at).map_err(|e| {
            runtime(format!(
                "{}: cannot remove the old layer: {e}",
                at.display()
            ))
        })?;
        eprintln!(
            "removed {}: the imagery layer of the replaced store (import with --imagery to make a new one)",
            at.display()
        );
    }
    Ok(())
}

pub fn summary_line(i: &ImageryImport) -> String {
    let s = &i.summary;
    format!(
        "imagery {}: {} texels/sample, {} pages ({} with imagery), {:.1} % of {} texels covered, {}; {:.2} s",
        i.path.display(),
        s.texels_per_sample,
        s.pages,
        s.covered_pages,
        100.0 * s.covered_texels as f64 / (s.texels.max(1)) as f64,
        s.texels,
        human_bytes(s.file_bytes),
        i.seconds
    )
}

pub fn summary_json(i: &ImageryImport) -> serde_json::Value {
    let s = &i.summary;
    serde_json::json!({
        "layer": i.path.display().to_string(),
        "texels_per_sample": s.texels_per_sample,
        "pages": s.pages,
        "covered_pages": s.covered_pages,
        "texels": s.texels,
        "covered_texels": s.covered_texels,
        "file_bytes": s.file_bytes,
        "seconds": i.seconds,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texels_per_sample_are_powers_of_two_up_to_the_limit() {
        for k in [None, Some(1), Some(2), Some(4)] {
            assert!(check_texels(k).is_ok(), "{k:?}");
        }
        for k in [0, 3, 8] {
            let e = check_texels(Some(k)).unwrap_err().message;
            assert!(
                e.contains("--imagery-texels") && e.contains(&k.to_string()),
                "{e}"
            );
        }
    }
}
