//! The frame plan: every decision of a frame, as a pure function of plain data (no Vulkan).
//!
//! [`select_frame`] places the clipmap levels around the eye — once per frame — turns the levels
//! that moved into strip uploads and selects the tiles for the frame's view(s). [`plan_frame`]
//! then spends one staging region on them and returns a [`FramePlan`]: strips staged this frame
//! or spilled into their own submissions, refined-tile pool uploads and evictions, late tiles
//! drawn coarser, the instance records and indirect commands, and the frame's statistics. The
//! renderer stages exactly what the plan says, records it and submits.
//!
//! Invariants (checked or tested in `plan_tests.rs`):
//! - **Budget order.** Clipmap strips come first and are mandatory: if they (with the frame's
//!   fixed pushes reserved) do not fit the region, they all spill into extra submissions before
//!   the frame; pool misses and then prefetches spend only what is left after the reserve.
//! - **Staged bytes.** `FramePlan::staged_bytes` is what staging the plan in order takes from a
//!   fresh region (alignment padding included) and never exceeds its capacity.
//! - **Late tiles.** A refined tile whose upload does not fit is drawn at its best resident
//!   resolution r' < r (r' = 0, the clipmap, always is): each node finer than level L − r'
//!   becomes its ancestor at that level, duplicates dropped, and the tile counts late once.
//! - **Instances.** Grouped by refinement (unrefined first), selection order inside a group;
//!   indirect command r starts at the sum of the groups before it; triangles = instances ×
//!   triangles per skirted tile.
//! - **Prefetch** happens only along the eye's motion, never evicts a slot drawn in the last
//!   [`PREFETCH_PROTECT_FRAMES`] frames, and stops at the first tile the budget cannot take.

use std::sync::Arc;

use glam::DVec3;

use aerie_terrain::bake::ErrorBake;
use aerie_terrain::camera::Camera;
use aerie_terrain::clipmap::{place_levels, CacheRegion, ClipmapDesc, LevelPlacement};
use aerie_terrain::pool::{RefinedTilePool, Request, TileKey};
use aerie_terrain::select::{
    neighbour_eps, select_tiles, select_tiles_multi, DrawItem, SelectParams, Selection, View,
};

use crate::render::gpu::{DrawIndexedIndirect, FrameUniforms, TileInstance};
use crate::render::jobs::{
    eye_samples, refined_upload, split_into_submissions, strip_uploads, ImageUpload, PlanError,
    StagingBudget, TEXEL_BYTES,
};
use crate::render::stats::{FrameStats, RESOLUTIONS};

/// Largest number of m×m instances one frame may draw (48 bytes each per frame in flight): the
/// instance buffers grow on demand up to this — `full` on a large dataset draws every visible
/// finest node.
pub const MAX_INSTANCES: usize = 1 << 20;

/// Reserved besides the frame's listed fixed pushes: the frame uniforms (144 bytes) and the
/// alignment padding in front of each of the fixed pushes (uniforms, indirect commands,
/// instances, overlay), so that a frame whose uploads were admitted never fails its pushes.
pub const FIXED_SLACK_BYTES: u64 = 1024;
/// Alignment padding in front of the overlay panel's pixels, on top of [`FIXED_SLACK_BYTES`].
pub const OVERLAY_SLACK_BYTES: u64 = 16;
/// Alignment padding each in-frame clipmap strip copy may add (offset alignments up to 64).
pub const STRIP_SLACK_BYTES: u64 = 64;
/// Headroom a pool upload must leave above the reserve: its own alignment padding plus that of
/// the uploads staged before it, which the reserve does not count.
pub const POOL_UPLOAD_SLACK_BYTES: u64 = 256;
/// A prefetch never evicts a slot drawn in this many most recent frames.
pub const PREFETCH_PROTECT_FRAMES: u64 = 2;

/// A refined-tile pool's bookkeeping: its LRU and the samples per slot side, 2^r(m−1)+1.
#[derive(Debug, Clone)]
pub struct PoolSlots {
    pub side: u32,
    pub lru: RefinedTilePool,
}

impl PoolSlots {
    pub fn slot_bytes(&self) -> u64 {
        self.side as u64 * self.side as u64 * TEXEL_BYTES
    }
}

