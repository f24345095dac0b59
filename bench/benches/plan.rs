//! Issue 15's CPU frame, stage by stage, on the selection target's scene (one channel at
//! 1280×720, τ = 1 px, 300 m above the ground, a generated 16385² dataset — `AERIE_BENCH_SIZE`
//! overrides — on the flat plane and on the ellipsoid), through the renderer's own planner
//! (`render::plan`) over an in-memory source: `select_frame` (clipmap placement, strips,
//! selection) and `plan_frame` (the staging budget, pool uploads, instance records, indirect
//! commands). Criterion times the whole plan per frame; the flight is then flown once more in
//! order from a fresh planner, each frame timed stage by stage (thread CPU time) for the
//! per-frame median and p99.

use std::hint::black_box;
use std::sync::Arc;

use aerie::render::desc::RendererDesc;
use aerie::render::plan::{plan_frame, select_frame, PlanState, TileMeshes};
use aerie::terrain::select::Selection;
use aerie::terrain::source::{InMemoryTerrain, TerrainSource};
use aerie_bench::{selection_size, thread_cpu_us, TargetScene};
use criterion::{criterion_group, criterion_main, Criterion};

/// Staging offsets are aligned as on lavapipe and most discrete GPUs.
const ALIGNMENT: u64 = 256;

/// Median and p99 of per-frame times.
fn median_p99(mut v: Vec<f64>) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
    (at(0.5), at(0.99))
}

fn plan_stages(c: &mut Criterion) {
    let size = selection_size();
    let viewport = (1280, 720);
    let mut group = c.benchmark_group(format!("plan_{size}_720p_agl300"));
    for geographic in [false, true] {
        eprintln!("generating and baking a {size}² dataset (geographic: {geographic})...");
        let scene = TargetScene::new(size, geographic);
        let cams = scene.flight_agl(600, viewport.0, viewport.1, 300.0);
        let name = scene.name;
        let mut desc = RendererDesc::default();
        desc.select.tau_px = 1.0;
        let ds = Arc::new(scene.ds);
        let source: Arc<dyn TerrainSource> = Arc::new(InMemoryTerrain::new(Arc::clone(&ds)));
        let clipmap = desc.clipmap(source.grid());
        let indices = TileMeshes::indices(desc.tile_size).1;
        let mut state = PlanState::new(
            Arc::new(scene.bake),
            Arc::clone(&source),
            clipmap,
            &desc.pool_capacity,
        );
        state.strips_around(cams[0].position);
        let mut sel = Selection::default();
        // One frame: (select µs, plan µs, instances), each stage in thread CPU time.
        let mut frame = |k: u64, timed: bool| {
            let camera = &cams[k as usize % cams.len()];
            let inputs = desc.solo_frame_inputs(k, camera, viewport, indices, ALIGNMENT);
            let t0 = if timed { thread_cpu_us() } else { 0.0 };
            let strips = select_frame(&mut state, &inputs, &mut sel);
            let t1 = if timed { thread_cpu_us() } else { 0.0 };
            let plan = plan_frame(&mut state, &inputs, &sel, strips).expect("plan");
            let t2 = if timed { thread_cpu_us() } else { 0.0 };
            (t1 - t0, t2 - t1, black_box(plan.instances.len()))
        };
        let mut k = 0u64;
        group.bench_function(format!("select_and_plan_tau1_{name}"), |b| {
            b.iter(|| {
                k += 1;
                frame(k, false)
            })
        });
        // The flight once more in order from a fresh planner, each frame's stages timed once
        // in thread CPU time (on a loaded machine the wall clock's p99 is the scheduler's time
        // slice). Once, not the least of several runs of a frame: a frame run again finds its
        // uploads done and its view ahead selected, and the least would hide both.
        let mut state = PlanState::new(
            Arc::clone(&state.bake),
            Arc::clone(&source),
            state.clipmap.clone(),
            &desc.pool_capacity,
        );
        state.strips_around(cams[0].position);
        let mut sel = Selection::default();
        let (mut select_us, mut plan_us, mut instances) = (Vec::new(), Vec::new(), 0);
        for (k, camera) in cams.iter().enumerate() {
            let inputs = desc.solo_frame_inputs(k as u64, camera, viewport, indices, ALIGNMENT);
            let t0 = thread_cpu_us();
            let strips = select_frame(&mut state, &inputs, &mut sel);
            let t1 = thread_cpu_us();
            let plan = plan_frame(&mut state, &inputs, &sel, strips).expect("plan");
            let t2 = thread_cpu_us();
            select_us.push(t1 - t0);
            plan_us.push(t2 - t1);
            instances = instances.max(black_box(plan.instances.len()));
        }
        let (s50, s99) = median_p99(select_us);
        let (p50, p99) = median_p99(plan_us);
        eprintln!(
            "plan {name}: per frame (thread CPU time) select_frame median {s50:.1} µs, p99 \
             {s99:.1} µs; plan_frame median {p50:.1} µs, p99 {p99:.1} µs; up to {instances} \
             instances"
        );
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30);
    targets = plan_stages
}
criterion_main!(benches);
