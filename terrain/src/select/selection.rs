//! What a selection takes and gives: the LOD mode and parameters, the views, the draw items
//! and per-level statistics.

use super::cdlod_morph::Morph;
use crate::camera::Camera;
use crate::geodesy::GeoGrid;

pub use super::bound::EARTH_RADIUS_M;

/// Highest refinement a tile may get (pool bindings exist for r = 1..=MAX_REFINEMENT).
pub const MAX_REFINEMENT: u32 = 6;

/// How the level of detail is decided. Everything else (levels, pipeline, uploads) is shared.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
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
    /// CDLOD (Strugar 2009): a quadtree over the tiles, LOD ranges doubling per level
    /// (`cdlod_range` node sides), selection by box distance to the eye (`cdlod.rs`).
    Cdlod,
    /// Hardware tessellation (seed 001): a static base mesh of triangular patches whose edge
    /// factors are a density map of second differences × a distance factor × `tess_density`
    /// (`tess_density.rs`, `tessellation.rs`); drawn by its own pipeline, not from the tiles.
    Tessellation,
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
    /// `Cdlod` mode: the LOD range of a level in its node sides (the ranges double per level).
    pub cdlod_range: f64,
    /// `Tessellation` mode: the global factor Tg (an edge of density 1 at the eye gets this many
    /// segments, up to the device's limit).
    pub tess_density: f64,
    /// A geographic dataset drawn on the WGS84 ellipsoid: node boxes, normals and the
    /// interpolation slack come from the curved surface (`curvature` is then moot). `None`:
    /// the flat plane. Set by the renderer from the dataset.
    pub earth: Option<GeoGrid>,
    /// `Bounded`: drop nodes hidden behind nearer terrain from every view (`horizon.rs`): a
    /// hidden node has no visible error, so it is neither refined nor drawn.
    pub horizon_cull: bool,
    /// `Bounded`: when a node misses τ, each quadrant that meets τ at the node's own resolution
    /// (its ε over the quadrant's box: the quadrant's surface is the node's there, so its error
    /// is within the node's ε) is drawn so — the quarter of the node's mesh, as a child node
    /// fully morphed onto the node's grid (`cdlod_morph.rs`) — instead of splitting into a
    /// finer child there.
    pub parent_quadrants: bool,
    /// With `parent_quadrants`, in the coarsest-first quadtree: a child that misses τ at its
    /// parent's resolution is also tried in sixteenths — each of its children at the parent's
    /// resolution, the bake's [`ErrorBake::fine_eps`](crate::bake::ErrorBake::fine_eps) — and
    /// drawn in the fewest triangles that meet τ (`walk::choose_parts`).
    pub sixteenths: bool,
    /// With `parent_quadrants`, in the coarsest-first quadtree: a node that meets τ but that
    /// no view sees whole (its box crosses a frustum plane) or that holds padding is drawn as
    /// only its quadrants some view sees and that hold terrain (one that crosses a plane too
    /// as its seen sixteenths), each at the node's resolution from the node's own level
    /// texture, when that draws fewer triangles (`Frame::seen_parts`) — what CDLOD's quadtree
    /// does with a node it culls in part.
    pub seen_quadrants: bool,
    /// Up to two of the bake's levels above the coarsest clipmap level, which no texture
    /// holds, drawn from that level's tiles as their stride-2 and stride-4 meshes (a tile as
    /// its parent's quadrant or its grandparent's sixteenth). `Bounded` (with
    /// `parent_quadrants`, in the coarsest-first quadtree): a root that meets τ is drawn the
    /// coarsest of those ways that meets τ (`coarser_roots.rs`). `Cdlod`: the quadtree starts
    /// at the top one of those levels, as the reference's starts at its `LODLevelCount`
    /// (`cdlod.rs`).
    pub coarser_roots: bool,
    /// `Bounded` with one view (plane or ellipsoid): a ring tile refined in an earlier frame is
    /// drawn again while its certificate says every node still meets τ (`carry.rs`), instead
    /// of walked afresh.
    pub carry: bool,
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
            cdlod_range: 6.0,
            tess_density: super::tess_density::TESS_PATCH as f64,
            earth: None,
            horizon_cull: false,
            parent_quadrants: true,
            sixteenths: true,
            seen_quadrants: true,
            coarser_roots: true,
            carry: true,
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
    /// The node drawn: a level-`node_level` tile, L−r ≤ node_level ≤ L; or, unrefined, a
    /// quadrant or sixteenth of the ring tile (node_level = L − 1 or L − 2, `morph` saying
    /// which) drawn at the tile's resolution from its level texture
    /// ([`SelectParams::seen_quadrants`]).
    pub node_level: u32,
    pub node_tx: u32,
    pub node_ty: u32,
    /// ε of the surface drawn over the node (level `node_level`), metres, curvature
    /// interpolation included.
    pub eps_m: f32,
    /// Its projected error bound, pixels.
    pub rho_px: f32,
    /// CDLOD's geomorph of the node (`cdlod_morph.rs`); [`Morph::NONE`] in every other mode.
    pub morph: Morph,
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
            morph: Morph::NONE,
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

