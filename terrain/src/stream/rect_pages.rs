//! Which pages a [`SampleRect`] reads, and where each of its samples lies in them. Pure.
//!
//! The rectangle's samples are level-0 samples `clamp(origin + (i, j)·2^level)`; they are read
//! from the coarsest store level whose grid holds every one of them: the rectangle's own
//! level when its origin is on that level's grid (the clamped edges always are: the grid's
//! last sample is a multiple of every level's step), a finer one when it is not, the store's
//! coarsest when the rectangle's level is coarser still. A sample on the edge shared by two
//! pages is read from the page it starts (the last page for the grid's own far edge).

use crate::source::SampleRect;
use crate::store::{Layout, PageId};

/// Where a rectangle's samples lie.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RectPages {
    /// The store level read.
    pub level: u32,
    /// Per column of the rectangle: page column and column inside that page.
    pub cols: Vec<(u32, u32)>,
    /// Per row: page row and row inside that page.
    pub rows: Vec<(u32, u32)>,
    /// The distinct page columns and rows, increasing.
    pub page_cols: Vec<u32>,
    pub page_rows: Vec<u32>,
}

impl RectPages {
    /// The pages read, row-major (south row first).
    pub fn pages(&self) -> impl Iterator<Item = PageId> + '_ {
        self.page_rows.iter().flat_map(move |&py| {
            self.page_cols.iter().map(move |&px| PageId {
                level: self.level,
                px,
                py,
            })
        })
    }
}

/// Level-0 coordinates `clamp(origin + i·step)` for `i < n` as (page, index in page) at
/// `level`; `span` level-`level` samples per page, `pages` pages on the axis.
fn axis(
    origin: i64,
    step: i64,
    n: u32,
    max: i64,
    level: u32,
    span: u32,
    pages: u32,
) -> Vec<(u32, u32)> {
    (0..i64::from(n))
        .map(|i| {
            let c = origin.saturating_add(i.saturating_mul(step)).clamp(0, max);
            let cl = (c >> level) as u32;
            let p = (cl / span).min(pages - 1);
            (p, cl - p * span)
        })
        .collect()
}

fn distinct(v: &[(u32, u32)]) -> Vec<u32> {
    let mut out: Vec<u32> = v.iter().map(|&(p, _)| p).collect();
    out.dedup();
    out
}

/// The pages and positions of `rect` in a store of `layout` over a `width × height` grid.
pub fn rect_pages(layout: &Layout, width: u32, height: u32, rect: &SampleRect) -> RectPages {
    // Past level 62 every sample but the first clamps to the grid's far edge anyway.
    let rl = rect.level.min(62);
    let top = layout.levels.len() as u32 - 1;
    let aligned = rect.origin[0]
        .trailing_zeros()
        .min(rect.origin[1].trailing_zeros());
    let level = rl.min(top).min(aligned);
    let step = 1i64 << rl;
    let g = layout.levels[level as usize];
    let span = layout.page_tiles * layout.q;
    let cols = axis(
        rect.origin[0],
        step,
        rect.size[0],
        i64::from(width) - 1,
        level,
        span,
        g.pages_x,
    );
    let rows = axis(
        rect.origin[1],
        step,
        rect.size[1],
        i64::from(height) - 1,
        level,
        span,
        g.pages_y,
    );
    RectPages {
        level,
        page_cols: distinct(&cols),
        page_rows: distinct(&rows),
        cols,
        rows,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aligned_unaligned_past_the_edges_and_coarser_than_the_store() {
        // 257 × 129 samples, q = 8, 3 levels, pages of 2 tiles: level 0 has 32 × 16 tiles,
        // 16 × 8 pages of 16 samples.
        let layout = Layout::new(257, 129, 8, 3, 2).unwrap();
        let r = SampleRect {
            level: 1,
            origin: [-4, 30],
            size: [4, 2],
        };
        let m = rect_pages(&layout, 257, 129, &r);
        assert_eq!(m.level, 1);
        // Columns -4, -2 clamp to 0; 0, 2 → level-1 columns 0, 0, 0, 1 (32 samples a page).
        assert_eq!(m.cols, vec![(0, 0), (0, 0), (0, 0), (0, 1)]);
        // Rows 30, 32 → level-1 rows 15 (page row 0) and 16, the first of page row 1.
        assert_eq!(m.rows, vec![(0, 15), (1, 0)]);
        // An odd origin reads level 0.
        let m = rect_pages(
            &layout,
            257,
            129,
            &SampleRect {
                level: 2,
                origin: [1, 16],
                size: [5, 1],
            },
        );
        assert_eq!(m.level, 0);
        assert_eq!(
            m.cols,
            vec![(0, 1), (0, 5), (0, 9), (0, 13), (1, 1)],
            "columns 1, 5, 9, 13, 17"
        );
        assert_eq!(m.rows, vec![(1, 0)]);
        assert_eq!(m.page_cols, vec![0, 1]);
        // Level 5 on a 3-level store reads level 2; the east edge is the last page's last column.
        let m = rect_pages(
            &layout,
            257,
            129,
            &SampleRect {
                level: 5,
                origin: [0, 0],
                size: [10, 2],
            },
        );
        assert_eq!(m.level, 2);
        let g = layout.levels[2];
        assert_eq!(m.cols[9], (g.pages_x - 1, 16));
        assert_eq!(m.cols[8], m.cols[9]);
        assert_eq!(m.page_cols, vec![0, 1, 2, 3]);
        assert_eq!(m.pages().count(), 4);
    }
}
