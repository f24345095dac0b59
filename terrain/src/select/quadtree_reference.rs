//! The selection's reference evaluation (tests only): every node's ε and box computed afresh,
//! one view at a time with the bound's plain functions — what the fast path (cached fixed
//! values, one pass over the corners) must reproduce exactly.

use std::cell::Cell;

use super::super::bound::{
    frustum_spread_gain, inside_of, min_depth_of, obliquity_of, outside_of, projected_error_px,
    spread_gain_of, vertical_gain_of,
};
use super::{Frame, NodeEval, NodeFixed};

thread_local! {
    static REFERENCE: Cell<bool> = const { Cell::new(false) };
    static EVERY_HYBRID: Cell<bool> = const { Cell::new(false) };
}

/// Whether selections on this thread evaluate exactly every child `Frame::quadrants_meeting`
/// finds within reach (no `Frame::gain_floor` skip).
pub(in crate::select) fn every_hybrid() -> bool {
    EVERY_HYBRID.with(|r| r.get())
}

/// Runs `f` with the selections on this thread evaluating every child within reach exactly.
pub(crate) fn with_every_hybrid<T>(f: impl FnOnce() -> T) -> T {
    EVERY_HYBRID.with(|r| r.set(true));
    let t = f();
    EVERY_HYBRID.with(|r| r.set(false));
    t
}

/// Whether selections on this thread take the reference path now.
pub(in crate::select) fn active() -> bool {
    REFERENCE.with(|r| r.get())
}

/// Runs `f` with the selections on this thread on the reference path.
pub(crate) fn with_reference<T>(f: impl FnOnce() -> T) -> T {
    REFERENCE.with(|r| r.set(true));
    let t = f();
    REFERENCE.with(|r| r.set(false));
    t
}

impl Frame<'_> {
    /// [`Frame::evaluate`] without the cache and without the fused corner pass.
    pub(super) fn evaluate_reference(
        &self,
        level: u32,
        tx: u32,
        ty: u32,
        cull: bool,
    ) -> Option<NodeEval> {
        let node = self.compute_fixed(level, tx, ty);
        self.evaluate_reference_as(level, &node, node.eps, node.slack, cull)
    }

    /// [`Frame::evaluate_as`] on the reference path.
    pub(super) fn evaluate_reference_as(
        &self,
        drawn: u32,
        node: &NodeFixed,
        eps: f64,
        slack: f64,
        cull: bool,
    ) -> Option<NodeEval> {
        let geo = node.geo;
        let (mut seen, mut straddles) = (false, false);
        let (mut rho_px, mut rho_norm) = (0.0f64, 0.0f64);
        let (mut gain, mut gain_slack) = (0.0f64, 0.0f64);
        for v in &self.views {
            let aabb = match &geo {
                Some(n) => n.aabb,
                None => self.aabb(drawn, node, v.camera.position),
            };
            let corners = aabb.corners().map(|c| v.to_view.transform_point3(c));
            let f = &v.camera.frustum;
            if cull && outside_of(&corners, f, v.camera.near) {
                continue;
            }
            seen = true;
            straddles |= cull && !inside_of(&corners, f, v.camera.near);
            let z_min = min_depth_of(&corners, v.camera.near);
            let c = match (&geo, cull) {
                (Some(n), true) => spread_gain_of(&corners, f, v.rotation * n.up, slack),
                (Some(n), false) => frustum_spread_gain(f, v.rotation * n.up, slack),
                (None, true) => vertical_gain_of(&corners, f, v.up),
                (None, false) => v.vertical_gain,
            };
            let (g, s) = match (&geo, cull) {
                (Some(n), true) => (
                    vertical_gain_of(&corners, f, v.rotation * n.up),
                    obliquity_of(&corners, f),
                ),
                (Some(_), false) => (0.0, 0.0),
                (None, _) => (c, 0.0),
            };
            gain = gain.max(g * v.focal_per_tau);
            gain_slack = gain_slack.max(s * v.focal_per_tau);
            let rho = projected_error_px(eps, z_min, v.focal, c);
            rho_px = rho_px.max(rho);
            rho_norm = rho_norm.max(rho * v.inv_tau);
        }
        seen.then_some(NodeEval::new(
            eps, rho_px, rho_norm, gain, gain_slack, straddles,
        ))
    }
}
