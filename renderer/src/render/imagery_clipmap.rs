//! The imagery clipmap's decisions (issue 17: a store's imagery streamed per page like the
//! heights). Pure: plain data in and out, no device.
//!
//! Each level L of the store's imagery layer (`aerie_terrain::drape::levels`: texel t centred
//! at level-0 grid coordinate (t + ½)·2^L/k − ½) keeps a square window of `side` texels
//! around the eye, one layer of a texture array, stored toroidally: absolute texel t sits at
//! t mod side, so a window that moves rewrites only the cells it uncovers. The window moves in
//! whole cells of [`CELL`] texels; each slot of the (side/CELL)² grid remembers which absolute
//! cell it holds and whether its texels are there. A level's window can be sampled only when
//! every one of its cells is filled ([`ImageryClipmap::region`]); the shader then falls back to
//! the next coarser level that can. Fills are ranked coarse levels first (something to draw
//! everywhere soonest), then by distance from the eye.
//!
//! Invariants (checked by the tests): a slot holds at most one cell, the one the window puts
//! there (cell c in slot c mod n); a cell is marked filled only after it was asked for since
//! the window last placed it; a region is reported only over filled cells.

use aerie_terrain::source::SampleRect;

use crate::render::gpu::IMAGERY_STREAM_LEVELS;

/// Texels per side of a cell: the unit in which windows move and fills are made.
pub const CELL: u32 = 64;

/// The streamed windows' largest side: at k = 2 a level-0 window spans 1,024 samples, four
/// times the default clipmap level (whose pages the heights keep resident anyway).
pub const MAX_STREAM_SIDE: u32 = 2048;

/// The smallest window worth streaming (two cells: the eye stays within the middle half).
pub const MIN_STREAM_SIDE: u32 = 2 * CELL;

/// Device bytes of a whole level raster of `w × h` texels with its full mip chain (4/3 of 4
/// bytes a texel), as `aerie_terrain::store::choose_level` counts them.
fn whole_level_bytes((w, h): (usize, usize)) -> f64 {
    (w * h) as f64 * 4.0 * 4.0 / 3.0
}

/// How a store's imagery layer is drawn within a byte budget: the coarse `base` level whole
/// (what the imagery texture holds, drawn everywhere) and, when even level 0 does not fit
/// whole, the finer levels `0..base` streamed in windows around the eye.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageryStreamPlan {
    pub base: u32,
    /// The streamed levels' windows (None: level `base` = 0 whole, or no room for windows).
    pub windows: Option<ImageryClipmapDesc>,
}

/// Plans a layer of `extents` (per level, its raster in texels) at `k` texels per sample into
/// `budget` bytes with textures of at most `max_side` texels a side:
/// - level 0 whole when it fits (nothing streamed);
/// - else the finest level fitting a quarter of the budget whole, and the levels finer than it
///   streamed in windows of the largest side (a multiple of [`CELL`], at most
///   [`MAX_STREAM_SIDE`] and no larger than level 0 needs) whose layers fit the other three
///   quarters (4 bytes a texel, no mips: a layer is a level), at most
///   [`IMAGERY_STREAM_LEVELS`] of them;
/// - else (windows under [`MIN_STREAM_SIDE`]) the finest level fitting the whole budget, as
///   before streaming existed. None: not even the coarsest level fits.
pub fn plan_imagery_stream(
    extents: &[(usize, usize)],
    k: u32,
    budget: u64,
    max_side: usize,
) -> Option<ImageryStreamPlan> {
    let fits = |l: usize, bytes: f64| {
        let e = extents[l];
        e.0.max(e.1) <= max_side && whole_level_bytes(e) <= bytes
    };
    let finest = |bytes: f64| (0..extents.len()).find(|&l| fits(l, bytes));
    let whole = finest(budget as f64)?;
    let plain = ImageryStreamPlan {
        base: whole as u32,
        windows: None,
    };
    if whole == 0 {
        return Some(plain);
    }
    // The uniforms hold at most IMAGERY_STREAM_LEVELS windows.
    let streamable = |&b: &usize| b > 0 && b <= IMAGERY_STREAM_LEVELS;
    let Some(base) = finest(budget as f64 / 4.0).filter(streamable) else {
        return Some(plain);
    };
    let layer_texels = budget as f64 * 0.75 / 4.0 / base as f64;
    let needed = extents[0].0.max(extents[0].1).div_ceil(CELL as usize) as u32 * CELL + CELL;
    let limit = (layer_texels.sqrt() as u32)
        .min(MAX_STREAM_SIDE)
        .min(max_side as u32)
        .min(needed);
    let side = limit / CELL * CELL;
    if side < MIN_STREAM_SIDE {
        return Some(plain);
    }
    Some(ImageryStreamPlan {
        base: base as u32,
        windows: Some(ImageryClipmapDesc {
            texels_per_sample: k,
            side,
            extents: extents[..base].to_vec(),
        }),
    })
}

