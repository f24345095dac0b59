//! Normal-map texels as plain data: for every level-L sample the level textures hold, the normal
//! of the full-resolution surface filtered over that sample's footprint, so a coarse tile is lit
//! like the level-0 surface (seed document 003). The renderer computes them on the CPU when a
//! level strip is gathered and uploads them with its heights into a texture of the same toroidal
//! layout (one RG8_SNORM texel per level-texture texel, `render/normal_textures.rs`).
//!
//! **Filter.** Level 0: the central difference (the vertex shader's own normal, so where level 0
//! is drawn the lighting stays as it was). Level L ≥ 1: the mean gradient of the bilinear
//! level-0 surface over the square of side 2^L level-0 samples centred on the sample (its
//! footprint), then `normalize(−gx, −gy, 1)`. Filtering commutes with differentiation, so this
//! is the normal of the box-filtered surface, and the mean gradient telescopes to the difference
//! of the mean heights on opposite edges: O(2^L) reads per texel instead of O(4^L) for a mean of
//! unit normals (which differs only by a length the renormalisation discards on gentle slopes).
//!
//! **Cost bound.** The edges are read at level s = max(0, L − [`EDGE_OCTAVES`]): exact (every
//! level-0 sample) for L ≤ 3, above that the edge means are taken over 2^EDGE_OCTAVES + 1 points,
//! every 2^s-th level-0 sample.
//!
//! **Streaming.** A level strip is admitted only with its normal texels: where the source does
//! not hold level s around it yet (a streamed store far from the eye), the strip's cells stay
//! pending and level s is asked for with them, so a streamed store draws exactly what the same
//! data in memory draws. The first frame's wait (`RendererDesc::start_up_rects`) includes the
//! coarsest level's footprints. (The arithmetic also takes a coarser source, down to level L
//! itself, where the footprint widens to two level-L samples: `NormalFootprint::candidates`.)

use aerie_terrain::clipmap::{toroidal_pieces, VertexRect};
use aerie_terrain::source::SampleRect;

/// Bytes per normal texel (RG8_SNORM: x and y; z ≥ 0 is reconstructed, a height field's normal
/// always points up). The step 1/127 in x, y is under 0.5° of tilt; z's error grows on faces
/// steeper than ~75° (0.03 at 84°), where Lambert shading barely depends on it.
pub const NORMAL_TEXEL_BYTES: u64 = 2;

/// At most this many octaves finer than the texel's level feed its footprint's edges.
pub const EDGE_OCTAVES: u32 = 3;

/// One normal texel: x and y of the unit normal (east, north), snorm8 (value · 127).
pub type NormalTexel = [i8; 2];

/// How the normal texels of a level-`level` upload read their heights: from level `source`
/// (level ≤ source ≤ level, see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NormalFootprint {
    pub level: u32,
    pub source: u32,
}

impl NormalFootprint {
    /// How a level-`level` texel reads its heights: level max(0, L − [`EDGE_OCTAVES`]).
    pub fn of_level(level: u32) -> NormalFootprint {
        NormalFootprint {
            level,
            source: level.saturating_sub(EDGE_OCTAVES),
        }
    }

    /// Every source level the arithmetic supports for a level-`level` texel, finest first
    /// (the renderer uses the first, [`Self::of_level`]).
    pub fn candidates(level: u32) -> impl Iterator<Item = NormalFootprint> {
        (level.saturating_sub(EDGE_OCTAVES)..=level)
            .map(move |source| NormalFootprint { level, source })
    }

    /// Half the footprint's side, level-0 samples (a multiple of 2^source).
    pub fn half(&self) -> i64 {
        if self.level == 0 {
            return 1;
        }
        (1i64 << (self.level - 1)).max(1 << self.source)
    }

    /// Source samples between adjacent texels.
    fn stride(&self) -> usize {
        1 << (self.level - self.source)
    }

    /// Source samples across one footprint (its side is `k` source spacings).
    fn k(&self) -> usize {
        ((2 * self.half()) >> self.source) as usize
    }

