//! Writing a store's imagery layer (`aerie import --imagery`): every page of every level
//! draped from the rasters ([`crate::drape::LevelDraper`]) on all cores, a batch of pages at a
//! time, compressed and written in the store's index order through an atomic file (nothing
//! under the final name until it is whole). Memory: the rasters, their mips and one batch.

use std::io::Write;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use aerie_io::{AtomicFile, FileSystem};

use super::error::{PageId, StoreError};
use super::imagery::{
    encode_entry, encode_header, encode_trailer, imagery_path, page_texels, ImageryEntry,
    ImageryHeader,
};
use super::page_io::par_pages;
use super::read::Store;
use crate::drape::{LevelDraper, TerrainGrid};

/// Pages draped between writes.
const BATCH: usize = 64;

/// What writing a layer did.
#[derive(Debug, Clone, PartialEq)]
pub struct ImagerySummary {
    pub texels_per_sample: u32,
    pub pages: u32,
    /// Pages with at least one texel a raster covered.
    pub covered_pages: u32,
    /// Texels in the layer, and of them covered by a raster.
    pub texels: u64,
    pub covered_texels: u64,
    pub file_bytes: u64,
}

/// The store's level-0 grid as the drape sees it, or why nothing can be draped on it.
pub fn store_grid(store: &Store) -> Result<TerrainGrid, StoreError> {
    let h = store.header();
    TerrainGrid::new(
        h.valid_width as usize,
        h.valid_height as usize,
        h.spacing_x,
        h.spacing_y,
        h.geo.as_ref(),
    )
    .map_err(|reason| StoreError::Params {
        reason: format!("{}: {reason}", store.path().display()),
    })
}

/// Writes the imagery layer of `store` (beside it, [`imagery_path`]) from `draper`;
/// `progress(done, pages)`.
pub fn write_imagery_in(
    fs: Arc<dyn FileSystem>,
    store: &Store,
    draper: &LevelDraper,
    sources: Vec<String>,
    zstd_level: i32,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<ImagerySummary, StoreError> {
    let path = imagery_path(store.path());
    let grid = store_grid(store)?;
    let layout = store.layout();
    let k = draper.texels_per_sample();
    let header = ImageryHeader::for_store(store.header(), k, sources);
    let n = layout.page_count() as usize;
    let write = |f: &mut AtomicFile, b: &[u8]| -> Result<(), StoreError> {
        f.write_all(b).map_err(|e| {
            StoreError::Write(aerie_io::WriteError {
                path: path.to_path_buf(),
                step: "write",
                source: e,
            })
        })
    };
    let mut f = AtomicFile::create_in(fs, &path)?;
    write(&mut f, &encode_header(&header))?;
    let mut offset = u64::from(header.header_size);
    let mut index = Vec::with_capacity(n * 36);
    let mut crcs = Vec::with_capacity(n * 4);
    let done = AtomicU64::new(0);
    let mut summary = ImagerySummary {
        texels_per_sample: k,
        pages: n as u32,
        covered_pages: 0,
        texels: 0,
        covered_texels: 0,
        file_bytes: 0,
    };
    for start in (0..n).step_by(BATCH) {
        let batch = start..(start + BATCH).min(n);
        let pages = drape_batch(draper, layout, &grid, batch.clone(), zstd_level, &|| {
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, n as u64)
        })
        .map_err(|reason| StoreError::Params { reason })?;
        for (i, (size, covered, bytes)) in batch.zip(pages) {
            let (level, px, py) = layout.page_at(i).expect("in layout");
            let e = ImageryEntry {
                id: PageId { level, px, py },
                cols: size[0] as u32,
                rows: size[1] as u32,
                offset,
                len: bytes.len() as u32,
                crc: crc32fast::hash(&bytes),
            };
            encode_entry(&e, &mut index);
            crcs.extend_from_slice(&e.crc.to_le_bytes());
            summary.texels += (size[0] * size[1]) as u64;
            summary.covered_texels += covered as u64;
            summary.covered_pages += u32::from(covered > 0);
            offset += bytes.len() as u64;
            write(&mut f, &bytes)?;
        }
    }
    index.extend_from_slice(&crcs);
    let trailer = encode_trailer(offset, n as u32, crc32fast::hash(&index));
    write(&mut f, &index)?;
    write(&mut f, &trailer)?;
    f.commit()?;
    summary.file_bytes = offset + (index.len() + trailer.len()) as u64;
    Ok(summary)
}

/// Each page's texel size, covered texels and compressed texels (empty over padding).
type DrapedPage = ([usize; 2], usize, Vec<u8>);

fn drape_batch(
    draper: &LevelDraper,
    layout: &super::format::Layout,
    grid: &TerrainGrid,
    batch: std::ops::Range<usize>,
    level: i32,
    tick: &(dyn Fn() + Sync),
) -> Result<Vec<DrapedPage>, String> {
    let k = draper.texels_per_sample();
    par_pages(layout, batch, level, tick, &|id, z| {
        let ([x0, y0], [w, h]) = page_texels(layout, grid, k, id);
        if w * h == 0 {
            return Ok(([w, h], 0, Vec::new()));
        }
        let (rgba, covered) = draper.window(id.level, x0, y0, w, h);
        let c = z.compress(&rgba).map_err(|e| format!("{id}: zstd: {e}"))?;
        Ok(([w, h], covered, c))
    })
}
