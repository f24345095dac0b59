//! The ridge country of the normal-map tests (`normal_maps.rs`, `gpu_normals.rs`): long ridges
//! carrying gullies 18–23 samples across, which level 0 resolves, the coarse levels' point
//! samples alias and their footprint means keep; 1024² samples of 30 m.

use aerie::terrain::Heightfield;

use crate::synthetic;

/// Metres between samples.
pub const SPACING: f64 = 30.0;
/// Samples per side.
pub const N: usize = 1024;

/// The height of sample (c, r), metres.
pub fn height(c: usize, r: usize) -> f32 {
    let (x, y) = (c as f64, r as f64);
    (800.0
        + 400.0 * (x / 80.0).sin() * (y / 110.0).cos()
        + 60.0 * (x / 2.9).sin() * (y / 3.7).sin()) as f32
}

pub fn ridges() -> Heightfield {
    let mut hf = synthetic(N, N, SPACING, 0.0, &[]);
    for r in 0..N {
        for c in 0..N {
            hf.heights[r * N + c] = height(c, r);
        }
    }
    hf
}
