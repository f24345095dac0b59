//! What a bake holds: its parameters and one table of per-tile numbers per level.

use crate::dataset::Dataset;

use super::error::BakeError;
use super::format::file_layout;

/// Bake parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BakeParams {
    /// Tile side in vertices, `m = 2^j + 1` with `1 ≤ j ≤ 8` (3 ..= 257); default 17.
    pub tile_size: u32,
    /// Number of levels to bake (0 = as many as fit the dataset).
    pub levels: u32,
}

impl Default for BakeParams {
    fn default() -> Self {
        BakeParams {
            tile_size: 17,
            levels: 0,
        }
    }
}

impl BakeParams {
    /// `j` with `m = 2^j + 1`, or an error saying what is accepted.
    pub fn log2_quads(&self) -> Result<u32, BakeError> {
        let m = self.tile_size;
        let q = m.wrapping_sub(1);
        if !(3..=257).contains(&m) || !q.is_power_of_two() {
            return Err(BakeError::Params {
                reason: format!("tile size {m} is not 2^j + 1 in 3..=257 (e.g. 9, 17, 33, 65)"),
            });
        }
        Ok(q.trailing_zeros())
    }

    /// Levels that fit the dataset: `min(Kx, Ky) − j + 1`, or 0 when not even one tile fits.
    pub fn max_levels(&self, ds: &Dataset) -> Result<u32, BakeError> {
        self.max_levels_for(ds.hf.width, ds.hf.height)
    }

    /// [`Self::max_levels`] for a padded grid of `width` × `height` (2^K + 1 each).
    pub fn max_levels_for(&self, width: usize, height: usize) -> Result<u32, BakeError> {
        let j = self.log2_quads()?;
        let (kx, ky) = ((width - 1).trailing_zeros(), (height - 1).trailing_zeros());
        Ok((kx.min(ky) + 1).saturating_sub(j))
    }

    /// The number of levels a bake with these parameters has on `ds`, or why it cannot be made.
    pub fn resolve_levels(&self, ds: &Dataset) -> Result<u32, BakeError> {
        self.resolve_levels_for(ds.hf.width, ds.hf.height)
    }

    /// [`Self::resolve_levels`] for a padded grid of `width` × `height`.
    pub fn resolve_levels_for(&self, width: usize, height: usize) -> Result<u32, BakeError> {
        let (w, h) = (width, height);
        let fit = self.max_levels_for(w, h)?;
        if fit == 0 {
            return Err(BakeError::Params {
                reason: format!(
                    "the dataset ({}×{} padded samples) is smaller than one {}×{} tile; use a smaller tile size",
                    w, h, self.tile_size, self.tile_size
                ),
            });
        }
        match self.levels {
            0 => Ok(fit),
            n if n <= fit => Ok(n),
            n => Err(BakeError::Params {
                reason: format!(
                    "{n} levels asked, but only {fit} fit a {}×{} dataset with {}×{} tiles (levels 0..={})",
                    w,
                    h,
                    self.tile_size,
                    self.tile_size,
                    fit - 1
                ),
            }),
        }
    }
}

/// One level's per-tile numbers, row-major by tile (`ty * tiles_x + tx`).
#[derive(Debug, Clone, PartialEq)]
pub struct LevelTable {
    pub level: u32,
    pub tiles_x: u32,
    pub tiles_y: u32,
    /// Maximum absolute vertical error of the level surface over the tile, metres (rounded
    /// up); 0 for tiles that are all padding.
    pub eps: Vec<f32>,
    /// ε of the next coarser level's surface over this tile (metres, rounded up): the tile
    /// drawn as a quadrant of its parent at the parent's resolution. Measured by the bake
    /// (≤ the parent's ε, the largest of the four is the parent's); from a file that keeps
    /// only the parents' ε, the parent's ε (a bound, looser). Empty on the coarsest level.
    pub coarse_eps: Vec<f32>,
    /// ε of the surface two levels coarser (level L+2) over this tile (metres, rounded up):
    /// the tile drawn as a sixteenth of its grandparent at the grandparent's resolution.
    /// Measured by the bake (≤ its parent's `coarse_eps`, the largest of the four siblings'
    /// is the parent's); from a file that keeps only quadrants or tiles, the parent's
    /// `coarse_eps` (a bound, looser). 0 under a grandparent that is all padding. Empty on
    /// the two coarsest levels.
    pub fine_eps: Vec<f32>,
    /// Smallest / largest full-resolution height in the tile (edges included), metres.
    pub min: Vec<f32>,
    pub max: Vec<f32>,
    /// False when every sample of the tile is padding.
    pub terrain: Vec<bool>,
}

