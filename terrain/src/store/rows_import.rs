//! The streamed import: a raw grid larger than memory ([`RawRows`]) made into a store reading
//! it a band of rows at a time, twice — once for the error bake (the same
//! [`BakeAccumulator`] as [`crate::bake::bake`], fed band by band with the level rows each band's
//! cells reach beyond it), once for the pages (a page row at a time, in index order, through
//! the same writer as [`super::write_store`]). Memory: the bake's tables and one band (≤ 256
//! rows), never the grid. The bytes written are those of the in-memory import of the same
//! file (tested).

use std::path::Path;
use std::sync::Arc;

use aerie_io::FileSystem;

use crate::bake::exact::{rows_needed, BakeAccumulator, BakeRows};
use crate::bake::{BakeParams, ErrorBake};
use crate::dataset::le_bytes;
use crate::load::{DemError, RawRows};

use super::error::{PageId, StoreError};
use super::format::Layout;
use super::write::{write_pages_in, ImportParams, PageSamples, SourceMeta, StoreSummary};

/// Rows read per band of the bake (≤ 32 MiB of f32 at 32769 samples per row).
const BAND_ROWS: usize = 256;

/// A band of padded rows and the rows beyond it that its cells' level surfaces reach.
struct Band {
    r0: usize,
    n: usize,
    width: usize,
    rows: Vec<f32>,
    extra: Vec<(usize, Vec<f32>)>,
}

impl BakeRows for Band {
    fn row(&self, r: usize) -> &[f32] {
        if (self.r0..self.r0 + self.n).contains(&r) {
            let i = r - self.r0;
            return &self.rows[i * self.width..(i + 1) * self.width];
        }
        self.extra
            .iter()
            .find(|(k, _)| *k == r)
            .map(|(_, v)| v.as_slice())
            .unwrap_or_else(|| panic!("row {r} is neither in the band nor among its extra rows"))
    }
}

/// Bakes `rows` (`params.levels` resolved for its padded size) a band at a time, with the
/// CRC-32 of its padded samples; `progress(samples done, samples)`.
pub fn bake_rows(
    rows: &RawRows,
    params: BakeParams,
    progress: &dyn Fn(u64, u64),
) -> Result<ErrorBake, DemError> {
    let (w, h) = rows.padded_size();
    let total = (w * h) as u64;
    let mut acc = BakeAccumulator::new(params, (w, h), rows.valid_size());
    let mut crc = crc32fast::Hasher::new();
    let mut band = Band {
        r0: 0,
        n: 0,
        width: w,
        rows: vec![0f32; BAND_ROWS.min(h) * w],
        extra: Vec::new(),
    };
    progress(0, total);
    for r0 in (0..h).step_by(BAND_ROWS) {
        let r1 = (r0 + BAND_ROWS).min(h);
        band.r0 = r0;
        band.n = r1 - r0;
        for (i, r) in (r0..r1).enumerate() {
            rows.read_row(r, &mut band.rows[i * w..(i + 1) * w])?;
        }
        crc.update(&le_bytes(&band.rows[..band.n * w]));
        band.extra.clear();
        for r in rows_needed(params.levels, h, r0, r1) {
            let mut v = vec![0f32; w];
            rows.read_row(r, &mut v)?;
            band.extra.push((r, v));
        }
        acc.add_rows(&band, r0, r1, &|d| {
            progress((r0 as u64 + d) * w as u64, total)
        });
    }
    progress(total, total);
    Ok(acc.finish(rows.spacing(), crc.finalize()))
}

/// One page row of one level, its level samples read from the source's rows.
struct RowPages<'a> {
    rows: &'a RawRows,
    /// Level-L samples per row and the first level-L column/row held.
    level_width: usize,
    y0: usize,
    buf: Vec<f32>,
    row: Vec<f32>,
}

impl PageSamples for RowPages<'_> {
    fn begin_row(&mut self, layout: &Layout, level: u32, py: u32) -> Result<(), StoreError> {
        let r = layout.rect(level, 0, py);
        let step = 1usize << level;
        let q = layout.q as usize;
        self.level_width = (self.row.len() - 1) / step + 1;
        self.y0 = r.ty0 as usize * q;
        self.buf.clear();
        for j in 0..r.rows as usize {
            self.rows.read_row((self.y0 + j) * step, &mut self.row)?;
            self.buf
                .extend((0..self.level_width).map(|c| self.row[c * step]));
        }
        Ok(())
    }

    fn samples(&self, layout: &Layout, id: PageId) -> Vec<f32> {
        let r = layout.rect(id.level, id.px, id.py);
        let c0 = r.tx0 as usize * layout.q as usize;
        debug_assert_eq!(r.ty0 as usize * layout.q as usize, self.y0);
        let mut out = Vec::with_capacity(r.samples());
        for j in 0..r.rows as usize {
            let at = j * self.level_width + c0;
            out.extend_from_slice(&self.buf[at..at + r.cols as usize]);
        }
        out
    }
}

/// Writes the store of `rows` and its `bake` (from [`bake_rows`]) at `path`, reading the
/// pages' samples a page row at a time; `progress(pages done, pages)`.
pub fn write_store_rows(
    path: &Path,
    rows: &RawRows,
    bake: &ErrorBake,
    params: &ImportParams,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<StoreSummary, StoreError> {
    write_store_rows_in(aerie_io::real(), path, rows, bake, params, progress)
}

/// [`write_store_rows`] through `fs`.
pub fn write_store_rows_in(
    fs: Arc<dyn FileSystem>,
    path: &Path,
    rows: &RawRows,
    bake: &ErrorBake,
    params: &ImportParams,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<StoreSummary, StoreError> {
    let (w, h) = rows.padded_size();
    if (bake.width as usize, bake.height as usize) != (w, h) {
        return Err(StoreError::Params {
            reason: format!(
                "the bake ({}×{}) was not made from {} ({w}×{h} padded)",
                bake.width,
                bake.height,
                rows.path().display()
            ),
        });
    }
    let meta = SourceMeta {
        spacing: rows.spacing(),
        voids_filled: 0,
        geo: rows.geo().cloned(),
        spacing_note: rows.spacing_note().to_string(),
    };
    let mut pages = RowPages {
        rows,
        level_width: 0,
        y0: 0,
        buf: Vec::new(),
        row: vec![0f32; w],
    };
    write_pages_in(fs, path, &meta, bake, params, &mut pages, progress)
}
