//! A root of the coarsest clipmap level drawn coarser than its level (pure): as its parent's
//! quadrant or its grandparent's sixteenth, where the bake holds those levels.
//!
//! The coarsest-first walk starts at the coarsest clipmap level's tiles, the first level whose
//! texture holds the whole dataset. The bake goes further, up to a tile covering the whole
//! dataset, but no texture does: a root that meets τ was drawn whole, however far it lay —
//! so at a coarse τ the walk could draw no fewer triangles than the roots in view, whole
//! (Inn valley cruise, tiles of 9: 2,836 triangles at τ = 50 or 1,000 alike, 15 roots whole
//! among them). The levels above need no texture of their own: a level-(L+1) surface is the
//! root's stride-2 mesh over its own texels, and a level-(L+2) one its stride-4 mesh — the
//! quarter and sixteenth meshes the walk already draws a node's children with
//! (`SelectParams::parent_quadrants`, `SelectParams::sixteenths`). So a root that meets τ is
//! tried as its parent's quadrant and as its grandparent's sixteenth (`Frame::evaluate_quadrant`:
//! the bake's `coarse_eps` and `fine_eps` over the root, each with that ancestor's sag and
//! spread, over the root's own box with the coarser cells' slack), and drawn the coarsest way
//! that meets τ — the same bound, from the same ε, as every quadrant and sixteenth the walk
//! draws below. Its neighbours drawn at other resolutions meet it with skirts or fills as any
//! two nodes do (`skirts.rs` compares resolutions, not levels).

use super::cdlod_morph::Morph;
use super::parts::NodeEval;
use super::selection::{DrawItem, LodMode};
use super::walk::Frame;

impl Frame<'_> {
    /// Root (level, tx, ty) — a tile of the coarsest clipmap level, which meets τ at its own
    /// resolution — drawn at its grandparent's resolution if that meets τ, else at its
    /// parent's if that does: the draw item and its mesh's triangles with two edges' skirts
    /// (`MeshCosts`). `None` where neither meets τ, the bake has no level above, or
    /// [`SelectParams::coarser_roots`](super::SelectParams::coarser_roots) is off.
    pub(super) fn coarser_root(&self, level: u32, tx: u32, ty: u32) -> Option<(DrawItem, u32)> {
        if !self.params.coarser_roots
            || !self.params.parent_quadrants
            || self.params.mode != LodMode::Bounded
            || level as usize + 1 >= self.bake.levels.len()
        {
            return None;
        }
        let parent = self.fixed(level + 1, tx / 2, ty / 2);
        // The root as one of the sixteenths of its grandparent (`sixteenths_below` of its
        // parent's level: the grandparent's level is in the bake, the mesh exists).
        let grand = self
            .sixteenths_below(level + 1)
            .then(|| self.fixed(level + 2, tx / 4, ty / 4));
        let (quadrant, _, sixteenth) =
            self.evaluate_quadrant(&parent, grand.as_ref(), level, tx, ty)?;
        let item = |e: &NodeEval, morph: Morph| DrawItem {
            morph,
            ..DrawItem::whole(level, tx, ty, e.eps as f32, e.rho_px as f32)
        };
        match sixteenth {
            Some(s) if s.rho_norm <= 1.0 => {
                Some((item(&s, Morph::SIXTEENTH), self.costs.sixteenth))
            }
            _ if quadrant.rho_norm <= 1.0 => {
                Some((item(&quadrant, Morph::QUADRANT), self.costs.quadrant))
            }
            _ => None,
        }
    }

    /// Triangles of draw items that are a node's seen parts (`Frame::seen_parts`): each a
    /// quadrant or a sixteenth mesh at the node's resolution, with two edges' skirts.
    pub(super) fn parts_triangles(&self, parts: &[DrawItem]) -> u32 {
        parts
            .iter()
            .map(|p| match p.level - p.node_level {
                2 => self.costs.sixteenth,
                1 => self.costs.quadrant,
                _ => self.costs.whole,
            })
            .sum()
    }
}
