//! Terrain preparation shared by every command that draws: the terrain source and its error
//! bake — a dataset loaded whole (with its bake file), or a tile store streamed page by page
//! (`--dem <name>.aerie`; `--load-whole` reads it into memory instead).

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use aerie_terrain::bake::{bake, bake_path_for, load_or_bake, BakeOutcome, BakeParams, ErrorBake};
use aerie_terrain::dataset::{load_dataset, Dataset};
use aerie_terrain::source::{InMemoryTerrain, SourceGrid, TerrainSource};
use aerie_terrain::stream::{StreamParams, StreamedStore};

use crate::app::args::StoreArgs;
use crate::app::failure::{bad_input, runtime, Failure};
use crate::render::desc::RendererDesc;

/// How long start-up waits for the coarsest level of a streamed store before giving up.
const START_UP_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(30);

/// What a command draws: the source, its bake, and what else it may need of the terrain.
pub struct Terrain {
    pub source: Arc<dyn TerrainSource>,
    pub bake: Arc<ErrorBake>,
    /// The samples in memory (a dataset, or a store read whole); None when streamed.
    pub dataset: Option<Arc<Dataset>>,
    /// The streamed store (its loader's totals, failures), when streamed.
    pub streamed: Option<Arc<StreamedStore>>,
    /// Seconds from the start of preparation until the first frame's samples were resident.
    pub prepare_s: f64,
}

impl Terrain {
    /// A dataset already in memory with its bake.
    pub fn in_memory(dataset: Arc<Dataset>, bake: Arc<ErrorBake>) -> Self {
        let source = InMemoryTerrain::with_checksum(dataset.clone(), bake.source_checksum);
        Terrain {
            source: Arc::new(source),
            bake,
            dataset: Some(dataset),
            streamed: None,
            prepare_s: 0.0,
        }
    }

    pub fn grid(&self) -> &SourceGrid {
        self.source.grid()
    }

    /// The highest full-resolution sample (from the bake: the coarsest level's tile maxima
    /// are the maxima of every sample under them).
    pub fn top_height(&self) -> f64 {
        let l = self.bake.levels.len() as u32 - 1;
        let t = &self.bake.levels[l as usize];
        let mut top = f64::MIN;
        for ty in 0..t.tiles_y {
            for tx in 0..t.tiles_x {
                top = top.max(self.bake.bounds(l, tx, ty).1 as f64);
            }
        }
        top
    }
}

/// The terrain at `path` for a renderer made with `desc`: a tile store streamed within
/// `store.cache_mb` (waiting only for the first frame's samples, the coarsest level), or read
/// whole with `--load-whole`; any other file loaded whole with its bake.
pub fn prepare_source(
    path: &Path,
    desc: &RendererDesc,
    store: &StoreArgs,
) -> Result<Terrain, Failure> {
    let t = Instant::now();
    let is_store = path.extension().is_some_and(|e| e == "aerie");
    if !is_store || store.load_whole {
        let (ds, bake) = prepare_terrain(path, desc.tile_size)?;
        let mut source = InMemoryTerrain::with_checksum(ds.clone(), bake.source_checksum);
        if is_store {
            // A store read whole keeps its imagery layer (drawn as a streamed one is).
            let s = aerie_terrain::store::Store::open(path).map_err(bad_input)?;
            let fs = aerie_io::real();
            if let Some(layer) =
                aerie_terrain::store::open_imagery_beside(&fs, path, &s).map_err(bad_input)?
            {
                source = source.with_imagery(layer);
            }
        }
        return Ok(Terrain {
            source: Arc::new(source),
            bake,
            dataset: Some(ds),
            streamed: None,
            prepare_s: t.elapsed().as_secs_f64(),
        });
    }
    let mut params = StreamParams {
        cache_bytes: store.cache_mb << 20,
        workers: store.stream_workers.max(1),
        ..StreamParams::default()
    };
    if store.stream_latency_ms > 0 {
        let faults = aerie_io::Faults {
            latency: Some(std::time::Duration::from_millis(store.stream_latency_ms)),
            ..Default::default()
        };
        params.fs = aerie_io::FaultyFs::new(faults).shared();
    }
    let (streamed, bake) = StreamedStore::open(path, params).map_err(bad_input)?;
    if bake.params.tile_size != desc.tile_size {
        return Err(bad_input(format!(
            "{}: the store was imported with tiles of {} vertices, the renderer uses {}: re-import with --tile-size {}",
            path.display(),
            bake.params.tile_size,
            desc.tile_size,
            desc.tile_size
        )));
    }
    let opened_s = t.elapsed().as_secs_f64();
    let rects = desc.start_up_rects(streamed.grid());
    let need = streamed.bytes_resident_for(&rects, true);
    if need > store.cache_mb << 20 {
        // The pins take at most a quarter of the budget, so 4/3 of the rest always fits.
        let enough = (streamed.bytes_resident_for(&rects, false) * 4).div_ceil(3 << 20);
        return Err(bad_input(format!(
            "{}: --cache-mb {}: the first frame needs {:.1} MiB of decoded pages resident at once (the coarsest clipmap level{} beside the pinned levels); give --cache-mb {enough} or more",
            path.display(),
            store.cache_mb,
            need as f64 / (1 << 20) as f64,
            if desc.normal_maps { " with its normals' footprint" } else { "" },
        )));
    }
    streamed
        .wait_resident(&rects, START_UP_TIMEOUT)
        .map_err(|e| runtime(format!("{}: start-up: {e}", path.display())))?;
    let g = streamed.grid();
    eprintln!(
        "streaming store {}: {}x{} samples (padded to {}x{}), {} levels, cache {} MiB, levels {:?} pinned; opened in {:.3} s, coarsest level resident after {:.3} s",
        path.display(),
        g.valid_width,
        g.valid_height,
        g.width,
        g.height,
        bake.levels.len(),
        store.cache_mb,
        streamed.pinned_levels(),
        opened_s,
        t.elapsed().as_secs_f64()
    );
    let streamed = Arc::new(streamed);
    Ok(Terrain {
        source: streamed.clone(),
        bake,
        dataset: None,
        streamed: Some(streamed),
        prepare_s: t.elapsed().as_secs_f64(),
    })
}

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
    // Projected grids other than UTM are not on the ellipsoid: say so where the user looks
    // first.
    if let Some(aerie_terrain::GeoReference::Projected { crs, .. }) = &hf.geo {
        if let Some(w) = aerie_terrain::geodesy::utm::flat_plane_warning(crs) {
            eprintln!("{w}");
        }
    }
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
