//! CDLOD (F. Strugar, "Continuous Distance-Dependent Level of Detail for Rendering
//! Heightmaps", JGT 2009; reference implementation fstrugar/CDLOD, `CDLODQuadTree::LODSelect`)
//! as a baseline: a quadtree over the bake's tiles, one LOD range per level doubling from the
//! finest, a node chosen by its bounding box's distance to the eye alone — no error test.
//!
//! The selection of the paper, level ℓ = 0 the finest, range(ℓ) = `cdlod_range` × side(ℓ):
//! a node whose box is not within range(ℓ) of the eye is left to its parent; a node outside
//! the frustum is done (nothing drawn); a node not within range(ℓ−1) — or at the finest level —
//! is drawn whole; otherwise its children are visited, and a child left to its parent is drawn
//! by the parent over that quadrant. The coarsest level's range is unbounded (the reference
//! ends it at the visibility distance; here the dataset ends first).
//!
//! The quadtree's levels: the clipmap's, and with `SelectParams::coarser_roots` up to two of
//! the bake's levels above its coarsest (`levels_above`), as the reference's quadtree has its
//! own `LODLevelCount` whatever texture it streams from. A node there is drawn as the
//! coarsest clipmap level's tiles under it (`draw_above`): one level up each tile fully
//! morphed onto the node's grid and then morphed by the node's zone, two levels up (the
//! root, which does not morph) each tile's stride-4 mesh. Inn valley cruise at tiles of 9,
//! k = 2: 2,528 triangles against 4,544 starting at the clipmap's coarsest level, the same
//! max error (7.31 px).
//!
//! Each drawn node carries its level's geomorph zone (`cdlod_morph.rs`): its vertices slide onto
//! the parent's grid as they near the end of its range, as the reference's vertex shader does;
//! the coarsest level, whose range is unbounded, does not morph.
//!
//! Departure, forced by the renderer drawing whole m×m nodes: a quadrant the parent covers is
//! drawn as the child node fully morphed onto the parent's grid — the parent's quarter mesh
//! exactly, its surface and its error — and then morphed by the parent's zone; it is counted
//! as the quarter mesh's triangles (the GPU also draws the collapsed ones, of no area).
//!
//! Where a node lies outside the clipmap's finer patch it is a ring tile of its level and its
//! subtree is drawn from one refined-tile pool slot, at most `max_refinement` levels finer
//! (the same cap every mode has).

use glam::{DVec2, DVec3};

use crate::bake::ErrorBake;
use crate::camera::Camera;
use crate::clipmap::LevelPlacement;
use crate::tiles::Aabb;

use super::bound::{
    curvature_interpolation_error, min_depth_of, outside_of, projected_error_px, tile_aabb,
    vertical_gain_of,
};
use super::cdlod_morph::{morph_zones, Morph};
use super::selection::{DrawItem, SelectParams, Selection, View, MAX_REFINEMENT};

/// The LOD range of level `level` (metres): `range_factor` node sides, so that it doubles per
/// level as in the paper (LOD-distance ratio 2).
pub fn cdlod_range_m(range_factor: f64, node_side_m0: f64, level: u32) -> f64 {
    range_factor * node_side_m0 * (1u64 << level) as f64
}

/// Distance from `eye` to the nearest point of `aabb` (0 inside): the sphere–box test of
/// `CDLODQuadTree` is `distance ≤ range`.
pub fn box_distance(eye: DVec3, aabb: &Aabb) -> f64 {
    (eye.clamp(aabb.min, aabb.max) - eye).length()
}

/// What a node's visit decided (`LODSelect`'s return value and its cases).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CdlodDecision {
    /// Outside its own range: the parent covers its area.
    LeftToParent,
    /// Outside every frustum: done, nothing drawn.
    Culled,
    /// Drawn whole at its level.
    Draw,
    /// Its children are visited.
    Split,
}

/// The pure rule of one node: `d` its box distance to the nearest eye, `range_here` /
/// `range_finer` the ranges of its level and the next finer one (`None` at the finest level
/// or the refinement cap), `root` for the coarsest level (unbounded range).
pub fn cdlod_decide(
    d: f64,
    range_here: f64,
    range_finer: Option<f64>,
    root: bool,
    visible: bool,
) -> CdlodDecision {
    if !root && d > range_here {
        return CdlodDecision::LeftToParent;
    }
    if !visible {
        return CdlodDecision::Culled;
    }
    match range_finer {
        Some(r) if d <= r => CdlodDecision::Split,
        _ => CdlodDecision::Draw,
    }
}

