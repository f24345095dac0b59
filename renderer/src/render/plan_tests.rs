//! The frame plan's invariants (see `plan.rs`), checked without a GPU.

use std::sync::Arc;

use glam::DVec3;

use crate::render::gpu::DrawIndexedIndirect;
use aerie_terrain::bake::{bake, BakeParams};
use aerie_terrain::camera::{Attitude, Camera, Frustum};
use aerie_terrain::clipmap::ClipmapDesc;
use aerie_terrain::dataset::Dataset;
use aerie_terrain::pool::TileKey;
use aerie_terrain::select::{select_tiles_multi, DrawItem, SelectParams, Selection};
use aerie_terrain::source::InMemoryTerrain;
use aerie_terrain::Heightfield;

use super::*;
use crate::render::jobs::{split_into_submissions, ImageUpload, StagingBudget};
use crate::render::stats::RESOLUTIONS;
use crate::render::terrain_draws::{edge_combo, EDGE_COMBOS, INSTANCE_KEYS};

const N: usize = 257;
const Q: u32 = 16;
/// Indices of one skirted 17×17 tile (any multiple of 3 does for the arithmetic), and of its
/// coarse and sixteenth meshes after it.
const INDICES: (u32, u32) = (0, 1728);
const MESHES: TileMeshes = TileMeshes {
    whole: INDICES,
    coarse: (1824, 480),
    sixteenth: (2352, 144),
    grid: [1536, 384, 96],
    edge: [48, 24, 12],
    fill: [24, 12, 6],
};
const ALIGN: u64 = 64;

fn rough_dataset() -> Arc<Dataset> {
    let hf = Heightfield {
        width: N,
        height: N,
        spacing_x: 10.0,
        spacing_y: 10.0,
        heights: (0..N * N)
            .map(|k| {
                let (c, r) = ((k % N) as f32, (k / N) as f32);
                40.0 * (c * 0.9).sin() + 35.0 * (r * 1.3).cos() + 3.0 * c
            })
            .collect(),
        geo: None,
        voids_filled: 0,
        spacing_note: String::new(),
    };
    Arc::new(Dataset::from_heightfield(hf, "plan test".into()))
}

fn clipmap() -> ClipmapDesc {
    ClipmapDesc {
        tile_quads: Q,
        patch_tiles: 8,
        margin_tiles: 2,
        width: N as u32,
        height: N as u32,
    }
}

fn state(pool_capacity: &[u32]) -> PlanState {
    let ds = rough_dataset();
    let b = Arc::new(bake(&ds, BakeParams::default(), &|_, _| {}));
    PlanState::new(
        b,
        Arc::new(InMemoryTerrain::new(ds)),
        clipmap(),
        pool_capacity,
    )
}

fn camera(x: f64, y: f64, z: f64, heading: f64) -> Camera {
    Camera::new(
        DVec3::new(x, y, z),
        Attitude::from_degrees(heading, -20.0, 0.0),
        Frustum::symmetric(90f64.to_radians(), 320, 180),
    )
}

fn inputs<'a>(
    frame: u64,
    camera: &'a Camera,
    select: &'a SelectParams,
    capacity: u64,
) -> FrameInputs<'a> {
    FrameInputs {
        frame,
        camera,
        viewport: (320, 180),
        channels: &[],
        channels_generation: 0,
        select,
        prefetch_frames: 0.0,
        skirt_factor: 2.0,
        skirt_min_m: 1.0,
        skirts: SkirtRule::WhereResolutionsDiffer,
        overlay_bytes: None,
        tile_meshes: MESHES,
        staging: StagingBudget::new(capacity, ALIGN),
    }
}

/// Every node of ring tile (level, tx, ty) split `r` times: 4^r nodes at level − r.
fn refined_tile(level: u32, tx: u32, ty: u32, r: u32) -> Vec<DrawItem> {
    let n = 1u32 << r;
    let mut v = Vec::new();
    for j in 0..n {
        for i in 0..n {
            v.push(DrawItem {
                refinement: r,
                node_level: level - r,
                node_tx: tx * n + i,
                node_ty: ty * n + j,
                ..DrawItem::whole(level, tx, ty, 0.5, 0.5)
            });
        }
    }
    v
}

fn selection(items: Vec<DrawItem>) -> Selection {
    Selection {
        items,
        ..Default::default()
    }
}

/// Bytes of the fixed pushes staged after the uploads for `instances` records and `draws`
/// commands, aligned.
fn fixed_pushes(used: u64, instances: usize, draws: usize) -> u64 {
    let mut b = StagingBudget::new(u64::MAX / 2, ALIGN);
    b.take(used).unwrap();
    b.take(std::mem::size_of::<FrameUniforms>() as u64).unwrap();
    b.take((std::mem::size_of::<DrawIndexedIndirect>() * draws) as u64)
        .unwrap();
    if instances > 0 {
        b.take((instances * std::mem::size_of::<TileInstance>()) as u64)
            .unwrap();
    }
    b.used() - used
}

fn strip(layer: u32, rows: u32) -> ImageUpload {
    ImageUpload {
        layer,
        texel: [0, 0],
        size: [65, rows],
        origin_sample: [0, 0],
        step: 1 << layer,
    }
}

