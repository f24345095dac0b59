//! The exact offline error bake (DESIGN.md, "The terrain technique", **Error**).
//!
//! For every clipmap level `L` (0 = finest) and every tile of `m × m` level-`L` vertices
//! (`m = 2^j + 1`), the bake stores
//!
//! ```text
//! ε(L, tile) = max |h(p) − ĥ_L(p)|   over every full-resolution sample p of the tile, edges included
//! ```
//!
//! where `ĥ_L` is the piecewise-linear surface of the level-`L` triangles: level-`L` vertices are
//! every `2^L` samples, each level-`L` cell (`2^L × 2^L` samples) is split by
//! [`mesh::TILE_DIAGONAL`](super::mesh::TILE_DIAGONAL) and evaluated with
//! [`mesh::quad_surface`](super::mesh::quad_surface) — the same function that defines the GPU
//! mesh's triangles — at `u = i / 2^L`, `v = j / 2^L` (exact binary fractions). It also stores
//! the min/max full-resolution height per tile (for culling boxes) and whether the tile holds
//! any real (non-padding) sample.
//!
//! **Padding.** Padding samples are part of the surface and of every tile that also holds a
//! real sample (their ε includes them). Tiles made only of padding are not terrain
//! (`terrain = false`): their ε is not measured and is stored as 0. Every real sample lies in a
//! terrain tile at every level, so [`ErrorBake::eps_refined`] still bounds the error at every
//! real sample; it ignores the error over padding-only subtiles.
//!
//! **Tiles.** Level-`L` tile `(tx, ty)` covers samples `cols tx·(m−1)·2^L ..= (tx+1)·(m−1)·2^L`
//! and the same for rows; neighbouring tiles share their edge samples. The dataset is padded to
//! `(2^Kx+1) × (2^Ky+1)` ([`Dataset`]), so every level has whole tiles:
//! `tiles_x = 2^Kx / ((m−1)·2^L)`. Levels `0 ..= min(Kx, Ky) − j` fit.
//!
//! **Numbers.** Heights are f32; `quad_surface` and the differences are evaluated in f64 and
//! each tile's maximum is rounded **up** to the next f32, so a stored ε is never below the f64
//! value and exceeds it by at most one f32 ulp. The f64 value is exact for heights on a coarse
//! grid (integer metres: SRTM, int16 GeoTIFF) and otherwise within a few f64 ulps of max |h|
//! (≈ 1e-12 m), far below the f32 rounding step. Level-0 ε is 0 (the surface is the samples).
//! The loops are written for speed (row-wise, AVX2 when the CPU has it) but perform the same
//! IEEE operations as calling `quad_surface` per sample, bit for bit (unit-tested).
//!
//! **File** (`<dataset name>.aerie-bake`, little-endian, [`write_bake`] / [`read_bake`]):
//!
//! ```text
//! offset size  field
//!      0    8  magic "AERIEBAK"
//!      8    4  u32 format version (1)
//!     12    4  u32 header size in bytes (96)
//!     16    4  u32 m, tile side in vertices (2^j + 1)
//!     20    4  u32 number of levels
//!     24    4  u32 width  (padded samples per row)
//!     28    4  u32 height (padded rows)
//!     32    4  u32 valid_width  (real samples per row; columns ≥ it are padding)
//!     36    4  u32 valid_height (real rows; rows ≥ it are padding)
//!     40    8  f64 spacing_x, metres
//!     48    8  f64 spacing_y, metres
//!     56    4  u32 source checksum: CRC-32 of the padded samples as f32 LE (Dataset::checksum)
//!     60    4  u32 flags (0)
//!     64    8  u64 file size in bytes, trailing CRC included
//!     72   20  reserved (0)
//!     92    4  u32 CRC-32 of bytes 0..92
//!     96       level sections, level 0 first; n = tiles_x · tiles_y, arrays row-major by tile
//!              (index ty · tiles_x + tx):
//!              +0 u32 level (= L)     +4 u32 tiles_x     +8 u32 tiles_y     +12 u32 0
//!              level 0:  +16 f32[n] min height    +16+4n f32[n] max height
//!              level ≥1: +16 f32[n] ε
//! size−4    4  u32 CRC-32 of bytes 0..size−4
//! ```
//!
//! Only what is measured is stored: level-0 ε is 0, a level-L tile's min/max is that of its
//! 2×2 level-(L−1) children, and the terrain flag follows from the real size, so the reader
//! derives those. At m = 17 the file is ≈ 0.9 % of the (padded) dataset's f32 size.
//! Reading checks magic, version, sizes, both CRCs, then the dataset (sizes, spacing, checksum):
//! every failure names the file, the field or byte offset and the reason, and says to re-run
//! `aerie bake`.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

use super::dataset::Dataset;
use super::mesh::{quad_surface, Diagonal, TILE_DIAGONAL};

