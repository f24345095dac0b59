//! The ε computation: the level surfaces against every full-resolution sample, on all cores.

use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

use crate::dataset::Dataset;
use crate::mesh::{quad_surface, Diagonal, TILE_DIAGONAL};

use super::table::{build_tables, level_geoms, BakeParams, ErrorBake, LevelGeom, MeasuredEps};

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
/// cell row, and |h − ĥ_L| at its west edge (`i = 0`); `S = 2^L` known at compile time so the
/// loop unrolls with constant `u`.
#[inline(always)]
fn cell_max_const<const S: usize>(h: &[f32], c: &Corners, v: f64) -> (f64, f64) {
    let h = &h[..S];
    let mut e = [0f64; S];
    for (i, (e, &hi)) in e.iter_mut().zip(h).enumerate() {
        let u = i as f64 * (1.0 / S as f64);
        *e = sample_err(hi, c, u, v);
    }
    let west = e[0];
    // Pairwise, so the maxima do not form one long dependency chain.
    let mut n = S;
    while n > 1 {
        n /= 2;
        for i in 0..n {
            e[i] = gt_max(e[i], e[i + n]);
        }
    }
    (e[0], west)
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

/// The max |h − ĥ_L| over the samples of one cell row (`S = 2^L`, `S ≥ 2`; west edge included,
/// east edge excluded) split at the middle sample: `(west, east)`, the middle sample (u = ½)
/// in both. Parts of half a cell: tiles of 3 vertices at levels ≥ 2.
#[inline(always)]
fn cell_halves_const<const S: usize>(h: &[f32], c: &Corners, v: f64) -> (f64, f64) {
    let h = &h[..S];
    let mut e = [0f64; S];
    for (i, (e, &hi)) in e.iter_mut().zip(h).enumerate() {
        let u = i as f64 * (1.0 / S as f64);
        *e = sample_err(hi, c, u, v);
    }
    let half = S / 2;
    let (mut w, mut east) = (e[half], e[half]);
    for &x in &e[..half] {
        w = gt_max(x, w);
    }
    for &x in &e[half + 1..] {
        east = gt_max(x, east);
    }
    (w, east)
}

/// The same as [`cell_halves_const`] for `s ≥ 64` known at run time.
#[inline(always)]
fn cell_halves_dyn(h: &[f32], c: &Corners, v: f64, s: usize) -> (f64, f64) {
    debug_assert!(s >= 64 && s.is_multiple_of(64));
    let inv = 1.0 / s as f64;
    let half = s / 2;
    let (mut w, mut east) = (0f64, 0f64);
    for i0 in (0..half).step_by(32) {
        w = gt_max(block_max::<32>(h, c, v, i0, inv), w);
    }
    for i0 in (half..s).step_by(32) {
        east = gt_max(block_max::<32>(h, c, v, i0, inv), east);
    }
    // The middle sample (u = ½ exactly) is the west half's east edge too.
    (gt_max(sample_err(h[half], c, 0.5, v), w), east)
}

/// For one full-resolution row and one level `L ≥ 1`: the max |h − ĥ_L| over each of `parts`
/// equal parts of each tile's row (each part's edge samples included: a sample where two
/// parts meet is in both) into `out[parts·tx + k]`, west to east. With 2 parts a part is a
/// row of one of the tile's quadrants, the level-(L−1) tiles it covers; with 4 parts (levels
/// ≥ 2) a row of one of its 16 blocks, the level-(L−2) tiles it covers. So these maxima give
/// ε of the level-L surface over each level-(L−1) or level-(L−2) tile, and their maximum the
/// tile's own ε.
///
/// ĥ_L is [`quad_surface`] over the level-L cell holding the sample. The loops assume the
/// cell row bends where the SW–NE diagonal crosses it, which `quad_surface` decides per sample
/// anyway; the match below makes a new [`Diagonal`] a compile error here. A part's east edge
/// is the next part's west edge, taken from there (u = 0 in its first cell), which equals
/// u = 1 in the part's last cell bit for bit (`sw + (se − sw)` is `se` exactly for f32
/// heights widened to f64); the row's last part evaluates its east edge at u = 1. A part of
/// half a cell (`parts` = 2 × cells per tile: tiles of 3 vertices at levels ≥ 2) ends at
/// u = ½, which both halves evaluate alike. Every sample's |h − ĥ| is the same IEEE value
/// whichever part it lands in, and a maximum of non-negative non-NaN values does not depend
/// on the order, so the parts' maxima merge into exactly the coarser parts' (a quadrant is
/// the largest of its blocks).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn level_row_part_max<const S: usize>(
    row: &[f32],
    hs: &[f32],
    hn: &[f32],
    s: usize,
    v: f64,
    cells_per_tile: usize,
    parts: usize,
    out: &mut [f64],
) {
    match TILE_DIAGONAL {
        Diagonal::SouthWestToNorthEast => {}
    }
    let s = if S > 0 { S } else { s };
    if cells_per_tile < parts {
        // Half a cell a part.
        debug_assert_eq!(parts, 2 * cells_per_tile);
        for (cx, o) in out.chunks_exact_mut(2).enumerate() {
            let c0 = cx * s;
            let c = Corners::at(hs, hn, c0, s);
            let (w, e) = if S > 0 {
                cell_halves_const::<S>(&row[c0..], &c, v)
            } else {
                cell_halves_dyn(&row[c0..], &c, v, s)
            };
            o[0] = w;
            // The east half's east edge: u = 1 in the cell.
            o[1] = gt_max(sample_err(row[c0 + s], &c, 1.0, v), e);
        }
        return;
    }
    let part = cells_per_tile / parts;
    for k in 0..out.len() {
        let first = k * part;
        // Four running maxima, one per cell modulo 4, merged at the end.
        let mut ms = [0f64; 4];
        let mut west = 0f64;
        for (i, cx) in (first..first + part).enumerate() {
            let c0 = cx * s;
            let c = Corners::at(hs, hn, c0, s);
            let (e, w) = if S > 0 {
                cell_max_const::<S>(&row[c0..], &c, v)
            } else {
                (cell_max_dyn(&row[c0..], &c, v, s), 0.0)
            };
            // The part's west edge, u = 0 in its first cell.
            if i == 0 {
                west = if S > 0 {
                    w
                } else {
                    sample_err(row[c0], &c, 0.0, v)
                };
            }
            ms[i & 3] = gt_max(e, ms[i & 3]);
        }
        out[k] = gt_max(gt_max(ms[0], ms[1]), gt_max(ms[2], ms[3]));
        // The previous part's east edge is this part's west edge (u = 0 here, u = 1 there:
        // the same value bit for bit).
        if k > 0 {
            out[k - 1] = gt_max(west, out[k - 1]);
        }
    }
    // The last part's east edge: u = 1 in its last cell.
    let cells = cells_per_tile * out.len() / parts;
    if let Some(o) = out.last_mut() {
        let c0 = (cells - 1) * s;
        let c = Corners::at(hs, hn, c0, s);
        *o = gt_max(sample_err(row[c0 + s], &c, 1.0, v), *o);
    }
}