#[test]
fn staging_budget_aligns_like_the_ring_and_refuses_without_spending() {
    let mut b = StagingBudget::new(256, 64);
    b.take(3).unwrap();
    b.take(5).unwrap();
    assert_eq!(b.used(), 69, "second allocation starts at 64");
    assert_eq!(b.remaining(), 187);
    let err = b.take(150).unwrap_err();
    assert_eq!(
        err.to_string(),
        "upload of 150 bytes exceeds this frame's staging budget (128 of 256 bytes left)"
    );
    assert_eq!(b.used(), 69, "a refused request spends nothing");
    b.take(128).unwrap();
    assert_eq!(b.remaining(), 0);
}

#[test]
fn strips_come_first_and_pool_misses_get_what_is_left() {
    let mut st = state(&[8, 8, 8, 8, 8, 0]);
    let select = SelectParams::default();
    let cam = camera(1280.0, 1280.0, 400.0, 0.0);
    // Three refined tiles of r = 1 (4 nodes each) and one unrefined tile.
    let mut items = refined_tile(2, 0, 1, 1);
    items.extend(refined_tile(2, 1, 1, 1));
    items.push(DrawItem::whole(2, 2, 1, 0.5, 0.5));
    items.extend(refined_tile(2, 3, 1, 1));
    let sel = selection(items);
    let strips = vec![strip(0, 10), strip(1, 7)];
    let strip_bytes: u64 = strips.iter().map(ImageUpload::bytes).sum();
    let slot = st.pools[0].slot_bytes();
    assert_eq!(slot, 33 * 33 * 4);
    let reserve = fixed_reserve(sel.items.len(), false, None);
    // Room for the strips, the reserve and exactly two slots with their slack.
    let capacity = 2 * ALIGN + strip_bytes + reserve + 2 * (slot + ALIGN) + POOL_UPLOAD_SLACK_BYTES;
    let inp = inputs(0, &cam, &select, capacity);
    let plan = plan_frame(&mut st, &inp, &sel, strips.clone()).unwrap();

    assert_eq!(plan.strips, strips, "strips fit: staged in the frame");
    assert!(plan.spilled_strips.is_empty());
    assert_eq!(plan.stats.bytes_clipmap, strip_bytes);
    assert_eq!((plan.stats.pool_misses, plan.stats.tiles_late), (2, 1));
    let uploaded: Vec<_> = plan
        .pool_uploads
        .iter()
        .map(|p| (p.key.tx, p.upload.layer))
        .collect();
    assert_eq!(
        uploaded,
        [(0, 0), (1, 1)],
        "misses in selection order, free slots in order"
    );
    assert_eq!(plan.late[0].key.tx, 3);
    assert_eq!(plan.late[0].drawn_refinement, 0);
    assert_eq!(plan.stats.bytes_refined, 2 * slot);
    // Staged = strips, two slots, the fixed pushes, each aligned; within the region.
    let mut b = StagingBudget::new(capacity, ALIGN);
    for s in &strips {
        b.take(s.bytes()).unwrap();
    }
    b.take(slot).unwrap();
    b.take(slot).unwrap();
    let instances = plan.instances.len();
    assert_eq!(
        instances,
        4 + 4 + 1 + 1,
        "late tile drawn as its one level-2 node"
    );
    assert_eq!(
        plan.staged_bytes,
        b.used() + fixed_pushes(b.used(), instances, plan.draws.len())
    );
    assert_eq!(plan.stats.bytes_uploaded, plan.staged_bytes);
    assert!(plan.staged_bytes <= capacity);
}

#[test]
fn strips_that_do_not_fit_spill_and_leave_the_region_to_the_pools() {
    let mut st = state(&[8, 8, 8, 8, 8, 0]);
    let select = SelectParams::default();
    let cam = camera(1280.0, 1280.0, 400.0, 0.0);
    let sel = selection(refined_tile(2, 1, 1, 1));
    let strips = vec![strip(0, 60), strip(1, 60), strip(2, 60)];
    let slot = st.pools[0].slot_bytes();
    let reserve = fixed_reserve(sel.items.len(), false, None);
    // One strip fits with the reserve, three do not; one slot fits after the reserve.
    let capacity = reserve + slot + POOL_UPLOAD_SLACK_BYTES + 2 * ALIGN + strips[0].bytes();
    let plan = plan_frame(
        &mut st,
        &inputs(0, &cam, &select, capacity),
        &sel,
        strips.clone(),
    );
    let plan = plan.unwrap();
    assert!(
        plan.strips.is_empty(),
        "all or nothing: strips are one update"
    );
    assert_eq!(plan.stats.budget_spills as usize, plan.spilled_strips.len());
    assert!(plan.spilled_strips.len() > 1);
    let rows: u32 = plan
        .spilled_strips
        .iter()
        .flatten()
        .map(|j| j.size[1])
        .sum();
    assert_eq!(rows, 180);
    assert_eq!(
        plan.stats.bytes_clipmap,
        strips.iter().map(ImageUpload::bytes).sum::<u64>()
    );
    assert_eq!(
        plan.stats.pool_misses, 1,
        "the pools get the frame's whole region"
    );
    assert!(plan.staged_bytes <= capacity);
}