/// The CPU state a plan reads and advances: clipmap cache regions, pool bookkeeping and the
/// previous eye (for prefetch), with the dataset's bake and sample spacing.
pub struct PlanState {
    pub bake: Arc<ErrorBake>,
    /// Metres between samples (x east, y north).
    pub spacing: [f64; 2],
    pub clipmap: ClipmapDesc,
    /// Each level's cached region (None: never filled).
    pub caches: Vec<Option<CacheRegion>>,
    /// Pools for r = 1..=MAX_REFINEMENT (index r − 1).
    pub pools: Vec<PoolSlots>,
    /// Eye of the previous planned frame.
    pub prev_eye: Option<DVec3>,
    prefetch_selection: Selection,
    shared: SharedSelection,
    /// Shared (multi-channel) selections made so far: one per frame, whatever the channel count.
    pub shared_selections: u64,
}

/// The selection shared by a set of channels, kept while the set and the level placement stay
/// the same: a frame renders each of its n channels once, and they all draw this one selection,
/// so it is made once per frame, not n times (each costs O(n): a frame would be O(n²)).
#[derive(Default)]
struct SharedSelection {
    /// The channels' generation, the placement and the parameters it was made for.
    key: Option<(u64, Vec<LevelPlacement>, SelectParams)>,
    selection: Selection,
}

impl PlanState {
    pub fn new(
        bake: Arc<ErrorBake>,
        spacing: [f64; 2],
        clipmap: ClipmapDesc,
        pool_capacity: &[u32],
    ) -> Self {
        let levels = clipmap.level_count() as usize;
        let pools = (1..=pool_capacity.len() as u32)
            .map(|r| PoolSlots {
                side: (clipmap.tile_quads << r) + 1,
                lru: RefinedTilePool::new(pool_capacity[r as usize - 1]),
            })
            .collect();
        Self {
            bake,
            spacing,
            clipmap,
            caches: vec![None; levels],
            pools,
            prev_eye: None,
            prefetch_selection: Selection::default(),
            shared: SharedSelection::default(),
            shared_selections: 0,
        }
    }

    /// The level-texture uploads that fill (or refresh) every level around `eye`.
    pub fn strips_around(&mut self, eye: DVec3) -> Vec<ImageUpload> {
        let placements = place_levels(&self.clipmap, eye_samples(eye, self.spacing));
        strip_uploads(&self.clipmap, &mut self.caches, &placements)
    }
}

/// What a plan reads besides its state: the frame's view, parameters and staging region.
#[derive(Clone, Copy)]
pub struct FrameInputs<'a> {
    pub frame: u64,
    pub camera: &'a Camera,
    pub viewport: (u32, u32),
    /// Channels (camera, viewport, τ) sharing one selection; empty: select for `camera` only.
    pub channels: &'a [(Camera, (u32, u32), f64)],
    /// Changes whenever `channels` does (the renderer counts its `set_channels` calls): the
    /// shared selection is reused while it stays the same.
    pub channels_generation: u64,
    pub select: &'a SelectParams,
    /// Prefetch looks this many frames ahead along the eye's motion (≤ 0: off).
    pub prefetch_frames: f64,
    pub skirt_factor: f32,
    pub skirt_min_m: f32,
    /// Bytes of the overlay panel staged with the frame (None: no overlay set).
    pub overlay_bytes: Option<u64>,
    /// Indices of one skirted tile in the shared index buffer: (first, count).
    pub tile_indices: (u32, u32),
    /// The frame's staging region, empty.
    pub staging: StagingBudget,
}

/// A pool upload: refined tile `key` into slot `upload.layer` of pool r = `key.refinement`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PoolUpload {
    pub key: TileKey,
    pub upload: ImageUpload,
    /// What the slot held before (evicted by this upload).
    pub evicted: Option<TileKey>,
    pub prefetch: bool,
}

/// A refined tile drawn coarser this frame: `key` was asked for, `drawn_refinement` was resident.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LateTile {
    pub key: TileKey,
    pub drawn_refinement: u32,
}

