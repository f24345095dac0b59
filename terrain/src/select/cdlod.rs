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
    let roots = &bake.levels[coarsest.level as usize];
    let mut scratch = Scratch::default();
    for ty in 0..roots.tiles_y {
        for tx in 0..roots.tiles_x {
            visit_clipmap(&ctx, top, tx, ty, true, &mut scratch, out);
        }
    }
    out.finest_level = out.levels.iter().position(|l| l.drawn > 0).unwrap_or(0) as u32;
    for s in out.levels.iter_mut() {
        s.skipped = s.drawn == 0;
    }
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
                        let stats = &mut out.levels[i - 1];
                        stats.considered += 1;
                        stats.drawn += 1;
                        stats.refined[0] += 1;
                        stats.nodes += 1;
                        let (eps, rho) = (s.eps.max(c.eps), s.rho_px.max(c.rho_px));
                        out.items.push(DrawItem {
                            morph: ctx.quadrant_morph(level, root),
                            ..DrawItem::whole(level - 1, cx, cy, eps as f32, rho as f32)
                        });
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
mod tests {
    use super::*;

    #[test]
    fn ranges_double_per_level() {
        assert_eq!(cdlod_range_m(3.0, 160.0, 0), 480.0);
        assert_eq!(cdlod_range_m(3.0, 160.0, 1), 960.0);
        assert_eq!(cdlod_range_m(3.0, 160.0, 4), 7680.0);
    }

    #[test]
    fn box_distance_is_zero_inside_and_euclidean_outside() {
        let b = Aabb {
            min: DVec3::new(0.0, 0.0, 0.0),
            max: DVec3::new(10.0, 10.0, 5.0),
        };
        assert_eq!(box_distance(DVec3::new(5.0, 5.0, 1.0), &b), 0.0);
        assert_eq!(box_distance(DVec3::new(13.0, 14.0, 5.0), &b), 5.0);
        assert_eq!(box_distance(DVec3::new(5.0, 5.0, 17.0), &b), 12.0);
    }

    #[test]
    fn decisions_follow_lod_select() {
        use CdlodDecision::*;
        // Outside its own range: the parent covers it, even when invisible.
        assert_eq!(
            cdlod_decide(101.0, 100.0, Some(50.0), false, true),
            LeftToParent
        );
        assert_eq!(
            cdlod_decide(101.0, 100.0, Some(50.0), false, false),
            LeftToParent
        );
        // A root has no range limit.
        assert_eq!(cdlod_decide(1e9, 100.0, Some(50.0), true, true), Draw);
        // In range but unseen: done.
        assert_eq!(cdlod_decide(80.0, 100.0, Some(50.0), false, false), Culled);
        // In range, beyond the finer range: whole; within it: split; finest: whole.
        assert_eq!(cdlod_decide(80.0, 100.0, Some(50.0), false, true), Draw);
        assert_eq!(cdlod_decide(50.0, 100.0, Some(50.0), false, true), Split);
        assert_eq!(cdlod_decide(10.0, 100.0, None, false, true), Draw);
    }

    /// A 257² bumpy dataset, its bake and clipmap (level-0 tiles of 16 quads × 10 m).
    fn scene() -> (crate::bake::ErrorBake, crate::clipmap::ClipmapDesc) {
        use crate::bake::{bake, BakeParams};
        use crate::dataset::Dataset;
        use crate::Heightfield;
        let n = 257;
        let hf = Heightfield {
            width: n,
            height: n,
            spacing_x: 10.0,
            spacing_y: 10.0,
            heights: (0..n * n)
                .map(|k| ((k % n) as f32 * 0.3).sin() * 20.0 + ((k / n) as f32 * 0.17).cos() * 9.0)
                .collect(),
            geo: None,
            voids_filled: 0,
            spacing_note: String::new(),
        };
        let ds = Dataset::from_heightfield(hf, "t".into());
        let b = bake(
            &ds,
            BakeParams {
                tile_size: 17,
                levels: 0,
            },
            &|_, _| {},
        );
        let desc = crate::clipmap::ClipmapDesc {
            tile_quads: 16,
            patch_tiles: 8,
            margin_tiles: 2,
            width: n as u32,
            height: n as u32,
        };
        (b, desc)
    }

    fn select(range: f64, eye: DVec3, pitch: f64) -> (Selection, crate::bake::ErrorBake) {
        use crate::camera::{Attitude, Frustum};
        use crate::clipmap::place_levels;
        let (b, desc) = scene();
        let params = SelectParams {
            mode: crate::select::LodMode::Cdlod,
            cdlod_range: range,
            max_refinement: 6,
            ..SelectParams::default()
        };
        let cam = Camera::new(
            eye,
            Attitude::from_degrees(30.0, pitch, 0.0),
            Frustum::symmetric(170f64.to_radians(), 64, 64),
        );
        let placements = place_levels(&desc, [eye.x / 10.0, eye.y / 10.0]);
        let mut sel = Selection::default();
        crate::select::select_tiles(&b, &desc, &placements, &cam, (64, 64), &params, &mut sel);
        (sel, b)
    }

