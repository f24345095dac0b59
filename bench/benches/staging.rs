//! Staging-ring cursor throughput (the pure `vk::staging::RingCursor`, no Vulkan): one frame's
//! typical allocations (uniforms, indirect commands, instances, clipmap strips, refined tiles)
//! until the region is full, region after region.

use std::hint::black_box;

use aerie::vk::staging::RingCursor;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};

const REGION: u64 = 8 << 20;

/// Fills one region with a frame's pattern of allocations; returns the bytes handed out.
fn frame(cursor: &mut RingCursor, region: usize) -> u64 {
    cursor.open(region);
    let mut bytes = 0;
    let pattern: [(u64, u64); 6] = [
        (288, 16),         // frame uniforms
        (140, 4),          // indirect draws
        (48 * 600, 16),    // instances
        (192 * 16 * 4, 4), // a clipmap strip
        (33 * 33 * 4, 4),  // a refined tile r = 1
        (65 * 65 * 4, 4),  // r = 2
    ];
    'fill: loop {
        for &(size, align) in &pattern {
            match cursor.alloc(size, align) {
                Ok(off) => {
                    black_box(off);
                    bytes += size;
                }
                Err(_) => break 'fill,
            }
        }
    }
    bytes
}

fn staging(c: &mut Criterion) {
    let mut cursor = RingCursor::new(REGION, 2, 256);
    let per_frame = frame(&mut cursor, 0);
    let mut group = c.benchmark_group("staging_ring");
    group.throughput(Throughput::Bytes(per_frame));
    let mut k = 0;
    group.bench_function("fill_8MiB_region", |b| {
        b.iter(|| {
            k += 1;
            frame(&mut cursor, k % 2)
        })
    });
    group.throughput(Throughput::Elements(1));
    group.bench_function("small_alloc", |b| {
        cursor.open(0);
        b.iter(|| {
            if cursor.remaining() < 1024 {
                cursor.open(0);
            }
            black_box(cursor.alloc(48, 16).ok())
        })
    });
    group.finish();
}

criterion_group!(benches, staging);
criterion_main!(benches);