/// Everything a frame does, as data.
#[derive(Debug, Clone, Default)]
pub struct FramePlan {
    /// Strip uploads streamed before the frame, one inner list per extra submission.
    pub spilled_strips: Vec<Vec<ImageUpload>>,
    /// Strip uploads staged in the frame's own region (layer = level).
    pub strips: Vec<ImageUpload>,
    /// Pool uploads in staging order (misses in selection order, then prefetches).
    pub pool_uploads: Vec<PoolUpload>,
    pub late: Vec<LateTile>,
    /// What is drawn: selected nodes (late tiles coarsened) with their pool slot.
    pub draw_list: Vec<(DrawItem, u32)>,
    /// Instance records, grouped by refinement (r = 0 first).
    pub instances: Vec<TileInstance>,
    /// One indexed indirect command per refinement group.
    pub draws: [DrawIndexedIndirect; RESOLUTIONS],
    /// Commands the multi-draw issues: every group, or none when nothing is drawn.
    pub draw_count: u32,
    /// Bytes staging the plan takes from the frame's region, padding included.
    pub staged_bytes: u64,
    pub stats: FrameStats,
}

/// Bytes the frame's fixed pushes need besides the uploads: indirect commands, one instance per
/// selected node (coarsening only lowers the count), the overlay, and their slack.
pub fn fixed_reserve(selected_nodes: usize, overlay_bytes: Option<u64>) -> u64 {
    let overlay = overlay_bytes.map_or(0, |b| b + OVERLAY_SLACK_BYTES);
    FIXED_SLACK_BYTES
        + (std::mem::size_of::<DrawIndexedIndirect>() * RESOLUTIONS) as u64
        + (selected_nodes * std::mem::size_of::<TileInstance>()) as u64
        + overlay
}

/// Places the levels around the eye, turns the levels that moved into strip uploads (advancing
/// the cache regions) and selects the frame's tiles into `out`: for `camera` alone, or once for
/// every channel (per tile the largest ρ/τ among the channels that see it).
pub fn select_frame(
    state: &mut PlanState,
    inputs: &FrameInputs,
    out: &mut Selection,
) -> Vec<ImageUpload> {
    let placements = place_levels(
        &state.clipmap,
        eye_samples(inputs.camera.position, state.spacing),
    );
    let strips = strip_uploads(&state.clipmap, &mut state.caches, &placements);
    if inputs.channels.is_empty() {
        let (camera, viewport) = (inputs.camera, inputs.viewport);
        select_tiles(
            &state.bake,
            &state.clipmap,
            &placements,
            camera,
            viewport,
            inputs.select,
            out,
        );
    } else {
        let key = (inputs.channels_generation, placements, *inputs.select);
        if state.shared.key.as_ref() == Some(&key) {
            out.clone_from(&state.shared.selection);
            return strips;
        }
        let placements = &key.1;
        let views: Vec<View> = inputs
            .channels
            .iter()
            .map(|(camera, viewport, tau_px)| View {
                camera,
                viewport: *viewport,
                tau_px: *tau_px,
            })
            .collect();
        select_tiles_multi(
            &state.bake,
            &state.clipmap,
            placements,
            &views,
            inputs.select,
            out,
        );
        state.shared_selections += 1;
        state.shared.selection.clone_from(out);
        state.shared.key = Some(key);
    }
    strips
}

/// Plans the frame for `selection` and the `strips` [`select_frame`] returned (see the module
/// invariants). Advances the pools' bookkeeping and the previous eye.
pub fn plan_frame(
    state: &mut PlanState,
    inputs: &FrameInputs,
    selection: &Selection,
    strips: Vec<ImageUpload>,
) -> Result<FramePlan, PlanError> {
    let mut plan = FramePlan {
        stats: selection_stats(inputs.frame, selection),
        ..Default::default()
    };
    let mut budget = inputs.staging;
    let reserve = fixed_reserve(selection.items.len(), inputs.overlay_bytes);

    // Strips first, mandatory: all in this frame, or all streamed before it.
    let strip_bytes: u64 = strips.iter().map(ImageUpload::bytes).sum();
    plan.stats.bytes_clipmap = strip_bytes;
    if strip_bytes + reserve + STRIP_SLACK_BYTES * strips.len() as u64 > budget.capacity() {
        // A jump (or a tiny budget).
        plan.spilled_strips =
            split_into_submissions(&strips, budget.capacity(), budget.alignment())?;
        plan.stats.budget_spills = plan.spilled_strips.len() as u32;
    } else {
        for s in &strips {
            budget.take(s.bytes())?;
        }
        plan.strips = strips;
    }

    for p in &mut state.pools {
        p.lru.begin_frame(inputs.frame);
    }
    resolve_refined_tiles(state, selection, &mut budget, reserve, &mut plan)?;
    prefetch(state, inputs, &mut budget, reserve, &mut plan)?;

    let (instances, groups) = build_instances(state, inputs, &plan.draw_list);
    let (draws, triangles) = indirect_draws(&groups, inputs.tile_indices);
    let total = instances.len();
    if total > MAX_INSTANCES {
        return Err(PlanError::Other(format!(
            "selection of {total} tiles exceeds the largest instance buffer ({MAX_INSTANCES})"
        )));
    }
    plan.draw_count = if total > 0 { RESOLUTIONS as u32 } else { 0 };
    plan.stats.instances = total as u32;
    plan.stats.triangles = triangles;
    plan.stats.draw_calls = (plan.draw_count > 0) as u32;

    // The fixed pushes, in the order the renderer stages them.
    budget.take(std::mem::size_of::<FrameUniforms>() as u64)?;
    budget.take(std::mem::size_of_val(&draws) as u64)?;
    if total > 0 {
        budget.take((total * std::mem::size_of::<TileInstance>()) as u64)?;
    }
    if let Some(bytes) = inputs.overlay_bytes.filter(|&b| b > 0) {
        budget.take(bytes)?;
    }
    plan.instances = instances;
    plan.draws = draws;
    plan.staged_bytes = budget.used();
    plan.stats.bytes_uploaded = budget.used();
    state.prev_eye = Some(inputs.camera.position);
    Ok(plan)
}