#[test]
fn split_into_submissions_keeps_every_row_in_order_within_each_region() {
    let jobs = [strip(0, 50), strip(1, 3), strip(2, 41)];
    let capacity = 20 * 65 * 4 + STREAM_SLACK;
    let subs = split_into_submissions(&jobs, capacity, ALIGN).unwrap();
    // Rows in order: (layer, first texel row) walks each job's rows without gaps.
    let mut next = [0u32; 3];
    for s in &subs {
        let mut b = StagingBudget::new(capacity, ALIGN);
        for (k, j) in s.iter().enumerate() {
            assert_eq!(j.texel[1], next[j.layer as usize], "{j:?}");
            assert_eq!(j.origin_sample[1], (j.texel[1] * j.step) as i64);
            next[j.layer as usize] += j.size[1];
            b.take(j.bytes()).unwrap();
            assert!(
                k == 0 || j.texel[1] == 0,
                "only a submission's first job is a tail"
            );
        }
    }
    assert_eq!(next, [50, 3, 41]);
    assert_eq!(
        split_into_submissions(&[], capacity, ALIGN).unwrap().len(),
        0
    );
    let err = split_into_submissions(&jobs, 65 * 4, ALIGN).unwrap_err();
    assert!(
        err.to_string()
            .contains("one level-texture row (260 bytes)"),
        "{err}"
    );
}

const STREAM_SLACK: u64 = crate::render::jobs::STREAM_ROW_SLACK_BYTES;

#[test]
fn a_late_tile_is_drawn_at_its_best_resident_resolution_coarsened_once() {
    let mut st = state(&[8, 8, 8, 8, 8, 0]);
    let select = SelectParams::default();
    let cam = camera(1280.0, 1280.0, 400.0, 0.0);
    // Frame 0: tile (3, 1, 1) at r = 1 is uploaded.
    let sel0 = selection(refined_tile(3, 1, 1, 1));
    let plan0 = plan_frame(&mut st, &inputs(0, &cam, &select, 1 << 20), &sel0, vec![]).unwrap();
    assert_eq!(plan0.stats.pool_misses, 1);
    let r1_slot = plan0.pool_uploads[0].upload.layer;
    // Frame 1: it needs r = 2 (16 nodes at level 1) but nothing fits: drawn at r = 1.
    let sel1 = selection(refined_tile(3, 1, 1, 2));
    let tight = fixed_reserve(16, false, None) + POOL_UPLOAD_SLACK_BYTES;
    let plan1 = plan_frame(&mut st, &inputs(1, &cam, &select, tight), &sel1, vec![]).unwrap();
    assert_eq!((plan1.stats.tiles_late, plan1.stats.pool_misses), (1, 0));
    let key = TileKey {
        level: 3,
        tx: 1,
        ty: 1,
        refinement: 2,
    };
    assert_eq!(
        plan1.late,
        [LateTile {
            key,
            drawn_refinement: 1,
            reason: LateReason::Budget,
        }]
    );
    let nodes: Vec<_> = plan1
        .draw_list
        .iter()
        .map(|(d, slot)| (d.refinement, d.node_level, d.node_tx, d.node_ty, *slot))
        .collect();
    assert_eq!(
        nodes,
        [
            (1, 2, 2, 2, r1_slot),
            (1, 2, 3, 2, r1_slot),
            (1, 2, 2, 3, r1_slot),
            (1, 2, 3, 3, r1_slot)
        ],
        "16 level-1 nodes become their 4 level-2 ancestors, each once"
    );
    for (d, _) in &plan1.draw_list {
        assert_eq!(d.eps_m, st.bake.eps(d.node_level, d.node_tx, d.node_ty));
    }
    // Another tile with nothing resident collapses to the tile itself from the clipmap.
    let sel2 = selection(refined_tile(3, 0, 1, 2));
    let plan2 = plan_frame(&mut st, &inputs(2, &cam, &select, tight), &sel2, vec![]).unwrap();
    let (d, slot) = plan2.draw_list[0];
    assert_eq!(plan2.draw_list.len(), 1);
    assert_eq!(
        (d.refinement, d.node_level, d.node_tx, d.node_ty, slot),
        (0, 3, 0, 1, 0)
    );
}

#[test]
fn nodes_address_their_part_of_the_slot() {
    // Level-3 tile (1, 2) at r = 2: its slot holds the tile at level 1, 4q + 1 samples a side.
    let item = DrawItem {
        refinement: 2,
        node_level: 2,
        node_tx: 3,
        node_ty: 4,
        ..DrawItem::whole(3, 1, 2, 0.0, 0.0)
    };
    assert_eq!(slot_placement(&item, Q), (32, 0, 2));
    assert_eq!(
        slot_placement(&DrawItem::whole(3, 1, 2, 0.0, 0.0), Q),
        (0, 0, 1)
    );
    // Every node of every split depth lies inside the slot, and the nodes of one depth tile it.
    for r in 1..=4u32 {
        let side = (Q << r) + 1;
        for depth in 0..=r {
            let level = 5;
            let n = 1u32 << depth;
            let mut covered = 0u64;
            for j in 0..n {
                for i in 0..n {
                    let node = DrawItem {
                        refinement: r,
                        node_level: level - depth,
                        node_tx: 3 * n + i,
                        node_ty: 2 * n + j,
                        ..DrawItem::whole(level, 3, 2, 0.0, 0.0)
                    };
                    let (x, y, stride) = slot_placement(&node, Q);
                    assert_eq!(stride, 1 << (r - depth));
                    assert!(x + stride * Q < side && y + stride * Q < side);
                    assert_eq!((x, y), (i * stride * Q, j * stride * Q));
                    covered += (stride as u64 * Q as u64).pow(2);
                }
            }
            assert_eq!(covered, ((side - 1) as u64).pow(2));
        }
    }
}

