//! The import writer: every page of every level cut from a dataset and its bake, coded,
//! compressed on all cores a batch at a time, and written as they come — header, pages,
//! bake section, index, trailer — atomically (temporary file + rename: an interrupted import leaves
//! nothing under the store's name, and a cut file has no trailer, so it never opens).
//!
//! The samples come through [`PageSamples`], a page row at a time in index order: from a
//! dataset in memory ([`write_store`]), or read a band of rows at a time from a source larger
//! than memory (`super::rows_import`); the bytes written are the same.

use std::io::Write;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use aerie_io::{AtomicFile, FileSystem};

use crate::bake::ErrorBake;
use crate::dataset::Dataset;

use super::bake_section;
use super::error::{PageId, StoreError};
use super::format::{
    encode_header, header_len, Coding, Layout, PageEntry, StoreHeader, INDEX_ENTRY, STORE_VERSION,
};
use super::index::{encode_entry, encode_trailer, Trailer, TRAILER};
use super::page_io::par_pages;
use super::pages::{cut_samples, cut_tables, encode_payload};

/// What an import is asked for beyond the data.
#[derive(Debug, Clone)]
pub struct ImportParams {
    /// The input files, one line each (kept in the header).
    pub sources: Vec<String>,
    /// Page side in tiles (power of two).
    pub page_tiles: u32,
    /// zstd level (1 = fastest … 19). On the Sierra Nevada SRTM3 mosaic: 3 → 6.62 MB in
    /// 0.16 s, 9 → 6.56 MB in 0.34 s, 19 → 6.28 MB in 2.48 s (2 cores).
    pub zstd_level: i32,
}

/// What was written.
#[derive(Debug, Clone, PartialEq)]
pub struct StoreSummary {
    pub header: StoreHeader,
    /// Real (non-padding) level-0 samples.
    pub real_samples: u64,
    /// Samples over all pages of all levels (edges shared between pages counted per page).
    pub page_samples: u64,
    pub pages: u32,
    /// Pages per coding: all exact i16, i16 with exceptions, f32.
    pub i16_pages: u32,
    pub exception_pages: u32,
    pub f32_pages: u32,
    /// Bytes of the pages as stored (compressed).
    pub page_bytes: u64,
    /// Bytes of the bake section as stored (compressed).
    pub bake_bytes: u64,
    /// Bytes of the whole file.
    pub file_bytes: u64,
    /// Max ε over the terrain tiles of each level, metres.
    pub max_eps: Vec<f32>,
}

impl StoreSummary {
    /// Samples as f32 over stored page bytes.
    pub fn ratio(&self) -> f64 {
        self.header.raw_sample_bytes as f64 / self.page_bytes.max(1) as f64
    }
}

/// Writes `ds` and its bake as a store at `path` (see the module documentation).
/// `progress(pages_done, pages)` is called from the worker threads.
pub fn write_store(
    path: &Path,
    ds: &Dataset,
    bake: &ErrorBake,
    params: &ImportParams,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<StoreSummary, StoreError> {
    write_store_in(aerie_io::real(), path, ds, bake, params, progress)
}

/// [`write_store`] through `fs` (tests use a `FaultyFs`).
pub fn write_store_in(
    fs: Arc<dyn FileSystem>,
    path: &Path,
    ds: &Dataset,
    bake: &ErrorBake,
    params: &ImportParams,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<StoreSummary, StoreError> {
    let bad = |reason: String| StoreError::Params { reason };
    if (bake.width as usize, bake.height as usize) != (ds.hf.width, ds.hf.height)
        || bake.source_checksum != ds.checksum()
    {
        return Err(bad(format!(
            "the bake ({}×{}, checksum {:#010x}) was not made from this dataset ({}×{})",
            bake.width, bake.height, bake.source_checksum, ds.hf.width, ds.hf.height
        )));
    }
    let meta = SourceMeta {
        spacing: (ds.hf.spacing_x, ds.hf.spacing_y),
        voids_filled: ds.hf.voids_filled as u64,
        geo: ds.hf.geo.clone(),
        spacing_note: ds.hf.spacing_note.clone(),
    };
    write_pages_in(
        fs,
        path,
        &meta,
        bake,
        params,
        &mut DatasetPages(ds),
        progress,
    )
}

/// What the header records of the source besides the bake.
pub(crate) struct SourceMeta {
    /// Metres between columns and between rows.
    pub spacing: (f64, f64),
    pub voids_filled: u64,
    pub geo: Option<crate::GeoReference>,
    pub spacing_note: String,
}

/// The samples of the pages, a page row at a time in index order.
pub(crate) trait PageSamples: Sync {
    /// Called (in index order) before the pages of page row `py` of `level` are cut.
    fn begin_row(&mut self, layout: &Layout, level: u32, py: u32) -> Result<(), StoreError>;
    /// The samples of page `id` (of the row begun last), south row first.
    fn samples(&self, layout: &Layout, id: PageId) -> Vec<f32>;
}

/// Pages cut from a dataset in memory.
struct DatasetPages<'a>(&'a Dataset);

impl PageSamples for DatasetPages<'_> {
    fn begin_row(&mut self, _: &Layout, _: u32, _: u32) -> Result<(), StoreError> {
        Ok(())
    }

    fn samples(&self, layout: &Layout, id: PageId) -> Vec<f32> {
        cut_samples(self.0, layout, id)
    }
}

