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
//! - **Prefetch** happens only along the eye's motion (and in the first frame after a load, for
//!   the views around the eye: `warm_start.rs`), never evicts a slot drawn in the last
//!   [`PREFETCH_PROTECT_FRAMES`] frames, and stops at the first tile the budget cannot take; a
//!   tile larger than a band is gathered a band of rows a frame and uploaded whole
//!   (`banded.rs`).
//! - **Streaming.** Every upload is admitted only with its samples gathered from the source
//!   (`gathered.rs`): a level strip whose samples are not resident stays pending in
//!   [`LevelContent`] and is retried each frame, the selection draws a level tile only when its
//!   texels are there (else coarser, late), and a refined tile whose samples are not resident
//!   is drawn at its best resident resolution and counted late (`tiles_late_stream`), as a
//!   budget miss is. What was missing is asked of the source at the end of the plan, largest
//!   projected error first, then nearest; prefetches below anything drawn.

use std::sync::Arc;

use glam::DVec3;

use aerie_terrain::bake::ErrorBake;
use aerie_terrain::camera::Camera;
use aerie_terrain::clipmap::{place_levels, ClipmapDesc, LevelPlacement};
use aerie_terrain::pool::{Request, TileKey};
use aerie_terrain::select::cdlod_morph::Morph;
use aerie_terrain::select::{select_tiles_multi_ready, DrawItem, SelectParams, Selection, View};
use aerie_terrain::source::TerrainSource;

use crate::render::ahead_select::{AheadJob, AheadSelector};
use crate::render::banded::{Banded, BandedTile};
use crate::render::feed::{Feed, DRAWN_PRIORITY, PREFETCH_PRIORITY};
pub use crate::render::frame_plan::{FrameInputs, FramePlan, LateReason, LateTile, PoolUpload};
use crate::render::gathered::Gatherer;

use aerie_terrain::geodesy::GeoGrid;

use crate::render::gpu::{FrameUniforms, TileInstance};
use crate::render::jobs::{
    eye_samples, split_level_uploads, within_data_cap, ImageUpload, PlanError, StagingBudget,
};
pub use crate::render::jobs::{
    FIXED_SLACK_BYTES, OVERLAY_SLACK_BYTES, POOL_UPLOAD_SLACK_BYTES, STRIP_SLACK_BYTES,
};
use crate::render::normal_map::normal_bytes;
pub use crate::render::pool_atlas::PoolSlots;
use crate::render::pool_atlas::{PoolAtlas, PoolLimits};
pub use crate::render::stats::selection_digest;
use crate::render::stats::selection_stats;
pub use crate::render::terrain_draws::{indirect_draws, TileMeshes};
use crate::render::tile_instances::{build_instances, InstanceCaches, InstanceFrame};
pub use crate::render::tile_instances::{fixed_reserve, slot_placement, SkirtRule};
use crate::render::warm_start::WarmViews;

/// Largest number of m×m instances one frame may draw (144 bytes each per frame in flight, 448
/// on a projected grid): the instance buffers grow on demand up to this — `full` on a large
/// dataset draws every visible finest node.
pub const MAX_INSTANCES: usize = 1 << 20;

/// A prefetch never evicts a slot drawn in this many most recent frames.
pub const PREFETCH_PROTECT_FRAMES: u64 = 2;
/// Frames between two selections of the view ahead: it looks `prefetch_frames` (20 by default)
/// ahead, so a selection a few frames old names nearly the same tiles, and each frame uploads
/// from it what the budget leaves room for. Re-selecting every frame cost as much CPU as the
/// frame's own selection (the Inn valley, 1280×720: 344 µs median).
pub const PREFETCH_RESELECT_FRAMES: u64 = 4;

