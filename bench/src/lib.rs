//! Shared set-up of aerie's criterion micro-benchmarks (`benches/`): generated datasets, their
//! bakes, clipmap descriptions and a flight of cameras. Run with `make bench` (or
//! `cargo bench -p aerie-bench`); `AERIE_BENCH_SIZE` sets the side of the selection dataset
//! (default 16385, the DESIGN.md target size: 1.07 GB generated and baked once, in memory).

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::terrain::bake::{bake, BakeParams, ErrorBake};
use aerie::terrain::clipmap::ClipmapDesc;
use aerie::terrain::dataset::Dataset;
use aerie::terrain::gen::{generate, DemKind, GenParams};
use glam::DVec3;

/// Vertices per tile side (the renderer's default m).
pub const TILE_SIZE: u32 = 17;

/// Side of the dataset the selection benchmark uses: `AERIE_BENCH_SIZE` or 16385.
pub fn selection_size() -> usize {
    std::env::var("AERIE_BENCH_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .filter(|&n: &usize| n >= 257)
        .unwrap_or(16385)
}

/// A generated `size`² terrain (deterministic) at 10 m spacing.
pub fn generated(size: usize, kind: DemKind) -> Dataset {
    let hf = generate(&GenParams {
        size,
        spacing: 10.0,
        kind,
        seed: 2026,
    });
    Dataset::from_heightfield(hf, format!("generated {} {size}²", kind.name()))
}

/// Every level's error bake (m = 17).
pub fn baked(ds: &Dataset) -> ErrorBake {
    bake(
        ds,
        BakeParams {
            tile_size: TILE_SIZE,
            levels: 0,
        },
        &|_, _| {},
    )
}

/// The renderer's default clipmap (n = 129, margin 2 tiles) over `width × height` samples.
pub fn clipmap_desc(width: usize, height: usize) -> ClipmapDesc {
    ClipmapDesc {
        tile_quads: TILE_SIZE - 1,
        patch_tiles: 8,
        margin_tiles: 2,
        width: width as u32,
        height: height as u32,
    }
}

/// `n` cameras of a 340 m/s pass at 30 fps across the middle of a `side_m`-wide square,
/// 600 m up, pitched 12° down, 90° FOV on `w × h`.
pub fn flight(side_m: f64, n: usize, w: u32, h: u32) -> Vec<Camera> {
    let frustum = Frustum::symmetric(90f64.to_radians(), w, h);
    let heading = 70f64.to_radians();
    let dir = DVec3::new(heading.sin(), heading.cos(), 0.0);
    let start = DVec3::new(side_m / 2.0, side_m / 2.0, 3_600.0) - dir * (n as f64 * 340.0 / 60.0);
    (0..n)
        .map(|k| {
            Camera::new(
                start + dir * (k as f64 * 340.0 / 30.0),
                Attitude::from_degrees(70.0, -12.0, 0.0),
                frustum,
            )
        })
        .collect()
}