/// The store at `path` from `bake` and the pages' samples (see the module documentation).
pub(crate) fn write_pages_in(
    fs: Arc<dyn FileSystem>,
    path: &Path,
    meta: &SourceMeta,
    bake: &ErrorBake,
    params: &ImportParams,
    pages: &mut dyn PageSamples,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<StoreSummary, StoreError> {
    let bad = |reason: String| StoreError::Params { reason };
    let q = bake.params.tile_size - 1;
    let levels = bake.levels.len() as u32;
    let layout = Layout::new(bake.width, bake.height, q, levels, params.page_tiles).ok_or_else(|| {
        bad(format!(
            "page side {} tiles is not a power of two, or {levels} levels of {}-vertex tiles do not tile {}×{}",
            params.page_tiles, bake.params.tile_size, bake.width, bake.height
        ))
    })?;
    let n = layout.page_count() as usize;
    let max_eps: Vec<f32> = bake
        .levels
        .iter()
        .map(|t| {
            t.eps
                .iter()
                .zip(&t.terrain)
                .filter(|(_, &k)| k)
                .fold(0f32, |a, (&e, _)| a.max(e))
        })
        .collect();
    let raw_sample_bytes: u64 = (0..n)
        .map(|i| {
            let (l, x, y) = layout.page_at(i).expect("in layout");
            4 * layout.rect(l, x, y).samples() as u64
        })
        .sum();
    let mut header = StoreHeader {
        version: STORE_VERSION,
        header_size: 0,
        tile_size: bake.params.tile_size,
        page_tiles: params.page_tiles,
        levels,
        width: bake.width,
        height: bake.height,
        valid_width: bake.valid_width,
        valid_height: bake.valid_height,
        page_count: n as u32,
        spacing_x: meta.spacing.0,
        spacing_y: meta.spacing.1,
        source_checksum: bake.source_checksum,
        voids_filled: meta.voids_filled,
        data_offset: 0,
        raw_sample_bytes,
        geo: meta.geo.clone(),
        spacing_note: meta.spacing_note.clone(),
        sources: params.sources.clone(),
        max_eps: max_eps.clone(),
    };
    header.header_size = header_len(&header) as u32;
    header.data_offset = u64::from(header.header_size);

    let mut f = AtomicFile::create_in(fs, path)?;
    let write = |f: &mut AtomicFile, b: &[u8]| -> Result<(), StoreError> {
        f.write_all(b).map_err(|e| {
            StoreError::Write(aerie_io::WriteError {
                path: path.to_path_buf(),
                step: "write",
                source: e,
            })
        })
    };
    write(&mut f, &encode_header(&header))?;
    // Pages are compressed a page row at a time on all cores and written in index order as
    // each row completes: memory holds one row of pages, not the file.
    let mut index = Vec::with_capacity(INDEX_ENTRY * n);
    let mut offset = header.data_offset;
    let mut counts = [0u32; 3];
    let done = AtomicU64::new(0);
    let mut start = 0;
    while start < n {
        let (level, _, py) = layout.page_at(start).expect("in layout");
        let row_pages = layout.levels[level as usize].pages_x as usize;
        let batch = start..start + row_pages;
        start = batch.end;
        pages.begin_row(&layout, level, py)?;
        let compressed = compress_batch(
            &*pages,
            bake,
            &layout,
            batch.clone(),
            params.zstd_level,
            &|| progress(done.fetch_add(1, Ordering::Relaxed) + 1, n as u64),
        )?;
        for (i, (coding, bytes)) in batch.zip(&compressed) {
            let (level, px, py) = layout.page_at(i).expect("in layout");
            let e = PageEntry {
                level,
                px,
                py,
                coding: *coding,
                offset,
                len: bytes.len() as u32,
                crc: crc32fast::hash(bytes),
            };
            encode_entry(&e, &mut index);
            offset += bytes.len() as u64;
            counts[coding.code() as usize] += 1;
            write(&mut f, bytes)?;
        }
    }
    let page_bytes = offset - header.data_offset;
    let section = zstd::bulk::compress(&bake_section::encode(bake), params.zstd_level.max(3))
        .map_err(|e| StoreError::Params {
            reason: format!("bake section: zstd: {e}"),
        })?;
    write(&mut f, &section)?;
    let trailer = Trailer {
        index_offset: offset + section.len() as u64,
        index_crc: crc32fast::hash(&index),
        bake_offset: offset,
        bake_len: section.len() as u64,
        bake_crc: crc32fast::hash(&section),
    };
    write(&mut f, &index)?;
    write(&mut f, &encode_trailer(&trailer, n as u32))?;
    f.commit()?;

    Ok(StoreSummary {
        real_samples: u64::from(bake.valid_width) * u64::from(bake.valid_height),
        page_samples: raw_sample_bytes / 4,
        pages: n as u32,
        i16_pages: counts[Coding::I16Gradient.code() as usize],
        exception_pages: counts[Coding::I16Exceptions.code() as usize],
        f32_pages: counts[Coding::F32Xor.code() as usize],
        page_bytes,
        bake_bytes: section.len() as u64,
        file_bytes: trailer.index_offset + (INDEX_ENTRY * n + TRAILER) as u64,
        max_eps,
        header,
    })
}

/// Pages `batch` (one page row) coded and compressed, in index order, on all cores; `tick`
/// after each.
fn compress_batch(
    pages: &dyn PageSamples,
    bake: &ErrorBake,
    layout: &Layout,
    batch: std::ops::Range<usize>,
    level: i32,
    tick: &(dyn Fn() + Sync),
) -> Result<Vec<(Coding, Vec<u8>)>, StoreError> {
    par_pages(layout, batch, level, tick, &|id, z| {
        let samples = pages.samples(layout, id);
        let tables = cut_tables(bake, layout, id);
        let rect = layout.rect(id.level, id.px, id.py);
        let (coding, raw) = encode_payload(id, rect, &samples, &tables);
        let c = z.compress(&raw).map_err(|e| format!("{id}: zstd: {e}"))?;
        Ok((coding, c))
    })
    .map_err(|reason| StoreError::Params { reason })
}
