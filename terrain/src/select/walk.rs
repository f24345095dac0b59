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
use super::cdlod_morph::Morph;
use super::node_cache::{NodeCache, NodeFixed};
use super::parts::{choose_parts, MeshCosts, NodeEval, Parts, Quadrant, Upgrade};
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

/// Child `k` of node (tx, ty) in the order of [`Quadrant`] arrays (south-west, south-east,
/// north-west, north-east).
#[inline]
pub(super) fn child_of(tx: u32, ty: u32, k: usize) -> (u32, u32) {
    (2 * tx + (k as u32 & 1), 2 * ty + (k as u32 >> 1))
}

/// Whether level-L tile (tx, ty) exists and holds any real (non-padding) sample.
pub(super) fn has_terrain(bake: &ErrorBake, level: u32, tx: u32, ty: u32) -> bool {
    let t = &bake.levels[level as usize];
    tx < t.tiles_x && ty < t.tiles_y && t.terrain[(ty * t.tiles_x + tx) as usize]
}

/// (ε, slack) of a node drawn at an ancestor's resolution: `raw` the bake's ε of that level's
/// surface over the node, plus the drawn cell's `sag`; on the ellipsoid the normals' `spread`
/// plus that sag relative to ε (as [`Frame::compute_fixed`] forms a node's own).
#[inline]
pub(super) fn drawn_at(raw: f32, sag: f64, spread: Option<f64>) -> (f64, f64) {
    let eps = raw as f64 + sag;
    let slack = spread.map_or(0.0, |s| s + if eps > 0.0 { sag / eps } else { 0.0 });
    (eps, slack)
}

/// A node that missed τ as its parent's quadrant but may still be drawn in parts: its
/// parent's fixed values (its children may be that parent's sixteenths) and, when
/// [`Frame::upgrade_quadrants`] bounded its children already, those.
#[derive(Clone, Copy)]
pub(super) struct TryParts<'k> {
    pub(super) parent: &'k NodeFixed,
    pub(super) kids: Option<&'k [Quadrant; 4]>,
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
    /// Carrying ([`SelectParams::carry`]): the parts the walk of the ring tile being refined
    /// found outside the frustum (level, tx, ty), for its record's certificate; `None` else.
    pub(super) culled: Option<std::cell::RefCell<Vec<(u32, u32, u32)>>>,
    /// The ring tile being refined: which of its nodes are quadrants drawn at their parent's
    /// resolution ([`SelectParams::parent_quadrants`]) or sixteenths at their grandparent's,
    /// by index in its node list.
    pub(super) quadrants: std::cell::RefCell<Vec<(usize, Morph)>>,
    /// The triangles of the node meshes, what [`choose_parts`] weighs.
    pub(super) costs: MeshCosts,
    /// The largest τ of the views (px).
    pub(super) tau_max: f64,
    /// One view on the plane, no horizon culling: f·g/τ for the least vertical gain g in its
    /// frustum ([`super::bound::frustum_gain_floor`]), what bounds an exact evaluation from
    /// below (see [`Frame::quadrants_meeting`]).
    pub(super) gain_floor: Option<f64>,
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
    /// 1/τ and f/τ, formed once a frame: a node's evaluation scales by them five times
    /// (multiplications, not divisions; the reference evaluation scales alike).
    pub(super) inv_tau: f64,
    pub(super) focal_per_tau: f64,
}