/// Parts of a tile row the bake measures at level `l ≥ 1`: 2 at level 1 (its quadrants), 4
/// above (its 16 blocks, the level-(L−2) tiles it covers).
#[inline]
fn row_parts(l: usize) -> usize {
    if l == 1 {
        2
    } else {
        4
    }
}

/// One worker's running maxima: per level L ≥ 1, ε of the level-L surface over each part of
/// its tiles — level 1 over each quadrant (indexed as level 0's tiles), each level L ≥ 2 over
/// each of the 16 blocks (indexed as level L−2's tiles; a quadrant is the largest of its 2×2
/// blocks) —, and level-0 min/max. Each row's maxima are rounded up to f32 before they are
/// merged — the same result as rounding the f64 maximum, since rounding up is monotonic — so
/// the parts take 4 bytes each per worker: 4 B per level-0 tile for level 1 and ≈ 16/3 B for
/// the blocks of levels ≥ 2, besides 8 B of min/max (a 32769² grid at m = 17: 39 MB of parts
/// and 34 MB of min/max a worker).
struct Acc {
    parts: Vec<Vec<f32>>,
    min0: Vec<f32>,
    max0: Vec<f32>,
}

impl Acc {
    fn new(geo: &[LevelGeom]) -> Self {
        let n0 = geo[0].tiles_x * geo[0].tiles_y;
        Acc {
            parts: geo
                .iter()
                .enumerate()
                .map(|(l, g)| {
                    if l == 0 {
                        Vec::new()
                    } else {
                        let p = row_parts(l);
                        vec![0f32; p * p * g.tiles_x * g.tiles_y]
                    }
                })
                .collect(),
            min0: vec![f32::INFINITY; n0],
            max0: vec![f32::NEG_INFINITY; n0],
        }
    }

