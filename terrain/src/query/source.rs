//! Where the queries read heights: the [`SurfaceSource`] trait (so a streamed store can serve
//! them later) and [`InMemorySource`], over a loaded [`Dataset`] and its [`ErrorBake`].

use std::sync::Arc;

use crate::bake::ErrorBake;
use crate::dataset::Dataset;

use super::hierarchy::{build_tile, decode, fine_len, level_offset};

/// The grid a source serves: the dataset's padded heightfield, tiled as its bake is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceGrid {
    /// Padded samples per row (`2^Kx + 1`).
    pub width: usize,
    /// Padded rows (`2^Ky + 1`).
    pub height: usize,
    /// Real samples per row; columns at or east of it are padding.
    pub valid_width: usize,
    /// Real rows; rows at or north of it are padding.
    pub valid_height: usize,
    /// Metres between columns (east-west).
    pub spacing_x: f64,
    /// Metres between rows (north-south).
    pub spacing_y: f64,
    /// Quads per level-0 tile side, `q = m − 1 = 2^j` (the bake's tile size minus one).
    pub tile_quads: usize,
    /// Levels of the bake (level `L` tiles are `q · 2^L` quads wide).
    pub levels: u32,
}

impl SurfaceGrid {
    /// `j` with `tile_quads = 2^j`.
    pub fn log2_tile_quads(&self) -> u32 {
        self.tile_quads.trailing_zeros()
    }

    /// Level-`level` tiles per axis.
    pub fn tiles(&self, level: u32) -> (u32, u32) {
        let t = self.tile_quads << level;
        (
            ((self.width - 1) / t) as u32,
            ((self.height - 1) / t) as u32,
        )
    }

    /// East and north extent of the real data, metres from sample (0, 0): queries answer on
    /// `[0, east] × [0, north]` and nowhere else.
    pub fn real_extent_m(&self) -> (f64, f64) {
        (
            (self.valid_width - 1) as f64 * self.spacing_x,
            (self.valid_height - 1) as f64 * self.spacing_y,
        )
    }
}

/// One resident level-0 tile: its `(q+1)²` samples (edges shared with the neighbours) and its
/// fine hierarchy ([`super::hierarchy`]).
#[derive(Debug, Clone, Copy)]
pub struct TileView<'a> {
    samples: &'a [f32],
    stride: usize,
    q: usize,
    min: f32,
    max: f32,
    fine: &'a [u8],
}

impl<'a> TileView<'a> {
    /// A view of tile samples `samples[j · stride + i]` (i east, j north, both `0 ..= q`),
    /// whose bake bounds are `min`, `max` and whose fine hierarchy is `fine` (built with
    /// [`super::hierarchy::build_tile`] against the same bounds). `None` when a slice is too
    /// short for that.
    pub fn new(
        samples: &'a [f32],
        stride: usize,
        q: usize,
        bounds: (f32, f32),
        fine: &'a [u8],
    ) -> Option<Self> {
        let fits = q.is_power_of_two()
            && q >= 2
            && stride > q
            && samples.len() > q * stride + q
            && fine.len() == fine_len(q);
        fits.then_some(TileView {
            samples,
            stride,
            q,
            min: bounds.0,
            max: bounds.1,
            fine,
        })
    }

    /// Sample (i, j) of the tile, `0 ≤ i, j ≤ q`.
    #[inline]
    pub fn h(&self, i: usize, j: usize) -> f64 {
        f64::from(self.samples[j * self.stride + i])
    }

    /// Upper bound of the heights of block (bi, bj) of level `k` (`1 ≤ k < j`), metres.
    #[inline]
    pub fn block_max(&self, k: u32, bi: usize, bj: usize) -> f64 {
        let n = self.q >> k;
        decode(
            self.min,
            self.max,
            self.fine[level_offset(self.q, k) + bj * n + bi],
        )
    }
}

/// What the queries need from whoever holds the terrain.
///
/// The per-tile maxima of every level are always available (a bake is small and lives in
/// RAM); the samples come tile by tile and may be missing. A query that needs a missing
/// level-0 tile answers `Pending` naming it.
pub trait SurfaceSource {
    /// The grid.
    fn grid(&self) -> &SurfaceGrid;

    /// Largest full-resolution height of level-`level` tile (tx, ty), metres (the bake's).
    fn tile_max(&self, level: u32, tx: u32, ty: u32) -> f32;

    /// Level-0 tile (tx, ty), or `None` when its samples are not resident.
    fn tile(&self, tx: u32, ty: u32) -> Option<TileView<'_>>;

    /// True when level-0 tile (tx, ty)'s samples are resident.
    fn is_resident(&self, tx: u32, ty: u32) -> bool {
        self.tile(tx, ty).is_some()
    }
}

/// Why a dataset and a bake cannot serve queries together; names the field and both values.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SourceError {
    /// The bake was made from other data.
    #[error("the bake does not belong to the dataset ({dataset_name}): {field} is {dataset} in the dataset and {bake} in the bake; re-run `aerie bake`")]
    Mismatch {
        dataset_name: String,
        field: &'static str,
        dataset: String,
        bake: String,
    },
}

/// Every tile resident: the loaded dataset, its bake, and the fine hierarchy of every tile
/// (built once, on all cores; [`InMemorySource::fine_bytes`] says its size).
#[derive(Debug, Clone)]
pub struct InMemorySource {
    dataset: Arc<Dataset>,
    bake: Arc<ErrorBake>,
    grid: SurfaceGrid,
    fine: Vec<u8>,
    per_tile: usize,
}

