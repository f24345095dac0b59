//! Terrain preparation shared by every command that draws: the dataset and its error bake.

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use aerie_terrain::bake::{bake, bake_path_for, load_or_bake, BakeOutcome, BakeParams, ErrorBake};
use aerie_terrain::dataset::{load_dataset, Dataset};

use crate::app::failure::{bad_input, Failure};

/// Loads the dataset (file or folder) and its error bake: reads `<name>.aerie-bake` when it is a
/// valid bake of this data, else bakes and writes it; when it cannot be written (read-only
/// folder, or a file that is not ours) the bake is kept in memory and the reason printed.
pub fn prepare_terrain(
    path: &Path,
    tile_size: u32,
) -> Result<(Arc<Dataset>, Arc<ErrorBake>), Failure> {
    let t = Instant::now();
    if path.extension().is_some_and(|e| e == "aerie") {
        return prepare_store(path, tile_size);
    }
    let ds = load_dataset(path).map_err(bad_input)?;
    let hf = &ds.hf;
    let (lo, hi) = hf.min_max();
    eprintln!(
        "loaded {}: {}x{} samples (padded to {}x{}), {:.0}..{:.0} m, {} voids filled, {} ({:.2} s)",
        path.display(),
        ds.valid_width,
        ds.valid_height,
        hf.width,
        hf.height,
        lo,
        hi,
        hf.voids_filled,
        hf.spacing_note,
        t.elapsed().as_secs_f64()
    );
    let params = BakeParams {
        tile_size,
        levels: 0,
    };
    params
        .resolve_levels(&ds)
        .map_err(|e| bad_input(format!("{}: {e}", path.display())))?;
    let bake_path = bake_path_for(path);
    let t = Instant::now();
    let quiet = |_: u64, _: u64| {};
    let b = match load_or_bake(&ds, &bake_path, params, false, &quiet) {
        Ok((b, outcome)) => {
            let what = match outcome {
                BakeOutcome::UpToDate => "read".to_string(),
                BakeOutcome::Baked => "baked and wrote".to_string(),
                BakeOutcome::Replaced(why) => format!("re-baked ({why}) and wrote"),
            };
            eprintln!(
                "{what} {} ({} levels, {:.2} s)",
                bake_path.display(),
                b.levels.len(),
                t.elapsed().as_secs_f64()
            );
            b
        }
        Err(e) => {
            let b = bake(&ds, params, &quiet);
            eprintln!(
                "baked in memory ({} levels, {:.2} s); not saved: {e}",
                b.levels.len(),
                t.elapsed().as_secs_f64()
            );
            b
        }
    };
    Ok((Arc::new(ds), Arc::new(b)))
}

/// A tile store (`aerie import`) read whole: its level-0 samples and its bake, checked against
/// the header's checksum (streaming pages to the clipmap is issue 13's next step).
fn prepare_store(path: &Path, tile_size: u32) -> Result<(Arc<Dataset>, Arc<ErrorBake>), Failure> {
    let t = Instant::now();
    let (ds, b) = aerie_terrain::store::load_store(path).map_err(bad_input)?;
    if b.params.tile_size != tile_size {
        return Err(bad_input(format!(
            "{}: the store was imported with tiles of {} vertices, the renderer uses {tile_size}: re-import with --tile-size {tile_size}, or set render.tile_size = {}",
            path.display(),
            b.params.tile_size,
            b.params.tile_size
        )));
    }
    eprintln!(
        "read store {}: {}x{} samples (padded to {}x{}), {} levels, {} ({:.2} s)",
        path.display(),
        ds.valid_width,
        ds.valid_height,
        ds.hf.width,
        ds.hf.height,
        b.levels.len(),
        ds.hf.spacing_note,
        t.elapsed().as_secs_f64()
    );
    Ok((Arc::new(ds), Arc::new(b)))
}
