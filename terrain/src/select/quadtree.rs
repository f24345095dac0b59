//! The selection itself: each level's ring tiles, culled and refined until the bound holds,
//! or (coarsening) a quadtree over the levels from the coarsest down.

use glam::{DVec2, DVec3};

use crate::bake::ErrorBake;
use crate::camera::Camera;
use crate::clipmap::{ring_tiles, ClipmapDesc, LevelPlacement};
use crate::tiles::Aabb;

use super::bound::{
    curvature_interpolation_error, frustum_spread_gain, frustum_vertical_gain, projected_error_px,
    tile_aabb, view_corners, CornerPass,
};
use super::cdlod_morph::Morph;
use super::node_cache::{NodeCache, NodeFixed};
use super::selection::{
    AllReady, DrawItem, LevelStats, LodMode, SelectParams, Selection, TileReadiness, View,
    MAX_REFINEMENT,
};

#[cfg(test)]
#[path = "quadtree_reference.rs"]
pub(super) mod reference;

/// Geometry of a dataset the selection needs (from the bake).
#[derive(Debug, Clone, Copy)]
struct Grid {
    q: u32,
    spacing: DVec2,
    valid_max: DVec2,
}

impl Grid {
    fn of(bake: &ErrorBake) -> Self {
        Self {
            q: bake.params.tile_size - 1,
            spacing: DVec2::new(bake.spacing_x, bake.spacing_y),
            valid_max: DVec2::new(
                (bake.valid_width - 1) as f64 * bake.spacing_x,
                (bake.valid_height - 1) as f64 * bake.spacing_y,
            ),
        }
    }

    /// Diagonal of a cell of level `level_drawn` in metres.
    fn cell_diagonal(&self, level_drawn: u32) -> f64 {
        (self.spacing * (1u64 << level_drawn) as f64).length()
    }

    /// Horizontal rectangle of a level tile in metres, clipped to the valid data.
    fn rect(&self, level: u32, tx: u32, ty: u32) -> (DVec2, DVec2) {
        let side = (self.q as u64) << level;
        let lo = DVec2::new((tx as u64 * side) as f64, (ty as u64 * side) as f64) * self.spacing;
        let hi = lo + DVec2::splat(side as f64) * self.spacing;
        (lo.min(self.valid_max), hi.min(self.valid_max))
    }
}

/// Nodes (level, tx, ty).
type NodeSet = std::collections::HashSet<(u32, u32, u32)>;

/// Whether level-L tile (tx, ty) exists and holds any real (non-padding) sample.
fn has_terrain(bake: &ErrorBake, level: u32, tx: u32, ty: u32) -> bool {
    let t = &bake.levels[level as usize];
    tx < t.tiles_x && ty < t.tiles_y && t.terrain[(ty * t.tiles_x + tx) as usize]
}

/// Context shared by every tile of a frame.
struct Frame<'a> {
    /// Distance mode: nodes split last frame, and the set being filled this frame.
    split_prev: Option<&'a NodeSet>,
    split_now: Option<&'a std::cell::RefCell<NodeSet>>,
    bake: &'a ErrorBake,
    grid: Grid,
    views: Vec<ViewCtx<'a>>,
    params: &'a SelectParams,
    ready: &'a dyn TileReadiness,
    /// The nodes' camera-independent values, kept across frames.
    cache: std::cell::RefCell<&'a mut NodeCache>,
    /// Tests: take the reference evaluation (`quadtree_reference.rs`).
    #[cfg(test)]
    reference: bool,
    /// Horizon culling: the eyes' horizons and the nodes it hid.
    horizon: Option<&'a super::horizon::HorizonSet>,
    hidden: std::cell::Cell<u32>,
    /// [`Grid::cell_diagonal`] of every level of the bake, formed once a frame (a square root
    /// per node evaluation otherwise).
    diagonals: Vec<f64>,
    /// The ring tile being refined: which of its nodes are quadrants drawn at their parent's
    /// resolution ([`SelectParams::parent_quadrants`]), by index in its node list.
    quadrants: std::cell::RefCell<Vec<usize>>,
}