    /// The source rectangle the texels of an upload with level-0 `origin` (its first sample)
    /// and `size` texels read: every footprint, edges included.
    pub fn rect(&self, origin: [i64; 2], size: [u32; 2]) -> SampleRect {
        let h = self.half();
        let span = |n: u32| {
            if n == 0 {
                0
            } else {
                ((n as usize - 1) * self.stride() + self.k() + 1) as u32
            }
        };
        SampleRect {
            level: self.source,
            origin: origin.map(|o| o - h),
            size: [span(size[0]), span(size[1])],
        }
    }
}

/// Bytes of the normal texels of a level strip of `size` texels (none without normal maps).
pub fn normal_bytes(size: [u32; 2], normals: bool) -> u64 {
    if normals {
        size[0] as u64 * size[1] as u64 * NORMAL_TEXEL_BYTES
    } else {
        0
    }
}

/// Encodes a gradient (metres per metre, east and north) as the unit normal's x, y in snorm8.
pub fn encode_normal(gx: f64, gy: f64) -> NormalTexel {
    let len = (gx * gx + gy * gy + 1.0).sqrt();
    let q = |v: f64| (v / len * 127.0).round().clamp(-127.0, 127.0) as i8;
    [q(-gx), q(-gy)]
}

/// The unit normal a texel stands for (what the shader reconstructs).
pub fn decode_normal(t: NormalTexel) -> [f32; 3] {
    let x = f32::from(t[0]) / 127.0;
    let y = f32::from(t[1]) / 127.0;
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    let len = (x * x + y * y + z * z).sqrt().max(1e-6);
    [x / len, y / len, z / len]
}

/// The mean gradient (east, north) of each of `size` texels from `block`, the samples of
/// `fp.rect(origin, size)` row-major; `spacing` is metres between level-0 samples.
pub fn footprint_gradients(
    fp: &NormalFootprint,
    block: &[f32],
    size: [u32; 2],
    spacing: [f64; 2],
) -> Vec<[f64; 2]> {
    let rect = fp.rect([0, 0], size);
    let bw = rect.size[0] as usize;
    assert_eq!(block.len(), rect.len(), "normal block size");
    let (stride, k) = (fp.stride(), fp.k());
    let scale = (1u64 << fp.source) as f64;
    let (dx, dy) = (spacing[0] * scale, spacing[1] * scale);
    let at = |c: usize, r: usize| f64::from(block[r * bw + c]);
    let mut out = Vec::with_capacity(size[0] as usize * size[1] as usize);
    for j in 0..size[1] as usize {
        for i in 0..size[0] as usize {
            let (a, b) = (i * stride, j * stride);
            if fp.level == 0 {
                // The central difference, as terrain.vert computes it at level 0.
                let gx = (at(a + 2, b + 1) - at(a, b + 1)) / (2.0 * dx);
                let gy = (at(a + 1, b + 2) - at(a + 1, b)) / (2.0 * dy);
                out.push([gx, gy]);
                continue;
            }
            // Trapezoid means along the edges: exact for the bilinear surface.
            let (mut sx, mut sy) = (0.0, 0.0);
            for t in 0..=k {
                let w = if t == 0 || t == k { 0.5 } else { 1.0 };
                sx += w * (at(a + k, b + t) - at(a, b + t));
                sy += w * (at(a + t, b + k) - at(a + t, b));
            }
            let kk = (k * k) as f64;
            out.push([sx / (kk * dx), sy / (kk * dy)]);
        }
    }
    out
}

/// The normal texels of `size` texels from `block` (see [`footprint_gradients`]), appended to
/// `out` row-major.
pub fn normal_texels(
    fp: &NormalFootprint,
    block: &[f32],
    size: [u32; 2],
    spacing: [f64; 2],
    out: &mut Vec<NormalTexel>,
) {
    let g = footprint_gradients(fp, block, size, spacing);
    out.extend(g.iter().map(|g| encode_normal(g[0], g[1])));
}

/// The level-L samples a level texture holds, `[lo, hi]` per axis (its cache region): what the
/// GPU normal pass ([`level_normal_texel`]) may read around a sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LevelRegion {
    pub lo: [i64; 2],
    pub hi: [i64; 2],
}

impl LevelRegion {
    /// The region of a level texture of `side` texels whose first sample is `origin`
    /// (`clipmap::CacheRegion`).
    pub fn of_cache(origin: [i64; 2], side: u32) -> LevelRegion {
        LevelRegion {
            lo: origin,
            hi: origin.map(|o| o + side as i64 - 1),
        }
    }
}