struct ViewCtx<'a> {
    camera: &'a Camera,
    to_view: glam::DMat4,
    up: DVec3,
    focal: f64,
}

struct Ctx<'a> {
    bake: &'a ErrorBake,
    params: &'a SelectParams,
    views: Vec<ViewCtx<'a>>,
    q: u32,
    spacing: DVec2,
    valid_max: DVec2,
    side0: f64,
    placements: &'a [LevelPlacement],
    /// Each level's morph zone (start, end), metres.
    zones: Vec<[f64; 2]>,
}

/// A node as CDLOD and the draw record see it.
struct Seen {
    distance: f64,
    visible: bool,
    eps: f64,
    rho_px: f64,
}

/// A node to draw (level, tx, ty, ε, ρ) and how it morphs.
type Node = ((u32, u32, u32, f32, f32), Morph);

/// One frame's scratch lists (a ring tile's nodes, and the same without their morph for
/// `Selection::push_refined`), allocated once per frame.
#[derive(Default)]
struct Scratch {
    nodes: Vec<Node>,
    plain: Vec<(u32, u32, u32, f32, f32)>,
}

impl Ctx<'_> {
    fn has_terrain(&self, level: u32, tx: u32, ty: u32) -> bool {
        let t = &self.bake.levels[level as usize];
        tx < t.tiles_x && ty < t.tiles_y && t.terrain[(ty * t.tiles_x + tx) as usize]
    }

    fn cell_diagonal(&self, level: u32) -> f64 {
        (self.spacing * (1u64 << level) as f64).length()
    }

    fn seen(&self, level: u32, tx: u32, ty: u32) -> Seen {
        let side = (self.q as u64) << level;
        let lo = DVec2::new((tx as u64 * side) as f64, (ty as u64 * side) as f64) * self.spacing;
        let hi = (lo + DVec2::splat(side as f64) * self.spacing).min(self.valid_max);
        let lo = lo.min(self.valid_max);
        let (min_h, max_h) = self.bake.bounds(level, tx, ty);
        let mut eps = self.bake.eps_refined(level, tx, ty, 0) as f64;
        if self.params.curvature {
            eps += curvature_interpolation_error(self.cell_diagonal(level));
        }
        let mut s = Seen {
            distance: f64::INFINITY,
            visible: false,
            eps,
            rho_px: 0.0,
        };
        // On the ellipsoid (geographic and UTM data) the node's box is where the renderer
        // draws it (`GeoGrid::node_geometry`), not its grid rectangle: far from the grid's
        // origin the two part by the meridians' convergence and the Earth's curvature, and a
        // flat box culled nodes the view shows (holes along the frustum's sides on the
        // Sierra Nevada and Northern England mosaics) and measured wrong distances.
        let geo_box = self
            .params
            .earth
            .map(|g| g.node_geometry(lo, hi, min_h, max_h).aabb);
        for v in &self.views {
            let eye = v.camera.position;
            let aabb = geo_box.unwrap_or_else(|| {
                tile_aabb(
                    lo,
                    hi,
                    min_h,
                    max_h,
                    eye,
                    self.params.curvature,
                    self.cell_diagonal(level),
                )
            });
            s.distance = s.distance.min(box_distance(eye, &aabb));
            let corners = aabb.corners().map(|c| v.to_view.transform_point3(c));
            let f = &v.camera.frustum;
            if outside_of(&corners, f, v.camera.near) {
                continue;
            }
            s.visible = true;
            let z_min = min_depth_of(&corners, v.camera.near);
            let c = vertical_gain_of(&corners, f, v.up);
            s.rho_px = s.rho_px.max(projected_error_px(eps, z_min, v.focal, c));
        }
        s
    }

    #[cfg(test)]
    fn seen_for_test(bake: &ErrorBake, level: u32, tx: u32, ty: u32, eye: DVec3) -> f64 {
        Self::seen_on(bake, None, level, tx, ty, eye)
    }

    /// The node's distance from `eye` with `earth` as the selection's Earth model.
    #[cfg(test)]
    fn seen_on(
        bake: &ErrorBake,
        earth: Option<crate::geodesy::GeoGrid>,
        level: u32,
        tx: u32,
        ty: u32,
        eye: DVec3,
    ) -> f64 {
        let params = SelectParams {
            earth,
            ..SelectParams::default()
        };
        let cam = Camera::new(
            eye,
            crate::camera::Attitude::from_degrees(0.0, -90.0, 0.0),
            crate::camera::Frustum::symmetric(1.0, 8, 8),
        );
        let v = View {
            camera: &cam,
            viewport: (8, 8),
            tau_px: 1.0,
        };
        let q = bake.params.tile_size - 1;
        let ctx = Ctx {
            bake,
            params: &params,
            views: vec![ViewCtx {
                camera: v.camera,
                to_view: cam.world_to_view(),
                up: DVec3::Z,
                focal: 1.0,
            }],
            q,
            spacing: DVec2::new(bake.spacing_x, bake.spacing_y),
            valid_max: DVec2::new(
                (bake.valid_width - 1) as f64 * bake.spacing_x,
                (bake.valid_height - 1) as f64 * bake.spacing_y,
            ),
            side0: 0.0,
            placements: &[],
            zones: Vec::new(),
        };
        ctx.seen(level, tx, ty).distance
    }

    fn range(&self, level: u32) -> f64 {
        cdlod_range_m(self.params.cdlod_range, self.side0, level)
    }

    /// How a node of `level` drawn whole morphs (`root`: the coarsest level does not).
    fn morph(&self, level: u32, root: bool) -> Morph {
        if root {
            return Morph::NONE;
        }
        let z = self.zones[level as usize];
        Morph {
            zone: [z[0] as f32, z[1] as f32],
            ..Morph::NONE
        }
    }

    /// How a quadrant of a `parent_level` node, drawn for it, morphs.
    fn quadrant_morph(&self, parent_level: u32, parent_root: bool) -> Morph {
        Morph {
            quadrant: true,
            parent_zone: self.morph(parent_level, parent_root).zone,
            ..Morph::NONE
        }
    }

    /// `LODSelect` of node (level, tx, ty); `finest` is the lowest level it may split to.
    /// Appends what it draws; returns false when the parent must cover the node's area.
    fn visit(
        &self,
        level: u32,
        tx: u32,
        ty: u32,
        finest: u32,
        root: bool,
        out: &mut Vec<Node>,
    ) -> bool {
        if !self.has_terrain(level, tx, ty) {
            return true;
        }
        let s = self.seen(level, tx, ty);
        let finer = (level > finest).then(|| self.range(level - 1));
        match cdlod_decide(s.distance, self.range(level), finer, root, s.visible) {
            CdlodDecision::LeftToParent => false,
            CdlodDecision::Culled => true,
            CdlodDecision::Draw => {
                let node = (level, tx, ty, s.eps as f32, s.rho_px as f32);
                out.push((node, self.morph(level, root)));
                true
            }
            CdlodDecision::Split => {
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let (cx, cy) = (2 * tx + dx, 2 * ty + dy);
                    if !self.visit(level - 1, cx, cy, finest, false, out) {
                        // The parent's quadrant: drawn as the child node morphed onto the
                        // parent's grid (module docs), at the parent's error.
                        let c = self.seen(level - 1, cx, cy);
                        if c.visible {
                            let (eps, rho) = (s.eps.max(c.eps), s.rho_px.max(c.rho_px));
                            let node = (level - 1, cx, cy, eps as f32, rho as f32);
                            out.push((node, self.quadrant_morph(level, root)));
                        }
                    }
                }
                true
            }
        }
    }
}