/// One channel's camera with what the bound needs from it.
struct ViewCtx<'a> {
    camera: &'a Camera,
    /// World → view, computed once per frame (not per node: the attitude's trigonometry).
    to_view: glam::DMat4,
    /// Its rotation (for the ellipsoid's normals).
    rotation: glam::DMat3,
    /// The world vertical in view space.
    up: DVec3,
    focal: f64,
    /// [`frustum_vertical_gain`].
    vertical_gain: f64,
    tau: f64,
}

/// A node as the views see it.
#[derive(Clone, Copy)]
struct NodeEval {
    eps: f64,
    /// Largest ρ (px) among the views that see the node.
    rho_px: f64,
    /// Largest ρ/τ among them: the node meets every channel's bound when ≤ 1.
    rho_norm: f64,
}

impl Frame<'_> {
    fn cell_diagonal(&self, level_drawn: u32) -> f64 {
        match self.diagonals.get(level_drawn as usize) {
            Some(&d) => d,
            None => self.grid.cell_diagonal(level_drawn),
        }
    }

    /// The node's camera-independent values (from the cache after the first time on the
    /// ellipsoid; on the plane they are two table reads, cheaper than the cache's lookup).
    fn fixed(&self, level: u32, tx: u32, ty: u32) -> NodeFixed {
        #[cfg(test)]
        if self.reference {
            return self.compute_fixed(level, tx, ty);
        }
        if self.params.earth.is_none() {
            return self.compute_fixed(level, tx, ty);
        }
        self.cache
            .borrow_mut()
            .get(level, tx, ty, || self.compute_fixed(level, tx, ty))
    }

    /// [`Self::fixed`] computed: ε of the level-ℓ surface over the level-ℓ tile (tx, ty) with
    /// the curvature interpolation (on the ellipsoid: the drawn cell's slack,
    /// `GeoGrid::cell_sag_m`), and the node on the ellipsoid (geographic data).
    fn compute_fixed(&self, level: u32, tx: u32, ty: u32) -> NodeFixed {
        let (lo, hi) = self.grid.rect(level, tx, ty);
        let (min_h, max_h) = self.bake.bounds(level, tx, ty);
        let raw = self.bake.eps_refined(level, tx, ty, 0) as f64;
        let (mut sag, mut geo) = (0.0, None);
        if let Some(g) = &self.params.earth {
            sag = g.cell_sag_m(lo, hi, 1 << level, min_h, max_h);
            geo = Some(g.node_geometry(lo, hi, min_h, max_h));
        } else if self.params.curvature {
            sag = curvature_interpolation_error(self.cell_diagonal(level));
        }
        let eps = raw + sag;
        // On the ellipsoid: the normals' turn and the cell slack, in any direction.
        let slack = geo.map_or(0.0, |n| n.spread + if eps > 0.0 { sag / eps } else { 0.0 });
        NodeFixed {
            eps,
            slack,
            sag,
            spread: geo.map_or(0.0, |n| n.spread),
            geo,
            lo,
            hi,
            min_h,
            max_h,
        }
    }

    /// The node's box as seen from `eye` (the curvature drop depends on the eye).
    fn aabb(&self, level: u32, node: &NodeFixed, eye: DVec3) -> Aabb {
        if let Some(n) = &node.geo {
            return n.aabb;
        }
        tile_aabb(
            node.lo,
            node.hi,
            node.min_h,
            node.max_h,
            eye,
            self.params.curvature,
            self.cell_diagonal(level),
        )
    }

    /// ε and the projected error in every view that sees the node; `None` when no view does.
    /// With `cull` false, views that do not see it count too (for level skipping).
    fn evaluate(&self, level: u32, tx: u32, ty: u32, cull: bool) -> Option<NodeEval> {
        #[cfg(test)]
        if self.reference {
            return self.evaluate_reference(level, tx, ty, cull);
        }
        let node = self.fixed(level, tx, ty);
        let own = (node.eps, node.slack);
        self.evaluate_as(level, &node, own, None, cull).map(|e| e.0)
    }

    /// The quadrant (level, tx, ty) of its parent drawn at the parent's resolution — the
    /// bake's ε of the parent's surface over the quadrant with the parent's curvature slack
    /// and normal spread (the quadrant's normals turn less than the parent's, its cells are
    /// the parent's) over the quadrant's own box — and the
    /// same node at its own resolution, from one pass over the box (with the parent's cell
    /// slack in it, the larger); `None` when no view sees the quadrant. `parent`: the parent's
    /// fixed values, formed once for its four quadrants.
    fn evaluate_quadrant(
        &self,
        parent: &NodeFixed,
        level: u32,
        tx: u32,
        ty: u32,
    ) -> Option<(NodeEval, NodeEval)> {
        #[cfg(test)]
        if self.reference {
            let parent = self.compute_fixed(level + 1, tx / 2, ty / 2);
            let node = self.compute_fixed(level, tx, ty);
            let (p, own) = (
                self.as_quadrant(&parent, level, tx, ty),
                (node.eps, node.slack),
            );
            let q = self.evaluate_reference_as(level + 1, &node, p.0, p.1, true)?;
            let o = self.evaluate_reference_as(level + 1, &node, own.0, own.1, true)?;
            return Some((q, o));
        }
        let node = self.fixed(level, tx, ty);
        let (p, own) = (
            self.as_quadrant(parent, level, tx, ty),
            (node.eps, node.slack),
        );
        let (q, o) = self.evaluate_as(level + 1, &node, p, Some(own), true)?;
        Some((q, o.unwrap_or(q)))
    }

    /// (ε, slack) of node (level, tx, ty) drawn at its parent's resolution, `parent` being
    /// its parent's fixed values: the bake's [`ErrorBake::coarse_eps`] plus the parent's sag,
    /// and on the ellipsoid the parent's spread plus that sag relative to this ε (as
    /// [`Self::compute_fixed`] forms a node's own).
    fn as_quadrant(&self, parent: &NodeFixed, level: u32, tx: u32, ty: u32) -> (f64, f64) {
        let eps = self.bake.coarse_eps(level, tx, ty) as f64 + parent.sag;
        let slack = match parent.geo {
            Some(_) => parent.spread + if eps > 0.0 { parent.sag / eps } else { 0.0 },
            None => 0.0,
        };
        (eps, slack)
    }

    /// [`Self::evaluate`] of the node `node` drawn at level `drawn`'s resolution (its own, or
    /// its parent's for a quadrant) for an error and gain slack `first`, and `second` from the
    /// same corners.
    fn evaluate_as(
        &self,
        drawn: u32,
        node: &NodeFixed,
        first: (f64, f64),
        second: Option<(f64, f64)>,
        cull: bool,
    ) -> Option<(NodeEval, Option<NodeEval>)> {
        let geo = node.geo;
        let (mut seen, mut hidden) = (false, false);
        let mut rho = [(0.0f64, 0.0f64); 2];
        for (vi, v) in self.views.iter().enumerate() {
            let aabb = match &geo {
                Some(n) => n.aabb,
                None => self.aabb(drawn, node, v.camera.position),
            };
            let corners = view_corners(&v.to_view, &aabb);
            let f = &v.camera.frustum;
            let pass = CornerPass::of(&corners, f, v.camera.near);
            // The one culling point: a node no view keeps is not drawn.
            if cull && pass.outside {
                continue;
            }
            if cull && self.horizon.is_some_and(|h| h.hides(vi, &aabb)) {
                hidden = true;
                continue;
            }
            seen = true;
            let z_min = pass.z_min.max(v.camera.near);
            // On the plane the gain does not depend on the slack: formed once for both errors.
            let flat_gain = match (&geo, cull) {
                (Some(_), _) => 0.0,
                (None, true) => pass.vertical_gain(f, v.up),
                (None, false) => v.vertical_gain,
            };
            let gain = |slack: f64| match (&geo, cull) {
                (Some(n), true) => pass.spread_gain(f, v.rotation * n.up, slack),
                (Some(n), false) => frustum_spread_gain(f, v.rotation * n.up, slack),
                (None, _) => flat_gain,
            };
            let errors = [Some(first), second];
            for (k, e) in errors.iter().enumerate() {
                let Some((eps, slack)) = *e else { continue };
                let r = projected_error_px(eps, z_min, v.focal, gain(slack));
                rho[k] = (rho[k].0.max(r), rho[k].1.max(r / v.tau));
            }
        }
        if hidden && !seen {
            self.hidden.set(self.hidden.get() + 1);
        }
        let eval = |eps: f64, (rho_px, rho_norm): (f64, f64)| NodeEval {
            eps,
            rho_px,
            rho_norm,
        };
        seen.then(|| (eval(first.0, rho[0]), second.map(|e| eval(e.0, rho[1]))))
    }

    /// Distance LOD: split while the eye is within `distance_factor` node sides of the node's
    /// box; a node split last frame stays split until 10 % beyond, an unsplit one splits only
    /// 10 % inside (hysteresis).
    fn wants_distance_split(&self, level: u32, tx: u32, ty: u32, was_split: bool) -> bool {
        let side = (self.grid.q as f64) * (1u64 << level) as f64 * self.grid.spacing.max_element();
        let node = self.fixed(level, tx, ty);
        let d = self
            .views
            .iter()
            .map(|v| {
                let p = v.camera.position;
                let aabb = self.aabb(level, &node, p);
                (p.clamp(aabb.min, aabb.max) - p).length()
            })
            .fold(f64::INFINITY, f64::min);
        let threshold = self.params.distance_factor * side;
        if was_split {
            d < threshold * 1.1
        } else {
            d < threshold * 0.9
        }
    }

    /// Splits node (ℓ, tx, ty) of a ring tile until every part meets τ or reaches `finest`;
    /// culled parts are dropped. Appends (ℓ, tx, ty, ε, ρ) and returns how many nodes miss τ.
    fn subdivide(
        &self,
        level: u32,
        tx: u32,
        ty: u32,
        finest: u32,
        out: &mut Vec<(u32, u32, u32, f32, f32)>,
    ) -> u32 {
        match self.evaluate(level, tx, ty, true) {
            Some(eval) => self.subdivide_seen(level, tx, ty, eval, finest, out),
            None => 0,
        }
    }

    /// [`Self::subdivide`] of a node some view sees, already evaluated (`eval`).
    fn subdivide_seen(
        &self,
        level: u32,
        tx: u32,
        ty: u32,
        eval: NodeEval,
        finest: u32,
        out: &mut Vec<(u32, u32, u32, f32, f32)>,
    ) -> u32 {
        let NodeEval {
            eps: e,
            rho_px: rho,
            rho_norm,
        } = eval;
        let split = match self.params.mode {
            LodMode::Full => true,
            LodMode::Distance => {
                let key = (level, tx, ty);
                let was_split = self.split_prev.is_some_and(|s| s.contains(&key));
                let want = self.wants_distance_split(level, tx, ty, was_split);
                if want && level > finest {
                    if let Some(s) = self.split_now {
                        s.borrow_mut().insert(key);
                    }
                }
                want
            }
            _ => rho_norm > 1.0,
        };
        if !split || level == finest {
            out.push((level, tx, ty, e as f32, rho as f32));
            return (rho_norm > 1.0 && self.params.mode == LodMode::Bounded) as u32;
        }
        let mut missed = 0;
        let quadrants = self.params.parent_quadrants && self.params.mode == LodMode::Bounded;
        let parent = quadrants.then(|| self.fixed(level, tx, ty));
        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let (cx, cy) = (2 * tx + dx, 2 * ty + dy);
            if !has_terrain(self.bake, level - 1, cx, cy) {
                continue;
            }
            if let Some(parent) = &parent {
                // The quadrant at this node's resolution first: its box is the child's, so
                // unseen here is unseen at any resolution.
                let Some((q, own)) = self.evaluate_quadrant(parent, level - 1, cx, cy) else {
                    continue;
                };
                if q.rho_norm <= 1.0 {
                    out.push((level - 1, cx, cy, q.eps as f32, q.rho_px as f32));
                    self.quadrants.borrow_mut().push(out.len() - 1);
                } else {
                    missed += self.subdivide_seen(level - 1, cx, cy, own, finest, out);
                }
                continue;
            }
            missed += self.subdivide(level - 1, cx, cy, finest, out);
        }
        missed
    }
}