impl LevelTable {
    #[inline]
    fn index(&self, tx: u32, ty: u32) -> usize {
        assert!(
            tx < self.tiles_x && ty < self.tiles_y,
            "tile ({tx}, {ty}) outside level {} ({}×{} tiles)",
            self.level,
            self.tiles_x,
            self.tiles_y
        );
        (ty * self.tiles_x + tx) as usize
    }

    pub fn len(&self) -> usize {
        self.eps.len()
    }

    pub fn is_empty(&self) -> bool {
        self.eps.is_empty()
    }
}

/// The result of a bake: parameters, what it was made from, and one table per level.
#[derive(Debug, Clone, PartialEq)]
pub struct ErrorBake {
    /// `levels` is the resolved count (never 0).
    pub params: BakeParams,
    pub width: u32,
    pub height: u32,
    pub valid_width: u32,
    pub valid_height: u32,
    pub spacing_x: f64,
    pub spacing_y: f64,
    /// CRC-32 of the padded samples ([`Dataset::checksum`]).
    pub source_checksum: u32,
    pub levels: Vec<LevelTable>,
}

/// The errors a bake measures, as a file keeps them (index: level; entry 0 is ignored).
#[derive(Debug, Clone, PartialEq)]
pub enum MeasuredEps {
    /// Level 1's surface over each of its tiles' four quadrants (indexed by level 0's tiles)
    /// and each level-L surface (L ≥ 2) over each of its tiles' 16 blocks (indexed by level
    /// L−2's tiles): the quadrants (the largest of their 2×2 blocks), the tiles' ε,
    /// [`LevelTable::coarse_eps`] and [`LevelTable::fine_eps`] follow.
    Blocks(Vec<Vec<f32>>),
    /// ε of each level-L surface (L ≥ 1) over each of its tiles' four quadrants, indexed by
    /// level L−1's tiles (older files): the tiles' ε and the quadrants'
    /// [`LevelTable::coarse_eps`] follow; a tile's ε at its grandparent's resolution is taken
    /// as its parent's there.
    Quadrants(Vec<Vec<f32>>),
    /// ε of each level-L tile (L ≥ 1) only (older files): a quadrant's ε at its parent's
    /// resolution is taken as the parent's, and at its grandparent's as the grandparent's.
    Tiles(Vec<Vec<f32>>),
}

/// What a bake measures, as a file keeps it: the grid it was made for, level-0 min/max per
/// tile and the errors of every level ≥ 1. [`ErrorBake::from_measured`] derives the rest
/// exactly as [`bake`](super::bake) does.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasuredBake {
    pub params: BakeParams,
    pub width: u32,
    pub height: u32,
    pub valid_width: u32,
    pub valid_height: u32,
    pub spacing_x: f64,
    pub spacing_y: f64,
    pub source_checksum: u32,
    pub min0: Vec<f32>,
    pub max0: Vec<f32>,
    pub eps: MeasuredEps,
}

impl ErrorBake {
    /// The bake of `m`'s measurements (the tables of levels ≥ 1 derived from level 0's min/max
    /// and the terrain flags from the real size, as [`bake`](super::bake) derives them), for
    /// readers of files that keep only the measured part (the bake file, the tile store).
    /// The caller has checked the table sizes against the grid.
    pub fn from_measured(m: MeasuredBake) -> ErrorBake {
        let q = (m.params.tile_size - 1) as usize;
        let geo = level_geoms(q, m.width as usize, m.height as usize, m.params.levels);
        let levels = build_tables(
            &geo,
            m.min0,
            m.max0,
            m.eps,
            m.valid_width as usize,
            m.valid_height as usize,
        );
        ErrorBake {
            params: m.params,
            width: m.width,
            height: m.height,
            valid_width: m.valid_width,
            valid_height: m.valid_height,
            spacing_x: m.spacing_x,
            spacing_y: m.spacing_y,
            source_checksum: m.source_checksum,
            levels,
        }
    }