/// Whether level-ℓ tile (tx, ty) lies in `placement`'s patch (ℓ = placement.level).
fn inside_patch(placement: &LevelPlacement, tx: u32, ty: u32) -> bool {
    let n = placement.patch_tiles as i64;
    let [ox, oy] = placement.patch_origin;
    (ox..ox + n).contains(&(tx as i64)) && (oy..oy + n).contains(&(ty as i64))
}

/// CDLOD's selection for `views` (a node is as near as its nearest eye, drawn when any view
/// sees it). `placements` finest first, as from `clipmap::place_levels`.
pub(super) fn select_cdlod(
    bake: &ErrorBake,
    placements: &[LevelPlacement],
    views: &[View],
    params: &SelectParams,
    out: &mut Selection,
) {
    let Some(coarsest) = placements.last() else {
        return;
    };
    let q = bake.params.tile_size - 1;
    let spacing = DVec2::new(bake.spacing_x, bake.spacing_y);
    let ctx = Ctx {
        bake,
        params,
        views: views
            .iter()
            .map(|v| {
                let (fx, fy) = v.camera.frustum.focal_px(v.viewport.0, v.viewport.1);
                ViewCtx {
                    camera: v.camera,
                    to_view: v.camera.world_to_view(),
                    up: v.camera.world_to_view_rotation() * DVec3::Z,
                    focal: fx.max(fy),
                }
            })
            .collect(),
        q,
        spacing,
        valid_max: DVec2::new(
            (bake.valid_width - 1) as f64 * bake.spacing_x,
            (bake.valid_height - 1) as f64 * bake.spacing_y,
        ),
        side0: q as f64 * spacing.max_element(),
        placements,
        zones: morph_zones(
            |l| cdlod_range_m(params.cdlod_range, q as f64 * spacing.max_element(), l),
            bake.levels.len().saturating_sub(1) as u32,
        ),
    };
    let top = placements.len() - 1;
    let above = levels_above(bake, coarsest.level, params);
    let roots = &bake.levels[(coarsest.level + above) as usize];
    let mut scratch = Scratch::default();
    for ty in 0..roots.tiles_y {
        for tx in 0..roots.tiles_x {
            if above == 0 {
                visit_clipmap(&ctx, top, tx, ty, true, &mut scratch, out);
            } else {
                visit_above(
                    &ctx,
                    coarsest.level + above,
                    tx,
                    ty,
                    true,
                    &mut scratch,
                    out,
                );
            }
        }
    }
    out.finest_level = out.levels.iter().position(|l| l.drawn > 0).unwrap_or(0) as u32;
    for s in out.levels.iter_mut() {
        s.skipped = s.drawn == 0;
    }
}