/// Selects the tiles to draw for one camera. `placements` come from `clipmap::place_levels`
/// (finest first). Reuses `out`'s allocations.
pub fn select_tiles(
    bake: &ErrorBake,
    desc: &ClipmapDesc,
    placements: &[LevelPlacement],
    camera: &Camera,
    viewport: (u32, u32),
    params: &SelectParams,
    out: &mut Selection,
) {
    let view = View {
        camera,
        viewport,
        tau_px: params.tau_px,
    };
    select_tiles_multi(bake, desc, placements, &[view], params, out);
}

/// One selection for several channels (DESIGN.md "Multi-channel"; issue 7): a tile is drawn
/// when any channel sees it, at the resolution the most demanding channel that sees it needs
/// (largest ρ/τ) — so a tile never differs between two adjacent channels and seams match.
pub fn select_tiles_multi(
    bake: &ErrorBake,
    desc: &ClipmapDesc,
    placements: &[LevelPlacement],
    views: &[View],
    params: &SelectParams,
    out: &mut Selection,
) {
    select_tiles_multi_ready(bake, desc, placements, views, params, &AllReady, out);
}

/// [`select_tiles_multi`] over level textures that may not hold every tile yet (a streamed
/// source): a level tile is drawn from its texture only when `ready` says its texels are
/// there; elsewhere the quadtree stops at the coarser level (refined from the pools where their
/// samples are resident) and the tile counts in [`Selection::stream_late`]. Outside the
/// quadtree (other modes, `coarsen` off) a ring tile not ready is not drawn and counts late.
pub fn select_tiles_multi_ready(
    bake: &ErrorBake,
    desc: &ClipmapDesc,
    placements: &[LevelPlacement],
    views: &[View],
    params: &SelectParams,
    ready: &dyn TileReadiness,
    out: &mut Selection,
) {
    out.items.clear();
    out.levels.clear();
    out.levels.resize(placements.len(), LevelStats::default());
    out.unbounded = 0;
    out.stream_late = 0;
    out.wants.clear();
    out.hidden = 0;
    if views.is_empty() {
        return;
    }
    if params.mode == LodMode::Cdlod {
        out.split.clear();
        return super::cdlod::select_cdlod(bake, placements, views, params, out);
    }
    let views: Vec<ViewCtx> = views
        .iter()
        .map(|v| {
            let (fx, fy) = v.camera.frustum.focal_px(v.viewport.0, v.viewport.1);
            ViewCtx {
                camera: v.camera,
                to_view: v.camera.world_to_view(),
                rotation: v.camera.world_to_view_rotation(),
                up: v.camera.world_to_view_rotation() * DVec3::Z,
                focal: fx.max(fy),
                vertical_gain: frustum_vertical_gain(v.camera),
                tau: v.tau_px,
            }
        })
        .collect();
    let split_prev = std::mem::take(&mut out.split);
    let mut cache = std::mem::take(&mut out.node_cache);
    cache.begin(bake, params.earth.as_ref(), params.curvature);
    let split_now = std::cell::RefCell::new(std::collections::HashSet::new());
    let distance = params.mode == LodMode::Distance;
    let mut horizon = std::mem::take(&mut out.horizon);
    let cull_hidden = params.horizon_cull && params.mode == LodMode::Bounded;
    if cull_hidden {
        let eyes: Vec<DVec3> = views.iter().map(|v| v.camera.position).collect();
        horizon.build(bake, params.earth.as_ref(), params.curvature, &eyes);
    }
    let grid = Grid::of(bake);
    let frame = Frame {
        split_prev: distance.then_some(&split_prev),
        split_now: distance.then_some(&split_now),
        bake,
        grid,
        diagonals: (0..=bake.levels.len() as u32)
            .map(|l| grid.cell_diagonal(l))
            .collect(),
        views,
        params,
        ready,
        cache: std::cell::RefCell::new(&mut cache),
        #[cfg(test)]
        reference: reference::active(),
        horizon: cull_hidden.then_some(&horizon),
        hidden: std::cell::Cell::new(0),
        quadrants: std::cell::RefCell::new(Vec::new()),
    };

    if params.mode == LodMode::Bounded && params.coarsen {
        select_coarsest_first(&frame, placements, out);
        out.hidden = frame.hidden.get();
        drop(frame);
        out.split = split_now.into_inner();
        out.node_cache = cache;
        out.horizon = horizon;
        return;
    }
    let finest = if params.mode == LodMode::Bounded {
        finest_needed_level(&frame, placements)
    } else {
        0
    };
    out.finest_level = finest;
    for s in out.levels.iter_mut().take(finest as usize) {
        s.skipped = true;
    }

    let mut ring = Vec::new();
    let mut nodes = Vec::new();
    for (i, placement) in placements.iter().enumerate().skip(finest as usize) {
        let finer = (i > finest as usize).then(|| &placements[i - 1]);
        ring.clear();
        ring_tiles(desc, placement, finer, &mut ring);
        let level = placement.level;
        for &[tx, ty] in &ring {
            if !has_terrain(bake, level, tx, ty) {
                continue;
            }
            out.levels[i].considered += 1;
            let Some(eval) = frame.evaluate(level, tx, ty, true) else {
                out.levels[i].culled += 1;
                continue;
            };
            let NodeEval {
                eps,
                rho_px: rho,
                rho_norm,
            } = eval;
            if !frame.ready.is_ready(level, tx, ty) {
                // Not drawn rather than drawn stale (only the quadtree can fall back coarser).
                out.stream_late += 1;
                out.wants.push((level, tx, ty, rho as f32));
                continue;
            }
            out.levels[i].drawn += 1;
            if params.mode == LodMode::Clipmap
                || (params.mode == LodMode::Bounded && rho_norm <= 1.0)
            {
                out.levels[i].refined[0] += 1;
                out.levels[i].nodes += 1;
                out.items
                    .push(DrawItem::whole(level, tx, ty, eps as f32, rho as f32));
                continue;
            }
            out.unbounded += refine_ring_tile(&frame, level, tx, ty, eval, i, &mut nodes, out);
        }
    }
    out.hidden = frame.hidden.get();
    drop(frame);
    out.split = split_now.into_inner();
    out.node_cache = cache;
    out.horizon = horizon;
}

