//! The fine part of the max-height hierarchy: maxima of blocks of quads inside one level-0
//! tile, below what the bake stores.
//!
//! A level-0 tile of `q = 2^j` quads per side holds, for every block level `k = 1 ..= j − 1`,
//! `(q >> k)²` blocks of `2^k × 2^k` quads; a block's maximum is the largest of its
//! `(2^k + 1)²` samples (edges included, as the bake counts them). Single quads (`k = 0`) are
//! not stored: their four corners are read directly. The tile itself (`k = j`) is the bake's
//! level-0 entry, and coarser nodes are the bake's coarser levels.
//!
//! **Storage**: one byte per block, quantised **upwards** against the tile's own bake bounds:
//! `bound(c) = min + c · (max − min) / 255` for `c < 255`, and `bound(255) = max` exactly, with
//! `c` the smallest code whose bound is ≥ the block's true maximum. So a decoded bound is never
//! below the truth (a ray skipped by it really passes above the block) and overestimates it by
//! at most `(max − min) / 255`. Per tile that is `Σ (q >> k)²` bytes, about `q² / 3`: 84 bytes
//! for the default `m = 17`, i.e. 0.33 byte per sample — 84 MiB on a 16385² grid, against
//! 1 GiB of f32 heights (f32 blocks would need 4×, 336 MiB).
//!
//! Layout of one tile's bytes: level `k = 1` first, then `k = 2`, …; inside a level, row-major
//! by block (`bj · (q >> k) + bi`, row 0 = south).

/// Bytes of the fine hierarchy of one tile of `q` quads per side (`q` a power of two ≥ 2).
pub fn fine_len(q: usize) -> usize {
    (1..q.trailing_zeros()).map(|k| (q >> k) * (q >> k)).sum()
}

/// Offset of block level `k` (1 ≤ k < j) in one tile's bytes.
#[inline]
pub fn level_offset(q: usize, k: u32) -> usize {
    (1..k).map(|l| (q >> l) * (q >> l)).sum()
}

/// The height bound a code stands for, given the tile's bake bounds; see the module
/// documentation. Build and query both go through this one function, so the guarantee checked
/// when building holds when querying.
#[inline]
pub fn decode(min: f32, max: f32, code: u8) -> f64 {
    if code == u8::MAX {
        f64::from(max)
    } else {
        let (lo, hi) = (f64::from(min), f64::from(max));
        lo + f64::from(code) * ((hi - lo) / 255.0)
    }
}

/// Smallest code whose bound is ≥ `block_max` (which must be ≤ `max`).
fn encode(min: f32, max: f32, block_max: f32) -> u8 {
    let (lo, hi, b) = (f64::from(min), f64::from(max), f64::from(block_max));
    if hi <= lo {
        return u8::MAX;
    }
    let mut c = (((b - lo) / ((hi - lo) / 255.0)).ceil()).clamp(0.0, 255.0) as u8;
    // The division and the product in `decode` may each round; step until the bound holds.
    while c > 0 && decode(min, max, c - 1) >= b {
        c -= 1;
    }
    while c < u8::MAX && decode(min, max, c) < b {
        c += 1;
    }
    c
}

