//! A node that meets τ drawn as only the parts of it that can show (pure): the quadrants some
//! view sees and that hold terrain — a quadrant that itself crosses a frustum plane as its
//! seen sixteenths —, each at the node's own resolution.
//!
//! The coarsest-first walk draws a node that meets τ whole. Where its box crosses a frustum
//! plane, some of its quadrants may lie wholly outside every view; where it reaches past the
//! grid's last sample, some hold only padding (drawn folded onto that sample). CDLOD's
//! quadtree never draws those: it culls a node's children one by one and draws each kept one
//! at its parent's resolution. Here the same: the node's children evaluated as quadrants at
//! its resolution (`Frame::quadrants`: the bake's ε of the node's surface over each — never
//! more than the node's —, each one's own box and gain), a seen one whose box crosses a plane
//! again as four sixteenths at the node's resolution (the bake's `fine_eps`), and the seen
//! parts drawn instead of the node when their meshes are fewer triangles than its (skirts
//! counted, instances not). Lavapipe suite, Inn valley and Sierra Nevada cruise and
//! manoeuvre, tiles of 9, τ = 20: 0.84–0.93× the triangles with quadrants alone, 0.93–0.97×
//! with an instance weighed as 64 triangles (one seen quadrant only), a further 0.96–1.00×
//! with sixteenths; every measured error unchanged.
//!
//! A part so drawn is the node's own surface over it (a quadrant: the child's stride-2 mesh
//! over its even vertices, which are the node's samples; a sixteenth: the grandchild's
//! stride-4 mesh), so the bound it meets is the one the node met, from a smaller box. It reads
//! the node's level texture, where the node's samples are (its own level may not hold that
//! place at all): the draw item names the node as its ring tile and the part as the node drawn
//! (`DrawItem::level` one or two above `node_level`, no refinement), and `terrain.vert` reads
//! texel `(origin + ij·step) >> level`, its normals a texel either side.

use super::cdlod_morph::Morph;
use super::parts::{NodeEval, Quadrant};
use super::selection::{DrawItem, LodMode};
use super::walk::{child_of, has_terrain, Frame};

impl Frame<'_> {
    /// Node (level, tx, ty), which meets τ (`eval`), drawn as its seen parts instead of whole:
    /// `true` when some view may not see all of it or a quadrant holds no terrain, and the
    /// seen quadrants with terrain — each one that itself crosses a frustum plane as its seen
    /// sixteenths (at the node's resolution too, the bake's `fine_eps`) where those are fewer
    /// triangles — are fewer triangles than the node; their draw items are then in `parts`
    /// (cleared first), each meeting τ.
    pub(super) fn seen_parts(
        &self,
        eval: &NodeEval,
        level: u32,
        tx: u32,
        ty: u32,
        parts: &mut Vec<DrawItem>,
    ) -> bool {
        parts.clear();
        if !self.params.seen_quadrants
            || !self.params.parent_quadrants
            || self.params.mode != LodMode::Bounded
            || level == 0
        {
            return false;
        }
        let padded = (0..4).any(|k| {
            let (cx, cy) = child_of(tx, ty, k);
            !has_terrain(self.bake, level - 1, cx, cy)
        });
        if !eval.straddles() && !padded {
            return false;
        }
        let node = self.fixed(level, tx, ty);
        let quads = self.quadrants(&node, None, level, tx, ty);
        let sixteenths = self.sixteenths_below(level - 1);
        // Triangles of each mesh with its skirts (instances not weighed in: the parts' records
        // stand for a node the frame draws anyway).
        let mut triangles = 0;
        for (k, quad) in quads.iter().enumerate() {
            let q = match quad {
                Quadrant::Seen { q, .. } if q.rho_norm <= 1.0 => q,
                // Rounding only (its ε and box are within the node's): drawn whole.
                Quadrant::Seen { .. } => return false,
                Quadrant::Unseen | Quadrant::NoTerrain => continue,
            };
            let (cx, cy) = child_of(tx, ty, k);
            let start = parts.len();
            if q.straddles() && sixteenths {
                let child = self.fixed(level - 1, cx, cy);
                let subs = self.quadrants(&child, Some(&node), level - 1, cx, cy);
                let mut ok = true;
                for (j, sub) in subs.iter().enumerate() {
                    match sub {
                        Quadrant::Seen { sub: Some(s), .. } if s.rho_norm <= 1.0 => {
                            let (gx, gy) = child_of(cx, cy, j);
                            parts.push(part(
                                level,
                                tx,
                                ty,
                                (level - 2, gx, gy),
                                s,
                                Morph::SIXTEENTH,
                            ));
                        }
                        Quadrant::Seen { .. } => ok = false,
                        Quadrant::Unseen | Quadrant::NoTerrain => {}
                    }
                }
                let n = (parts.len() - start) as u32;
                if ok && n * self.costs.sixteenth < self.costs.quadrant {
                    triangles += n * self.costs.sixteenth;
                    continue;
                }
                parts.truncate(start);
            }
            parts.push(part(level, tx, ty, (level - 1, cx, cy), q, Morph::QUADRANT));
            triangles += self.costs.quadrant;
        }
        triangles < self.costs.whole
    }
}

/// A part of node (level, tx, ty) drawn at the node's resolution from its level texture:
/// `drawn` (its level and tile), with its evaluation there.
fn part(
    level: u32,
    tx: u32,
    ty: u32,
    drawn: (u32, u32, u32),
    eval: &NodeEval,
    morph: Morph,
) -> DrawItem {
    DrawItem {
        node_level: drawn.0,
        node_tx: drawn.1,
        node_ty: drawn.2,
        morph,
        ..DrawItem::whole(level, tx, ty, eval.eps as f32, eval.rho_px as f32)
    }
}