/// `--normals gpu`: the normal texel of level-`level` sample `s` (level-L coordinates) from the
/// level's own heights — what `shaders/normal_map.comp` computes, in the same f32 arithmetic —,
/// the central difference of the level-L samples either side, 2^L × `spacing` metres apart.
/// A neighbour outside `region` is not in the level texture (its texel holds the other side of
/// the torus): it is clamped to the region, so the region's edge samples take the one-sided
/// difference. `h` gives a level-L sample's height (the source's, clamped to the grid as the
/// uploader clamps it).
pub fn level_normal_texel(
    h: &impl Fn([i64; 2]) -> f32,
    s: [i64; 2],
    region: &LevelRegion,
    level_spacing: [f32; 2],
) -> NormalTexel {
    let lo = [0, 1].map(|a| (s[a] - 1).max(region.lo[a]));
    let hi = [0, 1].map(|a| (s[a] + 1).min(region.hi[a]));
    let gx = (h([hi[0], s[1]]) - h([lo[0], s[1]]))
        / (((hi[0] - lo[0]).max(1)) as f32 * level_spacing[0]);
    let gy = (h([s[0], hi[1]]) - h([s[0], lo[1]]))
        / (((hi[1] - lo[1]).max(1)) as f32 * level_spacing[1]);
    let len = (gx * gx + gy * gy + 1.0).sqrt();
    // packSnorm4x8: round(clamp(v, −1, 1) · 127).
    let q = |v: f32| ((v / len).clamp(-1.0, 1.0) * 127.0).round() as i8;
    [q(-gx), q(-gy)]
}

/// [`level_normal_texel`] of the `size` level-L samples from `origin` (level-L coordinates),
/// appended to `out` row-major: the texels of one GPU normal job.
pub fn level_normal_texels(
    h: &impl Fn([i64; 2]) -> f32,
    origin: [i64; 2],
    size: [u32; 2],
    region: &LevelRegion,
    level_spacing: [f32; 2],
    out: &mut Vec<NormalTexel>,
) {
    for j in 0..size[1] as i64 {
        for i in 0..size[0] as i64 {
            let s = [origin[0] + i, origin[1] + j];
            out.push(level_normal_texel(h, s, region, level_spacing));
        }
    }
}

/// Metres between level-`level` samples for the GPU pass (f32, as pushed).
pub fn level_spacing(spacing: [f64; 2], level: u32) -> [f32; 2] {
    spacing.map(|s| (s * (1u64 << level) as f64) as f32)
}

/// The level-L vertex rectangle whose normal texels the GPU pass recomputes when `rect` (level-L
/// vertices, inside `region`) is uploaded: `rect` and the samples one beyond it on each side,
/// whose central differences read `rect`'s new heights, within the region. A sample's normal
/// reads only its neighbours, so after the last of its neighbourhood arrives it is recomputed
/// from resident heights (neighbours in pending cells are stale until they arrive, and their
/// arrival recomputes it; a tile is drawn only once its neighbour cells are resident).
pub fn gpu_normal_rect(
    origin: [i64; 2],
    size: [u32; 2],
    region: &LevelRegion,
) -> ([i64; 2], [u32; 2]) {
    let lo = [0, 1].map(|a| (origin[a] - 1).max(region.lo[a]));
    let hi = [0, 1].map(|a| (origin[a] + size[a] as i64).min(region.hi[a]));
    (lo, [0, 1].map(|a| (hi[a] - lo[a] + 1).max(0) as u32))
}

/// One piece of the GPU normal pass: `size` texels of layer `level` from `texel` (no toroidal
/// wrap inside), the level-L samples from `sample`, read within `region`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NormalJob {
    pub level: u32,
    pub texel: [u32; 2],
    pub size: [u32; 2],
    pub sample: [i64; 2],
    pub region: LevelRegion,
}

impl NormalJob {
    pub fn texels(&self) -> u64 {
        self.size[0] as u64 * self.size[1] as u64
    }
}