/// The statistics the selection alone decides.
fn selection_stats(frame: u64, sel: &Selection) -> FrameStats {
    let mut stats = FrameStats {
        frame,
        selection_digest: selection_digest(sel),
        finest_level: sel.finest_level,
        tiles_unbounded: sel.unbounded,
        ..Default::default()
    };
    for l in &sel.levels {
        stats.tiles_considered += l.considered;
        stats.tiles_culled += l.culled;
        stats.tiles_drawn += l.drawn;
        for (sum, n) in stats.tiles_by_refinement.iter_mut().zip(l.refined) {
            *sum += n;
        }
    }
    stats
}

/// FNV-1a over every selected node: channels drawn from one shared selection report the same.
pub fn selection_digest(sel: &Selection) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for i in &sel.items {
        for v in [
            i.level,
            i.tx,
            i.ty,
            i.refinement,
            i.node_level,
            i.node_tx,
            i.node_ty,
        ] {
            h = (h ^ v as u64).wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

/// Whether a pool upload of `slot_bytes` fits what is left above the reserve.
fn upload_fits(budget: &StagingBudget, slot_bytes: u64, reserve: u64) -> bool {
    budget.remaining() >= slot_bytes + reserve + POOL_UPLOAD_SLACK_BYTES
}

/// Finds or uploads the pool slot of every refined ring tile (its nodes follow one another in
/// the selection) and fills `plan.draw_list`. A miss that does not fit the budget leaves the
/// tile at its best resident resolution — its nodes coarsened to that level — and is late.
fn resolve_refined_tiles(
    state: &mut PlanState,
    selection: &Selection,
    budget: &mut StagingBudget,
    reserve: u64,
    plan: &mut FramePlan,
) -> Result<(), PlanError> {
    let q = state.clipmap.tile_quads;
    let items = &selection.items;
    let mut k = 0;
    while k < items.len() {
        let first = items[k];
        let end = k + items[k..]
            .iter()
            .take_while(|i| (i.level, i.tx, i.ty) == (first.level, first.tx, first.ty))
            .count();
        let group = &items[k..end];
        k = end;
        let r = first.refinement;
        if r == 0 {
            plan.draw_list.extend(group.iter().map(|&i| (i, 0)));
            continue;
        }
        let key = TileKey {
            level: first.level,
            tx: first.tx,
            ty: first.ty,
            refinement: r,
        };
        let pool = &mut state.pools[r as usize - 1];
        let slot_bytes = pool.slot_bytes();
        let side = pool.side;
        let request = pool
            .lru
            .request(key, &mut || upload_fits(budget, slot_bytes, reserve));
        let (resident_r, slot) = match request {
            Request::Hit { slot } => {
                plan.stats.pool_hits += 1;
                (r, slot)
            }
            Request::Miss { slot, evicted } => {
                plan.stats.pool_misses += 1;
                let upload = refined_upload(q, &key, slot, side);
                budget.take(upload.bytes())?;
                plan.stats.bytes_refined += upload.bytes();
                plan.pool_uploads.push(PoolUpload {
                    key,
                    upload,
                    evicted,
                    prefetch: false,
                });
                (r, slot)
            }
            Request::Unavailable => {
                plan.stats.tiles_late += 1;
                let best = best_resident(&mut state.pools, key);
                plan.late.push(LateTile {
                    key,
                    drawn_refinement: best.0,
                });
                best
            }
        };
        if resident_r == r {
            plan.draw_list.extend(group.iter().map(|&i| (i, slot)));
        } else {
            coarsen(&state.bake, group, resident_r, slot, &mut plan.draw_list);
        }
    }
    Ok(())
}

/// The best resolution below `key.refinement` resident for the tile, and its slot (marked drawn
/// this frame); r = 0, the clipmap, is always there.
fn best_resident(pools: &mut [PoolSlots], key: TileKey) -> (u32, u32) {
    for lower in (1..key.refinement).rev() {
        let k2 = TileKey {
            refinement: lower,
            ..key
        };
        let p2 = &mut pools[lower as usize - 1];
        if p2.lru.is_resident(&k2) {
            if let Request::Hit { slot } = p2.lru.request(k2, &mut || false) {
                return (lower, slot);
            }
        }
    }
    (0, 0)
}

/// Appends `group` (one ring tile's nodes) drawn at refinement `resident_r` < theirs: nodes
/// finer than level L − r' become their ancestor at that level, each drawn once.
fn coarsen(
    bake: &ErrorBake,
    group: &[DrawItem],
    resident_r: u32,
    slot: u32,
    draw_list: &mut Vec<(DrawItem, u32)>,
) {
    let floor = group[0].level - resident_r;
    let start = draw_list.len();
    for &i in group {
        let up = floor.saturating_sub(i.node_level);
        let node_level = i.node_level.max(floor);
        let (node_tx, node_ty) = (i.node_tx >> up, i.node_ty >> up);
        let coarse = DrawItem {
            refinement: resident_r,
            node_level,
            node_tx,
            node_ty,
            eps_m: bake.eps(node_level, node_tx, node_ty),
            ..i
        };
        let seen = draw_list[start..]
            .iter()
            .any(|(d, _)| (d.node_level, d.node_tx, d.node_ty) == (node_level, node_tx, node_ty));
        if !seen {
            draw_list.push((coarse, slot));
        }
    }
}

/// Uploads, with whatever budget is left, the refined tiles the eye will need
/// `prefetch_frames` frames from now along its motion (DESIGN.md "Pools": we budget and
/// prefetch them). Never evicts a slot drawn in the last [`PREFETCH_PROTECT_FRAMES`] frames.
fn prefetch(
    state: &mut PlanState,
    inputs: &FrameInputs,
    budget: &mut StagingBudget,
    reserve: u64,
    plan: &mut FramePlan,
) -> Result<(), PlanError> {
    let Some(prev) = state.prev_eye else {
        return Ok(());
    };
    let camera = inputs.camera;
    let motion = camera.position - prev;
    if motion.length_squared() < 1e-6 || inputs.prefetch_frames <= 0.0 {
        return Ok(());
    }
    let ahead = Camera {
        position: camera.position + motion * inputs.prefetch_frames,
        ..*camera
    };
    let placements = place_levels(&state.clipmap, eye_samples(ahead.position, state.spacing));
    select_tiles(
        &state.bake,
        &state.clipmap,
        &placements,
        &ahead,
        inputs.viewport,
        inputs.select,
        &mut state.prefetch_selection,
    );
    let q = state.clipmap.tile_quads;
    let mut last = None;
    for item in &state.prefetch_selection.items {
        if item.refinement == 0 || last == Some((item.level, item.tx, item.ty)) {
            continue;
        }
        last = Some((item.level, item.tx, item.ty));
        let key = TileKey {
            level: item.level,
            tx: item.tx,
            ty: item.ty,
            refinement: item.refinement,
        };
        let pool = &mut state.pools[item.refinement as usize - 1];
        if pool.lru.is_resident(&key) || pool.lru.capacity() == 0 {
            continue;
        }
        let slot_bytes = pool.slot_bytes();
        let request = pool.lru.prefetch(
            key,
            &mut || upload_fits(budget, slot_bytes, reserve),
            PREFETCH_PROTECT_FRAMES,
        );
        if let Request::Miss { slot, evicted } = request {
            let upload = refined_upload(q, &key, slot, pool.side);
            budget.take(upload.bytes())?;
            plan.stats.bytes_refined += upload.bytes();
            plan.stats.prefetched += 1;
            plan.pool_uploads.push(PoolUpload {
                key,
                upload,
                evicted,
                prefetch: true,
            });
        } else if !upload_fits(budget, slot_bytes, reserve) {
            break;
        }
    }
    Ok(())
}

/// Where a node lies in its pool slot: the slot holds the ring tile at level L − r, so a node
/// at `node_level` starts `(slot_x, slot_y)` slot texels in and steps `slot_stride` texels per
/// vertex. Unrefined nodes (r = 0) read the clipmap: (0, 0, 1).
pub fn slot_placement(item: &DrawItem, tile_quads: u32) -> (u32, u32, u32) {
    let r = item.refinement;
    if r == 0 {
        return (0, 0, 1);
    }
    let q = tile_quads as i64;
    let node = q << item.node_level;
    let origin = [item.node_tx as i64 * node, item.node_ty as i64 * node];
    let tile = q << item.level;
    let slot_step = 1i64 << (item.level - r);
    (
        ((origin[0] - item.tx as i64 * tile) / slot_step) as u32,
        ((origin[1] - item.ty as i64 * tile) / slot_step) as u32,
        1u32 << (item.node_level - (item.level - r)),
    )
}

/// Per-instance data grouped by refinement (unrefined first, then r = 1..): node origin
/// relative to the eye (f64 → f32), sample origin, vertex step, level, pool slot and the node's
/// place in it, skirt depth. Returns the concatenated records and each group's size.
fn build_instances(
    state: &PlanState,
    inputs: &FrameInputs,
    draw_list: &[(DrawItem, u32)],
) -> (Vec<TileInstance>, [u32; RESOLUTIONS]) {
    let q = state.clipmap.tile_quads;
    let eye = inputs.camera.position;
    let mut groups: [Vec<TileInstance>; RESOLUTIONS] = Default::default();
    let nodes: Vec<(u32, u32, u32, f32)> = draw_list
        .iter()
        .map(|(i, _)| (i.node_level, i.node_tx, i.node_ty, i.eps_m))
        .collect();
    let reach = neighbour_eps(&nodes);
    for (&(item, slot), &reach_m) in draw_list.iter().zip(&reach) {
        let node = (q as i64) << item.node_level;
        let origin = [item.node_tx as i64 * node, item.node_ty as i64 * node];
        let (slot_x, slot_y, slot_stride) = slot_placement(&item, q);
        groups[item.refinement as usize].push(TileInstance {
            origin_rel: [
                (origin[0] as f64 * state.spacing[0] - eye.x) as f32,
                (origin[1] as f64 * state.spacing[1] - eye.y) as f32,
            ],
            origin_sample: [origin[0] as i32, origin[1] as i32],
            step: 1 << item.node_level,
            level: item.level,
            refinement: item.refinement,
            slot,
            // ε + max(ε, neighbours' ε) at the default factor 2 (see neighbour_eps).
            skirt_m: 0.5 * inputs.skirt_factor * (item.eps_m + reach_m) + inputs.skirt_min_m,
            slot_x,
            slot_y,
            slot_stride,
        });
    }
    let sizes = groups.each_ref().map(|g| g.len() as u32);
    (groups.concat(), sizes)
}

/// One indexed indirect command per refinement group, each starting where the previous ended,
/// and the triangles they draw. A tile without indices draws nothing.
pub fn indirect_draws(
    group_sizes: &[u32; RESOLUTIONS],
    (first_index, index_count): (u32, u32),
) -> ([DrawIndexedIndirect; RESOLUTIONS], u64) {
    let mut draws = [DrawIndexedIndirect::default(); RESOLUTIONS];
    let mut first_instance = 0u32;
    let mut triangles = 0u64;
    for (draw, &n) in draws.iter_mut().zip(group_sizes) {
        *draw = DrawIndexedIndirect {
            index_count,
            instance_count: if index_count == 0 { 0 } else { n },
            first_index,
            vertex_offset: 0,
            first_instance,
        };
        first_instance += n;
        triangles += n as u64 * (index_count as u64 / 3);
    }
    (draws, triangles)
}

#[cfg(test)]
#[path = "plan_tests.rs"]
mod tests;