impl Frame<'_> {
    pub(super) fn cell_diagonal(&self, level_drawn: u32) -> f64 {
        match self.diagonals.get(level_drawn as usize) {
            Some(&d) => d,
            None => self.grid.cell_diagonal(level_drawn),
        }
    }

    /// The children [`Self::upgrade_quadrants`] formed for a node, to be taken instead of
    /// formed again — except on the reference path (tests), which forms them afresh, so the
    /// equivalence tests check that taking them changes nothing.
    pub(super) fn formed<'k>(&self, kids: Option<&'k [Quadrant; 4]>) -> Option<&'k [Quadrant; 4]> {
        #[cfg(test)]
        if self.reference {
            return None;
        }
        kids
    }

    /// Node (level, tx, ty) was found outside every view: kept for the carried record.
    #[inline]
    pub(super) fn note_culled(&self, level: u32, tx: u32, ty: u32) {
        if let Some(c) = &self.culled {
            c.borrow_mut().push((level, tx, ty));
        }
    }

    /// The one view's corners (view space) and world box of node (level, tx, ty), its bottom
    /// carrying the sag of cells two levels up (the most any of its parts is drawn with).
    pub(super) fn carried_box(
        &self,
        level: u32,
        tx: u32,
        ty: u32,
    ) -> (super::bound::ViewCorners, Aabb) {
        let v = &self.views[0];
        // From the node cache on the ellipsoid (the box's lattice is dear to form again).
        let aabb = self.with_fixed(level, tx, ty, |node| {
            self.aabb(level + 2, node, v.camera.position)
        });
        (view_corners(&v.to_view, &aabb), aabb)
    }

    /// On the plane, the curvature slack of a level-`level` cell (0 without curvature).
    #[inline]
    pub(super) fn flat_sag(&self, level: u32) -> f64 {
        if self.params.curvature {
            curvature_interpolation_error(self.cell_diagonal(level))
        } else {
            0.0
        }
    }

    /// The node's camera-independent values (from the cache after the first time on the
    /// ellipsoid; on the plane they are two table reads, cheaper than the cache's lookup).
    pub(super) fn fixed(&self, level: u32, tx: u32, ty: u32) -> NodeFixed {
        self.with_fixed(level, tx, ty, |node| *node)
    }

    /// `f` of [`Self::fixed`], read in place in the cache (no copy of the whole record). `f`
    /// must not ask for fixed values itself: the cache is borrowed while it runs.
    #[inline]
    pub(super) fn with_fixed<R>(
        &self,
        level: u32,
        tx: u32,
        ty: u32,
        f: impl FnOnce(&NodeFixed) -> R,
    ) -> R {
        #[cfg(test)]
        if self.reference {
            return f(&self.compute_fixed(level, tx, ty));
        }
        if self.params.earth.is_none() {
            return f(&self.compute_fixed(level, tx, ty));
        }
        let mut cache = self.cache.borrow_mut();
        f(cache.get(level, tx, ty, || self.compute_fixed(level, tx, ty)))
    }

    /// [`Self::fixed`] computed: ε of the level-ℓ surface over the level-ℓ tile (tx, ty) with
    /// the curvature interpolation (on the ellipsoid: the drawn cell's slack,
    /// `GeoGrid::cell_sag_m`), and the node on the ellipsoid (geographic data).
    pub(super) fn compute_fixed(&self, level: u32, tx: u32, ty: u32) -> NodeFixed {
        let (lo, hi) = self.grid.rect(level, tx, ty);
        let (min_h, max_h) = self.bake.bounds(level, tx, ty);
        let raw = self.bake.eps(level, tx, ty) as f64;
        let (sag, geo) = match &self.params.earth {
            Some(g) => (
                g.cell_sag_m(lo, hi, 1 << level, min_h, max_h),
                Some(g.node_geometry(lo, hi, min_h, max_h)),
            ),
            None => (self.flat_sag(level), None),
        };
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
        self.with_fixed(level, tx, ty, |node| {
            let own = (node.eps, node.slack);
            self.evaluate_as(level, node, &[own], cull).map(|e| e[0])
        })
    }

    /// The quadrant (level, tx, ty) of its parent drawn at the parent's resolution — the
    /// bake's ε of the parent's surface over the quadrant with the parent's curvature slack
    /// and normal spread (the quadrant's normals turn less than the parent's, its cells are
    /// the parent's) over the quadrant's own box —, the same node at its own resolution and,
    /// given its grandparent's fixed values `grand`, at the grandparent's resolution, from one
    /// pass over the box (with the coarsest drawn level's cell slack in it, the larger);
    /// `None` when no view sees the quadrant. `parent`: the parent's fixed values, formed once
    /// for its four quadrants.
    pub(super) fn evaluate_quadrant(
        &self,
        parent: &NodeFixed,
        grand: Option<&NodeFixed>,
        level: u32,
        tx: u32,
        ty: u32,
    ) -> Option<(NodeEval, NodeEval, Option<NodeEval>)> {
        let drawn = level + 1 + grand.is_some() as u32;
        #[cfg(test)]
        if self.reference {
            let parent = self.compute_fixed(level + 1, tx / 2, ty / 2);
            let node = self.compute_fixed(level, tx, ty);
            let p = self.as_quadrant(&parent, level, tx, ty);
            let q = self.evaluate_reference_as(drawn, &node, p.0, p.1, true)?;
            let o = self.evaluate_reference_as(drawn, &node, node.eps, node.slack, true)?;
            let sub = grand.map(|_| {
                let grand = self.compute_fixed(level + 2, tx / 4, ty / 4);
                let g = self.as_sixteenth(&grand, level, tx, ty);
                self.evaluate_reference_as(drawn, &node, g.0, g.1, true)
            });
            return Some((q, o, sub.flatten()));
        }
        let p = self.as_quadrant(parent, level, tx, ty);
        let g = grand.map(|grand| self.as_sixteenth(grand, level, tx, ty));
        let e = self.with_fixed(level, tx, ty, |node| {
            let own = (node.eps, node.slack);
            let errors = match g {
                Some(g) => [p, own, g],
                None => [p, own, own],
            };
            self.evaluate_as(drawn, node, &errors[..2 + g.is_some() as usize], true)
        })?;
        Some((e[0], e[1], g.map(|_| e[2])))
    }

    /// (ε, slack) of node (level, tx, ty) drawn at its grandparent's resolution, `grand` being
    /// its grandparent's fixed values: the bake's [`ErrorBake::fine_eps`] plus the
    /// grandparent's sag, as [`Self::as_quadrant`] forms a quadrant's.
    #[inline]
    pub(super) fn as_sixteenth(
        &self,
        grand: &NodeFixed,
        level: u32,
        tx: u32,
        ty: u32,
    ) -> (f64, f64) {
        let spread = grand.geo.map(|_| grand.spread);
        drawn_at(self.bake.fine_eps(level, tx, ty), grand.sag, spread)
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
        let spread = parent.geo.map(|_| parent.spread);
        drawn_at(self.bake.coarse_eps(level, tx, ty), parent.sag, spread)
    }

    /// [`Self::evaluate`] of the node `node` drawn at level `drawn`'s resolution (its own, or
    /// an ancestor's) for each (error, gain slack) of `errors` (one to three), all from the
    /// same corners; the entries past `errors.len()` repeat the first.
    pub(super) fn evaluate_as(
        &self,
        drawn: u32,
        node: &NodeFixed,
        errors: &[(f64, f64)],
        cull: bool,
    ) -> Option<[NodeEval; 3]> {
        debug_assert!((1..=3).contains(&errors.len()));
        let geo = node.geo;
        let (mut seen, mut hidden, mut straddles) = (false, false, false);
        let mut rho = [(0.0f64, 0.0f64); 3];
        let (mut gain_max, mut slack_max) = (0f64, 0f64);
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
            straddles |= cull && !pass.inside;
            let z_min = pass.z_min.max(v.camera.near);
            // On the plane the gain does not depend on the slack: formed once for all errors.
            let flat_gain = match (&geo, cull) {
                (Some(_), _) => 0.0,
                (None, true) => pass.vertical_gain(f, v.up),
                (None, false) => v.vertical_gain,
            };
            // On the ellipsoid the gain's two parts, formed once for all errors:
            // `CornerPass::spread_gain` is g for no slack and g + slack·c else, bit for bit.
            let (g, c) = match (&geo, cull) {
                (Some(n), true) => pass.gain_parts(f, v.rotation * n.up),
                _ => (flat_gain, 0.0),
            };
            let gain = |slack: f64| match (&geo, cull) {
                (Some(_), true) if slack <= 0.0 => g,
                (Some(_), true) => g + slack * c,
                (Some(n), false) => frustum_spread_gain(f, v.rotation * n.up, slack),
                (None, _) => flat_gain,
            };
            gain_max = gain_max.max(g * v.focal_per_tau);
            slack_max = slack_max.max(c * v.focal_per_tau);
            for (k, &(eps, slack)) in errors.iter().enumerate() {
                let r = projected_error_px(eps, z_min, v.focal, gain(slack));
                rho[k] = (rho[k].0.max(r), rho[k].1.max(r * v.inv_tau));
            }
        }
        if hidden && !seen {
            self.hidden.set(self.hidden.get() + 1);
        }
        let eval = |k: usize| {
            let k = if k < errors.len() { k } else { 0 };
            NodeEval::new(
                errors[k].0,
                rho[k].0,
                rho[k].1,
                gain_max,
                slack_max,
                straddles,
            )
        };
        seen.then(|| [eval(0), eval(1), eval(2)])
    }

    /// The four children of split node (level, tx, ty) as quadrants at its resolution
    /// (south-west, south-east, north-west, north-east), `parent` its fixed values; with
    /// `grand` (its parent's), each also as a sixteenth at the grandparent's resolution.
    pub(super) fn quadrants(
        &self,
        parent: &NodeFixed,
        grand: Option<&NodeFixed>,
        level: u32,
        tx: u32,
        ty: u32,
    ) -> [Quadrant; 4] {
        let mut out = [Quadrant::NoTerrain; 4];
        for (k, q) in out.iter_mut().enumerate() {
            let (cx, cy) = child_of(tx, ty, k);
            if has_terrain(self.bake, level - 1, cx, cy) {
                *q = match self.evaluate_quadrant(parent, grand, level - 1, cx, cy) {
                    None => {
                        self.note_culled(level - 1, cx, cy);
                        Quadrant::Unseen
                    }
                    Some((q, own, sub)) => Quadrant::Seen { q, own, sub },
                };
            }
        }
        out
    }

    /// Before split node (level, tx, ty)'s children are drawn or walked
    /// (`node` its fixed values): a child that missed τ as a quadrant by its own box but
    /// meets τ itself, and whose children (when `splittable`) all meet τ as sixteenths
    /// bounded from its box ([`Self::quadrants_meeting`]), meets τ at this node's resolution
    /// after all — so [`choose_parts`] weighs this node whole against its children with it
    /// (decided later, when the child is walked, it would be drawn as a quadrant beside
    /// siblings that add up to more than the node whole). Returns what it found of each child
    /// ([`Upgrade`]) in `found`: walked, one best drawn whole need not be tried in parts
    /// again, and one best drawn in parts takes the children formed here.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn upgrade_quadrants(
        &self,
        quads: &mut [Quadrant; 4],
        node: &NodeFixed,
        level: u32,
        tx: u32,
        ty: u32,
        splittable: impl Fn(u32, u32) -> bool,
        found: &mut [Upgrade; 4],
    ) {
        if !self.sixteenths_below(level - 1) {
            return;
        }
        for (k, quad) in quads.iter_mut().enumerate() {
            let Quadrant::Seen { q, own, .. } = quad else {
                continue;
            };
            let (cx, cy) = child_of(tx, ty, k);
            if q.rho_norm <= 1.0 || own.rho_norm > 1.0 || !splittable(cx, cy) {
                continue;
            }
            let child = self.fixed(level - 1, cx, cy);
            let kids = self.quadrants_meeting(own, &child, node, level - 1, cx, cy);
            match choose_parts(&kids, true, self.costs) {
                Parts::AsQuadrant { rho_px, rho_norm } => {
                    (q.rho_px, q.rho_norm) = (rho_px, rho_norm)
                }
                Parts::Whole(_) => found[k] = Upgrade::Whole,
                Parts::Children => found[k] = Upgrade::Children(kids),
            }
        }
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
            Some(eval) => self.subdivide_seen(level, tx, ty, eval, finest, None, out),
            None => 0,
        }
    }

    /// [`Self::subdivide`] of a node some view sees, already evaluated (`eval`). `retry`: when
    /// it missed τ as its parent's quadrant, its parent (its children may then be drawn as
    /// sixteenths of the parent, [`SelectParams::sixteenths`]).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn subdivide_seen(
        &self,
        level: u32,
        tx: u32,
        ty: u32,
        eval: NodeEval,
        finest: u32,
        retry: Option<TryParts<'_>>,
        out: &mut Vec<(u32, u32, u32, f32, f32)>,
    ) -> u32 {
        let NodeEval {
            eps: e,
            rho_px: rho,
            rho_norm,
            ..
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
        let quadrants = self.params.parent_quadrants && self.params.mode == LodMode::Bounded;
        let retry = retry.filter(|_| quadrants && self.sixteenths_below(level));
        let grand = retry.map(|r| r.parent);
        if (!split && grand.is_none()) || level == finest {
            out.push((level, tx, ty, e as f32, rho as f32));
            return (rho_norm > 1.0 && self.params.mode == LodMode::Bounded) as u32;
        }
        let mut missed = 0;
        if quadrants {
            let node = self.fixed(level, tx, ty);
            let mut found = [Upgrade::Untried; 4];
            let quads = match (grand, self.formed(retry.and_then(|r| r.kids))) {
                (Some(_), Some(kids)) if !split => *kids,
                (Some(g), None) if !split => self.quadrants_meeting(&eval, &node, g, level, tx, ty),
                _ => {
                    let mut quads = self.quadrants(&node, grand, level, tx, ty);
                    let splittable = |_, _| level - 1 > finest;
                    self.upgrade_quadrants(
                        &mut quads, &node, level, tx, ty, splittable, &mut found,
                    );
                    quads
                }
            };
            match choose_parts(&quads, !split, self.costs) {
                Parts::Whole(rho_px) => {
                    out.push((level, tx, ty, e as f32, rho_px.unwrap_or(rho) as f32));
                    return 0;
                }
                Parts::AsQuadrant { rho_px, .. } => {
                    // `grand` is this node's parent here.
                    let (peps, _) = self.as_quadrant(grand.unwrap(), level, tx, ty);
                    out.push((level, tx, ty, peps as f32, rho_px as f32));
                    self.quadrants
                        .borrow_mut()
                        .push((out.len() - 1, Morph::QUADRANT));
                    return 0;
                }
                Parts::Children => {}
            }
            for (k, quad) in quads.iter().enumerate() {
                let (cx, cy) = child_of(tx, ty, k);
                let Quadrant::Seen { q, own, sub } = *quad else {
                    continue;
                };
                let drawn = match sub {
                    Some(s) if s.rho_norm <= 1.0 => Some((s, Morph::SIXTEENTH)),
                    _ if q.rho_norm <= 1.0 => Some((q, Morph::QUADRANT)),
                    _ => None,
                };
                if let Some((d, morph)) = drawn {
                    out.push((level - 1, cx, cy, d.eps as f32, d.rho_px as f32));
                    self.quadrants.borrow_mut().push((out.len() - 1, morph));
                } else {
                    let retry = match &found[k] {
                        Upgrade::Whole => None,
                        Upgrade::Untried => Some(TryParts {
                            parent: &node,
                            kids: None,
                        }),
                        Upgrade::Children(kids) => Some(TryParts {
                            parent: &node,
                            kids: Some(kids),
                        }),
                    };
                    missed += self.subdivide_seen(level - 1, cx, cy, own, finest, retry, out);
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

    /// Whether the children of a level-`level` node may be drawn as sixteenths of its parent:
    /// asked for, a tile side the stride-4 mesh divides, and the parent's level in the bake.
    pub(super) fn sixteenths_below(&self, level: u32) -> bool {
        self.params.sixteenths
            && self.params.parent_quadrants
            && level >= 1
            && self.grid.q >= 4
            && self.grid.q.is_multiple_of(4)
            && (level as usize + 1) < self.bake.levels.len()
    }
}