#[test]
fn instances_are_grouped_by_refinement_and_commands_follow_each_other() {
    let mut st = state(&[8, 8, 8, 8, 8, 0]);
    let select = SelectParams::default();
    let cam = camera(1280.0, 1280.0, 400.0, 0.0);
    let mut items = vec![DrawItem::whole(2, 0, 0, 0.5, 0.5)];
    items.extend(refined_tile(3, 1, 1, 2));
    items.push(DrawItem::whole(2, 1, 0, 0.5, 0.5));
    items.extend(refined_tile(2, 3, 3, 1));
    let everywhere = FrameInputs {
        skirts: SkirtRule::Everywhere,
        ..inputs(0, &cam, &select, 1 << 20)
    };
    let plan = plan_frame(&mut st, &everywhere, &selection(items.clone()), vec![]);
    let plan = plan.unwrap();
    let r: Vec<u32> = plan.instances.iter().map(|i| i.refinement).collect();
    let mut sorted = r.clone();
    sorted.sort();
    assert_eq!(r, sorted, "grouped by refinement");
    assert_eq!(r.len(), 1 + 16 + 1 + 4);
    // Skirts on every edge: per group its grid, then the four edges' skirts in one range
    // after it, for the same instances.
    let (grid, edge) = (MESHES.grid[0], MESHES.edge[0]);
    let mut want = Vec::new();
    for (first, n) in [(0, 2), (2, 4), (6, 16)] {
        want.push((0, grid, first, n));
        want.push((grid, 4 * edge, first, n));
    }
    assert_eq!(crate::render::terrain_draws::draw_ranges(&plan.draws), want);
    assert_eq!(INDICES.1, grid + 4 * edge);
    // Selection order inside a group: the two unrefined tiles, west first.
    assert_eq!(plan.instances[0].origin_sample, [0, 0]);
    assert_eq!(plan.instances[1].origin_sample, [(Q << 2) as i32, 0]);
    // The eye-relative origin is the sample origin in metres minus the eye.
    let i = &plan.instances[1];
    assert_eq!(i.origin_rel, [(640.0 - 1280.0) as f32, -1280.0]);
    assert_eq!(plan.stats.instances, 22);
    assert_eq!(plan.stats.triangles, 22 * (INDICES.1 as u64 / 3));
    assert_eq!((plan.draw_count, plan.stats.draw_calls), (6, 1));
    // Skirts where resolutions differ: the same grids, fewer skirts (the two unrefined
    // tiles side by side at one level share an edge), and the commands follow each other.
    let needed = plan_frame(
        &mut st,
        &inputs(1, &cam, &select, 1 << 20),
        &selection(items),
        vec![],
    )
    .unwrap();
    assert!(needed.stats.triangles < plan.stats.triangles);
    assert_eq!(
        needed.stats.triangles,
        needed
            .draws
            .iter()
            .map(|d| d.instance_count as u64 * d.index_count as u64 / 3)
            .sum::<u64>()
    );
    let grids: u32 = needed
        .draws
        .iter()
        .filter(|d| d.first_index == 0 && d.index_count == grid)
        .map(|d| d.instance_count)
        .sum();
    assert_eq!(grids, 22, "every node's grid drawn once");
    assert!(needed
        .draws
        .iter()
        .all(|d| d.first_instance + d.instance_count <= 22));
    // Nothing selected: no commands issued, no instances staged.
    let empty = plan_frame(
        &mut st,
        &inputs(1, &cam, &select, 1 << 20),
        &selection(vec![]),
        vec![],
    );
    let empty = empty.unwrap();
    assert_eq!((empty.draw_count, empty.stats.draw_calls), (0, 0));
    assert_eq!(empty.staged_bytes, fixed_pushes(0, 0, 0));
    // A tile without indices draws nothing, whatever the instances.
    let mut sizes = [0u32; INSTANCE_KEYS];
    (
        sizes[0],
        sizes[EDGE_COMBOS + edge_combo(15, 0)],
        sizes[RESOLUTIONS * EDGE_COMBOS],
    ) = (3, 1, 2);
    let (draws, tris) = indirect_draws(&sizes, TileMeshes::default());
    assert!(draws.is_empty() && tris == 0);
}

/// A real selection that refines: low over the rough terrain, looking along +x. `cap` None:
/// a region with room for the fixed pushes only.
fn refining_frame(
    st: &mut PlanState,
    frame: u64,
    cam: &Camera,
    prefetch: f64,
    cap: Option<u64>,
) -> FramePlan {
    let select = SelectParams {
        tau_px: 0.5,
        ..SelectParams::default()
    };
    let mut inp = inputs(frame, cam, &select, 0);
    inp.prefetch_frames = prefetch;
    let mut sel = Selection::default();
    let strips = select_frame(st, &inp, &mut sel);
    let fixed = fixed_reserve(sel.items.len(), false, None) + POOL_UPLOAD_SLACK_BYTES;
    inp.staging = StagingBudget::new(cap.unwrap_or(fixed), ALIGN);
    let plan = plan_frame(st, &inp, &sel, strips).unwrap();
    assert!(plan.staged_bytes <= inp.staging.capacity());
    plan
}

/// Refined tiles drawn at their own refinement (not late) in a plan.
fn drawn_keys(p: &FramePlan) -> Vec<TileKey> {
    let mut keys: Vec<TileKey> = p
        .draw_list
        .iter()
        .filter(|(d, _)| d.refinement > 0)
        .map(|(d, _)| TileKey {
            level: d.level,
            tx: d.tx,
            ty: d.ty,
            refinement: d.refinement,
        })
        .collect();
    keys.dedup();
    keys
}