/// Builds one tile's fine hierarchy into `out` (`fine_len(q)` bytes) from its `(q+1)²`
/// samples (`samples[j · stride + i]`, i east, j north) and returns the largest sample, which
/// the caller compares with the bake's `max` (the codes are only conservative when the bake's
/// bounds are the tile's). `min`, `max`: the tile's bake bounds.
pub fn build_tile(
    q: usize,
    samples: &[f32],
    stride: usize,
    min: f32,
    max: f32,
    out: &mut [u8],
) -> f32 {
    debug_assert!(q.is_power_of_two() && q >= 2);
    debug_assert_eq!(out.len(), fine_len(q));
    let j = q.trailing_zeros();
    let n1 = q / 2;
    // Level 1 from the samples: per sample row, the max of each 3-sample run (2i ..= 2i+2),
    // then per block the max of three such rows.
    let mut run = vec![f32::NEG_INFINITY; n1 * (q + 1)];
    for r in 0..=q {
        let row = &samples[r * stride..r * stride + q + 1];
        for (bi, m) in run[r * n1..(r + 1) * n1].iter_mut().enumerate() {
            *m = row[2 * bi].max(row[2 * bi + 1]).max(row[2 * bi + 2]);
        }
    }
    let mut cur = vec![f32::NEG_INFINITY; n1 * n1];
    for bj in 0..n1 {
        for bi in 0..n1 {
            cur[bj * n1 + bi] = (0..3)
                .map(|d| run[(2 * bj + d) * n1 + bi])
                .fold(f32::NEG_INFINITY, f32::max);
        }
    }
    let mut n = n1;
    for k in 1..j {
        let off = level_offset(q, k);
        for (o, &b) in out[off..off + n * n].iter_mut().zip(&cur) {
            *o = encode(min, max, b);
        }
        // The next level: a block is exactly its 2×2 children (edges shared).
        let m = n / 2;
        let next: Vec<f32> = (0..m * m)
            .map(|i| {
                let (bi, bj) = (i % m, i / m);
                let c = |di: usize, dj: usize| cur[(2 * bj + dj) * n + 2 * bi + di];
                c(0, 0).max(c(1, 0)).max(c(0, 1)).max(c(1, 1))
            })
            .collect();
        cur = next;
        n = m;
    }
    cur.into_iter().fold(f32::NEG_INFINITY, f32::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_offsets() {
        assert_eq!(fine_len(2), 0);
        assert_eq!(fine_len(4), 4);
        assert_eq!(fine_len(16), 64 + 16 + 4);
        assert_eq!(
            fine_len(256),
            (1..8).map(|k| (256usize >> k).pow(2)).sum::<usize>()
        );
        assert_eq!(level_offset(16, 1), 0);
        assert_eq!(level_offset(16, 2), 64);
        assert_eq!(level_offset(16, 3), 80);
    }

    #[test]
    fn codes_never_fall_below_the_block_and_are_tight() {
        for (min, max) in [
            (0.0f32, 1.0f32),
            (473.0, 3461.0),
            (-12.5, 8848.86),
            (5.0, 5.0),
        ] {
            for i in 0..=1000 {
                let b = min + (max - min) * (i as f32 / 1000.0);
                let c = encode(min, max, b);
                let bound = decode(min, max, c);
                assert!(bound >= f64::from(b), "{min}..{max}: {b} → {c} → {bound}");
                if c > 0 && max > min {
                    assert!(
                        decode(min, max, c - 1) < f64::from(b),
                        "code {c} is not the smallest"
                    );
                }
                assert!(bound - f64::from(b) <= f64::from(max - min) / 255.0 + 1e-9);
            }
        }
    }

    #[test]
    fn blocks_hold_the_max_of_their_samples_edges_included() {
        let q = 8usize;
        let stride = 11; // wider than the tile: the builder must use the stride
        let h = |i: usize, j: usize| ((i * 7 + j * 13) % 17) as f32 * 10.0;
        let mut s = vec![0f32; stride * (q + 1)];
        for j in 0..=q {
            for i in 0..=q {
                s[j * stride + i] = h(i, j);
            }
        }
        // A spike on a shared block corner must show in all four blocks around it.
        s[4 * stride + 4] = 1000.0;
        let (min, max) = (0.0, 1000.0);
        let mut out = vec![0u8; fine_len(q)];
        let top = build_tile(q, &s, stride, min, max, &mut out);
        assert_eq!(top, 1000.0);
        for k in 1..3u32 {
            let n = q >> k;
            let side = 1usize << k;
            for bj in 0..n {
                for bi in 0..n {
                    let mut want = f32::NEG_INFINITY;
                    for j in bj * side..=(bj + 1) * side {
                        for i in bi * side..=(bi + 1) * side {
                            want = want.max(s[j * stride + i]);
                        }
                    }
                    let c = out[level_offset(q, k) + bj * n + bi];
                    let got = decode(min, max, c);
                    assert!(got >= f64::from(want), "k {k} block ({bi},{bj})");
                    assert!(got - f64::from(want) <= 1000.0 / 255.0 + 1e-9);
                }
            }
        }
    }
}
