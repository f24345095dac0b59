//! Tile selection per frame (one channel, all levels) on a generated 16385² dataset
//! (`AERIE_BENCH_SIZE` overrides), along a 340 m/s pass: DESIGN.md's target is ≤ 0.1 ms.
//! Also clipmap placement + cache update, and refined-tile pool requests per frame.

use std::hint::black_box;

use aerie::terrain::clipmap::{place_levels, update_cache, CacheRegion};
use aerie::terrain::gen::DemKind;
use aerie::terrain::pool::{RefinedTilePool, TileKey};
use aerie::terrain::select::{select_tiles, LodMode, SelectParams, Selection};
use aerie_bench::{baked, clipmap_desc, flight, generated, selection_size};
use criterion::{criterion_group, criterion_main, Criterion};

fn selection(c: &mut Criterion) {
    let size = selection_size();
    eprintln!("generating and baking a {size}² dataset (once)...");
    let ds = generated(size, DemKind::Ridged);
    let bake = baked(&ds);
    let (w, h, sx) = (ds.hf.width, ds.hf.height, ds.hf.spacing_x);
    drop(ds); // selection needs the bake only
    let clip = clipmap_desc(w, h);
    let side_m = (w - 1) as f64 * sx;
    let mut group = c.benchmark_group(format!("select_{size}"));
    for (name, mode, tau, viewport) in [
        ("bounded_tau1_1080p", LodMode::Bounded, 1.0, (1920, 1080)),
        ("bounded_tau5_1080p", LodMode::Bounded, 5.0, (1920, 1080)),
        ("clipmap_1080p", LodMode::Clipmap, 1.0, (1920, 1080)),
        ("distance_1080p", LodMode::Distance, 1.0, (1920, 1080)),
        ("cdlod_1080p", LodMode::Cdlod, 1.0, (1920, 1080)),
    ] {
        let cams = flight(side_m, 600, viewport.0, viewport.1);
        let params = SelectParams {
            mode,
            tau_px: tau,
            ..SelectParams::default()
        };
        let mut sel = Selection::default();
        let mut k = 0;
        group.bench_function(name, |b| {
            b.iter(|| {
                let cam = &cams[k % cams.len()];
                k += 1;
                let viewer = [cam.position.x / sx, cam.position.y / sx];
                let placements = place_levels(&clip, viewer);
                select_tiles(&bake, &clip, &placements, cam, viewport, &params, &mut sel);
                black_box(sel.items.len())
            })
        });
    }
    group.finish();

    let mut group = c.benchmark_group("clipmap_and_pools");
    let cams = flight(side_m, 600, 1920, 1080);
    let mut caches: Vec<Option<CacheRegion>> = vec![None; clip.level_count() as usize];
    let mut k = 0;
    group.bench_function("place_and_update_cache", |b| {
        b.iter(|| {
            let cam = &cams[k % cams.len()];
            k += 1;
            let placements = place_levels(&clip, [cam.position.x / sx, cam.position.y / sx]);
            let mut rects = 0;
            for (i, p) in placements.iter().enumerate() {
                let (region, r) = update_cache(&clip, caches[i].as_ref(), p);
                rects += r.len();
                caches[i] = Some(region);
            }
            black_box(rects)
        })
    });
    let mut pool = RefinedTilePool::new(256);
    let mut frame = 0u64;
    group.bench_function("pool_200_requests", |b| {
        b.iter(|| {
            frame += 1;
            pool.begin_frame(frame);
            let mut budget = 8;
            for i in 0..200u32 {
                let key = TileKey {
                    level: 3,
                    tx: (frame as u32 / 4 + i) % 512,
                    ty: i / 16,
                    refinement: 1,
                };
                black_box(pool.request(key, &mut || {
                    budget -= 1;
                    budget >= 0
                }));
            }
        })
    });
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(50);
    targets = selection
}
criterion_main!(benches);
