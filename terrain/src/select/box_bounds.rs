//! The children of a node that meets τ bounded from its box — no corner pass of their own:
//! `quadrants_within`, and `quadrants_meeting`, which evaluates exactly the children near τ
//! where that could change what is drawn: more of `walk`'s `Frame`.

use super::bound::{min_view_depth_of, projected_error_px, tile_aabb, view_corners, CornerPass};
use super::node_cache::NodeFixed;
use super::parts::{choose_parts, NodeEval, Parts, Quadrant, HYBRID_REACH};
use super::walk::{child_of, drawn_at, has_terrain, Frame};

impl Frame<'_> {
    /// The children of node (level, tx, ty) that meets τ itself (`eval`, at its resolution,
    /// `node` its fixed values) bounded from its box alone: as quadrants at its resolution and
    /// as sixteenths at its parent's (`parent`'s fixed values). Each child's surface lies in
    /// the node's box, so the node's gains bound the child's (on the ellipsoid the child's
    /// normals lie within the node's spread of the node's centre normal, so the slack is the
    /// node's spread and the drawn cell's sag over ε); only the child's own smallest depth
    /// (its box drawn at the parent's resolution, the larger) is formed — no corner pass, no
    /// cull (every child holding terrain counts as seen). A child drawn on this bound meets τ
    /// wherever it is drawn.
    fn quadrants_within(
        &self,
        eval: &NodeEval,
        node: &NodeFixed,
        parent: &NodeFixed,
        level: u32,
        tx: u32,
        ty: u32,
    ) -> [Quadrant; 4] {
        let mut out = [Quadrant::NoTerrain; 4];
        for (k, q) in out.iter_mut().enumerate() {
            let (cx, cy) = child_of(tx, ty, k);
            if !has_terrain(self.bake, level - 1, cx, cy) {
                continue;
            }
            let z = match node.geo {
                // The child's box on the ellipsoid (eye-independent, cached).
                Some(_) => {
                    let aabb = self.with_fixed(level - 1, cx, cy, |child| {
                        child.geo.map_or_else(|| unreachable!(), |g| g.aabb)
                    });
                    self.views
                        .iter()
                        .map(|v| min_view_depth_of(&v.to_view, &aabb).max(v.camera.near))
                        .fold(f64::INFINITY, f64::min)
                }
                // On the plane (`Self::aabb`), from the two table reads it needs.
                None => {
                    let (lo, hi) = self.grid.rect(level - 1, cx, cy);
                    let (min_h, max_h) = self.bake.bounds(level - 1, cx, cy);
                    let diagonal = self.cell_diagonal(level + 1);
                    self.views
                        .iter()
                        .map(|v| {
                            let (eye, curvature) = (v.camera.position, self.params.curvature);
                            let aabb = tile_aabb(lo, hi, min_h, max_h, eye, curvature, diagonal);
                            min_view_depth_of(&v.to_view, &aabb).max(v.camera.near)
                        })
                        .fold(f64::INFINITY, f64::min)
                }
            };
            // ε at a drawn level with that level's sag (as `as_quadrant` / `as_sixteenth`).
            let bounded = |raw: f32, sag: f64| {
                let (eps, slack) = drawn_at(raw, sag, node.geo.map(|_| node.spread));
                let gain = eval.gain + slack * eval.gain_slack();
                let rho_norm = projected_error_px(eps, z, gain, 1.0);
                NodeEval::new(
                    eps,
                    rho_norm * self.tau_max,
                    rho_norm,
                    eval.gain,
                    eval.gain_slack(),
                    // Within the node's box: fully inside the frustums when the node is.
                    eval.straddles(),
                )
            };
            let quadrant = bounded(self.bake.coarse_eps(level - 1, cx, cy), node.sag);
            let sub = bounded(self.bake.fine_eps(level - 1, cx, cy), parent.sag);
            *q = Quadrant::Seen {
                q: quadrant,
                own: quadrant,
                sub: Some(sub),
            };
        }
        out
    }

    /// The children of node (level, tx, ty) that meets τ itself, for [`choose_parts`]: bounded
    /// from its box ([`Self::quadrants_within`]); where that finds the node best drawn whole,
    /// each child that came within [`HYBRID_REACH`] of τ as a sixteenth is evaluated exactly
    /// too (its own box and gain, [`Self::evaluate_quadrant`]) and each of its bounds taken
    /// the smaller of the two — both hold — or the child dropped where no view sees it.
    ///
    /// Not where the exact evaluation could change nothing ([`Self::gain_floor`]): with one
    /// view on the plane the two share ε and depth, so they differ by the gain alone, and the
    /// child's gain is at least the frustum's least — a child whose bounds, scaled by that
    /// least gain over the node's, still miss τ as a sixteenth (and as a quadrant, unless it
    /// meets τ so already), and that the view does not cull, keeps what it meets τ as. Only
    /// its ρ stays the looser bound.
    pub(super) fn quadrants_meeting(
        &self,
        eval: &NodeEval,
        node: &NodeFixed,
        parent: &NodeFixed,
        level: u32,
        tx: u32,
        ty: u32,
    ) -> [Quadrant; 4] {
        let mut quads = self.quadrants_within(eval, node, parent, level, tx, ty);
        if !matches!(choose_parts(&quads, true, self.costs), Parts::Whole(_)) {
            return quads;
        }
        for (k, quad) in quads.iter_mut().enumerate() {
            let Quadrant::Seen {
                q, sub: Some(sub), ..
            } = quad
            else {
                continue;
            };
            if sub.rho_norm <= 1.0 || sub.rho_norm > HYBRID_REACH {
                continue;
            }
            let (cx, cy) = child_of(tx, ty, k);
            if let Some(floor) = self.gain_floor {
                // Above 1 by more than rounding, scaled down to the least gain.
                let misses = |r: f64| r * (floor / eval.gain) > 1.0 + 1e-9;
                if misses(sub.rho_norm)
                    && (q.rho_norm <= 1.0 || misses(q.rho_norm))
                    && !self.one_view_culls(level - 1, cx, cy, level + 1)
                {
                    continue;
                }
            }
            let tighter = |a: &mut NodeEval, b: NodeEval| {
                if b.rho_norm < a.rho_norm {
                    (a.rho_px, a.rho_norm) = (b.rho_px, b.rho_norm);
                }
            };
            match self.evaluate_quadrant(node, Some(parent), level - 1, cx, cy) {
                None => {
                    self.note_culled(level - 1, cx, cy);
                    *quad = Quadrant::Unseen
                }
                Some((eq, _, es)) => {
                    tighter(q, eq);
                    if let Some(es) = es {
                        tighter(sub, es);
                    }
                }
            }
        }
        quads
    }

    /// Whether the one view ([`Self::gain_floor`]'s) culls node (level, tx, ty) drawn at
    /// level `drawn` ([`Self::aabb`]'s box): the cull [`Self::evaluate_as`] does, without the
    /// gain's divisions.
    fn one_view_culls(&self, level: u32, tx: u32, ty: u32, drawn: u32) -> bool {
        debug_assert!(self.params.earth.is_none() && self.views.len() == 1);
        let v = &self.views[0];
        let node = self.fixed(level, tx, ty);
        let aabb = self.aabb(drawn, &node, v.camera.position);
        let corners = view_corners(&v.to_view, &aabb);
        CornerPass::cull_and_depth(&corners, &v.camera.frustum, v.camera.near).outside
    }
}
