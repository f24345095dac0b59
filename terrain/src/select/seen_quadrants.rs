//! A node that meets τ drawn as only the parts of it that can show (pure): the quadrants some
//! view sees and that hold terrain, each at the node's own resolution.
//!
//! The coarsest-first walk draws a node that meets τ whole. Where its box crosses a frustum
//! plane, some of its quadrants may lie wholly outside every view; where it reaches past the
//! grid's last sample, some hold only padding (drawn folded onto that sample). CDLOD's
//! quadtree never draws those: it culls a node's children one by one and draws each kept one
//! at its parent's resolution. Here the same: the node's children evaluated as quadrants at
//! its resolution (`Frame::quadrants`: the bake's ε of the node's surface over each — never
//! more than the node's —, each one's own box and gain), and the seen ones drawn instead of
//! the node when their meshes are fewer triangles than its (skirts counted, instances not:
//! the lavapipe suite's Inn valley and Sierra Nevada cruise and manoeuvre, tiles of 9, drew
//! 0.84–0.93× the triangles at τ = 20 so and 0.93–0.97× with an instance weighed as 64
//! triangles; every measured error unchanged).
//!
//! A quadrant so drawn is the node's own surface over the quadrant (the child's stride-2 mesh
//! over its even vertices, which are the node's samples), so the bound it meets is the one the
//! node met, from a smaller box; it reads the node's level texture, where the node's samples
//! are (its child's level may not hold that place at all): the draw item names the node as its
//! ring tile and the child as the node drawn (`DrawItem::level` one above `node_level`, no
//! refinement), and `terrain.vert` reads texel `(origin + ij·step) >> level`.

use super::cdlod_morph::Morph;
use super::parts::{NodeEval, Quadrant};
use super::selection::{DrawItem, LodMode};
use super::walk::{child_of, has_terrain, Frame};

impl Frame<'_> {
    /// The quadrants of node (level, tx, ty), which meets τ (`eval`), to draw instead of it
    /// whole: `Some` when some view may not see all of it or a quadrant holds no terrain, and
    /// the seen quadrants with terrain are fewer triangles; each then meets τ at the node's
    /// resolution (`Quadrant::Seen`'s `q`), the others are `Unseen` or `NoTerrain`.
    pub(super) fn seen_quadrants(
        &self,
        eval: &NodeEval,
        level: u32,
        tx: u32,
        ty: u32,
    ) -> Option<[Quadrant; 4]> {
        if !self.params.seen_quadrants
            || !self.params.parent_quadrants
            || self.params.mode != LodMode::Bounded
            || level == 0
        {
            return None;
        }
        let padded = (0..4).any(|k| {
            let (cx, cy) = child_of(tx, ty, k);
            !has_terrain(self.bake, level - 1, cx, cy)
        });
        if !eval.straddles && !padded {
            return None;
        }
        let node = self.fixed(level, tx, ty);
        let quads = self.quadrants(&node, None, level, tx, ty);
        // Fewer triangles than the node whole, each mesh with its skirts (instances not
        // weighed in: the seen quadrants' records stand for a node the frame draws anyway).
        let mut seen = 0;
        for quad in &quads {
            match quad {
                Quadrant::Seen { q, .. } if q.rho_norm <= 1.0 => seen += 1,
                // Rounding only (its ε and box are within the node's): drawn whole.
                Quadrant::Seen { .. } => return None,
                Quadrant::Unseen | Quadrant::NoTerrain => {}
            }
        }
        (seen * self.costs.quadrant < self.costs.whole).then_some(quads)
    }
}

/// The draw items of node (level, tx, ty)'s seen quadrants `quads` (from
/// [`Frame::seen_quadrants`]): each the child drawn at the node's resolution from the node's
/// level texture.
pub(super) fn seen_quadrant_items(
    quads: &[Quadrant; 4],
    level: u32,
    tx: u32,
    ty: u32,
) -> impl Iterator<Item = DrawItem> + '_ {
    quads.iter().enumerate().filter_map(move |(k, quad)| {
        let Quadrant::Seen { q, .. } = quad else {
            return None;
        };
        let (cx, cy) = child_of(tx, ty, k);
        Some(DrawItem {
            node_level: level - 1,
            node_tx: cx,
            node_ty: cy,
            morph: Morph::QUADRANT,
            ..DrawItem::whole(level, tx, ty, q.eps as f32, q.rho_px as f32)
        })
    })
}
