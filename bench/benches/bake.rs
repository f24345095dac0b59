//! Bake throughput (samples/s) on a generated 2049² ridged dataset, all cores: DESIGN.md's
//! target is ≥ 50 M samples/s on 2 cores. Also the generator itself.

use std::hint::black_box;

use aerie::terrain::gen::{generate, DemKind, GenParams};
use aerie_bench::{baked, generated};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};

fn bake(c: &mut Criterion) {
    let n = 2049usize;
    let ds = generated(n, DemKind::Ridged);
    let mut group = c.benchmark_group("bake");
    group.sample_size(10);
    group.throughput(Throughput::Elements((n * n) as u64));
    group.bench_function("bake_2049", |b| b.iter(|| black_box(baked(&ds))));
    let cliffs = generated(n, DemKind::Cliffs);
    group.bench_function("bake_2049_cliffs", |b| b.iter(|| black_box(baked(&cliffs))));
    group.bench_function("generate_ridged_2049", |b| {
        b.iter(|| {
            black_box(generate(&GenParams {
                size: n,
                spacing: 10.0,
                kind: DemKind::Ridged,
                seed: 1,
            }))
        })
    });
    group.finish();
}

criterion_group!(benches, bake);
criterion_main!(benches);
