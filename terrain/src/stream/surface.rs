//! The host's queries (height of terrain, line of sight) over the streamed pages: a
//! [`StreamedSurface`] is a snapshot of the level-0 pages resident when it was taken (their
//! `Arc`s: no copy, and an eviction after it does not pull a page from under a query), with
//! the fine hierarchy the loader built for each tile when its page arrived and the tile maxima
//! of every level from the store's bake section (always exact, never +∞). A query over a tile
//! not in the snapshot answers `Pending` naming it; the caller asks for that tile's level-0
//! page with its next request.

use std::collections::HashMap;
use std::sync::Arc;

use crate::bake::ErrorBake;
use crate::query::hierarchy::fine_len;
use crate::query::{SurfaceGrid, SurfaceSource, TileView};

use super::loader::Loaded;

/// Resident level-0 pages of a streamed store, for the queries.
pub struct StreamedSurface {
    pub(super) grid: SurfaceGrid,
    pub(super) page_tiles: u32,
    pub(super) bake: Arc<ErrorBake>,
    pub(super) pages: HashMap<(u32, u32), Arc<Loaded>>,
}

impl StreamedSurface {
    /// Level-0 pages in the snapshot.
    pub fn pages(&self) -> usize {
        self.pages.len()
    }
}

impl SurfaceSource for StreamedSurface {
    fn grid(&self) -> &SurfaceGrid {
        &self.grid
    }

    fn tile_max(&self, level: u32, tx: u32, ty: u32) -> f32 {
        let t = &self.bake.levels[level as usize];
        t.max[(ty * t.tiles_x + tx) as usize]
    }

    fn tile(&self, tx: u32, ty: u32) -> Option<TileView<'_>> {
        let p = self.page_tiles;
        let l = self.pages.get(&(tx / p, ty / p))?;
        let r = l.page.rect;
        let (i, j) = (tx.checked_sub(r.tx0)?, ty.checked_sub(r.ty0)?);
        if i >= r.ntx || j >= r.nty {
            return None;
        }
        let q = self.grid.tile_quads;
        let k = (j * r.ntx + i) as usize;
        let per = fine_len(q);
        let start = j as usize * q * r.cols as usize + i as usize * q;
        TileView::new(
            &l.page.samples[start..],
            r.cols as usize,
            q,
            (&l.page.min[k], &l.page.max[k]),
            l.fine.get(k * per..(k + 1) * per)?,
        )
    }
}