#[derive(Debug, Default)]
pub struct Selection {
    pub items: Vec<DrawItem>,
    pub levels: Vec<LevelStats>,
    /// Finest level drawn this frame.
    pub finest_level: u32,
    /// Tiles whose bound could not be met within `max_refinement`.
    pub unbounded: u32,
    /// `Distance` mode: nodes split this frame (level, tx, ty), the hysteresis state for the next.
    pub split: std::collections::HashSet<(u32, u32, u32)>,
    /// Ring tiles drawn coarser than the bound asks (or, outside the quadtree, not drawn)
    /// because the level texture they needed does not hold their samples yet (a streamed
    /// source still loading them): counted late, as pool misses are.
    pub stream_late: u32,
    /// The level tiles the selection wanted to draw but were not ready, (level, tx, ty,
    /// projected error in pixels that drawing them would remove), for the source's requests.
    pub wants: Vec<(u32, u32, u32, f32)>,
    /// The nodes' camera-independent values (ε, boxes on the ellipsoid), kept for the next
    /// frames of the same dataset.
    pub node_cache: super::node_cache::NodeCache,
    /// Nodes in some view's frustum but hidden behind nearer terrain in every view that has
    /// them ([`SelectParams::horizon_cull`]).
    pub hidden: u32,
    /// The horizons of the last frame (reused allocations, corner positions).
    pub horizon: super::horizon::HorizonSet,
    /// The ring tiles refined in earlier frames, drawn again while they hold
    /// ([`SelectParams::carry`]); like the node cache, never copied with a selection.
    pub carry: super::carry::Carry<SelectParams>,
}

/// Field by field, so that `clone_from` reuses the target's vectors and keeps its own node
/// cache and carried tiles (the derived one would replace the target whole, cache included).
impl Clone for Selection {
    fn clone(&self) -> Self {
        let mut s = Self::default();
        s.clone_from(self);
        s
    }

    fn clone_from(&mut self, source: &Self) {
        // Destructured: a new field does not compile until it is copied here too.
        let Self {
            items,
            levels,
            finest_level,
            unbounded,
            split,
            stream_late,
            wants,
            node_cache,
            hidden,
            horizon: _,
            carry: _,
        } = source;
        self.items.clone_from(items);
        self.levels.clone_from(levels);
        self.finest_level = *finest_level;
        self.unbounded = *unbounded;
        self.split.clone_from(split);
        self.stream_late = *stream_late;
        self.wants.clone_from(wants);
        self.node_cache.clone_from(node_cache);
        self.hidden = *hidden;
        // The horizon is rebuilt every frame: the target keeps its own allocations.
    }
}

impl Selection {
    /// Appends ring tile (level, tx, ty)'s `nodes` (level, tx, ty, ε, ρ) as the draw items of one
    /// pool slot — its refinement is the deepest node's — and counts them in level `level_index`'s
    /// statistics. Shared by every mode that refines ring tiles from the pools.
    pub(super) fn push_refined(
        &mut self,
        level_index: usize,
        level: u32,
        tx: u32,
        ty: u32,
        nodes: &[(u32, u32, u32, f32, f32)],
    ) {
        let r = nodes.iter().map(|n| level - n.0).max().unwrap_or(0);
        let stats = &mut self.levels[level_index];
        stats.refined[r as usize] += 1;
        stats.nodes += nodes.len() as u32;
        for &(node_level, node_tx, node_ty, eps_m, rho_px) in nodes {
            self.items.push(DrawItem {
                level,
                tx,
                ty,
                refinement: r,
                node_level,
                node_tx,
                node_ty,
                eps_m,
                rho_px,
                morph: Morph::NONE,
            });
        }
    }
}

/// Which level tiles the renderer can draw from its level textures now: their texels (and
/// their neighbours', read for normals) hold this placement's samples. The selection descends
/// into a finer level only where its tiles are ready, so nothing stale is ever drawn while a
/// streamed source fills the level textures over the following frames.
pub trait TileReadiness {
    fn is_ready(&self, level: u32, tx: u32, ty: u32) -> bool;
}

/// Every tile ready: a source held in memory, whose level textures are filled before drawing.
pub struct AllReady;

impl TileReadiness for AllReady {
    fn is_ready(&self, _level: u32, _tx: u32, _ty: u32) -> bool {
        true
    }
}

/// One display channel for [`select_tiles_multi`]: its camera, viewport and error bound.
#[derive(Debug, Clone, Copy)]
pub struct View<'a> {
    pub camera: &'a Camera,
    pub viewport: (u32, u32),
    pub tau_px: f64,
}