/// The CPU state a plan reads and advances: clipmap cache regions and what the level textures
/// hold, pool bookkeeping and the previous eye (for prefetch), with the dataset's bake, sample
/// spacing and the source its samples come from.
pub struct PlanState {
    pub bake: Arc<ErrorBake>,
    /// Metres between samples (x east, y north).
    pub spacing: [f64; 2],
    pub clipmap: ClipmapDesc,
    /// Pools for r = 1..=MAX_REFINEMENT (index r − 1).
    pub pools: Vec<PoolSlots>,
    /// Eye of the previous planned frame.
    pub prev_eye: Option<DVec3>,
    /// The level textures' caches and content, the source and this frame's samples from it.
    pub feed: Feed,
    pub(crate) prefetch_selection: Selection,
    /// Where the next selection of the view ahead is being made (`ahead_select.rs`).
    pub(crate) ahead: AheadSelector,
    /// The frame of the last reselect of the view ahead, and how many reselects were made.
    prefetch_selected_at: Option<u64>,
    pub prefetch_selections: u64,
    /// The one prefetched tile too large for one frame, gathered a band a frame (`banded.rs`).
    pub banded: BandedTile,
    shared: SharedSelection,
    /// Shared (multi-channel) selections made so far: one per frame, whatever the channel count.
    pub shared_selections: u64,
    /// A geographic dataset drawn on the WGS84 ellipsoid (`GeoGrid::of`); None: the flat plane.
    pub earth: Option<GeoGrid>,
    /// Whether the next frame's selection also selects the views around the eye
    /// (`warm_start.rs`: their nodes' cached values made then, their refined tiles prefetched
    /// by that frame's plan); it turns false once done. False unless set: the renderer sets it
    /// from `RendererDesc::warm_start` at each load.
    pub warm_start: bool,
    /// The refined tiles of those views, prefetched by the first frame's plan.
    pub warm_items: Vec<DrawItem>,
    /// The drawn nodes' eye-independent ellipsoid fields and their skirts, kept across frames.
    pub instance_caches: InstanceCaches,
    /// The grid's valid samples east and north.
    pub valid_samples: [u32; 2],
}

/// The selection shared by a set of channels, kept while the set and the level placement stay
/// the same: a frame renders each of its n channels once, and they all draw this one selection,
/// so it is made once per frame, not n times (each costs O(n): a frame would be O(n²)).
#[derive(Default)]
struct SharedSelection {
    /// The channels' generation, the placement, the parameters and the level textures'
    /// content generation it was made for.
    key: Option<(u64, Vec<LevelPlacement>, SelectParams, u64)>,
    selection: Selection,
}

impl PlanState {
    pub fn new(
        bake: Arc<ErrorBake>,
        source: Arc<dyn TerrainSource>,
        clipmap: ClipmapDesc,
        pool_capacity: &[u32],
    ) -> Self {
        let grid = source.grid();
        let spacing = [grid.spacing_x, grid.spacing_y];
        // Geographic and UTM grids are drawn on the ellipsoid (issue 14), the rest on the flat
        // plane: decided here, once, for every planner (renderer, `fly --no-draw`, benchmarks)
        // from the source's grid.
        let earth = GeoGrid::of(grid.geo.as_ref(), grid.spacing_x, grid.spacing_y);
        let valid_samples = [grid.valid_width, grid.valid_height];
        let feed = Feed::new(clipmap.clone(), spacing, Gatherer::new(source));
        let pools = (1..=pool_capacity.len() as u32)
            .map(|r| PoolSlots::new((clipmap.tile_quads << r) + 1, pool_capacity[r as usize - 1]))
            .collect();
        Self {
            bake,
            spacing,
            clipmap,
            pools,
            prev_eye: None,
            feed,
            prefetch_selection: Selection::default(),
            ahead: AheadSelector::threaded(),
            prefetch_selected_at: None,
            prefetch_selections: 0,
            banded: BandedTile::default(),
            shared: SharedSelection::default(),
            shared_selections: 0,
            earth,
            warm_start: false,
            warm_items: Vec::new(),
            instance_caches: InstanceCaches::default(),
            valid_samples,
        }
    }