const BIG: Option<u64> = Some(64 << 20);

/// The view ahead selected on the worker thread or inline when taken: the same plans frame by
/// frame — the protocol, not the worker's timing, decides what each frame prefetches from —
/// and the frames after a reselect prefetch from the selection of the previous reselect's
/// inputs (the first reselect's own, made on the frame thread, for the first two periods).
#[test]
fn the_view_ahead_selected_off_the_frame_thread_plans_as_inline() {
    let cam = |f: u64| camera(600.0 - 40.0 * f as f64, 1280.0, 300.0, 90.0);
    let run = |ahead: AheadSelector| {
        let mut st = state(&[64, 64, 64, 64, 64, 0]);
        st.ahead = ahead;
        let mut frames = Vec::new();
        let mut items = Vec::new();
        // Frame 30 comes after a gap: the request frame 13 sent is stale there, and frame 30
        // selects on its own thread again.
        for f in (0..15u64).chain([30]) {
            let p = refining_frame(&mut st, f, &cam(f), 20.0, BIG);
            let uploads: Vec<(TileKey, bool)> =
                p.pool_uploads.iter().map(|u| (u.key, u.prefetch)).collect();
            frames.push((uploads, p.stats.prefetched));
            items.push(st.prefetch_selection.items.clone());
        }
        (frames, items, st.prefetch_selections)
    };
    let (threaded, items, reselects) = run(AheadSelector::threaded());
    let prefetched: u32 = threaded.iter().map(|f| f.1).sum();
    assert!(prefetched > 0, "the flight prefetches");
    assert_eq!(reselects, 5, "frames 1, 5, 9, 13 and 30 select ahead");
    let (inline, inline_items, _) = run(AheadSelector::inline());
    assert_eq!(threaded, inline);
    assert_eq!(items, inline_items);
    // Frame 5 takes what frame 1 sent: frame 1's inputs, which frame 1 selected on its own.
    assert!(!items[1].is_empty());
    assert_eq!(items[5], items[1]);
    // Frame 9 takes frame 5's: the view ahead of a frame 160 m further on.
    assert_ne!(items[9], items[5]);
    // Frame 30 prefetches from its own view ahead, not from frame 13's.
    assert_ne!(items[15], items[14]);
    let mut own = Selection::default();
    let mut st = state(&[64, 64, 64, 64, 64, 0]);
    st.ahead = AheadSelector::inline();
    refining_frame(&mut st, 14, &cam(14), 20.0, BIG);
    refining_frame(&mut st, 30, &cam(30), 20.0, BIG);
    std::mem::swap(&mut own, &mut st.prefetch_selection);
    assert_eq!(items[15], own.items, "frame 30 selected its own view ahead");
    for f in [2, 3, 4] {
        assert_eq!(items[f], items[1], "frame {f} keeps the last reselect's");
    }
}

/// The first frame also selects the views around the eye (`warm_start.rs`): it draws what it
/// draws without them, prefetches their refined tiles (none of them drawn this frame), does
/// so once, and a view turned away in the next frames then finds its tiles in the pools.
#[test]
fn the_first_frame_prefetches_the_views_around_the_eye_and_draws_the_same() {
    let ahead = |f: u64| camera(600.0, 1280.0, 300.0, 90.0 + 30.0 * f as f64);
    let fly = |warm: bool| {
        let mut st = state(&[256, 256, 256, 256, 256, 0]);
        st.warm_start = warm;
        (0..4u64)
            .map(|f| refining_frame(&mut st, f, &ahead(f), 0.0, BIG))
            .collect::<Vec<_>>()
    };
    let (warm, cold) = (fly(true), fly(false));
    for (w, c) in warm.iter().zip(&cold) {
        assert_eq!(w.draw_list.len(), c.draw_list.len());
        assert!(
            w.draw_list
                .iter()
                .zip(&c.draw_list)
                .all(|(a, b)| a.0 == b.0),
            "the same nodes drawn"
        );
        assert_eq!(w.stats.triangles, c.stats.triangles);
    }
    assert_eq!(cold[0].stats.prefetched, 0, "no views around, no motion");
    assert!(
        warm[0].stats.prefetched > 0,
        "the views around are prefetched"
    );
    let drawn = drawn_keys(&warm[0]);
    let around: Vec<TileKey> = (warm[0].pool_uploads.iter())
        .filter(|u| u.prefetch)
        .map(|u| u.key)
        .collect();
    assert!(around.iter().all(|k| !drawn.contains(k)));
    assert_eq!(around.len() as u32, warm[0].stats.prefetched);
    assert!(warm[1..].iter().all(|p| p.stats.prefetched == 0), "once");
    // Turned 30°, 60° and 90° away: the tiles the turn needs are there already.
    let misses = |plans: &[FramePlan]| plans[1..].iter().map(|p| p.stats.pool_misses).sum::<u32>();
    assert!(misses(&cold) > 0, "the fixture must turn onto new tiles");
    assert!(
        misses(&warm) < misses(&cold),
        "{} against {}",
        misses(&warm),
        misses(&cold)
    );
}

