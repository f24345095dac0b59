//! What a selection takes and gives: the LOD mode and parameters, the views, the draw items
//! and per-level statistics.

use crate::camera::Camera;

/// Mean Earth radius used for the curvature drop d²/2R (DESIGN.md "Earth curvature").
pub const EARTH_RADIUS_M: f64 = 6_371_000.0;

/// Highest refinement a tile may get (pool bindings exist for r = 1..=MAX_REFINEMENT).
pub const MAX_REFINEMENT: u32 = 6;

/// How the level of detail is decided. Everything else (levels, pipeline, uploads) is shared.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum LodMode {
    /// Error-bounded tiled clipmaps: refine until ρ ≤ τ (ours).
    #[default]
    Bounded,
    /// Plain geometry clipmaps: the same levels, no error test, no refinement.
    Clipmap,
    /// Brute force: every visible tile at full resolution (r = L).
    Full,
    /// Classic discrete LOD by distance alone (seed 004): a node is split while the eye is
    /// closer than `distance_factor` × its side, with 10 % hysteresis against popping.
    Distance,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelectParams {
    pub mode: LodMode,
    /// Screen-space error bound, pixels.
    pub tau_px: f64,
    /// Apply the Earth-curvature drop (and include it in the AABBs).
    pub curvature: bool,
    /// Refinement cap (≤ MAX_REFINEMENT); tiles that would need more are drawn at the cap and
    /// counted as `unbounded`.
    pub max_refinement: u32,
    /// `Bounded`: draw every region at the coarsest clipmap level that meets τ there (a
    /// quadtree over the levels, from the coarsest down), instead of every level's whole ring
    /// with only entire levels skipped. Same bound, fewer triangles where the terrain is smooth
    /// or seen from high above.
    pub coarsen: bool,
    /// `Distance` mode: split a node while the eye is nearer than this many node sides.
    pub distance_factor: f64,
}

impl Default for SelectParams {
    fn default() -> Self {
        Self {
            mode: LodMode::Bounded,
            tau_px: 1.0,
            curvature: true,
            max_refinement: 5,
            coarsen: true,
            distance_factor: 3.0,
        }
    }
}

/// One m×m tile instance to draw: a *node* of a ring tile.
///
/// An unrefined ring tile (L, tx, ty) is one node: itself, heights from its clipmap level. A
/// refined ring tile takes its heights from one pool slot holding the tile at level L−r, and is
/// drawn as a quadtree of nodes: each node is the level-ℓ tile (node_tx, node_ty) for some
/// L−r ≤ ℓ ≤ L, split further only while its own projected error exceeds τ — so the far part of
/// a big coarse tile is not drawn at the resolution its near corner needs (beyond the document,
/// which refines the whole tile). Every node meets the bound on its own.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrawItem {
    /// The ring tile: clipmap level and tile coordinates (the pool key with `refinement`).
    pub level: u32,
    pub tx: u32,
    pub ty: u32,
    /// r: the pool slot holds the ring tile at level L−r (0 = unrefined, from the clipmap).
    pub refinement: u32,
    /// The node drawn: a level-`node_level` tile, L−r ≤ node_level ≤ L.
    pub node_level: u32,
    pub node_tx: u32,
    pub node_ty: u32,
    /// ε of the surface drawn over the node (level `node_level`), metres, curvature
    /// interpolation included.
    pub eps_m: f32,
    /// Its projected error bound, pixels.
    pub rho_px: f32,
}

impl DrawItem {
    /// The node of an unrefined ring tile: the tile itself.
    pub fn whole(level: u32, tx: u32, ty: u32, eps_m: f32, rho_px: f32) -> Self {
        Self {
            level,
            tx,
            ty,
            refinement: 0,
            node_level: level,
            node_tx: tx,
            node_ty: ty,
            eps_m,
            rho_px,
        }
    }
}

#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct LevelStats {
    /// Ring tiles of this level over the dataset.
    pub considered: u32,
    /// Ring tiles outside the frustum.
    pub culled: u32,
    /// Ring tiles drawn.
    pub drawn: u32,
    /// Drawn ring tiles per refinement r (index r).
    pub refined: [u32; MAX_REFINEMENT as usize + 1],
    /// Nodes (m×m instances) drawn for this level's tiles.
    pub nodes: u32,
    /// The level was skipped as too fine for the current height above ground.
    pub skipped: bool,
}

#[derive(Debug, Clone, Default)]
pub struct Selection {
    pub items: Vec<DrawItem>,
    pub levels: Vec<LevelStats>,
    /// Finest level drawn this frame.
    pub finest_level: u32,
    /// Tiles whose bound could not be met within `max_refinement`.
    pub unbounded: u32,
    /// `Distance` mode: nodes split this frame (level, tx, ty), the hysteresis state for the next.
    pub split: std::collections::HashSet<(u32, u32, u32)>,
}

/// One display channel for [`select_tiles_multi`]: its camera, viewport and error bound.
#[derive(Debug, Clone, Copy)]
pub struct View<'a> {
    pub camera: &'a Camera,
    pub viewport: (u32, u32),
    pub tau_px: f64,
}
