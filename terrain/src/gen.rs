//! Deterministic synthetic terrains for scale and stress tests (`aerie gen-dem`).
//!
//! Every sample is a pure function of (kind, seed, spacing, col, row): lattice value noise
//! from an integer hash, combined with `+ − × ÷`, `floor` and `abs` only (no `sin`/`exp`, whose
//! last bit may differ between C libraries). The same arguments give the same bytes on any
//! machine and any number of threads.
//!
//! Kinds (heights in metres, row 0 = south):
//! - `ridged`: ridged-noise mountains (Σ amp·(1 − |noise|)²), ≈ 0 .. 3000 m, wavelengths from
//!   24 km down to about two samples.
//! - `cliffs`: a smooth landscape cut into terraces: every [`CLIFF_STEP`] metres of the
//!   underlying surface there is a vertical wall of `0.85 · CLIFF_STEP` (170 m) between two
//!   adjacent samples — the worst case for a linear-interpolation error bound.
//! - `spikes`: gentle hills (< 400 m) with isolated single-sample needles 300 .. 1500 m tall:
//!   at most one per 16 × 16 block, never on the block's border, so no two needles touch.
//! - `flat`: every sample at [`FLAT_HEIGHT`] (100 m).
//! - `mixed`: quadrants — south-west ridged, south-east cliffs, north-west spikes, north-east
//!   flat — so one dataset holds every case (with walls where the quadrants meet).

use super::Heightfield;

/// Terrace height of `cliffs`, metres.
pub const CLIFF_STEP: f64 = 200.0;
/// Share of a terrace that is slope (the rest is the wall).
const CLIFF_SLOPE: f64 = 0.15;
/// Height of `flat`, metres.
pub const FLAT_HEIGHT: f32 = 100.0;
/// Block side of `spikes` (one needle at most per block).
pub const SPIKE_BLOCK: usize = 16;
/// A needle rises at least this far above the hills around it, metres.
pub const SPIKE_MIN: f64 = 300.0;

/// What to generate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DemKind {
    Ridged,
    Cliffs,
    Spikes,
    Flat,
    Mixed,
}

impl DemKind {
    pub const ALL: [DemKind; 5] = [
        DemKind::Ridged,
        DemKind::Cliffs,
        DemKind::Spikes,
        DemKind::Flat,
        DemKind::Mixed,
    ];

    pub fn name(self) -> &'static str {
        match self {
            DemKind::Ridged => "ridged",
            DemKind::Cliffs => "cliffs",
            DemKind::Spikes => "spikes",
            DemKind::Flat => "flat",
            DemKind::Mixed => "mixed",
        }
    }

    pub fn parse(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == s)
    }
}

/// A generated terrain's description.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GenParams {
    /// Samples per side (the grid is square).
    pub size: usize,
    /// Metres between samples, both axes.
    pub spacing: f64,
    pub kind: DemKind,
    pub seed: u64,
}