/// Draws ring tile (level, tx, ty) — which the finer levels do not cover, and which `eval`
/// says a view sees — as a quadtree of nodes from one pool slot (refinement up to the cap),
/// each split while it misses τ.
#[allow(clippy::too_many_arguments)]
fn refine_ring_tile(
    frame: &Frame,
    level: u32,
    tx: u32,
    ty: u32,
    eval: NodeEval,
    level_index: usize,
    nodes: &mut Vec<(u32, u32, u32, f32, f32)>,
    out: &mut Selection,
) -> u32 {
    let cap = frame.params.max_refinement.min(level).min(MAX_REFINEMENT);
    nodes.clear();
    frame.quadrants.borrow_mut().clear();
    let missed = frame.subdivide_seen(level, tx, ty, eval, level - cap, nodes);
    let first = out.items.len();
    out.push_refined(level_index, level, tx, ty, nodes);
    for &k in frame.quadrants.borrow().iter() {
        out.items[first + k].morph = Morph {
            quadrant: true,
            ..Morph::NONE
        };
    }
    missed
}

/// `Bounded` with [`SelectParams::coarsen`]: a quadtree over the clipmap levels. Every
/// coarsest-level tile is a root; a node that meets τ is drawn from its own level's texture;
/// one that misses it is split into its four children when the next finer level's patch holds
/// them (the patches nest with even origins, so a tile is wholly inside or outside it), else it
/// is a ring tile of its level and is refined from the pools. The result covers the same ground
/// as the ring-by-ring selection, each part by one node meeting τ (or unbounded at the cap),
/// at the coarsest level that does.
fn select_coarsest_first(frame: &Frame, placements: &[LevelPlacement], out: &mut Selection) {
    let Some(coarsest) = placements.last() else {
        return;
    };
    let roots = &frame.bake.levels[coarsest.level as usize];
    let mut nodes = Vec::new();
    let top = placements.len() - 1;
    // Nodes to visit, with their evaluation when a quadrant test made it already.
    let mut stack: Vec<(usize, u32, u32, Option<NodeEval>)> = (0..roots.tiles_y)
        .rev()
        .flat_map(|ty| (0..roots.tiles_x).rev().map(move |tx| (top, tx, ty, None)))
        .collect();
    while let Some((i, tx, ty, known)) = stack.pop() {
        let level = placements[i].level;
        if !has_terrain(frame.bake, level, tx, ty) {
            continue;
        }
        if i == top && !frame.ready.is_ready(level, tx, ty) {
            // The coarsest level is filled before the first frame; a root not there yet is not
            // drawn rather than drawn stale.
            out.stream_late += 1;
            out.wants.push((level, tx, ty, f32::MAX));
            continue;
        }
        // A split node is not a tile of its own: `considered` counts drawn + culled.
        let Some(eval) = known.or_else(|| frame.evaluate(level, tx, ty, true)) else {
            out.levels[i].considered += 1;
            out.levels[i].culled += 1;
            continue;
        };
        let NodeEval {
            eps,
            rho_px: rho,
            rho_norm,
        } = eval;
        if rho_norm <= 1.0 {
            let stats = &mut out.levels[i];
            stats.considered += 1;
            stats.drawn += 1;
            stats.refined[0] += 1;
            stats.nodes += 1;
            out.items
                .push(DrawItem::whole(level, tx, ty, eps as f32, rho as f32));
            continue;
        }
        let mut waiting = false;
        if i > 0 && inside_patch(&placements[i - 1], 2 * tx, 2 * ty) {
            // Children in the finer patch: descend (pushed so that they pop south-west first),
            // once all of them are in its texture; until then this node stands for them.
            let children =
                [(1, 1), (0, 1), (1, 0), (0, 0)].map(|(dx, dy)| (2 * tx + dx, 2 * ty + dy));
            let child_level = level - 1;
            let missing = |&(cx, cy): &(u32, u32)| {
                has_terrain(frame.bake, child_level, cx, cy)
                    && !frame.ready.is_ready(child_level, cx, cy)
            };
            if !children.iter().any(missing) {
                let parent = frame
                    .params
                    .parent_quadrants
                    .then(|| frame.fixed(level, tx, ty));
                for (cx, cy) in children {
                    if let Some(parent) = parent
                        .as_ref()
                        .filter(|_| has_terrain(frame.bake, child_level, cx, cy))
                    {
                        // The quadrant at this node's resolution, when it meets τ so (the
                        // child tile fully morphed onto this node's grid).
                        match frame.evaluate_quadrant(parent, child_level, cx, cy) {
                            None => {
                                out.levels[i - 1].considered += 1;
                                out.levels[i - 1].culled += 1;
                                continue;
                            }
                            Some((q, _)) if q.rho_norm <= 1.0 => {
                                let stats = &mut out.levels[i - 1];
                                stats.considered += 1;
                                stats.drawn += 1;
                                stats.refined[0] += 1;
                                stats.nodes += 1;
                                out.items.push(DrawItem {
                                    morph: Morph {
                                        quadrant: true,
                                        ..Morph::NONE
                                    },
                                    ..DrawItem::whole(
                                        child_level,
                                        cx,
                                        cy,
                                        q.eps as f32,
                                        q.rho_px as f32,
                                    )
                                });
                                continue;
                            }
                            Some((_, own)) => {
                                stack.push((i - 1, cx, cy, Some(own)));
                                continue;
                            }
                        }
                    }
                    stack.push((i - 1, cx, cy, None));
                }
                continue;
            }
            for &(cx, cy) in children.iter().filter(|c| missing(c)) {
                out.wants.push((child_level, cx, cy, rho as f32));
            }
            waiting = true;
        }
        out.levels[i].considered += 1;
        out.levels[i].drawn += 1;
        // Waiting for finer texels, the node is refined from the pools instead: beyond the
        // cap it is late for streaming, not a tile the cap leaves unbounded.
        let missed = refine_ring_tile(frame, level, tx, ty, eval, i, &mut nodes, out);
        if waiting {
            out.stream_late += (missed > 0) as u32;
        } else {
            out.unbounded += missed;
        }
    }
    let drawn_levels = out.levels.iter().position(|l| l.drawn > 0);
    out.finest_level = drawn_levels.unwrap_or(0) as u32;
    for s in out.levels.iter_mut() {
        s.skipped = s.drawn == 0;
    }
}

