//! One selection pass over the nodes: the frame's views, each node's camera-independent
//! values and its projected error in every view (the bound, `bound.rs`), a split node's
//! children as quadrants at its resolution, and the split walk of a ring tile's nodes.

use glam::{DVec2, DVec3};

use crate::bake::ErrorBake;
use crate::camera::Camera;
use crate::tiles::Aabb;

use super::bound::{
    curvature_interpolation_error, frustum_spread_gain, projected_error_px, tile_aabb,
    view_corners, CornerPass,
};
use super::node_cache::{NodeCache, NodeFixed};
use super::selection::{LodMode, SelectParams, TileReadiness};

#[cfg(test)]
#[path = "quadtree_reference.rs"]
pub(super) mod reference;

/// Geometry of a dataset the selection needs (from the bake).
#[derive(Debug, Clone, Copy)]
pub(super) struct Grid {
    pub(super) q: u32,
    pub(super) spacing: DVec2,
    pub(super) valid_max: DVec2,
}

impl Grid {
    pub(super) fn of(bake: &ErrorBake) -> Self {
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
    pub(super) fn cell_diagonal(&self, level_drawn: u32) -> f64 {
        (self.spacing * (1u64 << level_drawn) as f64).length()
    }

    /// Horizontal rectangle of a level tile in metres, clipped to the valid data.
    pub(super) fn rect(&self, level: u32, tx: u32, ty: u32) -> (DVec2, DVec2) {
        let side = (self.q as u64) << level;
        let lo = DVec2::new((tx as u64 * side) as f64, (ty as u64 * side) as f64) * self.spacing;
        let hi = lo + DVec2::splat(side as f64) * self.spacing;
        (lo.min(self.valid_max), hi.min(self.valid_max))
    }
}

/// Nodes (level, tx, ty).
pub(super) type NodeSet = std::collections::HashSet<(u32, u32, u32)>;

/// Whether level-L tile (tx, ty) exists and holds any real (non-padding) sample.
pub(super) fn has_terrain(bake: &ErrorBake, level: u32, tx: u32, ty: u32) -> bool {
    let t = &bake.levels[level as usize];
    tx < t.tiles_x && ty < t.tiles_y && t.terrain[(ty * t.tiles_x + tx) as usize]
}

/// Context shared by every tile of a frame.
pub(super) struct Frame<'a> {
    /// Distance mode: nodes split last frame, and the set being filled this frame.
    pub(super) split_prev: Option<&'a NodeSet>,
    pub(super) split_now: Option<&'a std::cell::RefCell<NodeSet>>,
    pub(super) bake: &'a ErrorBake,
    pub(super) grid: Grid,
    pub(super) views: Vec<ViewCtx<'a>>,
    pub(super) params: &'a SelectParams,
    pub(super) ready: &'a dyn TileReadiness,
    /// The nodes' camera-independent values, kept across frames.
    pub(super) cache: std::cell::RefCell<&'a mut NodeCache>,
    /// Tests: take the reference evaluation (`quadtree_reference.rs`).
    #[cfg(test)]
    pub(super) reference: bool,
    /// Horizon culling: the eyes' horizons and the nodes it hid.
    pub(super) horizon: Option<&'a super::horizon::HorizonSet>,
    pub(super) hidden: std::cell::Cell<u32>,
    /// [`Grid::cell_diagonal`] of every level of the bake, formed once a frame (a square root
    /// per node evaluation otherwise).
    pub(super) diagonals: Vec<f64>,
    /// The ring tile being refined: which of its nodes are quadrants drawn at their parent's
    /// resolution ([`SelectParams::parent_quadrants`]), by index in its node list.
    pub(super) quadrants: std::cell::RefCell<Vec<usize>>,
}

/// One channel's camera with what the bound needs from it.
pub(super) struct ViewCtx<'a> {
    pub(super) camera: &'a Camera,
    /// World → view, computed once per frame (not per node: the attitude's trigonometry).
    pub(super) to_view: glam::DMat4,
    /// Its rotation (for the ellipsoid's normals).
    pub(super) rotation: glam::DMat3,
    /// The world vertical in view space.
    pub(super) up: DVec3,
    pub(super) focal: f64,
    /// [`frustum_vertical_gain`].
    pub(super) vertical_gain: f64,
    pub(super) tau: f64,
}

/// A node as the views see it.
#[derive(Clone, Copy)]
pub(super) struct NodeEval {
    pub(super) eps: f64,
    /// Largest ρ (px) among the views that see the node.
    pub(super) rho_px: f64,
    /// Largest ρ/τ among them: the node meets every channel's bound when ≤ 1.
    pub(super) rho_norm: f64,
}