/// A worker left without a request for longer than it looks for one waits to be woken
/// (`ahead_select::POLL_FOR`), and the request that wakes it is answered: across the pause the
/// same views ahead as inline, frame by frame.
#[test]
fn a_worker_that_stopped_looking_is_woken_by_the_next_request() {
    let cam = |f: u64| camera(600.0 - 40.0 * f as f64, 1280.0, 300.0, 90.0);
    let run = |ahead: AheadSelector, pause: std::time::Duration| {
        let mut st = state(&[64, 64, 64, 64, 64, 0]);
        st.ahead = ahead;
        let mut items = Vec::new();
        for f in 0..10u64 {
            if f == 3 {
                // Frame 1's request was answered long ago; the worker stops looking.
                std::thread::sleep(pause);
            }
            refining_frame(&mut st, f, &cam(f), 20.0, BIG);
            items.push(st.prefetch_selection.items.clone());
        }
        (items, st.ahead.on_worker())
    };
    let pause = crate::render::ahead_select::POLL_FOR * 2;
    let (threaded, worker) = run(AheadSelector::threaded(), pause);
    let (inline, _) = run(AheadSelector::inline(), std::time::Duration::ZERO);
    assert!(
        worker,
        "the worker answered, not the frame thread in its place"
    );
    assert_eq!(threaded, inline);
    // Frame 9 takes what frame 5 sent to the sleeping worker: another view than frame 5's.
    assert!(!threaded[9].is_empty());
    assert_ne!(threaded[9], threaded[5]);
}

/// With bands of 1,000 samples every prefetched tile larger than that (the 33² slots and up)
/// comes a band a frame: a frame's prefetch gathers at most one band of such a tile; each pool
/// upload, banded or not, stages exactly the samples one gather of its rectangle gives; and a
/// banded tile is staged only once whole, in a frame after its last band.
#[test]
fn large_prefetches_come_a_band_a_frame_and_stage_their_whole_tile() {
    use crate::render::banded::BandedTile;
    use crate::render::gathered::SampleCursor;
    let mut st = state(&[64, 64, 64, 64, 64, 0]);
    st.banded = BandedTile::new(1000);
    let source = st.feed.gatherer.source().clone();
    let cam = |x: f64| camera(x, 1280.0, 300.0, 90.0);
    let (mut banded_uploads, mut bands_before) = (0, 0);
    for f in 0..24u64 {
        let in_hand = st.banded.key();
        let p = refining_frame(&mut st, f, &cam(600.0 - 25.0 * f as f64), 20.0, BIG);
        let bands = st.banded.bands - bands_before;
        bands_before = st.banded.bands;
        assert!(bands <= 1, "frame {f}: {bands} bands");
        // The frame's samples in staging order: spilled strips, strips, then pool uploads.
        let mut cursor = SampleCursor::new(st.feed.gatherer.samples());
        for job in p.spilled_strips.iter().flatten().chain(&p.strips) {
            cursor.next(job).unwrap();
        }
        for u in &p.pool_uploads {
            let got = cursor.next(&u.upload).expect("samples for every upload");
            let mut want = vec![0.0; got.len()];
            source.gather(&u.upload.sample_rect(), &mut want).unwrap();
            assert_eq!(got, want.as_slice(), "frame {f}: {:?}", u.key);
            if u.prefetch && u.upload.sample_rect().len() > 1000 {
                banded_uploads += 1;
                // In hand before the frame, whole (a frame that gathers a tile's last band
                // does not stage it), and let go.
                assert_eq!(in_hand, Some(u.key), "frame {f}");
                assert_ne!(st.banded.key(), Some(u.key), "frame {f}");
            }
        }
        assert_eq!(cursor.left(), 0);
    }
    assert!(banded_uploads > 0, "the flight prefetches banded tiles");
    assert!(
        st.banded.bands >= 2 * banded_uploads,
        "each of them in bands"
    );
}