    pub fn level(&self, level: u32) -> &LevelTable {
        &self.levels[level as usize]
    }

    /// ε of level-`level` tile (tx, ty), metres.
    #[inline]
    pub fn eps(&self, level: u32, tx: u32, ty: u32) -> f32 {
        let t = self.level(level);
        t.eps[t.index(tx, ty)]
    }

    /// ε of level `level + 1`'s surface over level-`level` tile (tx, ty), metres: the tile
    /// drawn as a quadrant at its parent's resolution ([`LevelTable::coarse_eps`]). Panics on
    /// the coarsest level, which has no parent.
    #[inline]
    pub fn coarse_eps(&self, level: u32, tx: u32, ty: u32) -> f32 {
        let t = self.level(level);
        t.coarse_eps[t.index(tx, ty)]
    }

    /// ε of level `level + 2`'s surface over level-`level` tile (tx, ty), metres: the tile
    /// drawn at its grandparent's resolution ([`LevelTable::fine_eps`]). Panics on the two
    /// coarsest levels.
    #[inline]
    pub fn fine_eps(&self, level: u32, tx: u32, ty: u32) -> f32 {
        let t = self.level(level);
        t.fine_eps[t.index(tx, ty)]
    }

    /// (min, max) full-resolution height of the tile, metres.
    #[inline]
    pub fn bounds(&self, level: u32, tx: u32, ty: u32) -> (f32, f32) {
        let t = self.level(level);
        let i = t.index(tx, ty);
        (t.min[i], t.max[i])
    }

    /// False when the tile is all padding.
    #[inline]
    pub fn is_terrain(&self, level: u32, tx: u32, ty: u32) -> bool {
        let t = self.level(level);
        t.terrain[t.index(tx, ty)]
    }

    /// ε of level-L tile (tx, ty) drawn with refinement r, i.e. with the level (L−r) surface:
    /// the max of ε over its `2^r × 2^r` level-(L−r) subtiles (exact: the subtiles' samples
    /// are the tile's samples and their surfaces are the level-(L−r) surface over the tile;
    /// padding-only subtiles count 0, see the module documentation).
    /// `r` larger than `level` is taken as `level` (full resolution, ε = 0).
    pub fn eps_refined(&self, level: u32, tx: u32, ty: u32, r: u32) -> f32 {
        let r = r.min(level);
        if r == 0 {
            return self.eps(level, tx, ty);
        }
        let fine = self.level(level - r);
        let k = 1u32 << r;
        let mut e = 0f32;
        for sy in ty * k..(ty + 1) * k {
            let row = &fine.eps[(sy * fine.tiles_x + tx * k) as usize..][..k as usize];
            e = row.iter().fold(e, |a, &b| a.max(b));
        }
        e
    }

    /// Total size of the bake file in bytes.
    pub fn file_size(&self) -> u64 {
        file_layout(
            self.width,
            self.height,
            self.params.tile_size,
            self.levels.len() as u32,
        )
        .total
    }

    /// Per-level distribution of ε over the tiles that hold terrain.
    pub fn level_stats(&self) -> Vec<LevelStats> {
        self.levels
            .iter()
            .map(|t| {
                let mut e: Vec<f32> = t
                    .eps
                    .iter()
                    .zip(&t.terrain)
                    .filter(|(_, &k)| k)
                    .map(|(&e, _)| e)
                    .collect();
                e.sort_by(f32::total_cmp);
                let rank = |p: f64| -> f32 {
                    if e.is_empty() {
                        return 0.0;
                    }
                    let k = ((p * e.len() as f64).ceil() as usize).clamp(1, e.len());
                    e[k - 1]
                };
                LevelStats {
                    level: t.level,
                    tiles: t.len(),
                    terrain_tiles: e.len(),
                    max: e.last().copied().unwrap_or(0.0),
                    p99: rank(0.99),
                    median: rank(0.5),
                    tile_extent_x_m: f64::from(self.params.tile_size - 1)
                        * f64::from(1u32 << t.level)
                        * self.spacing_x,
                    tile_extent_y_m: f64::from(self.params.tile_size - 1)
                        * f64::from(1u32 << t.level)
                        * self.spacing_y,
                }
            })
            .collect()
    }
}

