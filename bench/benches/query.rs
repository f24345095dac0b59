//! Host queries on the full-resolution surface: height of terrain and 10 km lines of sight,
//! on the embedded DEM (N47E011) and on a generated dataset (`AERIE_BENCH_SIZE`, default
//! 16385²). Issue 12's budgets: ≥ 100 HOT per 0.2 ms, ≥ 100 LOS of 10 km per 1 ms; each
//! iteration here is one batch of 100 queries, so compare with 200 µs and 1 ms.

use std::hint::black_box;
use std::path::PathBuf;
use std::sync::Arc;

use aerie::terrain::dataset::{load_dataset, Dataset};
use aerie::terrain::gen::DemKind;
use aerie::terrain::query::{first_hit, height_of_terrain, InMemorySource, Ray, SurfaceSource};
use aerie_bench::{baked, generated, selection_size};
use criterion::{criterion_group, criterion_main, Criterion};
use glam::DVec3;

/// A small deterministic generator (xorshift64*), uniform in [lo, hi).
struct Rng(u64);

impl Rng {
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        let u = (x.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * u
    }
}

fn source(ds: Dataset) -> InMemorySource {
    let bake = baked(&ds);
    InMemorySource::new(Arc::new(ds), Arc::new(bake)).expect("the bake of this dataset")
}

/// 100 points, and 100 segments of `len` metres from 2–300 m above the ground to 0–30 m
/// above it (the host's "can A see B" question; most are blocked part way).
fn workload(src: &InMemorySource, len: f64) -> (Vec<(f64, f64)>, Vec<Ray>) {
    let (east, north) = src.grid().real_extent_m();
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let hot = |x, y| {
        height_of_terrain(src, x, y)
            .ready()
            .map_or(0.0, |g| g.height_m)
    };
    let points = (0..100)
        .map(|_| (rng.range(0.0, east), rng.range(0.0, north)))
        .collect();
    let mut rays = Vec::new();
    while rays.len() < 100 {
        let (x, y) = (rng.range(0.0, east), rng.range(0.0, north));
        let az = rng.range(0.0, std::f64::consts::TAU);
        let (tx, ty) = (x + len * az.cos(), y + len * az.sin());
        if !(0.0..=east).contains(&tx) || !(0.0..=north).contains(&ty) {
            continue;
        }
        let from = DVec3::new(x, y, hot(x, y) + rng.range(2.0, 300.0));
        let to = DVec3::new(tx, ty, hot(tx, ty) + rng.range(0.0, 30.0));
        rays.push(Ray::segment(from, to).expect("finite"));
    }
    (points, rays)
}

fn bench_source(c: &mut Criterion, name: &str, src: &InMemorySource) {
    let (points, rays) = workload(src, 10_000.0);
    let mut group = c.benchmark_group(format!("query_{name}"));
    group.bench_function("hot_x100", |b| {
        b.iter(|| {
            let mut s = 0.0;
            for &(x, y) in &points {
                s += height_of_terrain(src, x, y)
                    .ready()
                    .map_or(0.0, |g| g.height_m);
            }
            black_box(s)
        })
    });
    group.bench_function("los_10km_x100", |b| {
        b.iter(|| {
            let mut hits = 0;
            for r in &rays {
                hits += first_hit(src, r).ready().flatten().is_some() as u32;
            }
            black_box(hits)
        })
    });
    group.finish();
}

fn queries(c: &mut Criterion) {
    let dem = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../assets/dem/N47E011.hgt.zip");
    let ds = load_dataset(&dem).expect("the embedded DEM loads");
    bench_source(c, "n47e011", &source(ds));
    let size = selection_size();
    eprintln!("generating and baking a {size}² dataset (once)...");
    bench_source(
        c,
        &format!("ridged_{size}"),
        &source(generated(size, DemKind::Ridged)),
    );
}

criterion_group!(benches, queries);
criterion_main!(benches);