/// How many of the bake's levels above the coarsest clipmap level (`coarsest`) CDLOD's
/// quadtree starts from: up to two with [`SelectParams::coarser_roots`] — no texture holds
/// them, and a node there is drawn as the coarsest level's tiles under it, each as its
/// parent's quadrant (the stride-2 mesh) or its grandparent's sixteenth (stride 4; tiles of a
/// multiple of 4 quads), the meshes the bounded mode's roots are drawn with (`coarser_roots.rs`).
fn levels_above(bake: &ErrorBake, coarsest: u32, params: &SelectParams) -> u32 {
    if !params.coarser_roots {
        return 0;
    }
    let q = bake.params.tile_size - 1;
    let meshes = if q >= 4 && q.is_multiple_of(4) { 2 } else { 1 };
    let held = (bake.levels.len() as u32).saturating_sub(coarsest + 1);
    held.min(meshes)
}

/// `LODSelect` of node (level, tx, ty) above the coarsest clipmap level (the last placement):
/// its children visited down to that level's tiles (`visit_clipmap`), and what it draws
/// itself — wholly, or over the quadrants its children leave to it — drawn as the coarsest
/// level's tiles under it ([`draw_above`]). Returns false when the parent covers its area.
fn visit_above(
    ctx: &Ctx,
    level: u32,
    tx: u32,
    ty: u32,
    root: bool,
    scratch: &mut Scratch,
    out: &mut Selection,
) -> bool {
    let top = ctx.placements.len() - 1;
    if level == ctx.placements[top].level {
        return visit_clipmap(ctx, top, tx, ty, root, scratch, out);
    }
    if !ctx.has_terrain(level, tx, ty) {
        return true;
    }
    let s = ctx.seen(level, tx, ty);
    let finer = Some(ctx.range(level - 1));
    match cdlod_decide(s.distance, ctx.range(level), finer, root, s.visible) {
        CdlodDecision::LeftToParent => false,
        CdlodDecision::Culled => true,
        CdlodDecision::Draw => {
            draw_above(ctx, level, root, (level, tx, ty), &s, out);
            true
        }
        CdlodDecision::Split => {
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let child = (level - 1, 2 * tx + dx, 2 * ty + dy);
                if !visit_above(ctx, child.0, child.1, child.2, false, scratch, out) {
                    draw_above(ctx, level, root, child, &s, out);
                }
            }
            true
        }
    }
}