#[inline]
fn mix(mut z: u64) -> u64 {
    // splitmix64 finaliser.
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[inline]
fn hash2(x: i64, y: i64, seed: u64) -> u64 {
    mix(seed ^ mix((x as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ (y as u64).rotate_left(32)))
}

/// Uniform in [−1, 1].
#[inline]
fn lattice(x: i64, y: i64, seed: u64) -> f64 {
    (hash2(x, y, seed) >> 11) as f64 * (2.0 / (1u64 << 53) as f64) - 1.0
}

#[inline(always)]
fn smooth(t: f64) -> f64 {
    t * t * (3.0 - 2.0 * t)
}

/// Value noise in [−1, 1] at (x, y) ≥ 0 lattice units, smoothstep-interpolated.
/// (Truncation is the floor for non-negative coordinates, and needs no libm call.)
#[inline]
fn value_noise(x: f64, y: f64, seed: u64) -> f64 {
    debug_assert!(x >= 0.0 && y >= 0.0);
    let (ix, iy) = (x as i64, y as i64);
    let (fx, fy) = (x - ix as f64, y - iy as f64);
    let (sx, sy) = (smooth(fx), smooth(fy));
    let a = lattice(ix, iy, seed);
    let b = lattice(ix + 1, iy, seed);
    let c = lattice(ix, iy + 1, seed);
    let d = lattice(ix + 1, iy + 1, seed);
    let ab = a + (b - a) * sx;
    let cd = c + (d - c) * sx;
    ab + (cd - ab) * sy
}

/// [`value_noise`] along part of one row (fixed y, `x_min ≤ x ≤ x_max`): the lattice values of
/// the row's two lattice lines are hashed once up front, so a sample costs two lerps and no
/// hashing or branching. Same arithmetic as `value_noise`, same results.
struct RowNoise {
    f: f64,
    sy: f64,
    ix0: i64,
    l0: Vec<f64>,
    l1: Vec<f64>,
}

impl RowNoise {
    fn new(f: f64, y: f64, seed: u64, x_min: f64, x_max: f64) -> Self {
        let yf = y * f;
        let iy = yf as i64;
        let ix0 = (x_min * f) as i64;
        let ix1 = (x_max * f) as i64 + 1;
        RowNoise {
            f,
            sy: smooth(yf - iy as f64),
            ix0,
            l0: (ix0..=ix1).map(|ix| lattice(ix, iy, seed)).collect(),
            l1: (ix0..=ix1).map(|ix| lattice(ix, iy + 1, seed)).collect(),
        }
    }

    #[inline(always)]
    fn at(&self, x: f64) -> f64 {
        let xf = x * self.f;
        let ix = xf as i64;
        let sx = smooth(xf - ix as f64);
        let k = (ix - self.ix0) as usize;
        let (l0, l1) = (&self.l0[k..], &self.l1[k..]);
        let (a, b, c, d) = (l0[0], l0[1], l1[0], l1[1]);
        let ab = a + (b - a) * sx;
        let cd = c + (d - c) * sx;
        ab + (cd - ab) * self.sy
    }
}

/// Octave seeds and frequencies, shared by the per-sample and per-row forms.
fn octave(wavelength: f64, o: u32, seed: u64, stride: u64) -> (f64, u64) {
    let mut f = 1.0 / wavelength;
    for _ in 0..o {
        f *= 2.0;
    }
    (f, seed.wrapping_add(u64::from(o) * stride))
}

const FBM_STRIDE: u64 = 0x1000_0001;
const RIDGE_STRIDE: u64 = 0x2000_0003;
const RIDGE_WAVELENGTH: f64 = 24_000.0;
const RIDGE_BASE_WAVELENGTH: f64 = 60_000.0;

/// Fractal sum of `octaves` value-noise octaves starting at `wavelength` metres, in ≈ [−1, 1].
fn fbm(x: f64, y: f64, wavelength: f64, octaves: u32, seed: u64) -> f64 {
    let (mut amp, mut sum, mut norm) = (1.0, 0.0, 0.0);
    for o in 0..octaves {
        let (f, s) = octave(wavelength, o, seed, FBM_STRIDE);
        sum += amp * value_noise(x * f, y * f, s);
        norm += amp;
        amp *= 0.5;
    }
    sum / norm
}

/// [`fbm`] along a row.
struct RowFbm {
    octaves: Vec<RowNoise>,
}

impl RowFbm {
    fn new(y: f64, wavelength: f64, octaves: u32, seed: u64, xs: (f64, f64)) -> Self {
        RowFbm {
            octaves: (0..octaves)
                .map(|o| {
                    let (f, s) = octave(wavelength, o, seed, FBM_STRIDE);
                    RowNoise::new(f, y, s, xs.0, xs.1)
                })
                .collect(),
        }
    }

    #[inline(always)]
    fn at(&self, x: f64) -> f64 {
        let (mut amp, mut sum, mut norm) = (1.0, 0.0, 0.0);
        for n in &self.octaves {
            sum += amp * n.at(x);
            norm += amp;
            amp *= 0.5;
        }
        sum / norm
    }
}

/// Octaves from `wavelength` down to about two samples.
fn octaves_for(wavelength: f64, spacing: f64) -> u32 {
    let mut n = 1;
    let mut w = wavelength;
    while w / 2.0 >= 2.0 * spacing && n < 16 {
        w /= 2.0;
        n += 1;
    }
    n
}

/// Ridged noise from per-octave noise values `n(o)`: Σ amp·(1 − |n|)², amplitude halving per
/// octave (two partial sums, so the octaves do not form one long dependency chain).
#[inline(always)]
fn ridged_sum(octaves: u32, mut n: impl FnMut(u32) -> f64, base: f64) -> f64 {
    let (mut amp, mut even, mut odd) = (1.0, 0.0f64, 0.0f64);
    for o in 0..octaves {
        let r = 1.0 - n(o).abs();
        if o & 1 == 0 {
            even += amp * (r * r);
        } else {
            odd += amp * (r * r);
        }
        amp *= 0.5;
    }
    // The sum is < 2; a broad base so valleys are not all at sea level.
    300.0 * (0.5 + 0.5 * base) + 1300.0 * (even + odd)
}

fn ridged(x: f64, y: f64, spacing: f64, seed: u64) -> f64 {
    let octaves = octaves_for(RIDGE_WAVELENGTH, spacing);
    let f = 1.0 / RIDGE_BASE_WAVELENGTH;
    let base = value_noise(x * f, y * f, seed ^ 0x55);
    ridged_sum(
        octaves,
        |o| {
            let (f, s) = octave(RIDGE_WAVELENGTH, o, seed, RIDGE_STRIDE);
            value_noise(x * f, y * f, s)
        },
        base,
    )
}

#[inline]
fn terraces(b: f64, detail: f64) -> f64 {
    let b = (0.5 + 0.5 * b) * 2400.0;
    let k = (b / CLIFF_STEP) as i64 as f64; // b ≥ 0: truncation is the floor
    k * CLIFF_STEP + CLIFF_SLOPE * (b - k * CLIFF_STEP) + 4.0 * detail
}

const CLIFF_WAVELENGTH: f64 = 6_000.0;
const CLIFF_DETAIL: f64 = 400.0;
const HILL_WAVELENGTH: f64 = 8_000.0;

fn cliffs(x: f64, y: f64, spacing: f64, seed: u64) -> f64 {
    terraces(
        fbm(x, y, CLIFF_WAVELENGTH, 4, seed ^ 0xc1),
        fbm(
            x,
            y,
            CLIFF_DETAIL,
            octaves_for(CLIFF_DETAIL, spacing),
            seed ^ 0xd7,
        ),
    )
}

/// Height added at (col, row) by a needle, if one stands there.
#[inline]
fn needle(col: usize, row: usize, seed: u64) -> f64 {
    let (bx, by) = (col / SPIKE_BLOCK, row / SPIKE_BLOCK);
    let h = hash2(bx as i64, by as i64, seed ^ 0x5eed);
    if h & 1 == 1 {
        let inner = (SPIKE_BLOCK - 2) as u64;
        let px = bx * SPIKE_BLOCK + 1 + ((h >> 8) % inner) as usize;
        let py = by * SPIKE_BLOCK + 1 + ((h >> 24) % inner) as usize;
        if (col, row) == (px, py) {
            return SPIKE_MIN + ((h >> 40) % 1201) as f64;
        }
    }
    0.0
}

#[inline]
fn hills(n: f64) -> f64 {
    200.0 + 150.0 * n
}

fn spikes(col: usize, row: usize, x: f64, y: f64, seed: u64) -> f64 {
    hills(fbm(x, y, HILL_WAVELENGTH, 3, seed ^ 0x5b)) + needle(col, row, seed)
}

fn kind_at(p: &GenParams, col: usize, row: usize) -> DemKind {
    match p.kind {
        DemKind::Mixed => {
            let half = p.size / 2;
            match (col >= half, row >= half) {
                (false, false) => DemKind::Ridged,
                (true, false) => DemKind::Cliffs,
                (false, true) => DemKind::Spikes,
                (true, true) => DemKind::Flat,
            }
        }
        k => k,
    }
}

/// Height of sample (col, row) of the terrain `p` describes, metres. The reference form;
/// [`generate_into`] computes the same values row by row.
pub fn sample(p: &GenParams, col: usize, row: usize) -> f32 {
    let (x, y) = (col as f64 * p.spacing, row as f64 * p.spacing);
    let seed = mix(p.seed ^ 0xae41e);
    let h = match kind_at(p, col, row) {
        DemKind::Ridged => ridged(x, y, p.spacing, seed),
        DemKind::Cliffs => cliffs(x, y, p.spacing, seed),
        DemKind::Spikes => spikes(col, row, x, y, seed),
        DemKind::Flat | DemKind::Mixed => f64::from(FLAT_HEIGHT),
    };
    h as f32
}

/// The per-row noise tables one kind needs.
enum RowKind {
    Ridged {
        octaves: Vec<RowNoise>,
        base: RowNoise,
    },
    Cliffs {
        terrain: RowFbm,
        detail: RowFbm,
    },
    Spikes {
        hills: RowFbm,
    },
    Flat,
}

impl RowKind {
    /// Tables for columns `cols` (non-empty) of the row at `y`.
    fn new(kind: DemKind, p: &GenParams, y: f64, seed: u64, cols: &std::ops::Range<usize>) -> Self {
        let xs = (
            cols.start as f64 * p.spacing,
            (cols.end - 1) as f64 * p.spacing,
        );
        match kind {
            DemKind::Ridged => RowKind::Ridged {
                octaves: (0..octaves_for(RIDGE_WAVELENGTH, p.spacing))
                    .map(|o| {
                        let (f, s) = octave(RIDGE_WAVELENGTH, o, seed, RIDGE_STRIDE);
                        RowNoise::new(f, y, s, xs.0, xs.1)
                    })
                    .collect(),
                base: RowNoise::new(1.0 / RIDGE_BASE_WAVELENGTH, y, seed ^ 0x55, xs.0, xs.1),
            },
            DemKind::Cliffs => RowKind::Cliffs {
                terrain: RowFbm::new(y, CLIFF_WAVELENGTH, 4, seed ^ 0xc1, xs),
                detail: RowFbm::new(
                    y,
                    CLIFF_DETAIL,
                    octaves_for(CLIFF_DETAIL, p.spacing),
                    seed ^ 0xd7,
                    xs,
                ),
            },
            DemKind::Spikes => RowKind::Spikes {
                hills: RowFbm::new(y, HILL_WAVELENGTH, 3, seed ^ 0x5b, xs),
            },
            DemKind::Flat | DemKind::Mixed => RowKind::Flat,
        }
    }

    /// Samples `cols` of row `row` into `out` (same length).
    fn fill(
        &self,
        p: &GenParams,
        row: usize,
        cols: std::ops::Range<usize>,
        out: &mut [f32],
        seed: u64,
    ) {
        for (col, o) in cols.zip(out.iter_mut()) {
            let x = col as f64 * p.spacing;
            let h = match self {
                RowKind::Ridged { octaves, base } => ridged_sum(
                    octaves.len() as u32,
                    |o| octaves[o as usize].at(x),
                    base.at(x),
                ),
                RowKind::Cliffs { terrain, detail } => terraces(terrain.at(x), detail.at(x)),
                RowKind::Spikes { hills: h } => hills(h.at(x)) + needle(col, row, seed),
                RowKind::Flat => f64::from(FLAT_HEIGHT),
            };
            *o = h as f32;
        }
    }
}

/// One row, with per-row noise tables for the kinds it holds.
fn fill_row(p: &GenParams, row: usize, out: &mut [f32]) {
    let y = row as f64 * p.spacing;
    let seed = mix(p.seed ^ 0xae41e);
    let half = p.size / 2;
    // Runs of columns of one kind: the whole row, or the two quadrants of `mixed`.
    let runs = if p.kind == DemKind::Mixed {
        [0..half, half..p.size]
    } else {
        [0..p.size, p.size..p.size]
    };
    for cols in runs {
        if cols.is_empty() {
            continue;
        }
        let kind = kind_at(p, cols.start, row);
        let rk = RowKind::new(kind, p, y, seed, &cols);
        let start = cols.start;
        rk.fill(p, row, cols.clone(), &mut out[start..cols.end], seed);
    }
}

/// Fills `out` (whole rows, `out.len() / p.size` of them) with rows `row0..`, on all cores.
/// `progress(rows_done)` is called from the calling thread.
pub fn generate_into(p: &GenParams, row0: usize, out: &mut [f32], progress: &dyn Fn(u64)) {
    let n = p.size;
    assert!(n >= 2 && out.len().is_multiple_of(n));
    let rows = out.len() / n;
    const CHUNK: usize = 16;
    let chunks: Vec<(usize, &mut [f32])> = out.chunks_mut(CHUNK * n).enumerate().collect();
    let total = chunks.len();
    let queue = std::sync::Mutex::new(chunks.into_iter());
    let done = std::sync::atomic::AtomicU64::new(0);
    let finished = std::sync::atomic::AtomicUsize::new(0);
    let threads = std::thread::available_parallelism()
        .map(|t| t.get())
        .unwrap_or(1)
        .clamp(1, total.max(1));
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| {
                loop {
                    let next = queue.lock().unwrap_or_else(|e| e.into_inner()).next();
                    let Some((k, chunk)) = next else { break };
                    for (i, r) in chunk.chunks_exact_mut(n).enumerate() {
                        fill_row(p, row0 + k * CHUNK + i, r);
                    }
                    done.fetch_add(
                        (chunk.len() / n) as u64,
                        std::sync::atomic::Ordering::Relaxed,
                    );
                }
                finished.fetch_add(1, std::sync::atomic::Ordering::Release);
            });
        }
        while finished.load(std::sync::atomic::Ordering::Acquire) < threads {
            std::thread::sleep(std::time::Duration::from_millis(50));
            progress(done.load(std::sync::atomic::Ordering::Relaxed));
        }
    });
    progress(rows as u64);
}