#[test]
fn prefetch_follows_the_motion_only_and_spares_recent_draws() {
    let mut st = state(&[64, 64, 64, 64, 64, 0]);
    // The first frame like any other (the views around the eye: `the_first_frame_...`).
    st.warm_start = false;
    let cam = |x: f64| camera(x, 1280.0, 300.0, 90.0);
    // Backing away westwards while looking east: the refined band ahead moves west.
    let first = refining_frame(&mut st, 0, &cam(600.0), 20.0, BIG);
    assert!(first.stats.pool_misses > 0, "the fixture must refine");
    assert_eq!(first.stats.prefetched, 0, "no previous eye, no motion");
    let still = refining_frame(&mut st, 1, &cam(600.0), 20.0, BIG);
    assert_eq!(still.stats.prefetched, 0, "no motion, nothing ahead");
    let moving = refining_frame(&mut st, 2, &cam(560.0), 20.0, BIG);
    assert!(
        moving.stats.prefetched > 0,
        "moving prefetches what lies ahead"
    );
    let ahead = moving.pool_uploads.iter().filter(|p| p.prefetch);
    let drawn = drawn_keys(&moving);
    assert!(
        ahead.clone().all(|p| !drawn.contains(&p.key)),
        "prefetch uploads only tiles not drawn this frame"
    );
    assert_eq!(ahead.count() as u32, moving.stats.prefetched);
    // The view ahead is selected once every PREFETCH_RESELECT_FRAMES moving frames; the
    // frames between keep prefetching from it.
    assert_eq!(st.prefetch_selections, 1);
    let mut prefetched = 0;
    for f in 3..3 + 2 * PREFETCH_RESELECT_FRAMES {
        let p = refining_frame(&mut st, f, &cam(560.0 - 40.0 * (f - 2) as f64), 20.0, BIG);
        prefetched += p.stats.prefetched;
    }
    assert_eq!(st.prefetch_selections, 3, "frames 2, 6 and 10 select ahead");
    assert!(prefetched > 0, "the frames between still prefetch");

    // Pools exactly as large as one frame needs: after that frame every slot was drawn in the
    // last two frames, so a prefetch finds no victim.
    let mut st = state(&[0, 0, 0, 0, 0, 0]);
    st.warm_start = false;
    let probe = refining_frame(&mut st, 0, &cam(600.0), 0.0, BIG);
    let mut caps = [0u32; 6];
    for l in &probe.late {
        caps[l.key.refinement as usize - 1] += 1;
    }
    let mut st = state(&caps);
    st.warm_start = false;
    let full = refining_frame(&mut st, 0, &cam(600.0), 0.0, BIG);
    assert_eq!(full.stats.tiles_late, 0);
    let recent = drawn_keys(&full);
    let next = refining_frame(&mut st, 1, &cam(610.0), 50.0, BIG);
    assert_eq!(next.stats.prefetched, 0, "every slot is protected");
    for p in next.pool_uploads.iter().filter(|p| p.prefetch) {
        assert!(!p.evicted.is_some_and(|e| recent.contains(&e)), "{p:?}");
    }
    assert!(st.pools.iter().all(|p| p.lru.counters().prefetches == 0));

    // No budget beyond the frame's fixed pushes: nothing is uploaded, nothing prefetched.
    let mut st = state(&[64, 64, 64, 64, 64, 0]);
    refining_frame(&mut st, 0, &cam(600.0), 20.0, BIG);
    let tight = refining_frame(&mut st, 1, &cam(640.0), 20.0, None);
    assert_eq!((tight.stats.prefetched, tight.stats.pool_misses), (0, 0));
    assert!(tight.pool_uploads.is_empty());
}

/// The digest names the selection: equal lists give equal digests, and changing any field of
/// any node, or the order of two nodes, changes it.
#[test]
fn the_selection_digest_changes_with_any_node_field_or_order() {
    let sel = Selection {
        items: (0..40u32)
            .map(|k| DrawItem {
                refinement: k % 3,
                node_level: 4 - k % 3,
                node_tx: 7 * k,
                node_ty: 3 * k + 1,
                ..DrawItem::whole(4, k, 2 * k, 1.0, 0.5)
            })
            .collect(),
        ..Selection::default()
    };
    let base = selection_digest(&sel);
    assert_eq!(base, selection_digest(&sel.clone()));
    let fields: [fn(&mut DrawItem); 7] = [
        |i| i.level += 1,
        |i| i.tx += 1,
        |i| i.ty += 1,
        |i| i.refinement += 1,
        |i| i.node_level += 1,
        |i| i.node_tx += 1,
        |i| i.node_ty += 1,
    ];
    for k in [0, 17, 39] {
        for (f, change) in fields.iter().enumerate() {
            let mut other = sel.clone();
            change(&mut other.items[k]);
            assert_ne!(selection_digest(&other), base, "node {k}, field {f}");
        }
    }
    let mut swapped = sel.clone();
    swapped.items.swap(3, 4);
    assert_ne!(selection_digest(&swapped), base);
    swapped.items.truncate(39);
    assert_ne!(selection_digest(&swapped), base);
}

#[test]
fn channels_share_one_selection_whichever_is_drawn() {
    let select = SelectParams {
        tau_px: 0.5,
        ..SelectParams::default()
    };
    let left = camera(1280.0, 1280.0, 300.0, 45.0);
    let right = camera(1280.0, 1280.0, 300.0, 135.0);
    let channels = vec![(left, (320, 180), 0.5), (right, (320, 180), 0.5)];
    let run = |drawn: &Camera| {
        let mut st = state(&[64, 64, 64, 64, 64, 0]);
        let mut inp = inputs(0, drawn, &select, 8 << 20);
        inp.channels = &channels;
        let mut sel = Selection::default();
        let strips = select_frame(&mut st, &inp, &mut sel);
        let plan = plan_frame(&mut st, &inp, &sel, strips).unwrap();
        (sel.items, plan.stats.selection_digest)
    };
    let (a, da) = run(&left);
    let (b, db) = run(&right);
    assert_eq!(a, b);
    assert_eq!(da, db);
    // The shared selection draws each tile at least as fine as either channel alone.
    let single = |cam: &Camera| {
        let mut st = state(&[64, 64, 64, 64, 64, 0]);
        let inp = inputs(0, cam, &select, 8 << 20);
        let mut sel = Selection::default();
        select_frame(&mut st, &inp, &mut sel);
        sel.items
    };
    for alone in [single(&left), single(&right)] {
        for i in alone.iter().filter(|i| i.refinement > 0) {
            let shared = a
                .iter()
                .filter(|s| (s.level, s.tx, s.ty) == (i.level, i.tx, i.ty))
                .map(|s| s.refinement)
                .max();
            assert!(shared >= Some(i.refinement), "{i:?} coarser when shared");
        }
    }
    assert!(
        a.iter().any(|i| i.refinement > 0),
        "the fixture must refine"
    );
}