    /// Lays every pool's slots out within `limits` (a device's image limits), before anything
    /// is uploaded. Err names the pool that cannot fit.
    pub fn fit_pools(&mut self, limits: PoolLimits) -> Result<(), String> {
        for (r, p) in (1..).zip(&mut self.pools) {
            debug_assert_eq!(
                p.lru.counters().misses,
                0,
                "pools laid out before any upload"
            );
            p.atlas = PoolAtlas::new(p.side, p.lru.capacity(), limits)
                .map_err(|e| format!("pool r={r}: {e}"))?;
        }
        Ok(())
    }

    /// Where the clipmap centres its levels for an eye at `eye` (world metres): the eye's grid
    /// position, which on the ellipsoid is not its world x, y.
    pub fn viewer(&self, eye: DVec3) -> [f64; 2] {
        match &self.earth {
            Some(g) => eye_samples(g.grid_of_world(eye), self.spacing),
            None => eye_samples(eye, self.spacing),
        }
    }

    /// The eye in the grid's metres (`viewer` × spacing, height kept): where the feed ranks
    /// what it asks for by nearness.
    pub fn grid_eye(&self, eye: DVec3) -> DVec3 {
        let v = self.viewer(eye);
        DVec3::new(v[0] * self.spacing[0], v[1] * self.spacing[1], eye.z)
    }

    /// Whether the grid is projected (UTM): its instances carry polynomials.
    pub fn projected(&self) -> bool {
        self.earth.is_some_and(|g| g.projected.is_some())
    }

    /// The frame's selection parameters with this dataset's Earth model.
    pub fn select_params(&self, params: &SelectParams) -> SelectParams {
        SelectParams {
            earth: self.earth,
            ..*params
        }
    }

    /// The level-texture uploads that fill (or refresh) every level around `eye`, of what the
    /// source holds now (their samples gathered; the rest is asked for and stays pending).
    /// Start-up, before the first frame: not capped by the per-frame data cap.
    pub fn strips_around(&mut self, eye: DVec3) -> Vec<ImageUpload> {
        self.feed.gatherer.begin_frame();
        let placements = place_levels(&self.clipmap, self.viewer(eye));
        let cap = std::mem::replace(&mut self.feed.data_cap_samples, usize::MAX);
        let strips = self.feed.update_levels(&placements, self.grid_eye(eye));
        self.feed.data_cap_samples = cap;
        self.feed.gatherer.send_requests();
        strips
    }
}