    fn merge(&mut self, o: &Acc) {
        for (a, b) in self.parts.iter_mut().zip(&o.parts) {
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

/// The full-resolution rows the bake reads: a dataset in memory, or a band of a source read a
/// band at a time (the streamed import), which must hold every row [`rows_needed`] names.
pub(crate) trait BakeRows: Sync {
    /// Padded row `r` (row 0 = south), every padded sample of it.
    fn row(&self, r: usize) -> &[f32];
}

impl BakeRows for Dataset {
    #[inline]
    fn row(&self, r: usize) -> &[f32] {
        let w = self.hf.width;
        &self.hf.heights[r * w..(r + 1) * w]
    }
}

/// The rows outside `r0..r1` that baking rows `r0..r1` reads: each level's vertex rows (every
/// 2^L-th row) bounding the band's cells, south and north, sorted, without repeats.
pub(crate) fn rows_needed(levels: u32, height: usize, r0: usize, r1: usize) -> Vec<usize> {
    let mut v = Vec::new();
    for l in 1..levels as usize {
        let s = 1usize << l;
        let south = r0 - r0 % s;
        let north = ((r1 - 1).div_ceil(s) * s).min(height - 1);
        v.extend([south, north].into_iter().filter(|&r| r < r0 || r >= r1));
    }
    v.sort_unstable();
    v.dedup();
    v
}

/// Rows `r0..r1` into the worker's maxima, with AVX2 when the CPU has it (same IEEE
/// operations in the same order either way, so the results are bit-identical).
#[allow(clippy::too_many_arguments)]
fn process_rows<R: BakeRows>(
    ds: &R,
    valid: (usize, usize),
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
        unsafe { process_rows_avx2(ds, valid, geo, q, r0, r1, acc, tile_max) };
        return;
    }
    process_rows_impl(ds, valid, geo, q, r0, r1, acc, tile_max);
}

/// [`process_rows_impl`] compiled for AVX2.
///
/// # Safety
///
/// The CPU running it must support AVX2 (`is_x86_feature_detected!("avx2")`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
unsafe fn process_rows_avx2<R: BakeRows>(
    ds: &R,
    valid: (usize, usize),
    geo: &[LevelGeom],
    q: usize,
    r0: usize,
    r1: usize,
    acc: &mut Acc,
    tile_max: &mut [f64],
) {
    process_rows_impl(ds, valid, geo, q, r0, r1, acc, tile_max);
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn process_rows_impl<R: BakeRows>(
    ds: &R,
    (valid_width, valid_height): (usize, usize),
    geo: &[LevelGeom],
    q: usize,
    r0: usize,
    r1: usize,
    acc: &mut Acc,
    tile_max: &mut [f64],
) {
    for r in r0..r1 {
        let row = ds.row(r);
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
            let (lo, _) = tile_rows_of(r, g.t, g.tiles_y);
            if lo * g.t >= valid_height {
                continue;
            }
            let real_tiles_x = valid_width.div_ceil(g.t).min(g.tiles_x);
            let s = 1usize << l;
            let j = r & (s - 1);
            let south = r - j;
            let north = if j == 0 { south } else { south + s };
            let (hs, hn) = (ds.row(south), ds.row(north));
            let v = j as f64 / s as f64;
            let p = row_parts(l);
            let out = &mut tile_max[..p * real_tiles_x];
            match s {
                2 => level_row_part_max::<2>(row, hs, hn, s, v, q, p, out),
                4 => level_row_part_max::<4>(row, hs, hn, s, v, q, p, out),
                8 => level_row_part_max::<8>(row, hs, hn, s, v, q, p, out),
                16 => level_row_part_max::<16>(row, hs, hn, s, v, q, p, out),
                32 => level_row_part_max::<32>(row, hs, hn, s, v, q, p, out),
                _ => level_row_part_max::<0>(row, hs, hn, s, v, q, p, out),
            }
            // The part rows (level L−1's or L−2's tile rows) this row belongs to.
            let (plo, phi) = tile_rows_of(r, g.t / p, p * g.tiles_y);
            let px = p * g.tiles_x;
            let a = &mut acc.parts[l];
            let lo = &mut a[plo * px..][..out.len()];
            for (x, &m) in lo.iter_mut().zip(out.iter()) {
                let m = round_up_f32(m);
                *x = if m > *x { m } else { *x };
            }
            if phi != plo {
                let hi = &mut a[phi * px..][..out.len()];
                for (x, &m) in hi.iter_mut().zip(out.iter()) {
                    let m = round_up_f32(m);
                    *x = if m > *x { m } else { *x };
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
pub(super) fn bake_with(
    ds: &Dataset,
    params: BakeParams,
    progress: &dyn Fn(u64, u64),
    simd: bool,
) -> ErrorBake {
    let levels = params.resolve_levels(ds).unwrap_or_else(|e| panic!("{e}"));
    let (w, h) = (ds.hf.width, ds.hf.height);
    let params = BakeParams {
        tile_size: params.tile_size,
        levels,
    };
    let mut acc = BakeAccumulator::new(params, (w, h), (ds.valid_width, ds.valid_height));
    acc.simd = simd;
    let total = (w * h) as u64;
    progress(0, total);
    acc.add_rows(ds, 0, h, &|rows| progress(rows * w as u64, total));
    progress(total, total);
    acc.finish((ds.hf.spacing_x, ds.hf.spacing_y), ds.checksum())
}

/// The bake's running maxima over rows given a band at a time, in order or not: every row of
/// the padded grid must be added exactly once (a row added twice changes nothing; one missing
/// leaves its tiles unmeasured). [`bake`] adds them all at once; the streamed import adds a
/// band at a time ([`BakeRows`] holding the band and its [`rows_needed`]).
pub(crate) struct BakeAccumulator {
    params: BakeParams,
    size: (usize, usize),
    valid: (usize, usize),
    q: usize,
    geo: Vec<LevelGeom>,
    /// One per worker thread, merged by [`Self::finish`].
    accs: Vec<Acc>,
    tile_max: Vec<Vec<f64>>,
    pub(crate) simd: bool,
}

impl BakeAccumulator {
    /// For a padded grid of `size` samples with `valid` real ones; `params.levels` resolved
    /// (≥ 1, fitting the grid).
    pub(crate) fn new(params: BakeParams, size: (usize, usize), valid: (usize, usize)) -> Self {
        let q = (params.tile_size - 1) as usize;
        let geo = level_geoms(q, size.0, size.1, params.levels);
        let threads = std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
            .clamp(1, size.1.div_ceil(CHUNK_ROWS));
        BakeAccumulator {
            params,
            size,
            valid,
            q,
            accs: (0..threads).map(|_| Acc::new(&geo)).collect(),
            tile_max: (0..threads).map(|_| vec![0f64; geo[0].tiles_x]).collect(),
            geo,
            simd: true,
        }
    }

    /// Rows `r0..r1` of `rows` on all cores; `progress(rows done of these)` from the calling
    /// thread.
    pub(crate) fn add_rows<R: BakeRows>(
        &mut self,
        rows: &R,
        r0: usize,
        r1: usize,
        progress: &dyn Fn(u64),
    ) {
        let chunks = (r1 - r0).div_ceil(CHUNK_ROWS);
        let threads = self.accs.len().min(chunks.max(1));
        let next = AtomicUsize::new(0);
        let rows_done = AtomicU64::new(0);
        let finished = AtomicUsize::new(0);
        let (geo, q, valid, simd) = (&self.geo, self.q, self.valid, self.simd);
        std::thread::scope(|s| {
            for (acc, tile_max) in self.accs.iter_mut().zip(&mut self.tile_max).take(threads) {
                let (next, rows_done, finished) = (&next, &rows_done, &finished);
                s.spawn(move || {
                    loop {
                        let c = next.fetch_add(1, Ordering::Relaxed);
                        if c >= chunks {
                            break;
                        }
                        let a = r0 + c * CHUNK_ROWS;
                        let b = (a + CHUNK_ROWS).min(r1);
                        process_rows(rows, valid, geo, q, a, b, acc, tile_max, simd);
                        rows_done.fetch_add((b - a) as u64, Ordering::Relaxed);
                    }
                    finished.fetch_add(1, Ordering::Release);
                });
            }
            while finished.load(Ordering::Acquire) < threads {
                std::thread::sleep(std::time::Duration::from_millis(50));
                progress(rows_done.load(Ordering::Relaxed));
            }
        });
    }

    /// The bake of every row added: the workers' maxima (rounded up to f32) merged, the
    /// tables built; `spacing` and `checksum` (of the padded samples) recorded.
    pub(crate) fn finish(self, spacing: (f64, f64), checksum: u32) -> ErrorBake {
        let mut accs = self.accs.into_iter();
        let mut acc = accs.next().expect("at least one worker");
        for o in accs {
            acc.merge(&o);
        }
        let parts = std::mem::take(&mut acc.parts);
        let tables = build_tables(
            &self.geo,
            std::mem::take(&mut acc.min0),
            std::mem::take(&mut acc.max0),
            MeasuredEps::Blocks(parts),
            self.valid.0,
            self.valid.1,
        );
        ErrorBake {
            params: self.params,
            width: self.size.0 as u32,
            height: self.size.1 as u32,
            valid_width: self.valid.0 as u32,
            valid_height: self.valid.1 as u32,
            spacing_x: spacing.0,
            spacing_y: spacing.1,
            source_checksum: checksum,
            levels: tables,
        }
    }
}
