//! The query service's [`SurfaceSource`] over an opened store: level-0 tiles are resident once
//! their page was loaded ([`StoreSource::load_tiles`]); tile maxima of the coarser levels come
//! from the pages read on the way and are +∞ (never skip) where no page told them, so a
//! question over tiles not loaded answers `Pending`, never a wrong answer.

use std::collections::{HashMap, HashSet};

use crate::query::hierarchy::{build_tile, fine_len};
use crate::query::{SurfaceGrid, SurfaceSource, TileView};

use super::error::{PageError, PageId};
use super::pages::Page;
use super::read::Store;

struct Resident {
    samples: Vec<f32>,
    min: f32,
    max: f32,
    fine: Vec<u8>,
}

/// Resident level-0 tiles of a store, for the host's queries.
pub struct StoreSource {
    grid: SurfaceGrid,
    page_tiles: u32,
    /// Per level, per tile: the bake's max, +∞ until a page said it.
    max: Vec<Vec<f32>>,
    tiles: HashMap<(u32, u32), Resident>,
    loaded: HashSet<PageId>,
}

impl StoreSource {
    /// No tile resident yet.
    pub fn new(store: &Store) -> Self {
        let h = store.header();
        let grid = SurfaceGrid {
            width: h.width as usize,
            height: h.height as usize,
            valid_width: h.valid_width as usize,
            valid_height: h.valid_height as usize,
            spacing_x: h.spacing_x,
            spacing_y: h.spacing_y,
            tile_quads: h.tile_size as usize - 1,
            levels: h.levels,
        };
        let max = store
            .layout()
            .levels
            .iter()
            .map(|l| vec![f32::INFINITY; (l.tiles_x * l.tiles_y) as usize])
            .collect();
        StoreSource {
            grid,
            page_tiles: h.page_tiles,
            max,
            tiles: HashMap::new(),
            loaded: HashSet::new(),
        }
    }

    /// Makes level-0 tiles resident: reads the level-0 page of each (all the page's tiles come
    /// with it) and the page above it at every coarser level (their tile maxima). Returns the
    /// number of pages read; a page that cannot be read stops with its error (what was loaded
    /// before stays).
    pub fn load_tiles(
        &mut self,
        store: &Store,
        tiles: impl IntoIterator<Item = (u32, u32)>,
    ) -> Result<usize, PageError> {
        let mut read = 0;
        for (tx, ty) in tiles {
            let (px, py) = (tx / self.page_tiles, ty / self.page_tiles);
            for level in 0..self.grid.levels {
                let id = PageId {
                    level,
                    px: px >> level,
                    py: py >> level,
                };
                if self.loaded.contains(&id) {
                    continue;
                }
                let page = store.read_page(id)?;
                self.take(store, &page)?;
                self.loaded.insert(id);
                read += 1;
            }
        }
        Ok(read)
    }

    /// Resident level-0 tiles.
    pub fn resident_tiles(&self) -> usize {
        self.tiles.len()
    }

    fn take(&mut self, store: &Store, page: &Page) -> Result<(), PageError> {
        let r = page.rect;
        let level = page.id.level;
        let tiles_x = store.layout().levels[level as usize].tiles_x;
        for j in 0..r.nty {
            for i in 0..r.ntx {
                let k = (j * r.ntx + i) as usize;
                self.max[level as usize][((r.ty0 + j) * tiles_x + r.tx0 + i) as usize] =
                    page.max[k];
            }
        }
        if level != 0 {
            return Ok(());
        }
        let q = self.grid.tile_quads;
        let mut scratch = Vec::new();
        for j in 0..r.nty {
            for i in 0..r.ntx {
                let k = (j * r.ntx + i) as usize;
                let mut samples = Vec::with_capacity((q + 1) * (q + 1));
                for row in 0..=q {
                    let at = (j as usize * q + row) * r.cols as usize + i as usize * q;
                    samples.extend_from_slice(&page.samples[at..at + q + 1]);
                }
                let (min, max) = (page.min[k], page.max[k]);
                let mut fine = vec![0u8; fine_len(q)];
                let got = build_tile(q, &samples, q + 1, (min, max), &mut fine, &mut scratch);
                if got != max {
                    let e = store.entry(page.id)?;
                    return Err(PageError::Content {
                        path: store.path().to_path_buf(),
                        page: page.id,
                        offset: e.offset,
                        end: e.offset + u64::from(e.len),
                        reason: format!(
                            "tile ({}, {}): its samples' maximum is {got}, its stored maximum {max}",
                            r.tx0 + i,
                            r.ty0 + j
                        ),
                    });
                }
                self.tiles.insert(
                    (r.tx0 + i, r.ty0 + j),
                    Resident {
                        samples,
                        min,
                        max,
                        fine,
                    },
                );
            }
        }
        Ok(())
    }
}

impl SurfaceSource for StoreSource {
    fn grid(&self) -> &SurfaceGrid {
        &self.grid
    }

    fn tile_max(&self, level: u32, tx: u32, ty: u32) -> f32 {
        let t = &self.max[level as usize];
        let nx = (self.grid.tiles(level).0) as usize;
        t[ty as usize * nx + tx as usize]
    }

    fn tile(&self, tx: u32, ty: u32) -> Option<TileView<'_>> {
        let t = self.tiles.get(&(tx, ty))?;
        let q = self.grid.tile_quads;
        TileView::new(&t.samples, q + 1, q, (&t.min, &t.max), &t.fine)
    }
}