    /// Looking straight down from high up every tile is seen: the nodes tile the ground
    /// exactly once, each drawn node is beyond the next finer range (it was not split), and a
    /// longer range draws more nodes.
    #[test]
    fn nodes_tile_the_ground_once_and_follow_the_ranges() {
        let eye = DVec3::new(700.0, 1900.0, 250.0);
        let mut counts = Vec::new();
        for range in [2.0, 4.0, 8.0] {
            let (sel, b) = select(range, eye, -89.9);
            let mut cover = vec![0u32; 16 * 16];
            for it in &sel.items {
                let l = it.node_level;
                assert!(it.node_level + it.refinement >= it.level, "{it:?}");
                for y in (it.node_ty << l)..((it.node_ty + 1) << l) {
                    for x in (it.node_tx << l)..((it.node_tx + 1) << l) {
                        if x < 16 && y < 16 {
                            cover[(y * 16 + x) as usize] += 1;
                        }
                    }
                }
                if l > 0 {
                    let t = Ctx::seen_for_test(&b, l, it.node_tx, it.node_ty, eye);
                    assert!(
                        t > cdlod_range_m(range, 160.0, l - 1),
                        "range {range}: {it:?} at {t} m should have split"
                    );
                }
            }
            assert!(cover.iter().all(|&c| c == 1), "range {range}: {cover:?}");
            counts.push(sel.items.len());
        }
        assert!(counts[0] < counts[1] && counts[1] < counts[2], "{counts:?}");
    }

    /// Every drawn node morphs over its own level's zone — the coarsest level not at all — and
    /// a quadrant drawn for its parent is fully morphed onto the parent's grid, then over the
    /// parent's zone; the selection itself (which nodes) is the same as without morphing.
    #[test]
    fn nodes_carry_their_levels_morph_zone() {
        let eye = DVec3::new(700.0, 1900.0, 250.0);
        let mut quadrants = 0;
        for range in [2.0, 4.0, 8.0] {
            let (sel, _) = select(range, eye, -60.0);
            // The roots: the coarsest clipmap level's tiles, whose range is unbounded.
            let desc = scene().1;
            let places = crate::clipmap::place_levels(&desc, [eye.x / 10.0, eye.y / 10.0]);
            let top = places.last().unwrap().level;
            let zones = morph_zones(|l| cdlod_range_m(range, 160.0, l), top);
            let zone = |l: u32| {
                let z = zones[l as usize];
                [z[0] as f32, z[1] as f32]
            };
            assert!(!sel.items.is_empty());
            for it in &sel.items {
                let m = it.morph;
                if m.quadrant {
                    quadrants += 1;
                    let parent = it.node_level + 1;
                    let want = if parent == top {
                        [0.0, 0.0]
                    } else {
                        zone(parent)
                    };
                    assert_eq!(m.parent_zone, want, "{it:?}");
                    assert_eq!(m.to_gpu()[..2], [-1.0, 0.0]);
                } else if it.node_level == top {
                    assert_eq!(m, Morph::NONE, "{it:?}");
                } else {
                    assert_eq!(m.zone, zone(it.node_level), "{it:?}");
                    assert!(m.zone[0] < m.zone[1]);
                }
            }
        }
        assert!(quadrants > 0, "no quadrant drawn for its parent");
    }

    /// On the ellipsoid a node's distance is to the box the renderer draws it in
    /// (`GeoGrid::node_geometry`), not to its flat grid rectangle: far from the grid's origin
    /// the two part (a 1/120° grid at 47° N, a level-3 node beside the origin's).
    #[test]
    fn on_the_ellipsoid_a_nodes_box_is_where_it_is_drawn() {
        let (b, _) = scene();
        let earth = crate::geodesy::GeoGrid::test_geographic(47.0, 11.0, 1.0 / 120.0, 47.0);
        let (level, tx, ty) = (3, 1, 1);
        let side = (16u64 << level) as f64 * 10.0;
        let lo = DVec2::new(tx as f64 * side, ty as f64 * side);
        let valid = DVec2::new(256.0 * 10.0, 256.0 * 10.0);
        let (lo, hi) = (lo.min(valid), (lo + DVec2::splat(side)).min(valid));
        let (min_h, max_h) = b.bounds(level, tx, ty);
        let drawn = earth.node_geometry(lo, hi, min_h, max_h).aabb;
        // An eye 500 m beside the drawn box's east face, level with it.
        let eye = DVec3::new(
            drawn.max.x + 500.0,
            0.5 * (drawn.min.y + drawn.max.y),
            drawn.max.z,
        );
        let on_earth = Ctx::seen_on(&b, Some(earth), level, tx, ty, eye);
        assert!(
            (on_earth - box_distance(eye, &drawn)).abs() < 1e-9,
            "{on_earth}"
        );
        let flat = Ctx::seen_for_test(&b, level, tx, ty, eye);
        // The flat rectangle's box is elsewhere (0.39 m here, 2.6 km from the origin; tens of
        // metres across a mosaic).
        assert!(
            (flat - on_earth).abs() > 0.1,
            "flat {flat} vs drawn {on_earth}"
        );
    }
}