/// First 8 bytes of every bake file.
pub const BAKE_MAGIC: [u8; 8] = *b"AERIEBAK";
/// The format version this build writes and reads.
pub const BAKE_VERSION: u32 = 1;
/// Header bytes before the first level section.
pub const HEADER_SIZE: usize = 96;
/// File name suffix of bake files.
pub const BAKE_EXTENSION: &str = "aerie-bake";

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
        let j = self.log2_quads()?;
        let (kx, ky) = ds.log2_sides();
        Ok((kx.min(ky) + 1).saturating_sub(j))
    }

    /// The number of levels a bake with these parameters has on `ds`, or why it cannot be made.
    pub fn resolve_levels(&self, ds: &Dataset) -> Result<u32, BakeError> {
        let fit = self.max_levels(ds)?;
        if fit == 0 {
            return Err(BakeError::Params {
                reason: format!(
                    "the dataset ({}×{} padded samples) is smaller than one {}×{} tile; use a smaller tile size",
                    ds.hf.width, ds.hf.height, self.tile_size, self.tile_size
                ),
            });
        }
        match self.levels {
            0 => Ok(fit),
            n if n <= fit => Ok(n),
            n => Err(BakeError::Params {
                reason: format!(
                    "{n} levels asked, but only {fit} fit a {}×{} dataset with {}×{} tiles (levels 0..={})",
                    ds.hf.width,
                    ds.hf.height,
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

impl ErrorBake {
    pub fn level(&self, level: u32) -> &LevelTable {
        &self.levels[level as usize]
    }

    /// ε of level-`level` tile (tx, ty), metres.
    pub fn eps(&self, level: u32, tx: u32, ty: u32) -> f32 {
        let t = self.level(level);
        t.eps[t.index(tx, ty)]
    }

    /// (min, max) full-resolution height of the tile, metres.
    pub fn bounds(&self, level: u32, tx: u32, ty: u32) -> (f32, f32) {
        let t = self.level(level);
        let i = t.index(tx, ty);
        (t.min[i], t.max[i])
    }

    /// False when the tile is all padding.
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

/// Why a bake could not be made, read or written. `Display` is one line naming the file and,
/// for a bad file, the field or byte offset, the reason and the fix.
#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    #[error("bake parameters: {reason}")]
    Params { reason: String },
    #[error("{path}: no such file; make it with `aerie bake <dataset>`")]
    NotFound { path: String },
    #[error("{path}: cannot read: {reason}")]
    Io { path: String, reason: String },
    #[error("{path}: cannot write: {reason}")]
    Write { path: String, reason: String },
    #[error("{path}: not an aerie bake file (bytes 0..8 are {found}, expected \"AERIEBAK\"); re-run `aerie bake` (with --force to overwrite this file)")]
    BadMagic { path: String, found: String },
    #[error("{path}: format version {found} (byte offset 8) is not supported: this build reads version {BAKE_VERSION}; re-run `aerie bake` to rebuild it")]
    Version { path: String, found: u32 },
    #[error(
        "{path}: truncated at byte offset {offset}: {reason}; re-run `aerie bake` to rebuild it"
    )]
    Truncated {
        path: String,
        offset: u64,
        reason: String,
    },
    #[error("{path}: field `{field}` at byte offset {offset}: {reason}; re-run `aerie bake` to rebuild it")]
    Corrupt {
        path: String,
        field: String,
        offset: u64,
        reason: String,
    },
    #[error("{path}: stale: {reason}; re-run `aerie bake` to rebuild it")]
    Stale { path: String, reason: String },
    #[error("{path}: {reason}")]
    Refused { path: String, reason: String },
}

fn show(p: &Path) -> String {
    p.display().to_string().replace(['\n', '\r'], " ")
}

// ---------------------------------------------------------------------------------------------
// The bake
// ---------------------------------------------------------------------------------------------

/// Rows per work item: small enough to share out evenly, large enough that the level-L vertex
/// rows a chunk needs stay in cache across its rows.
const CHUNK_ROWS: usize = 32;

/// Smallest f32 ≥ x (x ≥ 0, finite).
#[inline]
pub fn round_up_f32(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) >= x {
        f
    } else {
        f32::from_bits(f.to_bits() + 1)
    }
}

/// Tile rows of a level that sample row `r` belongs to: `(lo, hi)` (equal unless `r` is an
/// edge shared by two tile rows).
#[inline]
fn tile_rows_of(r: usize, t: usize, tiles_y: usize) -> (usize, usize) {
    let hi = (r / t).min(tiles_y - 1);
    let lo = if r.is_multiple_of(t) && r > 0 {
        r / t - 1
    } else {
        hi
    };
    (lo, hi)
}

/// `a > b ? a : b` — one `maxsd`/`maxpd`; the values are never NaN (heights are finite).
#[inline(always)]
fn gt_max(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

/// |h − ĥ| at one sample of a cell row, ĥ from [`quad_surface`] at (u, v).
#[inline(always)]
fn sample_err(h: f32, c: &Corners, u: f64, v: f64) -> f64 {
    (f64::from(h) - quad_surface(c.sw, c.se, c.nw, c.ne, u, v)).abs()
}

/// The four corner heights of one level-L cell.
struct Corners {
    sw: f64,
    se: f64,
    nw: f64,
    ne: f64,
}

impl Corners {
    #[inline(always)]
    fn at(hs: &[f32], hn: &[f32], c0: usize, s: usize) -> Self {
        Corners {
            sw: f64::from(hs[c0]),
            se: f64::from(hs[c0 + s]),
            nw: f64::from(hn[c0]),
            ne: f64::from(hn[c0 + s]),
        }
    }
}

/// Max |h − ĥ_L| over samples `i = 0 .. S` (west edge included, east edge excluded) of one
/// cell row; `S = 2^L` known at compile time so the loop unrolls with constant `u`.
#[inline(always)]
fn cell_max_const<const S: usize>(h: &[f32], c: &Corners, v: f64) -> f64 {
    let h = &h[..S];
    let mut e = [0f64; S];
    for (i, (e, &hi)) in e.iter_mut().zip(h).enumerate() {
        let u = i as f64 * (1.0 / S as f64);
        *e = sample_err(hi, c, u, v);
    }
    // Pairwise, so the maxima do not form one long dependency chain.
    let mut n = S;
    while n > 1 {
        n /= 2;
        for i in 0..n {
            e[i] = gt_max(e[i], e[i + n]);
        }
    }
    e[0]
}

/// Max |h − ĥ| over `B` samples of a cell row starting at sample `i0` (u = (i0 + i) / s).
#[inline(always)]
fn block_max<const B: usize>(h: &[f32], c: &Corners, v: f64, i0: usize, inv: f64) -> f64 {
    let h = &h[i0..i0 + B];
    let u0 = i0 as u32 as f64 * inv;
    let mut e = [0f64; B];
    for (i, (e, &hi)) in e.iter_mut().zip(h).enumerate() {
        // Exact: u0 and i·inv are multiples of 1/s < 1, so the sum is (i0 + i) / s exactly.
        *e = sample_err(hi, c, u0 + i as f64 * inv, v);
    }
    let mut n = B;
    while n > 1 {
        n /= 2;
        for i in 0..n {
            e[i] = gt_max(e[i], e[i + n]);
        }
    }
    e[0]
}

/// The same as [`cell_max_const`] for `s ≥ 64` known at run time (coarse levels).
#[inline(always)]
fn cell_max_dyn(h: &[f32], c: &Corners, v: f64, s: usize) -> f64 {
    debug_assert!(s >= 64 && s.is_multiple_of(64));
    let inv = 1.0 / s as f64;
    let (mut a, mut b) = (0f64, 0f64);
    for i0 in (0..s).step_by(64) {
        a = gt_max(block_max::<32>(h, c, v, i0, inv), a);
        b = gt_max(block_max::<32>(h, c, v, i0 + 32, inv), b);
    }
    gt_max(a, b)
}

/// For one full-resolution row and one level `L ≥ 1`: the max |h − ĥ_L| over each tile's
/// part of the row (both edge samples included) into `out[tx]`.
///
/// ĥ_L is [`quad_surface`] over the level-L cell holding the sample. The loops assume the
/// cell row bends where the SW–NE diagonal crosses it, which `quad_surface` decides per sample
/// anyway; the match below makes a new [`Diagonal`] a compile error here.
#[inline(always)]
fn level_row_tile_max<const S: usize>(
    row: &[f32],
    hs: &[f32],
    hn: &[f32],
    s: usize,
    v: f64,
    cells_per_tile: usize,
    out: &mut [f64],
) {
    match TILE_DIAGONAL {
        Diagonal::SouthWestToNorthEast => {}
    }
    let s = if S > 0 { S } else { s };
    for (tx, o) in out.iter_mut().enumerate() {
        let first = tx * cells_per_tile;
        // Four running maxima, one per cell modulo 4, merged at the end.
        let mut ms = [0f64; 4];
        for (k, cx) in (first..first + cells_per_tile).enumerate() {
            let c0 = cx * s;
            let c = Corners::at(hs, hn, c0, s);
            let e = if S > 0 {
                cell_max_const::<S>(&row[c0..], &c, v)
            } else {
                cell_max_dyn(&row[c0..], &c, v, s)
            };
            ms[k & 3] = gt_max(e, ms[k & 3]);
        }
        let m = gt_max(gt_max(ms[0], ms[1]), gt_max(ms[2], ms[3]));
        // The tile's east edge: u = 1 in its last cell.
        let c0 = (first + cells_per_tile - 1) * s;
        let c = Corners::at(hs, hn, c0, s);
        *o = gt_max(sample_err(row[c0 + s], &c, 1.0, v), m);
    }
}

#[derive(Clone, Copy)]
struct LevelGeom {
    /// Samples per tile side minus one: (m − 1) · 2^L.
    t: usize,
    tiles_x: usize,
    tiles_y: usize,
}

/// One worker's running maxima: ε per level (f64, level 0 unused) and level-0 min/max.
struct Acc {
    eps: Vec<Vec<f64>>,
    min0: Vec<f32>,
    max0: Vec<f32>,
}

impl Acc {
    fn new(geo: &[LevelGeom]) -> Self {
        let n0 = geo[0].tiles_x * geo[0].tiles_y;
        Acc {
            eps: geo
                .iter()
                .enumerate()
                .map(|(l, g)| {
                    if l == 0 {
                        Vec::new()
                    } else {
                        vec![0.0; g.tiles_x * g.tiles_y]
                    }
                })
                .collect(),
            min0: vec![f32::INFINITY; n0],
            max0: vec![f32::NEG_INFINITY; n0],
        }
    }

    fn merge(&mut self, o: &Acc) {
        for (a, b) in self.eps.iter_mut().zip(&o.eps) {
            for (x, y) in a.iter_mut().zip(b) {
                *x = x.max(*y);
            }
        }
        for (x, y) in self.min0.iter_mut().zip(&o.min0) {
            *x = x.min(*y);
        }
        for (x, y) in self.max0.iter_mut().zip(&o.max0) {
            *x = x.max(*y);
        }
    }
}

/// Rows `r0..r1` into the worker's maxima, with AVX2 when the CPU has it (same IEEE
/// operations in the same order either way, so the results are bit-identical).
#[allow(clippy::too_many_arguments)]
fn process_rows(
    ds: &Dataset,
    geo: &[LevelGeom],
    q: usize,
    r0: usize,
    r1: usize,
    acc: &mut Acc,
    tile_max: &mut [f64],
    simd: bool,
) {
    #[cfg(target_arch = "x86_64")]
    if simd && std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2 (checked just above).
        unsafe { process_rows_avx2(ds, geo, q, r0, r1, acc, tile_max) };
        return;
    }
    process_rows_impl(ds, geo, q, r0, r1, acc, tile_max);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn process_rows_avx2(
    ds: &Dataset,
    geo: &[LevelGeom],
    q: usize,
    r0: usize,
    r1: usize,
    acc: &mut Acc,
    tile_max: &mut [f64],
) {
    process_rows_impl(ds, geo, q, r0, r1, acc, tile_max);
}

#[inline(always)]
fn process_rows_impl(
    ds: &Dataset,
    geo: &[LevelGeom],
    q: usize,
    r0: usize,
    r1: usize,
    acc: &mut Acc,
    tile_max: &mut [f64],
) {
    let w = ds.hf.width;
    let heights = &ds.hf.heights;
    for r in r0..r1 {
        let row = &heights[r * w..(r + 1) * w];
        // Level 0: height bounds.
        let g = geo[0];
        let (lo, hi) = tile_rows_of(r, g.t, g.tiles_y);
        for tx in 0..g.tiles_x {
            let seg = &row[tx * g.t..=(tx + 1) * g.t];
            let (mut mn, mut mx) = (seg[0], seg[0]);
            for &h in seg {
                mn = if h < mn { h } else { mn };
                mx = if h > mx { h } else { mx };
            }
            for ty in [lo, hi] {
                let i = ty * g.tiles_x + tx;
                acc.min0[i] = acc.min0[i].min(mn);
                acc.max0[i] = acc.max0[i].max(mx);
            }
        }
        // Levels ≥ 1: errors against the level surface, for tiles holding real samples only
        // (a tile is real when its south-west sample is; all-padding tiles keep ε = 0).
        for (l, g) in geo.iter().enumerate().skip(1) {
            let (lo, hi) = tile_rows_of(r, g.t, g.tiles_y);
            if lo * g.t >= ds.valid_height {
                continue;
            }
            let real_tiles_x = ds.valid_width.div_ceil(g.t).min(g.tiles_x);
            let s = 1usize << l;
            let j = r & (s - 1);
            let south = r - j;
            let north = if j == 0 { south } else { south + s };
            let hs = &heights[south * w..(south + 1) * w];
            let hn = &heights[north * w..(north + 1) * w];
            let v = j as f64 / s as f64;
            let out = &mut tile_max[..real_tiles_x];
            match s {
                2 => level_row_tile_max::<2>(row, hs, hn, s, v, q, out),
                4 => level_row_tile_max::<4>(row, hs, hn, s, v, q, out),
                8 => level_row_tile_max::<8>(row, hs, hn, s, v, q, out),
                16 => level_row_tile_max::<16>(row, hs, hn, s, v, q, out),
                32 => level_row_tile_max::<32>(row, hs, hn, s, v, q, out),
                _ => level_row_tile_max::<0>(row, hs, hn, s, v, q, out),
            }
            let a = &mut acc.eps[l];
            for (tx, &m) in out.iter().enumerate() {
                for ty in [lo, hi] {
                    let i = ty * g.tiles_x + tx;
                    a[i] = gt_max(m, a[i]);
                }
            }
        }
    }
}

/// Bakes ε, min/max and the terrain flags of every level, on all cores.
///
/// `progress(done, total)` is called from the calling thread, in samples (rows × width).
/// Panics when `params` do not fit the dataset: check with [`BakeParams::resolve_levels`] first.
pub fn bake(ds: &Dataset, params: BakeParams, progress: &dyn Fn(u64, u64)) -> ErrorBake {
    bake_with(ds, params, progress, true)
}

/// [`bake`]; `simd = false` keeps to the baseline instruction set (tests compare the two).
fn bake_with(
    ds: &Dataset,
    params: BakeParams,
    progress: &dyn Fn(u64, u64),
    simd: bool,
) -> ErrorBake {
    let levels = params.resolve_levels(ds).unwrap_or_else(|e| panic!("{e}"));
    let (w, h) = (ds.hf.width, ds.hf.height);
    let q = (params.tile_size - 1) as usize;
    let geo = level_geoms(q, w, h, levels);
    let total = (w * h) as u64;
    let chunks = h.div_ceil(CHUNK_ROWS);
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
        .clamp(1, chunks);
    let next = AtomicUsize::new(0);
    let rows_done = AtomicU64::new(0);
    let finished = AtomicUsize::new(0);
    progress(0, total);
    let accs: Vec<Acc> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|_| {
                s.spawn(|| {
                    let mut acc = Acc::new(&geo);
                    let mut tile_max = vec![0f64; geo[0].tiles_x];
                    loop {
                        let c = next.fetch_add(1, Ordering::Relaxed);
                        if c >= chunks {
                            break;
                        }
                        let r0 = c * CHUNK_ROWS;
                        let r1 = (r0 + CHUNK_ROWS).min(h);
                        process_rows(ds, &geo, q, r0, r1, &mut acc, &mut tile_max, simd);
                        rows_done.fetch_add((r1 - r0) as u64, Ordering::Relaxed);
                    }
                    finished.fetch_add(1, Ordering::Release);
                    acc
                })
            })
            .collect();
        while finished.load(Ordering::Acquire) < threads {
            std::thread::sleep(std::time::Duration::from_millis(50));
            progress(rows_done.load(Ordering::Relaxed) * w as u64, total);
        }
        handles
            .into_iter()
            .map(|h| h.join().expect("bake worker panicked"))
            .collect()
    });
    let mut accs = accs.into_iter();
    let mut acc = accs.next().expect("at least one worker");
    for o in accs {
        acc.merge(&o);
    }
    progress(total, total);

    let eps: Vec<Vec<f32>> = acc
        .eps
        .iter()
        .map(|e| e.iter().map(|&e| round_up_f32(e)).collect())
        .collect();
    let tables = build_tables(
        &geo,
        std::mem::take(&mut acc.min0),
        std::mem::take(&mut acc.max0),
        eps,
        ds.valid_width,
        ds.valid_height,
    );
    ErrorBake {
        params: BakeParams {
            tile_size: params.tile_size,
            levels,
        },
        width: w as u32,
        height: h as u32,
        valid_width: ds.valid_width as u32,
        valid_height: ds.valid_height as u32,
        spacing_x: ds.hf.spacing_x,
        spacing_y: ds.hf.spacing_y,
        source_checksum: ds.checksum(),
        levels: tables,
    }
}

