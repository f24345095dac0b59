//! Gather throughput: filling staging memory with the samples of a clipmap strip or a refined
//! tile from a generated 4097² dataset (what the renderer does for every upload).

use std::hint::black_box;

use aerie::terrain::gather::gather;
use aerie::terrain::gen::DemKind;
use aerie_bench::generated;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};

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

criterion_group!(benches, gathers);
criterion_main!(benches);
