//! The frame plan's data: what a plan reads besides its state ([`FrameInputs`]) and everything
//! a frame does ([`FramePlan`]: uploads, late tiles, what is drawn, the instance records and
//! indirect commands). Plain data, made by `plan.rs`, carried out by `upload.rs` and
//! `frame_record.rs`.

use aerie_terrain::camera::Camera;
use aerie_terrain::pool::TileKey;
use aerie_terrain::select::{DrawItem, SelectParams};

use crate::render::gpu::{DrawIndexedIndirect, GeoPolynomial, TileInstance};
use crate::render::jobs::{ImageUpload, StagingBudget};
use crate::render::stats::FrameStats;
use crate::render::terrain_draws::TileMeshes;
use crate::render::tile_instances::SkirtRule;

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
    /// Which edges get skirts (`RendererDesc::skirts`); CDLOD draws none either way.
    pub skirts: SkirtRule,
    /// Bytes of the overlay panel staged with the frame (None: no overlay set).
    pub overlay_bytes: Option<u64>,
    /// Where the tile's whole and coarse meshes lie in the shared index buffer.
    pub tile_meshes: TileMeshes,
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

/// Why a refined tile was drawn coarser.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LateReason {
    /// Its upload did not fit what was left of the frame's staging region, or of its data cap.
    Budget,
    /// Every slot of its pool was handed out this frame.
    NoSlot,
    /// Its samples were not resident in the source (asked for).
    Stream,
}

/// A refined tile drawn coarser this frame: `key` was asked for, `drawn_refinement` was resident.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LateTile {
    pub key: TileKey,
    pub drawn_refinement: u32,
    pub reason: LateReason,
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
    /// Instance records, grouped by refinement (r = 0 first), whole nodes before quadrants.
    pub instances: Vec<TileInstance>,
    /// On a projected grid each instance's polynomials, in the same order; else empty.
    pub polynomials: Vec<GeoPolynomial>,
    /// The indirect commands: per group its grids, the skirts of each set of edges.
    pub draws: Vec<DrawIndexedIndirect>,
    /// Commands the multi-draw issues: `draws`' length.
    pub draw_count: u32,
    /// Whether every strip (spilled or not) is staged with its normal texels after its heights.
    pub normal_maps: bool,
    /// Bytes staging the plan takes from the frame's region, padding included.
    pub staged_bytes: u64,
    pub stats: FrameStats,
}