/// The GPU normal jobs of a level upload of `size` level-`level` samples from `origin` (level-L
/// vertices; a piece of a strip, inside the level's cache region from `cache_origin`, in a
/// texture of `side` texels): its [`gpu_normal_rect`], split where it wraps around the torus.
pub fn gpu_normal_jobs(
    level: u32,
    origin: [i64; 2],
    size: [u32; 2],
    cache_origin: [i64; 2],
    side: u32,
) -> Vec<NormalJob> {
    let region = LevelRegion::of_cache(cache_origin, side);
    let (lo, size) = gpu_normal_rect(origin, size, &region);
    let rect = VertexRect { origin: lo, size };
    toroidal_pieces(&rect, side)
        .into_iter()
        .map(|p| NormalJob {
            level,
            texel: p.texel,
            size: p.size,
            sample: [0, 1].map(|a| lo[a] + p.src_offset[a] as i64),
            region,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rough generated terrain: detail down to two samples, under a long slope.
    fn height(c: i64, r: i64) -> f32 {
        let (x, y) = (c as f64, r as f64);
        (3.0 * x
            + 0.5 * y
            + 40.0 * (x * 0.9).sin() * (y * 0.7).cos()
            + 25.0 * (x * 0.13 + y * 0.31).sin()
            + 7.0 * ((x * 2.3).sin() + (y * 1.7).cos())) as f32
    }

    const W: i64 = 300;
    const SPACING: [f64; 2] = [30.0, 20.0];

    /// What the source serves: level-0 sample coordinates clamped into the grid.
    fn h0(c: i64, r: i64) -> f64 {
        f64::from(height(c.clamp(0, W - 1), r.clamp(0, W - 1)))
    }

    fn block_of(fp: &NormalFootprint, origin: [i64; 2], size: [u32; 2]) -> Vec<f32> {
        let rect = fp.rect(origin, size);
        let step = 1i64 << rect.level;
        let mut v = Vec::new();
        for j in 0..rect.size[1] as i64 {
            for i in 0..rect.size[0] as i64 {
                v.push(h0(rect.origin[0] + i * step, rect.origin[1] + j * step) as f32);
            }
        }
        v
    }

    /// Brute force, cell by cell: the mean over the footprint's level-s cells of each bilinear
    /// cell's mean gradient (the cell's two edge differences averaged).
    fn brute_gradient(level: u32, source: u32, c: i64, r: i64) -> [f64; 2] {
        let fp = NormalFootprint { level, source };
        if level == 0 {
            return [
                (h0(c + 1, r) - h0(c - 1, r)) / (2.0 * SPACING[0]),
                (h0(c, r + 1) - h0(c, r - 1)) / (2.0 * SPACING[1]),
            ];
        }
        let (h, s) = (fp.half(), 1i64 << source);
        let (mut gx, mut gy, mut n) = (0.0, 0.0, 0.0);
        let mut y = r - h;
        while y < r + h {
            let mut x = c - h;
            while x < c + h {
                gx += (h0(x + s, y) - h0(x, y) + h0(x + s, y + s) - h0(x, y + s))
                    / (2.0 * s as f64 * SPACING[0]);
                gy += (h0(x, y + s) - h0(x, y) + h0(x + s, y + s) - h0(x + s, y))
                    / (2.0 * s as f64 * SPACING[1]);
                n += 1.0;
                x += s;
            }
            y += s;
        }
        [gx / n, gy / n]
    }

    #[test]
    fn texels_equal_the_brute_force_level0_mean_gradient() {
        for level in 0..=6u32 {
            for fp in NormalFootprint::candidates(level) {
                let step = 1i64 << level;
                let origin = [5 * step, 3 * step];
                let size = [7, 5];
                let g = footprint_gradients(&fp, &block_of(&fp, origin, size), size, SPACING);
                for j in 0..size[1] as i64 {
                    for i in 0..size[0] as i64 {
                        let (c, r) = (origin[0] + i * step, origin[1] + j * step);
                        let want = brute_gradient(level, fp.source, c, r);
                        let got = g[(j * size[0] as i64 + i) as usize];
                        for a in 0..2 {
                            assert!(
                                (got[a] - want[a]).abs() < 1e-9,
                                "{fp:?} texel ({i}, {j}) axis {a}: {} vs brute force {}",
                                got[a],
                                want[a]
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn finest_candidate_is_level0_up_to_level3_and_footprint_is_centred() {
        for level in 0..=3 {
            assert_eq!(NormalFootprint::of_level(level).source, 0);
        }
        let fp = NormalFootprint::of_level(6);
        assert_eq!(fp.source, 3);
        // Level 6: footprint 64 samples wide, read at level 3 (9 points per edge).
        let r = fp.rect([640, 128], [1, 1]);
        assert_eq!((r.origin, r.size, r.level), ([608, 96], [9, 9], 3));
        // The coarsest candidate is the drawn level's central difference.
        let last = NormalFootprint::candidates(6).last().unwrap();
        assert_eq!((last.source, last.half(), last.k()), (6, 64, 2));
    }

    #[test]
    fn texels_depend_only_on_the_sample_not_on_the_upload_split() {
        // A strip split at the toroidal wrap into two pieces gives the texels of the whole.
        let level = 2;
        let fp = NormalFootprint { level, source: 0 };
        let step = 1i64 << level;
        let (origin, size) = ([4 * step, 8 * step], [12u32, 3u32]);
        let mut whole = Vec::new();
        normal_texels(&fp, &block_of(&fp, origin, size), size, SPACING, &mut whole);
        let mut pieces = Vec::new();
        for (o, w) in [(0i64, 5u32), (5, 7)] {
            let po = [origin[0] + o * step, origin[1]];
            let mut p = Vec::new();
            normal_texels(&fp, &block_of(&fp, po, [w, 3]), [w, 3], SPACING, &mut p);
            pieces.push((o as usize, w as usize, p));
        }
        for j in 0..3 {
            for (o, w, p) in &pieces {
                for i in 0..*w {
                    assert_eq!(
                        p[j * w + i],
                        whole[j * 12 + o + i],
                        "texel ({}, {j})",
                        o + i
                    );
                }
            }
        }
    }

    #[test]
    fn encoding_round_trips_within_the_snorm_step() {
        // Up to 72° slopes: z is reconstructed from x and y, so its error grows as the face
        // steepens (0.03 at 84°).
        for (gx, gy) in [(0.0, 0.0), (0.3, -0.2), (-2.0, 1.5), (3.0, 0.0)] {
            let len = (gx * gx + gy * gy + 1.0f64).sqrt();
            let want = [-gx / len, -gy / len, 1.0 / len];
            let got = decode_normal(encode_normal(gx, gy));
            for a in 0..3 {
                assert!(
                    (f64::from(got[a]) - want[a]).abs() < 0.02,
                    "({gx}, {gy}) axis {a}: {got:?} vs {want:?}"
                );
            }
        }
        assert_eq!(encode_normal(0.0, 0.0), [0, 0]);
    }

    #[test]
    fn coarse_texels_keep_detail_the_drawn_level_loses() {
        // At level 3 the level's own central difference (point samples 16 apart) and the
        // full-resolution footprint mean differ on this rough terrain.
        let level = 3;
        let fine = NormalFootprint { level, source: 0 };
        let coarse = NormalFootprint { level, source: 3 };
        let (origin, size) = ([80, 80], [6u32, 6u32]);
        let a = footprint_gradients(&fine, &block_of(&fine, origin, size), size, SPACING);
        let b = footprint_gradients(&coarse, &block_of(&coarse, origin, size), size, SPACING);
        let most = a
            .iter()
            .zip(&b)
            .map(|(a, b)| (a[0] - b[0]).abs().max((a[1] - b[1]).abs()))
            .fold(0.0, f64::max);
        assert!(most > 0.05, "largest slope difference {most}");
    }

    /// Level-L heights of the rough test terrain at sample `s` of level `level`.
    fn level_height(level: u32) -> impl Fn([i64; 2]) -> f32 {
        move |s: [i64; 2]| h0(s[0] << level, s[1] << level) as f32
    }

    fn within_one_step(got: NormalTexel, want: NormalTexel) -> bool {
        (0..2).all(|a| (i32::from(got[a]) - i32::from(want[a])).abs() <= 1)
    }

    #[test]
    fn gpu_texel_is_the_central_difference_inside_and_one_sided_at_the_region_edge() {
        let region = LevelRegion::of_cache([10, 20], 16);
        assert_eq!(region.hi, [25, 35]);
        for level in [0, 2, 5] {
            let h = level_height(level);
            let sp = level_spacing(SPACING, level);
            let d = [0, 1].map(|a| SPACING[a] * (1u64 << level) as f64);
            let hf = |c: i64, r: i64| f64::from(h([c, r]));
            for s in [[15, 27], [10, 27], [25, 35], [10, 20]] {
                let (w, e) = ((s[0] - 1).max(10), (s[0] + 1).min(25));
                let (south, north) = ((s[1] - 1).max(20), (s[1] + 1).min(35));
                let gx = (hf(e, s[1]) - hf(w, s[1])) / ((e - w) as f64 * d[0]);
                let gy = (hf(s[0], north) - hf(s[0], south)) / ((north - south) as f64 * d[1]);
                let got = level_normal_texel(&h, s, &region, sp);
                let want = encode_normal(gx, gy);
                assert!(
                    within_one_step(got, want),
                    "level {level} sample {s:?}: {got:?} vs {want:?}"
                );
            }
        }
        // A plane: the one-sided edges give the same normal as the interior.
        let plane = |s: [i64; 2]| (3.0 * s[0] as f64 - 2.0 * s[1] as f64) as f32;
        let want = encode_normal(3.0 / 30.0, -2.0 / 20.0);
        for s in [[10, 20], [17, 28], [25, 35]] {
            assert_eq!(level_normal_texel(&plane, s, &region, [30.0, 20.0]), want);
        }
    }

    #[test]
    fn gpu_texels_at_level0_are_the_cpu_texels_inside_the_region() {
        let fp = NormalFootprint::of_level(0);
        let (origin, size) = ([40, 50], [24u32, 9u32]);
        let mut cpu = Vec::new();
        normal_texels(&fp, &block_of(&fp, origin, size), size, SPACING, &mut cpu);
        let region = LevelRegion::of_cache([0, 0], 128);
        let mut gpu = Vec::new();
        let sp = level_spacing(SPACING, 0);
        level_normal_texels(&level_height(0), origin, size, &region, sp, &mut gpu);
        assert_eq!(cpu.len(), gpu.len());
        for (k, (c, g)) in cpu.iter().zip(&gpu).enumerate() {
            assert!(within_one_step(*g, *c), "texel {k}: gpu {g:?}, cpu {c:?}");
        }
    }

    #[test]
    fn gpu_jobs_cover_the_upload_and_its_border_within_the_region_without_wrapping() {
        let side = 32u32;
        // A region straddling the torus' seam and negative samples.
        let cache = [-7i64, 40];
        let region = LevelRegion::of_cache(cache, side);
        let cases = [
            // An inner strip: one sample of border on every side.
            ([0i64, 45i64], [8u32, 5u32], [-1i64, 44i64], [10u32, 7u32]),
            // At the region's west and south edges: no border beyond them.
            ([-7, 40], [4, 32], [-7, 40], [5, 32]),
            // At the east and north edges.
            ([20, 70], [5, 2], [19, 69], [6, 3]),
        ];
        for (origin, size, lo, ext) in cases {
            assert_eq!(gpu_normal_rect(origin, size, &region), (lo, ext));
            let jobs = gpu_normal_jobs(3, origin, size, cache, side);
            let mut seen = std::collections::HashSet::new();
            for j in &jobs {
                assert_eq!(j.level, 3);
                assert_eq!(j.region, region);
                for a in 0..2 {
                    assert!(j.texel[a] + j.size[a] <= side, "{j:?} wraps");
                    let t = j.sample[a].rem_euclid(side as i64);
                    assert_eq!(t, j.texel[a] as i64, "{j:?}: texel = sample mod side");
                }
                for y in 0..j.size[1] as i64 {
                    for x in 0..j.size[0] as i64 {
                        let s = [j.sample[0] + x, j.sample[1] + y];
                        assert!((0..2).all(|a| s[a] >= region.lo[a] && s[a] <= region.hi[a]));
                        assert!(seen.insert(s), "{s:?} twice");
                    }
                }
            }
            assert_eq!(seen.len() as u32, ext[0] * ext[1], "{origin:?}");
        }
    }
}
