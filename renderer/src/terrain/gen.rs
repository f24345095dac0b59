//! Deterministic synthetic terrains for scale and stress tests (`aerie gen-dem`).
//!
//! Every sample is a pure function of (kind, seed, spacing, col, row): lattice value noise
//! from an integer hash, combined with `+ − × ÷`, `floor` and `abs` only (no `sin`/`exp`, whose
//! last bit may differ between C libraries). The same arguments give the same bytes on any
//! machine and any number of threads.
//!
//! Kinds (heights in metres, row 0 = south):
//! - `ridged`: ridged multifractal mountains, ≈ 0 .. 3000 m, wavelengths 24 km down to 2 samples.
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

/// Value noise in [−1, 1] at (x, y) lattice units, smoothstep-interpolated.
#[inline]
fn value_noise(x: f64, y: f64, seed: u64) -> f64 {
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let (ix, iy) = (x0 as i64, y0 as i64);
    let sx = fx * fx * (3.0 - 2.0 * fx);
    let sy = fy * fy * (3.0 - 2.0 * fy);
    let a = lattice(ix, iy, seed);
    let b = lattice(ix + 1, iy, seed);
    let c = lattice(ix, iy + 1, seed);
    let d = lattice(ix + 1, iy + 1, seed);
    let ab = a + (b - a) * sx;
    let cd = c + (d - c) * sx;
    ab + (cd - ab) * sy
}

/// Fractal sum of `octaves` value-noise octaves starting at `wavelength` metres, in ≈ [−1, 1].
fn fbm(x: f64, y: f64, wavelength: f64, octaves: u32, seed: u64) -> f64 {
    let (mut f, mut amp, mut sum, mut norm) = (1.0 / wavelength, 1.0, 0.0, 0.0);
    for o in 0..octaves {
        sum += amp * value_noise(x * f, y * f, seed.wrapping_add(u64::from(o) * 0x1000_0001));
        norm += amp;
        amp *= 0.5;
        f *= 2.0;
    }
    sum / norm
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

fn ridged(x: f64, y: f64, spacing: f64, seed: u64) -> f64 {
    const WAVELENGTH: f64 = 24_000.0;
    let octaves = octaves_for(WAVELENGTH, spacing);
    let (mut f, mut amp, mut sum, mut weight) = (1.0 / WAVELENGTH, 1.0, 0.0, 1.0);
    for o in 0..octaves {
        let n = value_noise(x * f, y * f, seed.wrapping_add(u64::from(o) * 0x2000_0003));
        let r = 1.0 - n.abs();
        let r = r * r * weight;
        weight = (r * 2.0).clamp(0.0, 1.0);
        sum += r * amp;
        amp *= 0.5;
        f *= 2.0;
    }
    // sum ≤ 2; a broad base so valleys are not all at sea level.
    let base = 0.5 + 0.5 * value_noise(x / 60_000.0, y / 60_000.0, seed ^ 0x55);
    300.0 * base + 1300.0 * sum
}

fn cliffs(x: f64, y: f64, spacing: f64, seed: u64) -> f64 {
    let b = 0.5 + 0.5 * fbm(x, y, 6_000.0, 4, seed ^ 0xc1); // 0..1, smooth
    let b = b * 2400.0;
    let k = (b / CLIFF_STEP).floor();
    let terrace = k * CLIFF_STEP + CLIFF_SLOPE * (b - k * CLIFF_STEP);
    let detail = 4.0 * fbm(x, y, 400.0, octaves_for(400.0, spacing), seed ^ 0xd7);
    terrace + detail
}

fn spikes(col: usize, row: usize, x: f64, y: f64, seed: u64) -> f64 {
    let hills = 200.0 + 150.0 * fbm(x, y, 8_000.0, 3, seed ^ 0x5b);
    let (bx, by) = (col / SPIKE_BLOCK, row / SPIKE_BLOCK);
    let h = hash2(bx as i64, by as i64, seed ^ 0x5eed);
    if h & 1 == 1 {
        let inner = (SPIKE_BLOCK - 2) as u64;
        let px = bx * SPIKE_BLOCK + 1 + ((h >> 8) % inner) as usize;
        let py = by * SPIKE_BLOCK + 1 + ((h >> 24) % inner) as usize;
        if (col, row) == (px, py) {
            let tall = SPIKE_MIN + ((h >> 40) % 1201) as f64;
            return hills + tall;
        }
    }
    hills
}

/// Height of sample (col, row) of the terrain `p` describes, metres.
pub fn sample(p: &GenParams, col: usize, row: usize) -> f32 {
    let (x, y) = (col as f64 * p.spacing, row as f64 * p.spacing);
    let seed = mix(p.seed ^ 0xae41e);
    let kind = match p.kind {
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
    };
    let h = match kind {
        DemKind::Ridged => ridged(x, y, p.spacing, seed),
        DemKind::Cliffs => cliffs(x, y, p.spacing, seed),
        DemKind::Spikes => spikes(col, row, x, y, seed),
        DemKind::Flat | DemKind::Mixed => f64::from(FLAT_HEIGHT),
    };
    h as f32
}

/// Fills `out` (whole rows, `out.len() / p.size` of them) with rows `row0..`, on all cores.
/// `progress(rows_done)` is called from the calling thread.
pub fn generate_into(p: &GenParams, row0: usize, out: &mut [f32], progress: &dyn Fn(u64)) {
    let n = p.size;
    assert!(n >= 2 && out.len() % n == 0);
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
                    for (i, v) in chunk.iter_mut().enumerate() {
                        *v = sample(p, i % n, row0 + k * CHUNK + i / n);
                    }
                    done.fetch_add((chunk.len() / n) as u64, std::sync::atomic::Ordering::Relaxed);
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
        for kind in [DemKind::Ridged, DemKind::Cliffs, DemKind::Spikes, DemKind::Mixed] {
            let a = generate(&p(kind, 7));
            let b = generate(&p(kind, 7));
            let c = generate(&p(kind, 8));
            assert_eq!(a.heights, b.heights, "{kind:?}");
            assert_ne!(a.heights, c.heights, "{kind:?}");
            assert!(a.heights.iter().all(|h| h.is_finite()));
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