/// Node `level` (above the coarsest clipmap level; `root`: the coarsest of all, which does
/// not morph) drawn over `area` (itself or one of its quadrants) as the coarsest clipmap
/// level's tiles there that hold terrain and that a view sees: one level above them each
/// tile is the node's quadrant, fully morphed onto its grid and then morphed by the node's
/// zone, as `visit` draws a quadrant its parent covers; two levels above, a sixteenth at the
/// node's resolution (the coarsest level: no morph). ε and ρ are the node's and the tile's
/// larger, as for a covered quadrant.
fn draw_above(
    ctx: &Ctx,
    level: u32,
    root: bool,
    area: (u32, u32, u32),
    s: &Seen,
    out: &mut Selection,
) {
    let top = ctx.placements.len() - 1;
    let tile_level = ctx.placements[top].level;
    let morph = match level - tile_level {
        1 => ctx.quadrant_morph(level, root),
        _ => {
            debug_assert!(
                root && level - tile_level == 2,
                "a sixteenth at the top only"
            );
            Morph {
                sixteenth: true,
                ..ctx.quadrant_morph(level, true)
            }
        }
    };
    let shift = area.0 - tile_level;
    let n = 1u32 << shift;
    for ty in area.2 * n..(area.2 + 1) * n {
        for tx in area.1 * n..(area.1 + 1) * n {
            if !ctx.has_terrain(tile_level, tx, ty) {
                continue;
            }
            let c = ctx.seen(tile_level, tx, ty);
            let stats = &mut out.levels[top];
            stats.considered += 1;
            if !c.visible {
                stats.culled += 1;
                continue;
            }
            push_covered(out, top, (tile_level, tx, ty), s, &c, morph);
        }
    }
}

/// Tile (level, tx, ty) of clipmap level index `i`, seen as `c` (visible), drawn unrefined
/// for the coarser node `s` that covers it, as `morph` says: ε and ρ the larger of the two;
/// counted drawn in level `i`'s stats (the caller counts it considered).
fn push_covered(
    out: &mut Selection,
    i: usize,
    (level, tx, ty): (u32, u32, u32),
    s: &Seen,
    c: &Seen,
    morph: Morph,
) {
    let stats = &mut out.levels[i];
    stats.drawn += 1;
    stats.refined[0] += 1;
    stats.nodes += 1;
    let (eps, rho) = (s.eps.max(c.eps), s.rho_px.max(c.rho_px));
    out.items.push(DrawItem {
        morph,
        ..DrawItem::whole(level, tx, ty, eps as f32, rho as f32)
    });
}

/// A node of clipmap level index `i` whose area the finer patch may hold: while it splits and
/// its children are in the next finer patch it is no tile of its own; otherwise it is a ring
/// tile, drawn (with its CDLOD subtree) from its level's texture or one pool slot.
/// Returns false when the parent covers its area.
fn visit_clipmap(
    ctx: &Ctx,
    i: usize,
    tx: u32,
    ty: u32,
    root: bool,
    scratch: &mut Scratch,
    out: &mut Selection,
) -> bool {
    let level = ctx.placements[i].level;
    if !ctx.has_terrain(level, tx, ty) {
        return true;
    }
    let s = ctx.seen(level, tx, ty);
    let descend = i > 0 && inside_patch(&ctx.placements[i - 1], 2 * tx, 2 * ty);
    let finer = (level > 0).then(|| ctx.range(level - 1));
    let decision = cdlod_decide(s.distance, ctx.range(level), finer, root, s.visible);
    match decision {
        CdlodDecision::LeftToParent => return false,
        CdlodDecision::Culled => {
            out.levels[i].considered += 1;
            out.levels[i].culled += 1;
            return true;
        }
        CdlodDecision::Split if descend => {
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let (cx, cy) = (2 * tx + dx, 2 * ty + dy);
                if !visit_clipmap(ctx, i - 1, cx, cy, false, scratch, out) {
                    let c = ctx.seen(level - 1, cx, cy);
                    if c.visible {
                        out.levels[i - 1].considered += 1;
                        let morph = ctx.quadrant_morph(level, root);
                        push_covered(out, i - 1, (level - 1, cx, cy), &s, &c, morph);
                    }
                }
            }
            return true;
        }
        _ => {}
    }
    // A ring tile: its subtree from one pool slot, at most `cap` levels finer.
    let cap = ctx.params.max_refinement.min(level).min(MAX_REFINEMENT);
    let Scratch { nodes, plain } = scratch;
    nodes.clear();
    ctx.visit(level, tx, ty, level - cap, root, nodes);
    out.levels[i].considered += 1;
    out.levels[i].drawn += 1;
    plain.clear();
    plain.extend(nodes.iter().map(|n| n.0));
    let first = out.items.len();
    out.push_refined(i, level, tx, ty, plain);
    for (item, n) in out.items[first..].iter_mut().zip(nodes.iter()) {
        item.morph = n.1;
    }
    true
}

#[cfg(test)]
#[path = "cdlod_tests.rs"]
mod tests;