fn level_geoms(q: usize, width: usize, height: usize, levels: u32) -> Vec<LevelGeom> {
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

/// The level tables from what is measured (level-0 min/max, ε of levels ≥ 1; `eps[0]` is
/// ignored) and what follows from it: level-0 ε = 0; a level-L tile is exactly its 2×2
/// level-(L−1) children (edges included), so its min/max is theirs; a tile is terrain when its
/// south-west sample is real; all-padding tiles have ε = 0. The file stores the measured part.
fn build_tables(
    geo: &[LevelGeom],
    min0: Vec<f32>,
    max0: Vec<f32>,
    mut eps: Vec<Vec<f32>>,
    valid_width: usize,
    valid_height: usize,
) -> Vec<LevelTable> {
    let mut tables: Vec<LevelTable> = Vec::with_capacity(geo.len());
    for (l, g) in geo.iter().enumerate() {
        let n = g.tiles_x * g.tiles_y;
        let (min, max) = if l == 0 {
            (min0.clone(), max0.clone())
        } else {
            let f: &LevelTable = &tables[l - 1];
            let fx = f.tiles_x as usize;
            let mut mn = Vec::with_capacity(n);
            let mut mx = Vec::with_capacity(n);
            for ty in 0..g.tiles_y {
                for tx in 0..g.tiles_x {
                    let kids = [
                        (2 * ty) * fx + 2 * tx,
                        (2 * ty) * fx + 2 * tx + 1,
                        (2 * ty + 1) * fx + 2 * tx,
                        (2 * ty + 1) * fx + 2 * tx + 1,
                    ];
                    mn.push(kids.iter().map(|&k| f.min[k]).fold(f32::INFINITY, f32::min));
                    mx.push(
                        kids.iter()
                            .map(|&k| f.max[k])
                            .fold(f32::NEG_INFINITY, f32::max),
                    );
                }
            }
            (mn, mx)
        };
        let terrain: Vec<bool> = (0..n)
            .map(|i| {
                let (tx, ty) = (i % g.tiles_x, i / g.tiles_x);
                tx * g.t < valid_width && ty * g.t < valid_height
            })
            .collect();
        let e = if l == 0 {
            vec![0.0; n]
        } else {
            let mut e = std::mem::take(&mut eps[l]);
            for (e, &t) in e.iter_mut().zip(&terrain) {
                if !t {
                    *e = 0.0;
                }
            }
            e
        };
        tables.push(LevelTable {
            level: l as u32,
            tiles_x: g.tiles_x as u32,
            tiles_y: g.tiles_y as u32,
            eps: e,
            min,
            max,
            terrain,
        });
    }
    tables
}

// ---------------------------------------------------------------------------------------------
// The file
// ---------------------------------------------------------------------------------------------

struct Section {
    offset: usize,
    tiles_x: u32,
    tiles_y: u32,
}

struct Layout {
    sections: Vec<Section>,
    total: u64,
}

/// Byte size of level `l`'s section with n tiles: min + max at level 0, ε above.
fn section_size(l: u32, n: usize) -> usize {
    16 + if l == 0 { 8 * n } else { 4 * n }
}

fn file_layout(width: u32, height: u32, m: u32, levels: u32) -> Layout {
    let q = u64::from(m - 1);
    let mut offset = HEADER_SIZE;
    let mut sections = Vec::new();
    for l in 0..levels {
        let t = q << l;
        let tiles_x = ((u64::from(width) - 1) / t) as u32;
        let tiles_y = ((u64::from(height) - 1) / t) as u32;
        sections.push(Section {
            offset,
            tiles_x,
            tiles_y,
        });
        offset += section_size(l, tiles_x as usize * tiles_y as usize);
    }
    Layout {
        sections,
        total: offset as u64 + 4,
    }
}

/// Where the bake of a dataset lives: `<name>.aerie-bake` next to the file (the full file
/// name is kept: `N47E011.hgt.zip` → `N47E011.hgt.zip.aerie-bake`); for a folder of tiles,
/// next to the folder: `srtm/` → `srtm.aerie-bake` (so the folder holds only tiles).
pub fn bake_path_for(dataset_path: &Path) -> PathBuf {
    let p = if dataset_path.file_name().is_none() {
        std::fs::canonicalize(dataset_path).unwrap_or_else(|_| dataset_path.to_path_buf())
    } else {
        dataset_path.to_path_buf()
    };
    let mut name = p.file_name().map(|n| n.to_owned()).unwrap_or_default();
    name.push(".");
    name.push(BAKE_EXTENSION);
    p.with_file_name(name)
}

fn put_u32(b: &mut [u8], at: usize, v: u32) {
    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

fn put_u64(b: &mut [u8], at: usize, v: u64) {
    b[at..at + 8].copy_from_slice(&v.to_le_bytes());
}

fn put_f32s(b: &mut [u8], at: usize, v: &[f32]) {
    for (d, x) in b[at..at + 4 * v.len()].chunks_exact_mut(4).zip(v) {
        d.copy_from_slice(&x.to_le_bytes());
    }
}

/// Serialises a bake into `buf` (exactly `b.file_size()` bytes, zeroed).
fn encode(b: &ErrorBake, buf: &mut [u8]) {
    let layout = file_layout(b.width, b.height, b.params.tile_size, b.levels.len() as u32);
    assert_eq!(buf.len() as u64, layout.total);
    buf[0..8].copy_from_slice(&BAKE_MAGIC);
    put_u32(buf, 8, BAKE_VERSION);
    put_u32(buf, 12, HEADER_SIZE as u32);
    put_u32(buf, 16, b.params.tile_size);
    put_u32(buf, 20, b.levels.len() as u32);
    put_u32(buf, 24, b.width);
    put_u32(buf, 28, b.height);
    put_u32(buf, 32, b.valid_width);
    put_u32(buf, 36, b.valid_height);
    put_u64(buf, 40, b.spacing_x.to_bits());
    put_u64(buf, 48, b.spacing_y.to_bits());
    put_u32(buf, 56, b.source_checksum);
    put_u32(buf, 60, 0);
    put_u64(buf, 64, layout.total);
    let hcrc = crc32fast::hash(&buf[..92]);
    put_u32(buf, 92, hcrc);
    for (t, s) in b.levels.iter().zip(&layout.sections) {
        let n = t.len();
        assert_eq!((t.tiles_x, t.tiles_y), (s.tiles_x, s.tiles_y));
        let o = s.offset;
        put_u32(buf, o, t.level);
        put_u32(buf, o + 4, t.tiles_x);
        put_u32(buf, o + 8, t.tiles_y);
        if t.level == 0 {
            put_f32s(buf, o + 16, &t.min);
            put_f32s(buf, o + 16 + 4 * n, &t.max);
        } else {
            put_f32s(buf, o + 16, &t.eps);
        }
    }
    let end = buf.len() - 4;
    let crc = crc32fast::hash(&buf[..end]);
    put_u32(buf, end, crc);
}

/// Writes the bake to `path` through a memory-mapped temporary file in the same folder, renamed
/// over `path` when complete: a crash never leaves a half-written bake under the real name.
/// Overwrites `path` — callers decide whether that is allowed ([`load_or_bake`] does).
pub fn write_bake(path: &Path, b: &ErrorBake) -> Result<(), BakeError> {
    let werr = |p: &Path, e: &dyn std::fmt::Display| BakeError::Write {
        path: show(p),
        reason: e.to_string().replace(['\n', '\r'], " "),
    };
    let size = b.file_size();
    let mut tmp_name = path.file_name().map(|n| n.to_owned()).unwrap_or_default();
    tmp_name.push(format!(".tmp{}", std::process::id()));
    let tmp = path.with_file_name(tmp_name);
    let result = (|| -> Result<(), BakeError> {
        let f = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(true)
            .open(&tmp)
            .map_err(|e| werr(&tmp, &e))?;
        f.set_len(size).map_err(|e| werr(&tmp, &e))?;
        // SAFETY: the file was just created by this process under a name nobody else uses and
        // is not resized while mapped.
        let mut map = unsafe { memmap2::MmapMut::map_mut(&f) }.map_err(|e| werr(&tmp, &e))?;
        encode(b, &mut map);
        map.flush().map_err(|e| werr(&tmp, &e))?;
        drop(map);
        f.sync_all().map_err(|e| werr(&tmp, &e))?;
        std::fs::rename(&tmp, path).map_err(|e| werr(path, &e))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

fn get_u32(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}

fn get_u64(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
}

fn get_f32s(b: &[u8], at: usize, n: usize) -> Vec<f32> {
    b[at..at + 4 * n]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// Decodes a bake file's bytes, checking structure only (not the dataset).
fn decode(path: &Path, bytes: &[u8]) -> Result<ErrorBake, BakeError> {
    let p = show(path);
    let len = bytes.len() as u64;
    let truncated = |offset: u64, reason: String| BakeError::Truncated {
        path: p.clone(),
        offset,
        reason,
    };
    let corrupt = |field: &str, offset: u64, reason: String| BakeError::Corrupt {
        path: p.clone(),
        field: field.to_string(),
        offset,
        reason,
    };
    let head = &bytes[..bytes.len().min(8)];
    if head != &BAKE_MAGIC[..head.len()] || bytes.is_empty() {
        let found = if bytes.is_empty() {
            "empty".to_string()
        } else {
            format!("{:?}", String::from_utf8_lossy(head))
        };
        return Err(BakeError::BadMagic { path: p, found });
    }
    if len < 12 {
        return Err(truncated(
            len,
            format!("the file is {len} bytes and ends before the format version (bytes 8..12)"),
        ));
    }
    let version = get_u32(bytes, 8);
    if version != BAKE_VERSION {
        return Err(BakeError::Version {
            path: p,
            found: version,
        });
    }
    if len < HEADER_SIZE as u64 {
        return Err(truncated(
            len,
            format!("the file is {len} bytes and ends inside the {HEADER_SIZE}-byte header"),
        ));
    }
    let hcrc = crc32fast::hash(&bytes[..92]);
    if get_u32(bytes, 92) != hcrc {
        return Err(corrupt(
            "header CRC-32",
            92,
            format!(
                "stored {:#010x}, header bytes 0..92 give {hcrc:#010x}",
                get_u32(bytes, 92)
            ),
        ));
    }
    if get_u32(bytes, 12) as usize != HEADER_SIZE {
        return Err(corrupt(
            "header size",
            12,
            format!("{} (expected {HEADER_SIZE})", get_u32(bytes, 12)),
        ));
    }
    let m = get_u32(bytes, 16);
    let levels = get_u32(bytes, 20);
    let (width, height) = (get_u32(bytes, 24), get_u32(bytes, 28));
    let (vw, vh) = (get_u32(bytes, 32), get_u32(bytes, 36));
    let params = BakeParams {
        tile_size: m,
        levels,
    };
    params
        .log2_quads()
        .map_err(|e| corrupt("tile size", 16, e.to_string()))?;
    for (name, off, v) in [("width", 24, width), ("height", 28, height)] {
        if v < 2 || !(v - 1).is_power_of_two() {
            return Err(corrupt(name, off, format!("{v} is not 2^K + 1")));
        }
    }
    if vw == 0 || vw > width || vh == 0 || vh > height {
        return Err(corrupt(
            "valid size",
            32,
            format!("{vw}×{vh} real samples in a {width}×{height} grid"),
        ));
    }
    let kmin = (width - 1)
        .trailing_zeros()
        .min((height - 1).trailing_zeros());
    let j = (m - 1).trailing_zeros();
    if levels == 0 || kmin < j || levels > kmin - j + 1 {
        return Err(corrupt(
            "levels",
            20,
            format!("{levels} levels do not fit a {width}×{height} grid with {m}×{m} tiles"),
        ));
    }
    let sx = f64::from_bits(get_u64(bytes, 40));
    let sy = f64::from_bits(get_u64(bytes, 48));
    let layout = file_layout(width, height, m, levels);
    let promised = get_u64(bytes, 64);
    if promised != layout.total {
        return Err(corrupt(
            "file size",
            64,
            format!("{promised}, but the parameters give {} bytes", layout.total),
        ));
    }
    if len < layout.total {
        // Say which part the file ends in.
        let mut part = "the trailing CRC-32".to_string();
        for (l, s) in layout.sections.iter().enumerate() {
            let n = s.tiles_x as u64 * s.tiles_y as u64;
            let o = s.offset as u64;
            let parts: &[(u64, &str)] = if l == 0 {
                &[
                    (o, "section header"),
                    (o + 16, "min array"),
                    (o + 16 + 4 * n, "max array"),
                ]
            } else {
                &[(o, "section header"), (o + 16, "ε array")]
            };
            let end = o + section_size(l as u32, n as usize) as u64;
            if len < end {
                let (start, what) = parts
                    .iter()
                    .rev()
                    .find(|(start, _)| len >= *start)
                    .copied()
                    .unwrap_or(parts[0]);
                part = format!("level {l} {what} (starts at byte offset {start})");
                break;
            }
        }
        return Err(truncated(
            len,
            format!(
                "the file is {len} bytes, the header promises {}; it ends inside {part}",
                layout.total
            ),
        ));
    }
    if len > layout.total {
        return Err(corrupt(
            "file size",
            64,
            format!(
                "the file is {len} bytes, {} more than the {} the header promises",
                len - layout.total,
                layout.total
            ),
        ));
    }
    let end = bytes.len() - 4;
    let crc = crc32fast::hash(&bytes[..end]);
    if get_u32(bytes, end) != crc {
        return Err(corrupt(
            "file CRC-32",
            end as u64,
            format!(
                "stored {:#010x}, bytes 0..{end} give {crc:#010x} (the file was changed after it was written)",
                get_u32(bytes, end)
            ),
        ));
    }
    let mut eps = Vec::with_capacity(levels as usize);
    let (mut min0, mut max0) = (Vec::new(), Vec::new());
    for (l, s) in layout.sections.iter().enumerate() {
        let o = s.offset;
        let n = s.tiles_x as usize * s.tiles_y as usize;
        let (lv, tx, ty) = (
            get_u32(bytes, o),
            get_u32(bytes, o + 4),
            get_u32(bytes, o + 8),
        );
        if (lv, tx, ty) != (l as u32, s.tiles_x, s.tiles_y) {
            return Err(corrupt(
                "level section header",
                o as u64,
                format!(
                    "level {lv} with {tx}×{ty} tiles, expected level {l} with {}×{} tiles",
                    s.tiles_x, s.tiles_y
                ),
            ));
        }
        if l == 0 {
            min0 = get_f32s(bytes, o + 16, n);
            max0 = get_f32s(bytes, o + 16 + 4 * n, n);
            eps.push(Vec::new());
        } else {
            eps.push(get_f32s(bytes, o + 16, n));
        }
    }
    let q = (m - 1) as usize;
    let geo = level_geoms(q, width as usize, height as usize, levels);
    let tables = build_tables(&geo, min0, max0, eps, vw as usize, vh as usize);
    Ok(ErrorBake {
        params,
        width,
        height,
        valid_width: vw,
        valid_height: vh,
        spacing_x: sx,
        spacing_y: sy,
        source_checksum: get_u32(bytes, 56),
        levels: tables,
    })
}

/// Reads a bake file made for `ds`: checks the magic, version, sizes and CRCs, then that it
/// belongs to `ds` (grid size, real size, spacing, sample checksum). Errors name the file,
/// the field or byte offset and the reason, and say to re-run `aerie bake`.
pub fn read_bake(path: &Path, ds: &Dataset) -> Result<ErrorBake, BakeError> {
    let b = read_bake_file(path)?;
    check_belongs(path, &b, ds)?;
    Ok(b)
}

/// Reads and checks a bake file on its own, without a dataset to compare it with.
pub fn read_bake_file(path: &Path) -> Result<ErrorBake, BakeError> {
    let bytes = std::fs::read(path).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            BakeError::NotFound { path: show(path) }
        } else {
            BakeError::Io {
                path: show(path),
                reason: e.to_string(),
            }
        }
    })?;
    decode(path, &bytes)
}

fn check_belongs(path: &Path, b: &ErrorBake, ds: &Dataset) -> Result<(), BakeError> {
    let stale = |reason: String| BakeError::Stale {
        path: show(path),
        reason,
    };
    if (b.width as usize, b.height as usize) != (ds.hf.width, ds.hf.height)
        || (b.valid_width as usize, b.valid_height as usize) != (ds.valid_width, ds.valid_height)
    {
        return Err(stale(format!(
            "made for a {}×{} grid ({}×{} real samples), the dataset is {}×{} ({}×{} real)",
            b.width,
            b.height,
            b.valid_width,
            b.valid_height,
            ds.hf.width,
            ds.hf.height,
            ds.valid_width,
            ds.valid_height
        )));
    }
    if b.spacing_x != ds.hf.spacing_x || b.spacing_y != ds.hf.spacing_y {
        return Err(stale(format!(
            "made for {} m × {} m spacing, the dataset has {} m × {} m",
            b.spacing_x, b.spacing_y, ds.hf.spacing_x, ds.hf.spacing_y
        )));
    }
    let sum = ds.checksum();
    if sum != b.source_checksum {
        return Err(stale(format!(
            "source checksum {:#010x} (byte offset 56) differs from the dataset's {sum:#010x}: the samples changed since the bake",
            b.source_checksum
        )));
    }
    Ok(())
}

/// What is at a bake path, judged against the dataset and the parameters asked for.
#[derive(Debug)]
pub enum Existing {
    /// Nothing there: bake and write.
    Missing,
    /// A valid bake of this dataset with these parameters.
    UpToDate(Box<ErrorBake>),
    /// An aerie bake that may be replaced, and why it must be (stale, other parameters,
    /// truncated, corrupt, older version, or `--force`).
    Replace(String),
}

/// Decides what to do about the file at `bake_path` (levels 0 in `params` = as many as fit).
/// A file that is not a bake, or a bake of a newer format version, is an error
/// ([`BakeError::Refused`]) unless `force`; `force` also replaces an up-to-date bake.
pub fn check_existing(
    ds: &Dataset,
    bake_path: &Path,
    params: BakeParams,
    force: bool,
) -> Result<Existing, BakeError> {
    let levels = params.resolve_levels(ds)?;
    match read_bake(bake_path, ds) {
        Ok(b) => {
            if force {
                Ok(Existing::Replace(format!(
                    "{}: valid, re-baked because of --force",
                    show(bake_path)
                )))
            } else if b.params.tile_size == params.tile_size && b.params.levels == levels {
                Ok(Existing::UpToDate(Box::new(b)))
            } else {
                Ok(Existing::Replace(format!(
                    "{}: made with m = {} and {} levels, m = {} and {} levels asked",
                    show(bake_path),
                    b.params.tile_size,
                    b.params.levels,
                    params.tile_size,
                    levels
                )))
            }
        }
        Err(BakeError::NotFound { .. }) => Ok(Existing::Missing),
        Err(e @ (BakeError::BadMagic { .. } | BakeError::Version { .. })) => {
            let newer = matches!(e, BakeError::Version { found, .. } if found > BAKE_VERSION);
            let not_bake = matches!(e, BakeError::BadMagic { .. });
            if (newer || not_bake) && !force {
                let what = if not_bake {
                    "exists and is not an aerie bake file"
                } else {
                    "is a bake of a newer format version than this build writes"
                };
                return Err(BakeError::Refused {
                    path: show(bake_path),
                    reason: format!(
                        "{what}; not overwriting it (use --force to replace it, or --out to write elsewhere)"
                    ),
                });
            }
            Ok(Existing::Replace(e.to_string()))
        }
        Err(
            e @ (BakeError::Truncated { .. } | BakeError::Corrupt { .. } | BakeError::Stale { .. }),
        ) => Ok(Existing::Replace(e.to_string())),
        Err(e) => Err(e),
    }
}

/// What [`load_or_bake`] did.
#[derive(Debug, Clone, PartialEq)]
pub enum BakeOutcome {
    /// A valid bake with the same checksum and parameters was already there.
    UpToDate,
    /// There was no file; a new bake was written.
    Baked,
    /// An existing bake was replaced, for the reason given.
    Replaced(String),
}

/// Reads the bake at `bake_path` when it is a valid bake of `ds` with `params`, else bakes
/// and writes it, following [`check_existing`]: never overwrites a file that is not a bake
/// (or a newer version's) unless `force`, and says in the outcome why a bake was replaced.
pub fn load_or_bake(
    ds: &Dataset,
    bake_path: &Path,
    params: BakeParams,
    force: bool,
    progress: &dyn Fn(u64, u64),
) -> Result<(ErrorBake, BakeOutcome), BakeError> {
    let outcome = match check_existing(ds, bake_path, params, force)? {
        Existing::UpToDate(b) => return Ok((*b, BakeOutcome::UpToDate)),
        Existing::Missing => BakeOutcome::Baked,
        Existing::Replace(why) => BakeOutcome::Replaced(why),
    };
    let b = bake(ds, params, progress);
    write_bake(bake_path, &b)?;
    Ok((b, outcome))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Heightfield;

    fn ds(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Dataset {
        let mut heights = Vec::with_capacity(w * h);
        for r in 0..h {
            for c in 0..w {
                heights.push(f(c, r));
            }
        }
        Dataset::from_heightfield(
            Heightfield {
                width: w,
                height: h,
                spacing_x: 10.0,
                spacing_y: 10.0,
                heights,
                geo: None,
                voids_filled: 0,
                spacing_note: String::new(),
            },
            "test".into(),
        )
    }

    #[test]
    fn planes_have_zero_error_and_a_spike_shows_at_every_level() {
        let d = ds(33, 33, |c, r| 3.0 * c as f32 - 2.0 * r as f32);
        let b = bake(
            &d,
            BakeParams {
                tile_size: 5,
                levels: 0,
            },
            &|_, _| {},
        );
        assert_eq!(b.levels.len(), 4); // 32 = 2^5, m − 1 = 4 = 2^2 → levels 0..=3
        assert!(b.levels.iter().all(|t| t.eps.iter().all(|&e| e == 0.0)));
        // One needle at an odd sample: invisible to every coarse level, error = its height.
        let d = ds(33, 33, |c, r| if (c, r) == (5, 7) { 100.0 } else { 0.0 });
        let b = bake(
            &d,
            BakeParams {
                tile_size: 5,
                levels: 0,
            },
            &|_, _| {},
        );
        assert_eq!(b.eps(0, 1, 1), 0.0);
        assert_eq!(b.eps(1, 0, 0), 100.0);
        assert_eq!(b.eps(2, 0, 0), 100.0);
        assert_eq!(b.eps(3, 0, 0), 100.0);
        assert_eq!(b.eps(1, 1, 1), 0.0);
        assert_eq!(b.bounds(3, 0, 0), (0.0, 100.0));
        assert_eq!(b.eps_refined(3, 0, 0, 2), 100.0);
        assert_eq!(b.eps_refined(3, 0, 0, 3), 0.0);
        assert_eq!(b.eps_refined(3, 0, 0, 9), 0.0);
    }

    #[test]
    fn the_diagonal_matters() {
        // Level-1 cell [2,4]² holds a plane that bends along its SW-NE diagonal: exact for the
        // mesh's diagonal (ε = 0); the other diagonal would give ĥ(3,3) = 0 and ε = 4.
        let f = |c: usize, r: usize| match (c, r) {
            (4, 4) => 8.0,
            (4, 3) | (3, 4) | (3, 3) => 4.0,
            _ => 0.0,
        };
        let b = bake(
            &ds(5, 5, f),
            BakeParams {
                tile_size: 3,
                levels: 2,
            },
            &|_, _| {},
        );
        assert_eq!(b.eps(1, 0, 0), 0.0);
        let g = |c: usize, r: usize| if (c, r) == (3, 3) { 0.0 } else { f(c, r) };
        let b = bake(
            &ds(5, 5, g),
            BakeParams {
                tile_size: 3,
                levels: 2,
            },
            &|_, _| {},
        );
        assert_eq!(b.eps(1, 0, 0), 4.0);
    }

    /// The bake's fast loops give bit for bit what evaluating `quad_surface` at every sample
    /// gives (before and after rounding up), with and without AVX2.
    #[test]
    fn kernels_equal_per_sample_quad_surface() {
        let mut seed = 7u64;
        let mut rnd = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 33) as f64 / (1u64 << 31) as f64) as f32
        };
        let vals: Vec<f32> = (0..300 * 260).map(|_| rnd() * 900.0 - 100.0).collect();
        let d = ds(300, 260, |c, r| vals[r * 300 + c]);
        for m in [3, 5, 17] {
            let params = BakeParams {
                tile_size: m,
                levels: 0,
            };
            let fast = bake_with(&d, params, &|_, _| {}, true);
            let plain = bake_with(&d, params, &|_, _| {}, false);
            assert_eq!(fast, plain, "m = {m}");
            let q = (m - 1) as usize;
            for t in &fast.levels {
                let l = t.level;
                let s = 1usize << l;
                let side = q << l;
                for ty in 0..t.tiles_y as usize {
                    for tx in 0..t.tiles_x as usize {
                        let mut e = 0f64;
                        for r in ty * side..=(ty + 1) * side {
                            for c in tx * side..=(tx + 1) * side {
                                if l == 0 {
                                    continue;
                                }
                                let cx = (c / s).min((d.hf.width - 1) / s - 1);
                                let cy = (r / s).min((d.hf.height - 1) / s - 1);
                                let h = |c, r| f64::from(d.hf.at(c, r));
                                let (c0, r0) = (cx * s, cy * s);
                                let surf = quad_surface(
                                    h(c0, r0),
                                    h(c0 + s, r0),
                                    h(c0, r0 + s),
                                    h(c0 + s, r0 + s),
                                    (c - c0) as f64 / s as f64,
                                    (r - r0) as f64 / s as f64,
                                );
                                e = e.max((h(c, r) - surf).abs());
                            }
                        }
                        let i = ty * t.tiles_x as usize + tx;
                        let want = if t.terrain[i] { round_up_f32(e) } else { 0.0 };
                        assert_eq!(t.eps[i].to_bits(), want.to_bits(), "L{l} ({tx},{ty})");
                    }
                }
            }
        }
    }

    #[test]
    fn round_up_never_goes_below() {
        for x in [0.0, 1.0, 0.1, 1e-30, 3.000_000_000_100, 12_345.678_901_234] {
            let f = round_up_f32(x);
            assert!(f64::from(f) >= x);
            assert!(f64::from(f) - x <= f64::from(f) * 1.2e-7 + 1e-45);
        }
    }

    #[test]
    fn params_are_checked() {
        let d = ds(9, 9, |_, _| 0.0);
        assert!(BakeParams {
            tile_size: 16,
            levels: 0
        }
        .resolve_levels(&d)
        .is_err());
        assert!(BakeParams {
            tile_size: 17,
            levels: 0
        }
        .resolve_levels(&d)
        .is_err());
        assert_eq!(
            BakeParams {
                tile_size: 9,
                levels: 0
            }
            .resolve_levels(&d)
            .unwrap(),
            1
        );
        let e = BakeParams {
            tile_size: 3,
            levels: 5,
        }
        .resolve_levels(&d)
        .unwrap_err();
        assert!(e.to_string().contains("only 3 fit"), "{e}");
    }

    #[test]
    fn bake_paths() {
        assert_eq!(
            bake_path_for(Path::new("/d/N47E011.hgt.zip")),
            Path::new("/d/N47E011.hgt.zip.aerie-bake")
        );
        assert_eq!(
            bake_path_for(Path::new("/d/srtm/")),
            Path::new("/d/srtm.aerie-bake")
        );
    }
}
