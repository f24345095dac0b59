//! Gather throughput: filling staging memory with the samples of a clipmap strip or a refined
//! tile from a generated 4097² dataset (what the renderer does for every upload) — from a warm
//! cache (the same region again), and cold (`gather_cold`: the caches flushed before each
//! gather and the region moved, as a frame's pool miss finds them).

use std::hint::black_box;

use aerie::terrain::gather::gather;
use aerie::terrain::gen::DemKind;
use aerie_bench::generated;
use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};

fn gathers(c: &mut Criterion) {
    let ds = generated(4097, DemKind::Ridged);
    let hf = &ds.hf;
    let mut group = c.benchmark_group("gather");
    // (name, origin sample, step, size): a level-0 strip, a level-3 strip (strided), refined
    // tiles r = 4 from level 4 (step 1) and r = 2 from level 5 (step 8).
    for (name, origin, step, size) in [
        ("strip_L0_192x16", [1000i64, 2000], 1u32, [192u32, 16]),
        ("strip_L3_16x192", [512, 640], 8, [16, 192]),
        ("refined_257x257_step1", [1024, 1024], 1, [257, 257]),
        ("refined_65x65_step8", [2048, 512], 8, [65, 65]),
        ("edge_clamped_192x192_step16", [3000, 3000], 16, [192, 192]),
    ] {
        let mut out = vec![0f32; (size[0] * size[1]) as usize];
        group.throughput(Throughput::Bytes(out.len() as u64 * 4));
        group.bench_function(name, |b| {
            b.iter(|| {
                gather(hf, origin, step, size, &mut out);
                black_box(out[0])
            })
        });
    }
    group.finish();
}

/// Refined tiles gathered with the caches cold: before each gather 64 MiB are written (more
/// than the last-level cache) and the region moves by a prime step, so neither its rows nor
/// their pages' translations are cached.
fn cold_gathers(c: &mut Criterion) {
    let ds = generated(4097, DemKind::Ridged);
    let hf = &ds.hf;
    let mut flush = vec![0u8; 64 << 20];
    let mut group = c.benchmark_group("gather_cold");
    for (name, step, size) in [
        ("refined_129x129_step1", 1u32, [129u32, 129]),
        ("refined_129x129_step2", 2, [129, 129]),
        ("refined_129x129_step4", 4, [129, 129]),
        ("refined_65x65_step16", 16, [65, 65]),
    ] {
        let mut out = vec![0f32; (size[0] * size[1]) as usize];
        let span = (size[0] as i64 - 1) * step as i64 + 1;
        let room = hf.width as i64 - span;
        let mut k = 0i64;
        group.throughput(Throughput::Bytes(out.len() as u64 * 4));
        group.bench_function(name, |b| {
            b.iter_batched(
                || {
                    for byte in flush.iter_mut().step_by(64) {
                        *byte = byte.wrapping_add(1);
                    }
                    k += 1;
                    [(k * 7919) % room, (k * 104_729) % room]
                },
                |origin| {
                    gather(hf, origin, step, size, &mut out);
                    black_box(out[0])
                },
                BatchSize::PerIteration,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, gathers, cold_gathers);
criterion_main!(benches);
