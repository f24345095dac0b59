//! Issue 15's selection target: one channel at 1280×720, τ = 1 px, 300 m above the ground, on
//! a generated 16385² dataset (`AERIE_BENCH_SIZE` overrides) on the flat plane and on the
//! ellipsoid (a 1″ geographic grid), with ring tiles carried across frames where they may be
//! (`SelectParams::carry`, the default: one view, plane or ellipsoid) and walked afresh every frame
//! (`_walked_afresh`). Besides criterion's figures, the flight is flown three more times in
//! order (thread CPU time, each frame's least) for the per-frame median and p99; and with the
//! seen parts (`SelectParams::seen_quadrants`) on and off, interleaved frame by frame, for what
//! they cost. Then how much of each frame's cut the cut of 1, 8
//! and 30 frames before already drew (the same nodes in the same parts): what a selection
//! carried across frames could keep.

use std::hint::black_box;

use aerie::camera::Camera;
use aerie::terrain::clipmap::place_levels;
use aerie::terrain::select::{select_tiles, DrawItem, SelectParams, Selection};
use aerie_bench::{selection_size, thread_cpu_us, TargetScene};
use criterion::{criterion_group, criterion_main, Criterion};

fn selection_target(c: &mut Criterion) {
    let size = selection_size();
    let viewport = (1280, 720);
    let mut group = c.benchmark_group(format!("select_target_{size}_720p_agl300"));
    for geographic in [false, true] {
        eprintln!("generating and baking a {size}² dataset (geographic: {geographic})...");
        let scene = TargetScene::new(size, geographic);
        let cams = scene.flight_agl(600, viewport.0, viewport.1, 300.0);
        for carry in [true, false] {
            let params = SelectParams {
                earth: scene.earth,
                carry,
                ..SelectParams::default()
            };
            let way = if carry { "" } else { "_walked_afresh" };
            let mut sel = Selection::default();
            let mut k = 0;
            group.bench_function(format!("bounded_tau1_{}{way}", scene.name), |b| {
                b.iter(|| {
                    k += 1;
                    black_box(run(&scene, &cams[k % cams.len()], &params, &mut sel))
                })
            });
            // Thread CPU time, each frame's least over three passes of the flight in order,
            // each from a fresh selection (a selection carries ring tiles from the frame
            // before, so a frame is timed after the one before it, never after itself): on a
            // loaded machine the wall clock's p99 is the scheduler's time slice, not the
            // selection's.
            let mut times = vec![f64::INFINITY; cams.len()];
            let (mut carried, mut drawn) = (0u64, 0u64);
            // Ring tiles walked per frame, and of them for their record's age (the last pass).
            let (mut walked, mut aged) = (vec![0u32; cams.len()], vec![0u32; cams.len()]);
            for _ in 0..3 {
                let mut sel = Selection::default();
                for (k, (cam, least)) in cams.iter().zip(times.iter_mut()).enumerate() {
                    let t = thread_cpu_us();
                    black_box(run(&scene, cam, &params, &mut sel));
                    *least = least.min(thread_cpu_us() - t);
                    carried += sel.carry.stats.carried_nodes as u64;
                    drawn += sel.items.len() as u64;
                    walked[k] = sel.carry.stats.walked_tiles;
                    aged[k] = sel.carry.stats.aged_tiles;
                }
            }
            // The first frame walks every ring tile: left out.
            let (walked, aged) = (&mut walked[1..], &mut aged[1..]);
            walked.sort_unstable();
            aged.sort_unstable();
            times.sort_by(f64::total_cmp);
            let at = |q: f64| times[((times.len() - 1) as f64 * q).round() as usize];
            eprintln!(
                "select_target {}{way}: per frame (thread CPU time) median {:.1} µs, p99 {:.1} µs, max {:.1} µs, {} items, {:.1} % of the drawn nodes carried from the frame before",
                scene.name,
                at(0.5),
                at(0.99),
                at(1.0),
                sel.items.len(),
                100.0 * carried as f64 / drawn.max(1) as f64
            );
            if carry {
                let med = |v: &[u32]| v[v.len() / 2];
                eprintln!(
                    "select_target {}: ring tiles walked per frame median {}, max {}; of them for their record's age median {}, max {}",
                    scene.name,
                    med(walked),
                    walked[walked.len() - 1],
                    med(aged),
                    aged[aged.len() - 1]
                );
            }
        }
        // The seen parts (`SelectParams::seen_quadrants`) on and off, interleaved frame by
        // frame in one process (the order swapped each pass), each frame's least of three: on
        // a loaded machine runs minutes apart differ more than the two do.
        let variants = [true, false].map(|seen_quadrants| SelectParams {
            earth: scene.earth,
            seen_quadrants,
            ..SelectParams::default()
        });
        let mut least = [
            vec![f64::INFINITY; cams.len()],
            vec![f64::INFINITY; cams.len()],
        ];
        for pass in 0..3 {
            let mut sels = [Selection::default(), Selection::default()];
            for (f, cam) in cams.iter().enumerate() {
                for k in [pass % 2, 1 - pass % 2] {
                    let t = thread_cpu_us();
                    black_box(run(&scene, cam, &variants[k], &mut sels[k]));
                    least[k][f] = least[k][f].min(thread_cpu_us() - t);
                }
            }
        }
        let median = |v: &[f64]| {
            let mut v = v.to_vec();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let ratios: Vec<f64> = least[0].iter().zip(&least[1]).map(|(a, b)| a / b).collect();
        eprintln!(
            "select_target {}: seen parts on {:.1} µs, off {:.1} µs per frame (medians, interleaved); per-frame ratio median {:.3}",
            scene.name,
            median(&least[0]),
            median(&least[1]),
            median(&ratios)
        );
        // The cuts of fresh walks: what a carried selection can keep.
        let params = SelectParams {
            earth: scene.earth,
            carry: false,
            ..SelectParams::default()
        };
        let mut sel = Selection::default();
        let cuts: Vec<Vec<CutKey>> = cams
            .iter()
            .map(|cam| {
                run(&scene, cam, &params, &mut sel);
                let mut keys: Vec<CutKey> = sel.items.iter().map(cut_key).collect();
                keys.sort_unstable();
                keys
            })
            .collect();
        for lag in [1, 8, 30] {
            let (kept, least) = cut_coherence(&cuts, lag);
            eprintln!(
                "select_target {}: nodes drawn {lag} frame(s) ({:.1} m) before, in the same parts: {:.2} % of a frame's, least {:.2} %",
                scene.name,
                lag as f64 * 100.0 / 60.0,
                100.0 * kept,
                100.0 * least
            );
        }
    }
    group.finish();
}

/// One frame's selection into `sel`; the nodes drawn.
fn run(scene: &TargetScene, cam: &Camera, params: &SelectParams, sel: &mut Selection) -> usize {
    let placements = place_levels(&scene.clip, scene.viewer(cam));
    let viewport = (1280, 720);
    select_tiles(
        &scene.bake,
        &scene.clip,
        &placements,
        cam,
        viewport,
        params,
        sel,
    );
    sel.items.len()
}

/// A drawn node and how it is drawn: ring tile, node, levels up it takes its mesh from.
type CutKey = (u32, u32, u32, u32, u32, u32, u32);

fn cut_key(i: &DrawItem) -> CutKey {
    let (l, x, y) = (i.level, i.tx, i.ty);
    let up = i.morph.levels_up();
    (l, x, y, i.node_level, i.node_tx, i.node_ty, up)
}

/// Over every frame with one `lag` frames before it: the share of all its drawn nodes that the
/// earlier cut drew the same way, and the least share of one frame. `cuts` are sorted.
fn cut_coherence(cuts: &[Vec<CutKey>], lag: usize) -> (f64, f64) {
    let (mut kept, mut total, mut least) = (0usize, 0usize, 1.0f64);
    for (before, now) in cuts.iter().zip(cuts.iter().skip(lag)) {
        let same = now
            .iter()
            .filter(|k| before.binary_search(k).is_ok())
            .count();
        (kept, total) = (kept + same, total + now.len());
        least = least.min(same as f64 / now.len().max(1) as f64);
    }
    (kept as f64 / total.max(1) as f64, least)
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30);
    targets = selection_target
}
criterion_main!(benches);