/// Channels sharing a selection: the n renders of a frame (one per channel) select once, so a
/// frame costs O(n), not O(n²); each render gets the selection made for all the channels, and
/// a new channel set (the next frame's cameras) selects again.
#[test]
fn channels_sharing_a_selection_select_once_per_frame() {
    let mut st = state(&[8, 8, 8, 8, 8, 0]);
    let select = SelectParams::default();
    let n = 12;
    for frame in 0..3u64 {
        let chans: Vec<(Camera, (u32, u32), f64)> = (0..n)
            .map(|k| {
                let heading = k as f64 * 360.0 / n as f64;
                (
                    camera(1280.0 + 40.0 * frame as f64, 1280.0, 300.0, heading),
                    (320, 180),
                    1.0,
                )
            })
            .collect();
        // What one selection for all of them gives.
        let views: Vec<View> = chans
            .iter()
            .map(|(camera, viewport, tau_px)| View {
                camera,
                viewport: *viewport,
                tau_px: *tau_px,
            })
            .collect();
        let placements = place_levels(&st.clipmap, eye_samples(chans[0].0.position, st.spacing));
        let mut want = Selection::default();
        select_tiles_multi(
            &st.bake,
            &st.clipmap,
            &placements,
            &views,
            &select,
            &mut want,
        );
        assert!(!want.items.is_empty());
        for (cam, _, _) in &chans {
            let mut inp = inputs(frame, cam, &select, 1 << 24);
            inp.channels = &chans;
            inp.channels_generation = frame + 1;
            let mut sel = Selection::default();
            select_frame(&mut st, &inp, &mut sel);
            assert_eq!(sel.items, want.items, "frame {frame}");
        }
    }
    assert_eq!(st.shared_selections, 3, "one shared selection per frame");
}

/// Every planner — the renderer, `fly --no-draw`, the benchmarks — plans a geographic grid on
/// the ellipsoid and the rest on the flat plane: the planner decides it from its source's grid
/// (`fly --no-draw` once planned geographic data flat, so its CPU figures were of another
/// path than the renderer's), and the frame's instance records then carry ellipsoid frames.
#[test]
fn geographic_data_is_planned_on_the_ellipsoid_by_every_planner() {
    let frame_of = |st: &mut PlanState| {
        let select = SelectParams::default();
        let cam = camera(1280.0, 1280.0, 900.0, 30.0);
        let inp = inputs(0, &cam, &select, 64 << 20);
        let mut sel = Selection::default();
        let strips = select_frame(st, &inp, &mut sel);
        plan_frame(st, &inp, &sel, strips).unwrap()
    };
    let mut flat = state(&[8; 6]);
    assert!(flat.earth.is_none());
    let plan = frame_of(&mut flat);
    assert!(!plan.instances.is_empty());
    assert!(plan.instances.iter().all(|i| i.geo_origin == [0.0; 4]));

    let d = 1.0 / 1200.0;
    let mut hf = rough_dataset().hf.clone();
    hf.geo = Some(aerie_terrain::GeoReference::Geographic {
        south_lat_deg: 47.0,
        west_lon_deg: 11.0,
        dlat_deg: d,
        dlon_deg: d,
    });
    (hf.spacing_x, hf.spacing_y) = aerie_terrain::load::geographic_spacing_m(47.05, d, d);
    let ds = Arc::new(Dataset::from_heightfield(
        hf,
        "plan test, geographic".into(),
    ));
    let b = Arc::new(bake(&ds, BakeParams::default(), &|_, _| {}));
    let mut geo = PlanState::new(b, Arc::new(InMemoryTerrain::new(ds)), clipmap(), &[8; 6]);
    let earth = geo
        .earth
        .expect("a geographic grid is drawn on the ellipsoid");
    assert_eq!((earth.south_lat_deg, earth.west_lon_deg), (47.0, 11.0));
    let plan = frame_of(&mut geo);
    assert!(!plan.instances.is_empty());
    // geo_origin.w is the grid's latitude step in radians: the shader's ellipsoid path.
    let dlat = d.to_radians() as f32;
    assert!(plan.instances.iter().all(|i| i.geo_origin[3] == dlat));
}

/// The staging region grows only when the frame's fixed pushes would take more than half of
/// it, to a power of two that holds them beside the upload budget.
#[test]
fn the_staging_region_grows_only_for_records_that_crowd_it() {
    use crate::render::jobs::staging_to_hold;
    const MIB: u64 = 1 << 20;
    assert_eq!(staging_to_hold(8 * MIB, 8 * MIB, 4 * MIB), None);
    assert_eq!(
        staging_to_hold(8 * MIB, 8 * MIB, 4 * MIB + 1),
        Some(16 * MIB)
    );
    assert_eq!(staging_to_hold(8 * MIB, 8 * MIB, 9 * MIB), Some(32 * MIB));
    // A tiny upload budget: the records' double.
    assert_eq!(staging_to_hold(MIB / 2, MIB / 2, 3 * MIB), Some(8 * MIB));
    // Once grown, the same records fit.
    assert_eq!(staging_to_hold(16 * MIB, 8 * MIB, 4 * MIB + 1), None);
    // The reserve counts every selected node's record.
    let per = std::mem::size_of::<TileInstance>() as u64;
    assert!(fixed_reserve(10_000, false, None) >= 10_000 * per);
    // And on a projected grid each one's polynomials besides.
    let poly = std::mem::size_of::<crate::render::gpu::GeoPolynomial>() as u64;
    assert!(fixed_reserve(10_000, true, None) >= 10_000 * (per + poly));
    assert!(fixed_reserve(10_000, false, None) < 10_000 * (per + poly));
}