/// A whole generated terrain in memory (tests, small sizes).
pub fn generate(p: &GenParams) -> Heightfield {
    let mut heights = vec![0f32; p.size * p.size];
    generate_into(p, 0, &mut heights, &|_| {});
    Heightfield {
        width: p.size,
        height: p.size,
        spacing_x: p.spacing,
        spacing_y: p.spacing,
        heights,
        geo: None,
        voids_filled: 0,
        spacing_note: format!(
            "generated {} terrain (seed {}): {} m E-W, {} m N-S",
            p.kind.name(),
            p.seed,
            p.spacing,
            p.spacing
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(kind: DemKind, seed: u64) -> GenParams {
        GenParams {
            size: 129,
            spacing: 10.0,
            kind,
            seed,
        }
    }

    #[test]
    fn same_seed_same_samples_other_seed_other_samples() {
        for kind in [
            DemKind::Ridged,
            DemKind::Cliffs,
            DemKind::Spikes,
            DemKind::Mixed,
        ] {
            let a = generate(&p(kind, 7));
            let b = generate(&p(kind, 7));
            let c = generate(&p(kind, 8));
            assert_eq!(a.heights, b.heights, "{kind:?}");
            assert_ne!(a.heights, c.heights, "{kind:?}");
            assert!(a.heights.iter().all(|h| h.is_finite()));
        }
    }

    #[test]
    fn rows_equal_the_per_sample_reference() {
        for kind in DemKind::ALL {
            for spacing in [10.0, 3.7] {
                let q = GenParams {
                    size: 300,
                    spacing,
                    kind,
                    seed: 11,
                };
                let hf = generate(&q);
                for row in [0, 1, 17, 150, 299] {
                    for col in 0..300 {
                        assert_eq!(
                            hf.at(col, row).to_bits(),
                            sample(&q, col, row).to_bits(),
                            "{kind:?} ({col},{row})"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn noise_is_bounded() {
        for i in 0..10_000 {
            let v = value_noise(i as f64 * 0.37, i as f64 * 0.11, 3);
            assert!((-1.0..=1.0).contains(&v));
        }
    }
}