/// ε distribution of one level over its terrain tiles (nearest-rank percentiles).
#[derive(Debug, Clone, PartialEq)]
pub struct LevelStats {
    pub level: u32,
    pub tiles: usize,
    pub terrain_tiles: usize,
    pub max: f32,
    pub p99: f32,
    pub median: f32,
    /// Ground size of one tile of this level, metres.
    pub tile_extent_x_m: f64,
    pub tile_extent_y_m: f64,
}

/// Header of the `--report` CSV.
pub const REPORT_CSV_HEADER: &str =
    "level,sample_step,tiles,terrain_tiles,tile_extent_x_m,tile_extent_y_m,max_eps_m,p99_eps_m,median_eps_m\n";

/// The `--report` table as CSV (one row per level).
pub fn report_csv(stats: &[LevelStats]) -> String {
    let mut s = String::from(REPORT_CSV_HEADER);
    for l in stats {
        s.push_str(&format!(
            "{},{},{},{},{:.3},{:.3},{},{},{}\n",
            l.level,
            1u64 << l.level,
            l.tiles,
            l.terrain_tiles,
            l.tile_extent_x_m,
            l.tile_extent_y_m,
            l.max,
            l.p99,
            l.median
        ));
    }
    s
}

/// Tile geometry of one level.
#[derive(Clone, Copy)]
pub(super) struct LevelGeom {
    /// Samples per tile side minus one: (m − 1) · 2^L.
    pub(super) t: usize,
    pub(super) tiles_x: usize,
    pub(super) tiles_y: usize,
}

pub(super) fn level_geoms(q: usize, width: usize, height: usize, levels: u32) -> Vec<LevelGeom> {
    (0..levels)
        .map(|l| {
            let t = q << l;
            LevelGeom {
                t,
                tiles_x: (width - 1) / t,
                tiles_y: (height - 1) / t,
            }
        })
        .collect()
}