/// The imagery clipmap's shape.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageryClipmapDesc {
    /// Texels per level sample per axis (the layer's k: 1, 2 or 4).
    pub texels_per_sample: u32,
    /// Texels per side of every level's window (a multiple of [`CELL`]).
    pub side: u32,
    /// Per level, the layer's raster extent in texels (`level_extent`).
    pub extents: Vec<(usize, usize)>,
}

impl ImageryClipmapDesc {
    /// Cells per side of a window.
    pub fn cells(&self) -> u32 {
        self.side / CELL
    }

    pub fn levels(&self) -> u32 {
        self.extents.len() as u32
    }

    pub fn validate(&self) -> Result<(), String> {
        let k = self.texels_per_sample;
        if !(k.is_power_of_two() && k <= CELL) {
            return Err(format!(
                "{k} texels per sample: a power of two up to {CELL}"
            ));
        }
        if self.side == 0 || !self.side.is_multiple_of(CELL) {
            return Err(format!(
                "window of {} texels: a positive multiple of {CELL}",
                self.side
            ));
        }
        Ok(())
    }
}

/// One cell to fill: where its texels come from and where they go.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CellFill {
    pub level: u32,
    /// The absolute cell (texel / CELL per axis) on its level's raster.
    pub cell: [i64; 2],
    /// The cell's texel offset in the level's layer (toroidal slot · CELL).
    pub texel: [u32; 2],
    /// The level samples whose texels the cell holds (`TerrainSource::gather_imagery`).
    pub rect: SampleRect,
    /// The cell lies wholly outside the level's raster: its texels are transparent, nothing to
    /// read (but the slot still has to be cleared of the cell it held before).
    pub empty: bool,
}

/// One level's window.
#[derive(Debug, Clone, PartialEq)]
struct LevelWindow {
    /// First cell of the window per axis; None before the first placement.
    origin: Option<[i64; 2]>,
    /// Per slot (row-major, n × n): the absolute cell it holds and whether its texels are there.
    held: Vec<Option<([i64; 2], bool)>>,
}

/// Every level's window and what its slots hold.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageryClipmap {
    desc: ImageryClipmapDesc,
    levels: Vec<LevelWindow>,
}

impl ImageryClipmap {
    pub fn new(desc: ImageryClipmapDesc) -> Result<Self, String> {
        desc.validate()?;
        let n = desc.cells() as usize;
        let levels = (0..desc.levels())
            .map(|_| LevelWindow {
                origin: None,
                held: vec![None; n * n],
            })
            .collect();
        Ok(Self { desc, levels })
    }

    pub fn desc(&self) -> &ImageryClipmapDesc {
        &self.desc
    }

    /// Level-L texel coordinate of level-0 grid coordinate `g`.
    fn texel_of(&self, level: u32, g: f64) -> f64 {
        (g + 0.5) * f64::from(self.desc.texels_per_sample) / f64::from(1u32 << level) - 0.5
    }

    /// The window's first cell per axis for an eye at level-0 grid coordinates `eye`: the
    /// window centred on the eye's texel, snapped to whole cells.
    pub fn window_origin(&self, level: u32, eye: [f64; 2]) -> [i64; 2] {
        let half = f64::from(self.desc.side) / 2.0;
        eye.map(|g| ((self.texel_of(level, g) - half) / f64::from(CELL)).round() as i64)
    }

