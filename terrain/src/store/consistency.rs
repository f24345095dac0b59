//! What can be checked at open that the header, the bake section and the pages agree, in
//! O(index + bake) time and a few page reads, so that a store assembled from mismatched parts
//! (a header or bake section of another import, a hand-edited count) is refused at open with
//! the byte offset and the reason instead of failing page by page during a flight.
//!
//! Checked (beyond what [`Store::open`] checks of the header, trailer and index):
//! - the header's raw sample bytes are what its layout's pages hold as f32;
//! - the header's filled voids fit its real samples;
//! - the header's max ε per level is the bake section's largest ε over that level's terrain
//!   tiles (the import writes both from one bake);
//! - the coarsest level's pages (at most [`MAX_TOP_PAGES`]) and level 0's first page read,
//!   verify (CRC, content, tables against the bake section), every sample lies within its
//!   tile's full-resolution min/max, and the coarsest level is the exact power-of-two
//!   subsampling of level 0 where the two pages overlap.

use super::error::{PageId, StoreError};
use super::format::Layout;
use super::pages::Page;
use super::read::Store;
use crate::bake::ErrorBake;

/// At most this many pages of the coarsest level are read at open (it has one page unless
/// the grid is far larger than a page at that level).
pub const MAX_TOP_PAGES: u32 = 4;

/// Byte offsets of the header fields checked here.
const VOIDS_AT: u64 = 72;
const RAW_BYTES_AT: u64 = 88;

/// Bytes the layout's pages hold as f32 samples.
pub fn layout_sample_bytes(layout: &Layout) -> u64 {
    (0..layout.page_count() as usize)
        .filter_map(|i| layout.page_at(i))
        .map(|(l, x, y)| 4 * layout.rect(l, x, y).samples() as u64)
        .sum()
}

/// The largest ε over the terrain tiles of each level (the header's max ε, as the import
/// computes it).
pub fn max_eps_per_level(bake: &ErrorBake) -> Vec<f32> {
    bake.levels
        .iter()
        .map(|t| {
            t.eps
                .iter()
                .zip(&t.terrain)
                .filter(|(_, &k)| k)
                .fold(0f32, |a, (&e, _)| a.max(e))
        })
        .collect()
}

/// The first sample of `page` outside its tile's full-resolution [min, max] in `bake`:
/// (sample column, row, value, min, max). A level's samples are a subsampling of level 0, so
/// each lies within the bounds of the tiles it belongs to.
fn sample_outside_bounds(
    page: &Page,
    bake: &ErrorBake,
    q: u32,
) -> Option<(u32, u32, f32, f32, f32)> {
    let t = bake.levels.get(page.id.level as usize)?;
    let r = page.rect;
    for j in 0..r.rows {
        for i in 0..r.cols {
            // A sample on a tile edge lies in the tiles on both sides: checking one is enough.
            let tx = (r.tx0 + (i / q).min(r.ntx - 1)).min(t.tiles_x - 1);
            let ty = (r.ty0 + (j / q).min(r.nty - 1)).min(t.tiles_y - 1);
            let b = (ty * t.tiles_x + tx) as usize;
            let v = page.at(i, j);
            if !(t.min[b] <= v && v <= t.max[b]) {
                return Some((i, j, v, t.min[b], t.max[b]));
            }
        }
    }
    None
}

/// The first level-`L` sample of `top` that is not the level-0 sample of `base` at the same
/// place (where `base` covers it): (top column, row, top value, level-0 value).
fn subsampling_mismatch(top: &Page, base: &Page, q: u32) -> Option<(u32, u32, f32, f32)> {
    let step = 1u64 << top.id.level;
    let (bx0, by0) = (
        base.rect.tx0 as u64 * q as u64,
        base.rect.ty0 as u64 * q as u64,
    );
    let (tx0, ty0) = (
        top.rect.tx0 as u64 * q as u64,
        top.rect.ty0 as u64 * q as u64,
    );
    for j in 0..top.rect.rows {
        let y0 = (ty0 + j as u64) * step;
        if y0 < by0 || y0 - by0 >= base.rect.rows as u64 {
            continue;
        }
        for i in 0..top.rect.cols {
            let x0 = (tx0 + i as u64) * step;
            if x0 < bx0 || x0 - bx0 >= base.rect.cols as u64 {
                continue;
            }
            let (a, b) = (top.at(i, j), base.at((x0 - bx0) as u32, (y0 - by0) as u32));
            if a.to_bits() != b.to_bits() {
                return Some((i, j, a, b));
            }
        }
    }
    None
}