/// A child of a split node seen as a quadrant of it ([`Frame::quadrants`]).
#[derive(Clone, Copy)]
pub(super) enum Quadrant {
    /// All padding: never drawn.
    NoTerrain,
    /// No view sees it.
    Unseen,
    /// `q` at the parent's resolution, `own` at its own.
    Seen { q: NodeEval, own: NodeEval },
}

/// When every child holding terrain is seen and meets τ at the parent's resolution (and one
/// does), the parent's surface meets τ wherever it is drawn: the parent is drawn whole, one
/// instance instead of four quarter meshes of the same triangles. Returns the largest
/// quadrant ρ (px) and ρ/τ then.
pub(super) fn whole_from_quadrants(quads: &[Quadrant; 4]) -> Option<(f64, f64)> {
    let mut rho = None::<(f64, f64)>;
    for q in quads {
        match q {
            Quadrant::NoTerrain => {}
            Quadrant::Unseen => return None,
            Quadrant::Seen { q, .. } if q.rho_norm <= 1.0 => {
                let (px, n) = rho.unwrap_or((0.0, 0.0));
                rho = Some((px.max(q.rho_px), n.max(q.rho_norm)));
            }
            Quadrant::Seen { .. } => return None,
        }
    }
    rho
}

impl Frame<'_> {
    pub(super) fn cell_diagonal(&self, level_drawn: u32) -> f64 {
        match self.diagonals.get(level_drawn as usize) {
            Some(&d) => d,
            None => self.grid.cell_diagonal(level_drawn),
        }
    }

    /// The node's camera-independent values (from the cache after the first time on the
    /// ellipsoid; on the plane they are two table reads, cheaper than the cache's lookup).
    pub(super) fn fixed(&self, level: u32, tx: u32, ty: u32) -> NodeFixed {
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
    pub(super) fn compute_fixed(&self, level: u32, tx: u32, ty: u32) -> NodeFixed {
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
    pub(super) fn aabb(&self, level: u32, node: &NodeFixed, eye: DVec3) -> Aabb {
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
    pub(super) fn evaluate(&self, level: u32, tx: u32, ty: u32, cull: bool) -> Option<NodeEval> {
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
    pub(super) fn evaluate_quadrant(
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
    #[inline]
    pub(super) fn as_quadrant(
        &self,
        parent: &NodeFixed,
        level: u32,
        tx: u32,
        ty: u32,
    ) -> (f64, f64) {
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
    pub(super) fn evaluate_as(
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

    /// The four children of split node (level, tx, ty) as quadrants at its resolution
    /// (south-west, south-east, north-west, north-east), `parent` its fixed values.
    pub(super) fn quadrants(
        &self,
        parent: &NodeFixed,
        level: u32,
        tx: u32,
        ty: u32,
    ) -> [Quadrant; 4] {
        let mut out = [Quadrant::NoTerrain; 4];
        for (k, q) in out.iter_mut().enumerate() {
            let (cx, cy) = (2 * tx + (k as u32 & 1), 2 * ty + (k as u32 >> 1));
            if has_terrain(self.bake, level - 1, cx, cy) {
                *q = match self.evaluate_quadrant(parent, level - 1, cx, cy) {
                    None => Quadrant::Unseen,
                    Some((q, own)) => Quadrant::Seen { q, own },
                };
            }
        }
        out
    }

    /// Distance LOD: split while the eye is within `distance_factor` node sides of the node's
    /// box; a node split last frame stays split until 10 % beyond, an unsplit one splits only
    /// 10 % inside (hysteresis).
    pub(super) fn wants_distance_split(
        &self,
        level: u32,
        tx: u32,
        ty: u32,
        was_split: bool,
    ) -> bool {
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
    pub(super) fn subdivide(
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
    pub(super) fn subdivide_seen(
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
        if quadrants {
            let parent = self.fixed(level, tx, ty);
            let quads = self.quadrants(&parent, level, tx, ty);
            if let Some((rho_px, _)) = whole_from_quadrants(&quads) {
                out.push((level, tx, ty, e as f32, rho_px as f32));
                return 0;
            }
            for (k, quad) in quads.iter().enumerate() {
                let (cx, cy) = (2 * tx + (k as u32 & 1), 2 * ty + (k as u32 >> 1));
                let Quadrant::Seen { q, own } = *quad else {
                    continue;
                };
                if q.rho_norm <= 1.0 {
                    out.push((level - 1, cx, cy, q.eps as f32, q.rho_px as f32));
                    self.quadrants.borrow_mut().push(out.len() - 1);
                } else {
                    missed += self.subdivide_seen(level - 1, cx, cy, own, finest, out);
                }
            }
            return missed;
        }
        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let (cx, cy) = (2 * tx + dx, 2 * ty + dy);
            if !has_terrain(self.bake, level - 1, cx, cy) {
                continue;
            }
            missed += self.subdivide(level - 1, cx, cy, finest, out);
        }
        missed
    }
}