    /// Places every level's window around the eye; slots the windows now put other cells in
    /// are marked empty.
    pub fn place(&mut self, eye: [f64; 2]) {
        let n = self.desc.cells() as i64;
        for level in 0..self.desc.levels() {
            let origin = self.window_origin(level, eye);
            let w = &mut self.levels[level as usize];
            if w.origin == Some(origin) {
                continue;
            }
            w.origin = Some(origin);
            for cy in origin[1]..origin[1] + n {
                for cx in origin[0]..origin[0] + n {
                    let slot = slot_index([cx, cy], n);
                    if w.held[slot].is_none_or(|(c, _)| c != [cx, cy]) {
                        w.held[slot] = Some(([cx, cy], false));
                    }
                }
            }
        }
    }

    /// The cells not filled yet, coarse levels first, then nearest the eye (level-0 grid
    /// coordinates) first.
    pub fn wanted(&self, eye: [f64; 2]) -> Vec<CellFill> {
        let n = self.desc.cells() as i64;
        let mut out = Vec::new();
        for level in (0..self.desc.levels()).rev() {
            let w = &self.levels[level as usize];
            let mut cells: Vec<(f64, CellFill)> = w
                .held
                .iter()
                .filter_map(|h| h.filter(|(_, filled)| !filled).map(|(c, _)| c))
                .map(|c| {
                    let centre = (CELL as f64) / 2.0;
                    let d = (0..2)
                        .map(|a| {
                            let t = self.texel_of(level, eye[a]);
                            (c[a] as f64 * f64::from(CELL) + centre - t).powi(2)
                        })
                        .sum::<f64>();
                    (d, self.fill(level, c, n))
                })
                .collect();
            cells.sort_by(|a, b| a.0.total_cmp(&b.0));
            out.extend(cells.into_iter().map(|(_, f)| f));
        }
        out
    }

    fn fill(&self, level: u32, cell: [i64; 2], n: i64) -> CellFill {
        let k = i64::from(self.desc.texels_per_sample);
        let per = i64::from(CELL) / k; // level samples per cell side
        let (ew, eh) = self.desc.extents[level as usize];
        let inside = |c: i64, e: usize| {
            let (t0, t1) = (c * i64::from(CELL), (c + 1) * i64::from(CELL));
            t1 > 0 && t0 < e as i64
        };
        CellFill {
            level,
            cell,
            texel: cell.map(|c| (c.rem_euclid(n) as u32) * CELL),
            rect: SampleRect {
                level,
                origin: cell.map(|c| (c * per) << level),
                size: [per as u32; 2],
            },
            empty: !(inside(cell[0], ew) && inside(cell[1], eh)),
        }
    }

    /// Records that `fill`'s texels were uploaded; ignored when the window has moved on and
    /// the slot now holds another cell.
    pub fn filled(&mut self, fill: &CellFill) {
        let n = self.desc.cells() as i64;
        let w = &mut self.levels[fill.level as usize];
        let slot = slot_index(fill.cell, n);
        if let Some((c, done)) = w.held[slot].as_mut() {
            if *c == fill.cell {
                *done = true;
            }
        }
    }

    /// The level's window in absolute texels (origin, side) when every cell of it is filled,
    /// else None: what the shader may sample, inset by half a texel.
    pub fn region(&self, level: u32) -> Option<([i64; 2], u32)> {
        let w = self.levels.get(level as usize)?;
        let origin = w.origin?;
        let complete = w.held.iter().all(|h| h.is_some_and(|(_, filled)| filled));
        complete.then(|| (origin.map(|c| c * i64::from(CELL)), self.desc.side))
    }
}

/// The slot (row-major in the n × n grid) of absolute cell `c`.
fn slot_index(c: [i64; 2], n: i64) -> usize {
    (c[1].rem_euclid(n) * n + c[0].rem_euclid(n)) as usize
}

#[cfg(test)]
#[path = "imagery_clipmap_tests.rs"]
mod tests;