/// Whether level-ℓ tile (tx, ty) lies in `placement`'s patch (ℓ = placement.level).
fn inside_patch(placement: &LevelPlacement, tx: u32, ty: u32) -> bool {
    let n = placement.patch_tiles as i64;
    let [ox, oy] = placement.patch_origin;
    (ox..ox + n).contains(&(tx as i64)) && (oy..oy + n).contains(&(ty as i64))
}

/// The finest level worth drawing: level L is skipped when every level-(L+1) tile under its
/// patch already meets τ unrefined from where the eye is — drawing L would add triangles and
/// no accuracy. Skipping never breaks the bound: the coarser level then covers that area and
/// refines where it must.
fn finest_needed_level(frame: &Frame, placements: &[LevelPlacement]) -> u32 {
    let coarsest = placements.len().saturating_sub(1);
    for i in 0..coarsest {
        let patch = &placements[i];
        let next = &placements[i + 1];
        let lvl = next.level;
        let (t0x, t0y) = (
            patch.patch_origin[0].div_euclid(2),
            patch.patch_origin[1].div_euclid(2),
        );
        let n = (patch.patch_tiles / 2) as i64;
        let table = &frame.bake.levels[lvl as usize];
        let (tiles_x, tiles_y) = (table.tiles_x, table.tiles_y);
        let mut all_fine = true;
        'tiles: for ty in t0y.max(0)..(t0y + n).min(tiles_y as i64) {
            for tx in t0x.max(0)..(t0x + n).min(tiles_x as i64) {
                let (tx, ty) = (tx as u32, ty as u32);
                if !has_terrain(frame.bake, lvl, tx, ty) {
                    continue;
                }
                let needs_more = frame
                    .evaluate(lvl, tx, ty, false)
                    .is_some_and(|n| n.rho_norm > 1.0);
                if needs_more {
                    all_fine = false;
                    break 'tiles;
                }
            }
        }
        if !all_fine {
            return i as u32;
        }
    }
    coarsest as u32
}