impl Store {
    /// Refuses, naming the byte offset and the reason, a store whose header, bake section
    /// (`bake`, from [`Store::read_bake`]) and pages disagree (see the module's list). Reads
    /// at most [`MAX_TOP_PAGES`] + 1 pages; the rest is O(index + bake).
    pub fn check_consistency(&self, bake: &ErrorBake) -> Result<(), StoreError> {
        let h = self.header();
        let layout = self.layout();
        let fmt = |offset: u64, field: &'static str, reason: String| StoreError::Format {
            path: self.path().to_path_buf(),
            offset,
            field,
            reason,
        };
        let want = layout_sample_bytes(layout);
        if h.raw_sample_bytes != want {
            return Err(fmt(
                RAW_BYTES_AT,
                "raw sample bytes",
                format!(
                    "{} bytes, but the layout's {} pages hold {want} bytes of f32 samples: the header does not describe these pages",
                    h.raw_sample_bytes, h.page_count
                ),
            ));
        }
        let real = u64::from(h.valid_width) * u64::from(h.valid_height);
        if h.voids_filled > real {
            return Err(fmt(
                VOIDS_AT,
                "voids filled",
                format!(
                    "{} filled voids in {}×{} = {real} real samples",
                    h.voids_filled, h.valid_width, h.valid_height
                ),
            ));
        }
        // The max ε values end the header's variable part, before its CRC.
        let eps_at = u64::from(h.header_size) - 4 - 4 * u64::from(h.levels);
        for (l, (&header, bake)) in h.max_eps.iter().zip(max_eps_per_level(bake)).enumerate() {
            if header.to_bits() != bake.to_bits() {
                return Err(fmt(
                    eps_at + 4 * l as u64,
                    "max ε",
                    format!(
                        "level {l}: {header} m in the header, {bake} m in the bake section: the bake section is not this store's"
                    ),
                ));
            }
        }
        let top = h.levels - 1;
        let g = layout.levels[top as usize];
        let mut top_pages = Vec::new();
        'rows: for py in 0..g.pages_y {
            for px in 0..g.pages_x {
                if top_pages.len() as u32 == MAX_TOP_PAGES {
                    break 'rows;
                }
                top_pages.push(PageId { level: top, px, py });
            }
        }
        let base_id = PageId {
            level: 0,
            px: 0,
            py: 0,
        };
        let offset_of = |id: PageId| self.entry(id).map_or(0, |e| e.offset);
        let read = |id: PageId| -> Result<Page, StoreError> {
            let at = offset_of(id);
            let bad = |reason: String| fmt(at, "page", format!("{id}: {reason}"));
            let page = self
                .read_page(id)
                .map_err(|e| bad(format!("read at open to check the store: {e}")))?;
            page.check_tables(bake).map_err(bad)?;
            if let Some((i, j, v, lo, hi)) = sample_outside_bounds(&page, bake, layout.q) {
                return Err(bad(format!(
                    "sample ({i}, {j}) is {v} m, outside its tile's {lo}..{hi} m in the bake section"
                )));
            }
            Ok(page)
        };
        let base = read(base_id)?;
        for id in top_pages {
            let page = read(id)?;
            if top == 0 {
                continue;
            }
            if let Some((i, j, a, b)) = subsampling_mismatch(&page, &base, layout.q) {
                return Err(fmt(
                    offset_of(id),
                    "page",
                    format!(
                        "{id}: sample ({i}, {j}) is {a} m, level 0 has {b} m there: level {top} is not the subsampling of level 0"
                    ),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_bytes_count_every_page_once() {
        // 65×65, 17-vertex tiles, 2 levels, pages of 2×2 tiles: level 0 has 2×2 pages of
        // 33² samples, level 1 one page of 33².
        let layout = Layout::new(65, 65, 16, 2, 2).unwrap();
        assert_eq!(layout_sample_bytes(&layout), 4 * (4 * 33 * 33 + 33 * 33));
    }
}