impl InMemorySource {
    /// Checks that `bake` was made from `dataset` (sizes, spacing, and every level-0 tile's
    /// maximum against its samples) and builds the fine hierarchy.
    pub fn new(dataset: Arc<Dataset>, bake: Arc<ErrorBake>) -> Result<Self, SourceError> {
        let hf = &dataset.hf;
        let mismatch = |field: &'static str, d: String, b: String| SourceError::Mismatch {
            dataset_name: dataset.source.clone(),
            field,
            dataset: d,
            bake: b,
        };
        for (field, d, b) in [
            ("width", hf.width, bake.width as usize),
            ("height", hf.height, bake.height as usize),
            (
                "valid_width",
                dataset.valid_width,
                bake.valid_width as usize,
            ),
            (
                "valid_height",
                dataset.valid_height,
                bake.valid_height as usize,
            ),
        ] {
            if d != b {
                return Err(mismatch(field, d.to_string(), b.to_string()));
            }
        }
        for (field, d, b) in [
            ("spacing_x", hf.spacing_x, bake.spacing_x),
            ("spacing_y", hf.spacing_y, bake.spacing_y),
        ] {
            if d != b {
                return Err(mismatch(field, d.to_string(), b.to_string()));
            }
        }
        if bake.levels.is_empty() {
            return Err(mismatch("levels", "≥ 1".into(), "0".into()));
        }
        let grid = SurfaceGrid {
            width: hf.width,
            height: hf.height,
            valid_width: dataset.valid_width,
            valid_height: dataset.valid_height,
            spacing_x: hf.spacing_x,
            spacing_y: hf.spacing_y,
            tile_quads: bake.params.tile_size as usize - 1,
            levels: bake.levels.len() as u32,
        };
        let (fine, per_tile) = build_fine(&dataset, &bake, &grid).map_err(|(tx, ty, got)| {
            mismatch(
                "a level-0 tile's maximum",
                format!("{got} at tile ({tx}, {ty})"),
                bake.bounds(0, tx, ty).1.to_string(),
            )
        })?;
        Ok(InMemorySource {
            dataset,
            bake,
            grid,
            fine,
            per_tile,
        })
    }

    /// Bytes of the fine hierarchy (what this source adds to the dataset and its bake).
    pub fn fine_bytes(&self) -> usize {
        self.fine.len()
    }

    /// The dataset.
    pub fn dataset(&self) -> &Arc<Dataset> {
        &self.dataset
    }

    /// The bake.
    pub fn bake(&self) -> &Arc<ErrorBake> {
        &self.bake
    }
}

impl SurfaceSource for InMemorySource {
    fn grid(&self) -> &SurfaceGrid {
        &self.grid
    }

    #[inline]
    fn tile_max(&self, level: u32, tx: u32, ty: u32) -> f32 {
        self.bake.bounds(level, tx, ty).1
    }

    #[inline]
    fn tile(&self, tx: u32, ty: u32) -> Option<TileView<'_>> {
        let (nx, ny) = self.grid.tiles(0);
        if tx >= nx || ty >= ny {
            return None;
        }
        let q = self.grid.tile_quads;
        let w = self.grid.width;
        let i = ty as usize * nx as usize + tx as usize;
        let start = ty as usize * q * w + tx as usize * q;
        TileView::new(
            &self.dataset.hf.heights[start..],
            w,
            q,
            self.bake.bounds(0, tx, ty),
            &self.fine[i * self.per_tile..(i + 1) * self.per_tile],
        )
    }
}

/// Every tile's fine hierarchy, tile rows shared out over the cores; `Err((tx, ty, max))` for
/// a tile whose samples' maximum is not the bake's.
fn build_fine(
    ds: &Dataset,
    bake: &ErrorBake,
    grid: &SurfaceGrid,
) -> Result<(Vec<u8>, usize), (u32, u32, f32)> {
    let q = grid.tile_quads;
    let per_tile = fine_len(q);
    let (nx, ny) = grid.tiles(0);
    let (nx, ny) = (nx as usize, ny as usize);
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
        .clamp(1, ny.max(1));
    let rows_per = ny.div_ceil(threads).max(1);
    let w = grid.width;
    let heights = &ds.hf.heights;
    // One tile row range per thread, each filling its own bytes (joined in order below).
    let build_rows = |rows: std::ops::Range<usize>| -> Result<Vec<u8>, (u32, u32, f32)> {
        let mut out = vec![0u8; rows.len() * nx * per_tile];
        for (dr, ty) in rows.enumerate() {
            for tx in 0..nx {
                let at = (dr * nx + tx) * per_tile;
                let start = ty * q * w + tx * q;
                let (min, max) = bake.bounds(0, tx as u32, ty as u32);
                let got = build_tile(
                    q,
                    &heights[start..],
                    w,
                    min,
                    max,
                    &mut out[at..at + per_tile],
                );
                if got != max {
                    return Err((tx as u32, ty as u32, got));
                }
            }
        }
        Ok(out)
    };
    let parts: Vec<Result<Vec<u8>, (u32, u32, f32)>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..ny)
            .step_by(rows_per)
            .map(|r0| {
                let rows = r0..(r0 + rows_per).min(ny);
                s.spawn(move || build_rows(rows))
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("fine hierarchy thread"))
            .collect()
    });
    let mut fine = Vec::with_capacity(nx * ny * per_tile);
    for p in parts {
        fine.extend_from_slice(&p?);
    }
    Ok((fine, per_tile))
}