/// Places the levels around the eye, turns what the levels lack into strip uploads of the
/// samples the source holds (advancing the cache regions and their content) and selects the
/// frame's tiles into `out` over what the level textures will hold: for `camera` alone, or
/// once for every channel (per tile the largest ρ/τ among the channels that see it).
pub fn select_frame(
    state: &mut PlanState,
    inputs: &FrameInputs,
    out: &mut Selection,
) -> Vec<ImageUpload> {
    state.feed.gatherer.begin_frame();
    let eye = state.grid_eye(inputs.camera.position);
    let placements = place_levels(&state.clipmap, state.viewer(inputs.camera.position));
    let strips = state.feed.update_levels(&placements, eye);
    let params = state.select_params(inputs.select);
    if std::mem::take(&mut state.warm_start) {
        let views = WarmViews {
            bake: &state.bake,
            clipmap: &state.clipmap,
            placements: &placements,
            viewport: inputs.viewport,
            tau_px: inputs.select.tau_px,
            params: &params,
            content: &state.feed.content,
        };
        state.warm_items = views.refined_items(inputs.camera, out);
    }
    if inputs.channels.is_empty() {
        let view = View {
            camera: inputs.camera,
            viewport: inputs.viewport,
            tau_px: inputs.select.tau_px,
        };
        select_tiles_multi_ready(
            &state.bake,
            &state.clipmap,
            &placements,
            &[view],
            &params,
            &state.feed.content,
            out,
        );
    } else {
        let generation = state.feed.content.generation();
        let key = (inputs.channels_generation, placements, params, generation);
        if state.shared.key.as_ref() == Some(&key) {
            out.clone_from(&state.shared.selection);
            state.feed.want_tiles(&out.wants, eye);
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
        select_tiles_multi_ready(
            &state.bake,
            &state.clipmap,
            placements,
            &views,
            &params,
            &state.feed.content,
            out,
        );
        state.shared_selections += 1;
        state.shared.selection.clone_from(out);
        state.shared.key = Some(key);
    }
    state.feed.want_tiles(&out.wants, eye);
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
    let reserve = fixed_reserve(
        selection.items.len(),
        state.projected(),
        inputs.overlay_bytes,
    );

    // Strips first, mandatory: all in this frame, or all streamed before it; with normal maps
    // each strip's normal texels are staged right after its heights.
    let normals = state.feed.gatherer.normal_maps();
    plan.normal_maps = normals;
    let strip_bytes: u64 = strips.iter().map(ImageUpload::bytes).sum();
    let normal_total: u64 = strips.iter().map(|s| normal_bytes(s.size, normals)).sum();
    plan.stats.bytes_clipmap = strip_bytes + normal_total;
    plan.stats.bytes_normals = normal_total;
    let allocations = strips.len() as u64 * (1 + normals as u64);
    if strip_bytes + normal_total + reserve + STRIP_SLACK_BYTES * allocations > budget.capacity() {
        // A jump (or a tiny budget).
        plan.spilled_strips =
            split_level_uploads(&strips, budget.capacity(), budget.alignment(), normals)?;
        plan.stats.budget_spills = plan.spilled_strips.len() as u32;
    } else {
        for s in &strips {
            budget.take(s.bytes())?;
            if normals {
                budget.take(normal_bytes(s.size, true))?;
            }
        }
        plan.strips = strips;
    }

    for p in &mut state.pools {
        p.lru.begin_frame(inputs.frame);
    }
    resolve_refined_tiles(state, selection, &mut budget, reserve, &mut plan)?;
    prefetch(state, inputs, &mut budget, reserve, &mut plan)?;

    let gatherer = &mut state.feed.gatherer;
    gatherer.send_requests();
    plan.stats.cpu_terrain_data_us = gatherer.time().as_secs_f64() * 1e6;
    plan.stats.cpu_normals_us = gatherer.normal_time().as_secs_f64() * 1e6;
    plan.stats.set_stream(&gatherer.stream_stats());
    plan.stats.cells_pending = state.feed.pending_cells();

    let (instances, polynomials, groups) = build_instances(
        &InstanceFrame {
            tile_quads: state.clipmap.tile_quads,
            spacing: state.spacing,
            earth: state.earth.as_ref(),
            eye: inputs.camera.position,
            skirt_factor: inputs.skirt_factor,
            skirt_min_m: inputs.skirt_min_m,
            skirts: inputs.skirts.for_mode(inputs.select.mode),
            valid_samples: state.valid_samples,
            pools: &state.pools,
        },
        &plan.draw_list,
        &mut state.instance_caches,
    );
    // Quadrants drawn for their parents (bounded's and CDLOD's) draw the coarse mesh: the
    // parent's quarter mesh they show.
    let (draws, triangles) = indirect_draws(&groups, inputs.tile_meshes);
    let total = instances.len();
    if total > MAX_INSTANCES {
        return Err(PlanError::Other(format!(
            "selection of {total} tiles exceeds the largest instance buffer ({MAX_INSTANCES})"
        )));
    }
    plan.draw_count = draws.len() as u32;
    plan.stats.instances = total as u32;
    plan.stats.triangles = triangles;
    plan.stats.draw_calls = (plan.draw_count > 0) as u32;

    // The fixed pushes, in the order the renderer stages them.
    budget.take(std::mem::size_of::<FrameUniforms>() as u64)?;
    budget.take(std::mem::size_of_val(draws.as_slice()) as u64)?;
    if total > 0 {
        budget.take((total * std::mem::size_of::<TileInstance>()) as u64)?;
    }
    if !polynomials.is_empty() {
        budget.take(std::mem::size_of_val(polynomials.as_slice()) as u64)?;
    }
    if let Some(bytes) = inputs.overlay_bytes.filter(|&b| b > 0) {
        budget.take(bytes)?;
    }
    plan.instances = instances;
    plan.polynomials = polynomials;
    plan.draws = draws;
    plan.staged_bytes = budget.used();
    plan.stats.bytes_uploaded = budget.used();
    state.prev_eye = Some(inputs.camera.position);
    Ok(plan)
}

/// The statistics the selection alone decides.
/// Samples an upload gathers.
fn job_samples(job: &ImageUpload) -> usize {
    job.size[0] as usize * job.size[1] as usize
}

/// Whether a pool upload of `slot_bytes` fits what is left above the reserve.
pub(crate) fn upload_fits(budget: &StagingBudget, slot_bytes: u64, reserve: u64) -> bool {
    budget.remaining() >= slot_bytes + reserve + POOL_UPLOAD_SLACK_BYTES
}

/// Finds or uploads the pool slot of every refined ring tile (its nodes follow one another in
/// the selection) and fills `plan.draw_list`. A miss that does not fit the budget, or whose
/// samples the source does not hold (asked for, by the tile's projected error), leaves the
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
        let job = pool.atlas.upload(q, &key, 0);
        let gatherer = &mut state.feed.gatherer;
        let (mut not_resident, mut no_budget) = (false, false);
        let cap = state.feed.data_cap_samples;
        // Admitted only with its samples in hand (the slot is assigned after).
        let request = pool.lru.request(key, &mut || {
            if !upload_fits(budget, slot_bytes, reserve)
                || !within_data_cap(gatherer.samples().len(), job_samples(&job), cap)
            {
                no_budget = true;
                return false;
            }
            not_resident = gatherer.gather(&job).is_err();
            !not_resident
        });
        let (resident_r, slot) = match request {
            Request::Hit { slot } => {
                plan.stats.pool_hits += 1;
                (r, slot)
            }
            Request::Miss { slot, evicted } => {
                plan.stats.pool_misses += 1;
                let upload = pool.atlas.upload(q, &key, slot);
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
                if not_resident {
                    plan.stats.tiles_late_stream += 1;
                    let rho = group.iter().map(|i| i.rho_px).fold(0.0f32, f32::max);
                    state
                        .feed
                        .gatherer
                        .want(job.sample_rect(), DRAWN_PRIORITY + rho);
                }
                let best = best_resident(&mut state.pools, key);
                plan.late.push(LateTile {
                    key,
                    drawn_refinement: best.0,
                    reason: if not_resident {
                        LateReason::Stream
                    } else if no_budget {
                        LateReason::Budget
                    } else {
                        LateReason::NoSlot
                    },
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
            // A node drawn coarser than chosen is no longer in its level's morph zone.
            morph: if node_level == i.node_level {
                i.morph
            } else {
                Morph::NONE
            },
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
/// prefetch them), of what the source holds; asks for the rest, and for the level cells the
/// levels will expose there. Never evicts a slot drawn in the last [`PREFETCH_PROTECT_FRAMES`]
/// frames. The first frame after a load prefetches the refined tiles of the views around the
/// eye first (`warm_start.rs`).
fn prefetch(
    state: &mut PlanState,
    inputs: &FrameInputs,
    budget: &mut StagingBudget,
    reserve: u64,
    plan: &mut FramePlan,
) -> Result<(), PlanError> {
    let warm = std::mem::take(&mut state.warm_items);
    if !warm.is_empty() {
        prefetch_items(state, &warm, inputs, budget, reserve, plan)?;
    }
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
    let placements = place_levels(&state.clipmap, state.viewer(ahead.position));
    let ahead_grid = state.grid_eye(ahead.position);
    state.feed.want_ahead(&placements, ahead_grid);
    let stale = state
        .prefetch_selected_at
        .is_none_or(|f| inputs.frame >= f + PREFETCH_RESELECT_FRAMES || inputs.frame < f);
    if stale {
        let job = AheadJob {
            bake: state.bake.clone(),
            clipmap: state.clipmap.clone(),
            placements: placements.clone(),
            camera: ahead,
            viewport: inputs.viewport,
            params: state.select_params(inputs.select),
        };
        let last = state.prefetch_selected_at;
        let fresh = last
            .is_some_and(|f| inputs.frame >= f && inputs.frame < f + 2 * PREFETCH_RESELECT_FRAMES);
        state
            .ahead
            .reselect(job, fresh, &mut state.prefetch_selection);
        state.prefetch_selected_at = Some(inputs.frame);
        state.prefetch_selections += 1;
    }
    let items = std::mem::take(&mut state.prefetch_selection.items);
    let done = prefetch_items(state, &items, inputs, budget, reserve, plan);
    state.prefetch_selection.items = items;
    done
}

/// The prefetch of `items`' refined tiles, in order, while the budget lasts.
fn prefetch_items(
    state: &mut PlanState,
    items: &[DrawItem],
    inputs: &FrameInputs,
    budget: &mut StagingBudget,
    reserve: u64,
    plan: &mut FramePlan,
) -> Result<(), PlanError> {
    let q = state.clipmap.tile_quads;
    if let Some(k) = state.banded.key() {
        // Drawn (so uploaded whole) since: its rows in hand are not needed.
        if state.pools[k.refinement as usize - 1].lru.is_resident(&k) {
            state.banded.forget();
        }
    }
    let mut last = None;
    let mut rank = 0u32;
    for item in items {
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
        let job = pool.atlas.upload(q, &key, 0);
        let gatherer = &mut state.feed.gatherer;
        let mut not_resident = false;
        // A tile too large for one frame's gathering comes a band a frame; it is admitted
        // (slot and staging) once whole.
        let banded = &mut state.banded;
        let in_bands = banded.bands_needed(&job.sample_rect());
        if in_bands {
            match banded.advance(key, job.sample_rect(), inputs.frame, gatherer) {
                Banded::Ready => {}
                Banded::Gathering | Banded::Waiting => continue,
                Banded::NotResident => not_resident = true,
            }
        }
        let cap = state.feed.data_cap_samples;
        let request = pool.lru.prefetch(
            key,
            &mut || {
                if not_resident
                    || !upload_fits(budget, slot_bytes, reserve)
                    || !within_data_cap(gatherer.samples().len(), job_samples(&job), cap)
                {
                    return false;
                }
                if in_bands {
                    let Some(samples) = banded.take(key) else {
                        return false;
                    };
                    gatherer.append(samples);
                    return true;
                }
                not_resident = gatherer.gather(&job).is_err();
                !not_resident
            },
            PREFETCH_PROTECT_FRAMES,
        );
        if let Request::Miss { slot, evicted } = request {
            let upload = pool.atlas.upload(q, &key, slot);
            budget.take(upload.bytes())?;
            plan.stats.bytes_refined += upload.bytes();
            plan.stats.prefetched += 1;
            plan.pool_uploads.push(PoolUpload {
                key,
                upload,
                evicted,
                prefetch: true,
            });
        } else if not_resident {
            rank += 1;
            state
                .feed
                .gatherer
                .want(job.sample_rect(), PREFETCH_PRIORITY / (1.0 + rank as f32));
        } else if !upload_fits(budget, slot_bytes, reserve) {
            break;
        }
    }
    Ok(())
}

#[cfg(test)]
#[path = "plan_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "plan_stream_tests.rs"]
mod stream_tests;