/// The level tables from what is measured (level-0 min/max, the errors of levels ≥ 1) and
/// what follows from it: level-0 ε = 0; a level-L tile is exactly its 2×2 level-(L−1)
/// children (edges included), so its min/max is theirs and, with quadrants measured, its ε is
/// the largest of theirs at its resolution (with blocks measured, a quadrant's ε is the
/// largest of its 2×2 blocks' the same way); a tile is terrain when its south-west sample is
/// real; all-padding tiles have ε = 0, and so have the quadrants and blocks of an
/// all-padding tile. The file stores the measured part.
pub(super) fn build_tables(
    geo: &[LevelGeom],
    min0: Vec<f32>,
    max0: Vec<f32>,
    eps: MeasuredEps,
    valid_width: usize,
    valid_height: usize,
) -> Vec<LevelTable> {
    // Per level L ≥ 1 its tiles' ε, or the quadrants' (indexed by level L−1's tiles); the
    // blocks (indexed by level L−2's tiles) where measured.
    let (tiles_eps, mut quads, mut blocks) = match eps {
        MeasuredEps::Tiles(e) => (Some(e), None, None),
        MeasuredEps::Quadrants(q) => (None, Some(q), None),
        MeasuredEps::Blocks(mut b) => {
            let q = (0..geo.len())
                .map(|l| match l {
                    0 => Vec::new(),
                    1 => std::mem::take(&mut b[1]),
                    _ => {
                        let g = &geo[l];
                        let quads = LevelGeom {
                            t: g.t / 2,
                            tiles_x: 2 * g.tiles_x,
                            tiles_y: 2 * g.tiles_y,
                        };
                        children_fold(&quads, 4 * g.tiles_x, &b[l], &b[l]).1
                    }
                })
                .collect();
            (None, Some(q), Some(b))
        }
    };
    let mut tables: Vec<LevelTable> = Vec::with_capacity(geo.len());
    let terrain_of = |g: &LevelGeom| -> Vec<bool> {
        (0..g.tiles_x * g.tiles_y)
            .map(|i| {
                let (tx, ty) = (i % g.tiles_x, i / g.tiles_x);
                tx * g.t < valid_width && ty * g.t < valid_height
            })
            .collect()
    };
    for (l, g) in geo.iter().enumerate() {
        let n = g.tiles_x * g.tiles_y;
        let (min, max) = if l == 0 {
            (min0.clone(), max0.clone())
        } else {
            let f = &tables[l - 1];
            let (mn, mx) = children_fold(g, f.tiles_x as usize, &f.min, &f.max);
            (mn, mx)
        };
        let terrain = terrain_of(g);
        let mut e = if l == 0 {
            vec![0.0; n]
        } else {
            match (&tiles_eps, &quads) {
                (Some(e), _) => e[l].clone(),
                (None, Some(q)) => children_fold(g, 2 * g.tiles_x, &q[l], &q[l]).1,
                (None, None) => unreachable!("tiles' or quadrants' ε"),
            }
        };
        for (e, &t) in e.iter_mut().zip(&terrain) {
            if !t {
                *e = 0.0;
            }
        }
        tables.push(LevelTable {
            level: l as u32,
            tiles_x: g.tiles_x as u32,
            tiles_y: g.tiles_y as u32,
            eps: e,
            coarse_eps: Vec::new(),
            fine_eps: Vec::new(),
            min,
            max,
            terrain,
        });
    }
    // Each tile at its parent's resolution.
    for l in 1..tables.len() {
        let coarse = match &mut quads {
            Some(q) => zero_outside_terrain(std::mem::take(&mut q[l]), &tables[l], 2),
            None => {
                let (parent, child) = (&tables[l], &tables[l - 1]);
                let px = parent.tiles_x as usize;
                (0..child.len())
                    .map(|i| {
                        let (cx, cy) = (i % (2 * px), i / (2 * px));
                        parent.eps[(cy / 2) * px + cx / 2]
                    })
                    .collect()
            }
        };
        tables[l - 1].coarse_eps = coarse;
    }
    // Each tile at its grandparent's resolution: measured, or bounded by its parent's there.
    for l in 2..tables.len() {
        let fine = match &mut blocks {
            Some(b) => zero_outside_terrain(std::mem::take(&mut b[l]), &tables[l], 4),
            None => {
                let (parent, child) = (&tables[l - 1], &tables[l - 2]);
                let px = parent.tiles_x as usize;
                (0..child.len())
                    .map(|i| {
                        let (cx, cy) = (i % (2 * px), i / (2 * px));
                        parent.coarse_eps[(cy / 2) * px + cx / 2]
                    })
                    .collect()
            }
        };
        tables[l - 2].fine_eps = fine;
    }
    tables
}

/// `parts` (a table of `k × k` parts per tile of `table`, row-major over the parts) with the
/// parts of tiles that are all padding set to 0.
fn zero_outside_terrain(mut parts: Vec<f32>, table: &LevelTable, k: usize) -> Vec<f32> {
    let tx = table.tiles_x as usize;
    for (i, p) in parts.iter_mut().enumerate() {
        let (cx, cy) = (i % (k * tx), i / (k * tx));
        if !table.terrain[(cy / k) * tx + cx / k] {
            *p = 0.0;
        }
    }
    parts
}

/// Per level-`g` tile, the min of `lo` and the max of `hi` over its 2×2 children in a table
/// `fx` children wide.
fn children_fold(g: &LevelGeom, fx: usize, lo: &[f32], hi: &[f32]) -> (Vec<f32>, Vec<f32>) {
    let n = g.tiles_x * g.tiles_y;
    let (mut mn, mut mx) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for ty in 0..g.tiles_y {
        for tx in 0..g.tiles_x {
            let kids = [
                (2 * ty) * fx + 2 * tx,
                (2 * ty) * fx + 2 * tx + 1,
                (2 * ty + 1) * fx + 2 * tx,
                (2 * ty + 1) * fx + 2 * tx + 1,
            ];
            mn.push(kids.iter().map(|&k| lo[k]).fold(f32::INFINITY, f32::min));
            mx.push(
                kids.iter()
                    .map(|&k| hi[k])
                    .fold(f32::NEG_INFINITY, f32::max),
            );
        }
    }
    (mn, mx)
}
