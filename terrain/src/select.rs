//! Tile selection, the decision half of the core technique (DESIGN.md "The terrain technique"):
//! for each clipmap level, the tiles of its ring; per tile an AABB from the baked min/max
//! (Earth curvature included) → frustum cull; the projected error
//! `ρ = ε·f·c / (z_min − ε)` (DESIGN.md, the bound that holds anywhere on screen) → the smallest
//! refinement r with ρ(ε(L−r)) ≤ τ. Pure CPU: plain data in, plain data out.

use glam::{DVec2, DVec3};

use super::bake::ErrorBake;
use super::clipmap::{ring_tiles, ClipmapDesc, LevelPlacement};
use super::tiles::Aabb;
use crate::camera::{Camera, Frustum};

/// Mean Earth radius used for the curvature drop d²/2R (DESIGN.md "Earth curvature").
pub const EARTH_RADIUS_M: f64 = 6_371_000.0;

/// Highest refinement a tile may get (pool bindings exist for r = 1..=MAX_REFINEMENT).
pub const MAX_REFINEMENT: u32 = 6;

/// How the level of detail is decided. Everything else (levels, pipeline, uploads) is shared.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum LodMode {
    /// Error-bounded tiled clipmaps: refine until ρ ≤ τ (ours).
    #[default]
    Bounded,
    /// Plain geometry clipmaps: the same levels, no error test, no refinement.
    Clipmap,
    /// Brute force: every visible tile at full resolution (r = L).
    Full,
    /// Classic discrete LOD by distance alone (seed 004): a node is split while the eye is
    /// closer than `distance_factor` × its side, with 10 % hysteresis against popping.
    Distance,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelectParams {
    pub mode: LodMode,
    /// Screen-space error bound, pixels.
    pub tau_px: f64,
    /// Apply the Earth-curvature drop (and include it in the AABBs).
    pub curvature: bool,
    /// Refinement cap (≤ MAX_REFINEMENT); tiles that would need more are drawn at the cap and
    /// counted as `unbounded`.
    pub max_refinement: u32,
    /// `Bounded`: draw every region at the coarsest clipmap level that meets τ there (a
    /// quadtree over the levels, from the coarsest down), instead of every level's whole ring
    /// with only entire levels skipped. Same bound, fewer triangles where the terrain is smooth
    /// or seen from high above.
    pub coarsen: bool,
    /// `Distance` mode: split a node while the eye is nearer than this many node sides.
    pub distance_factor: f64,
}

impl Default for SelectParams {
    fn default() -> Self {
        Self {
            mode: LodMode::Bounded,
            tau_px: 1.0,
            curvature: true,
            max_refinement: 5,
            coarsen: true,
            distance_factor: 3.0,
        }
    }
}

/// One m×m tile instance to draw: a *node* of a ring tile.
///
/// An unrefined ring tile (L, tx, ty) is one node: itself, heights from its clipmap level. A
/// refined ring tile takes its heights from one pool slot holding the tile at level L−r, and is
/// drawn as a quadtree of nodes: each node is the level-ℓ tile (node_tx, node_ty) for some
/// L−r ≤ ℓ ≤ L, split further only while its own projected error exceeds τ — so the far part of
/// a big coarse tile is not drawn at the resolution its near corner needs (beyond the document,
/// which refines the whole tile). Every node meets the bound on its own.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrawItem {
    /// The ring tile: clipmap level and tile coordinates (the pool key with `refinement`).
    pub level: u32,
    pub tx: u32,
    pub ty: u32,
    /// r: the pool slot holds the ring tile at level L−r (0 = unrefined, from the clipmap).
    pub refinement: u32,
    /// The node drawn: a level-`node_level` tile, L−r ≤ node_level ≤ L.
    pub node_level: u32,
    pub node_tx: u32,
    pub node_ty: u32,
    /// ε of the surface drawn over the node (level `node_level`), metres, curvature
    /// interpolation included.
    pub eps_m: f32,
    /// Its projected error bound, pixels.
    pub rho_px: f32,
}

impl DrawItem {
    /// The node of an unrefined ring tile: the tile itself.
    pub fn whole(level: u32, tx: u32, ty: u32, eps_m: f32, rho_px: f32) -> Self {
        Self {
            level,
            tx,
            ty,
            refinement: 0,
            node_level: level,
            node_tx: tx,
            node_ty: ty,
            eps_m,
            rho_px,
        }
    }
}

#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct LevelStats {
    /// Ring tiles of this level over the dataset.
    pub considered: u32,
    /// Ring tiles outside the frustum.
    pub culled: u32,
    /// Ring tiles drawn.
    pub drawn: u32,
    /// Drawn ring tiles per refinement r (index r).
    pub refined: [u32; MAX_REFINEMENT as usize + 1],
    /// Nodes (m×m instances) drawn for this level's tiles.
    pub nodes: u32,
    /// The level was skipped as too fine for the current height above ground.
    pub skipped: bool,
}

#[derive(Debug, Clone, Default)]
pub struct Selection {
    pub items: Vec<DrawItem>,
    pub levels: Vec<LevelStats>,
    /// Finest level drawn this frame.
    pub finest_level: u32,
    /// Tiles whose bound could not be met within `max_refinement`.
    pub unbounded: u32,
    /// `Distance` mode: nodes split this frame (level, tx, ty), the hysteresis state for the next.
    pub split: std::collections::HashSet<(u32, u32, u32)>,
}

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

    /// Horizontal rectangle of a level tile in metres, clipped to the valid data.
    fn rect(&self, level: u32, tx: u32, ty: u32) -> (DVec2, DVec2) {
        let side = (self.q as u64) << level;
        let lo = DVec2::new((tx as u64 * side) as f64, (ty as u64 * side) as f64) * self.spacing;
        let hi = lo + DVec2::splat(side as f64) * self.spacing;
        (lo.min(self.valid_max), hi.min(self.valid_max))
    }
}

/// Extra vertical error from drawing the curvature drop linearly between vertices: over a cell
/// of diagonal `w` the chord of d²/2R departs from it by at most w²/8R.
pub fn curvature_interpolation_error(cell_diagonal_m: f64) -> f64 {
    cell_diagonal_m * cell_diagonal_m / (8.0 * EARTH_RADIUS_M)
}

/// Box of a tile in world space, curvature drop included: the drop is d²/2R for the horizontal
/// distance d from the eye, so the box bottom moves down by the farthest corner's drop (plus the
/// interpolation slack of the coarsest cell drawn) and the top by the nearest point's.
pub fn tile_aabb(
    lo: DVec2,
    hi: DVec2,
    min_h: f32,
    max_h: f32,
    eye: DVec3,
    curvature: bool,
    cell_diagonal_m: f64,
) -> Aabb {
    let (mut zlo, mut zhi) = (min_h as f64, max_h as f64);
    if curvature {
        let e = eye.truncate();
        let nearest = e.clamp(lo, hi);
        let far = DVec2::new(
            if (e.x - lo.x).abs() > (e.x - hi.x).abs() {
                lo.x
            } else {
                hi.x
            },
            if (e.y - lo.y).abs() > (e.y - hi.y).abs() {
                lo.y
            } else {
                hi.y
            },
        );
        let d_min = (nearest - e).length();
        let d_max = (far - e).length();
        zhi -= d_min * d_min / (2.0 * EARTH_RADIUS_M);
        zlo -=
            d_max * d_max / (2.0 * EARTH_RADIUS_M) + curvature_interpolation_error(cell_diagonal_m);
    }
    Aabb {
        min: DVec3::new(lo.x, lo.y, zlo),
        max: DVec3::new(hi.x, hi.y, zhi),
    }
}

/// Smallest view depth of a box (view depth is linear, so a corner attains it), clamped to the
/// near plane.
pub fn min_view_depth(camera: &Camera, aabb: &Aabb) -> f64 {
    let m = camera.world_to_view();
    min_depth_of(&aabb.corners().map(|c| m.transform_point3(c)), camera.near)
}

/// [`min_view_depth`] of corners already in view space.
fn min_depth_of(corners: &[DVec3; 8], near: f64) -> f64 {
    corners
        .iter()
        .map(|c| c.z)
        .fold(f64::INFINITY, f64::min)
        .max(near)
}

/// [`super::tiles::outside_frustum`] of corners already in view space.
fn outside_of(corners: &[DVec3; 8], f: &Frustum, near: f64) -> bool {
    let all = |outside: &dyn Fn(&DVec3) -> bool| corners.iter().all(outside);
    all(&|p| p.z < near)
        || all(&|p| p.x > f.tan_right * p.z)
        || all(&|p| p.x < f.tan_left * p.z)
        || all(&|p| -p.y > f.tan_up * p.z)
        || all(&|p| -p.y < f.tan_down * p.z)
}

/// The screen factor of a *vertical* error over the part of a box inside the frustum — the `c`
/// of DESIGN.md's `ρ = ε·f·c / (z_min − ε)`, tightened for the direction terrain errors have.
///
/// A point p (view coordinates, a = x/z, b = y/z) displaced by ε' along the world vertical
/// (unit w in view space, |ε'| ≤ ε) moves on screen by exactly
/// `f·|ε'|·|(w_x − a·w_z, w_y − b·w_z)| / (z + ε'·w_z) ≤ f·ε·g / (z_min − ε)`
/// with `g = max |(w_x − a·w_z, w_y − b·w_z)|` over the (a, b) the box shows. Both squared
/// components are convex in one variable each, so their maxima over the box's (a, b) ranges —
/// the corners' ranges clamped to the frustum, a rectangle holding everything visible of the box
/// — are at range ends. `g ≤ sqrt(1 + a² + b²)` (the largest singular value of
/// [[1, 0, −a], [0, 1, −b]]), the direction-free obliquity, which looking level at 90° × 59°
/// overstates the vertical error's projection by up to 1.52×. A corner at or behind the eye
/// plane falls back to the whole frustum's ranges.
pub fn box_vertical_gain(camera: &Camera, aabb: &Aabb) -> f64 {
    let m = camera.world_to_view();
    let w = camera.world_to_view_rotation() * DVec3::Z;
    vertical_gain_of(
        &aabb.corners().map(|c| m.transform_point3(c)),
        &camera.frustum,
        w,
    )
}

/// [`box_vertical_gain`] of corners already in view space; `w` is the world vertical there.
fn vertical_gain_of(corners: &[DVec3; 8], f: &Frustum, w: DVec3) -> f64 {
    let (mut a_lo, mut a_hi, mut b_lo, mut b_hi) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for v in corners {
        if v.z <= 1e-9 {
            return vertical_gain(w, [f.tan_left, f.tan_right], [-f.tan_up, -f.tan_down]);
        }
        let (a, b) = (v.x / v.z, v.y / v.z);
        (a_lo, a_hi) = (a_lo.min(a), a_hi.max(a));
        (b_lo, b_hi) = (b_lo.min(b), b_hi.max(b));
    }
    // View y is down: b = y/z lies in [−tan_up, −tan_down].
    let a = [a_lo, a_hi].map(|a| a.clamp(f.tan_left, f.tan_right));
    let b = [b_lo, b_hi].map(|b| b.clamp(-f.tan_up, -f.tan_down));
    vertical_gain(w, a, b)
}

/// [`box_vertical_gain`] over the whole frustum (for boxes not culled against it).
pub fn frustum_vertical_gain(camera: &Camera) -> f64 {
    let f = camera.frustum;
    let w = camera.world_to_view_rotation() * DVec3::Z;
    vertical_gain(w, [f.tan_left, f.tan_right], [-f.tan_up, -f.tan_down])
}

fn vertical_gain(w: DVec3, a: [f64; 2], b: [f64; 2]) -> f64 {
    let gx = a.map(|a| (w.x - a * w.z).powi(2));
    let gy = b.map(|b| (w.y - b * w.z).powi(2));
    (gx[0].max(gx[1]) + gy[0].max(gy[1])).sqrt()
}

/// The projected-error bound in pixels of a vertical error `eps` anywhere in a box whose
/// smallest view depth is `z_min` (DESIGN.md: ρ = ε·f·c / (z_min − ε)).
pub fn projected_error_px(eps: f64, z_min: f64, focal_px: f64, obliquity: f64) -> f64 {
    if eps <= 0.0 {
        return 0.0;
    }
    let z = z_min - eps;
    if z <= 0.0 {
        f64::INFINITY
    } else {
        eps * focal_px * obliquity / z
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
}

/// One channel's camera with what the bound needs from it.
struct ViewCtx<'a> {
    camera: &'a Camera,
    /// World → view, computed once per frame (not per node: the attitude's trigonometry).
    to_view: glam::DMat4,
    /// The world vertical in view space.
    up: DVec3,
    focal: f64,
    /// [`frustum_vertical_gain`].
    vertical_gain: f64,
    tau: f64,
}

/// One display channel for [`select_tiles_multi`]: its camera, viewport and error bound.
#[derive(Debug, Clone, Copy)]
pub struct View<'a> {
    pub camera: &'a Camera,
    pub viewport: (u32, u32),
    pub tau_px: f64,
}

/// A node as the views see it.
struct NodeEval {
    eps: f64,
    /// Largest ρ (px) among the views that see the node.
    rho_px: f64,
    /// Largest ρ/τ among them: the node meets every channel's bound when ≤ 1.
    rho_norm: f64,
}

impl Frame<'_> {
    fn cell_diagonal(&self, level_drawn: u32) -> f64 {
        (self.grid.spacing * (1u64 << level_drawn) as f64).length()
    }

    /// ε of level-L tile drawn with refinement r, curvature interpolation included.
    fn eps(&self, level: u32, tx: u32, ty: u32, r: u32) -> f64 {
        let mut e = self.bake.eps_refined(level, tx, ty, r) as f64;
        if self.params.curvature {
            e += curvature_interpolation_error(self.cell_diagonal(level - r));
        }
        e
    }

    /// ε of the level-ℓ surface over the level-ℓ tile (tx, ty), curvature slack included.
    fn eps_node(&self, level: u32, tx: u32, ty: u32) -> f64 {
        self.eps(level, tx, ty, 0)
    }

    /// The node's box as seen from `eye` (the curvature drop depends on the eye).
    fn aabb(&self, level: u32, tx: u32, ty: u32, eye: DVec3) -> Aabb {
        let (lo, hi) = self.grid.rect(level, tx, ty);
        let (min_h, max_h) = self.bake.bounds(level, tx, ty);
        tile_aabb(
            lo,
            hi,
            min_h,
            max_h,
            eye,
            self.params.curvature,
            self.cell_diagonal(level),
        )
    }

    /// ε and the projected error in every view that sees the node; `None` when no view does.
    /// With `cull` false, views that do not see it count too (for level skipping).
    fn evaluate(&self, level: u32, tx: u32, ty: u32, cull: bool) -> Option<NodeEval> {
        let eps = self.eps_node(level, tx, ty);
        let mut seen = false;
        let (mut rho_px, mut rho_norm) = (0.0f64, 0.0f64);
        for v in &self.views {
            let aabb = self.aabb(level, tx, ty, v.camera.position);
            let corners = aabb.corners().map(|c| v.to_view.transform_point3(c));
            let f = &v.camera.frustum;
            if cull && outside_of(&corners, f, v.camera.near) {
                continue;
            }
            seen = true;
            let z_min = min_depth_of(&corners, v.camera.near);
            let c = if cull {
                vertical_gain_of(&corners, f, v.up)
            } else {
                v.vertical_gain
            };
            let rho = projected_error_px(eps, z_min, v.focal, c);
            rho_px = rho_px.max(rho);
            rho_norm = rho_norm.max(rho / v.tau);
        }
        seen.then_some(NodeEval {
            eps,
            rho_px,
            rho_norm,
        })
    }

    /// Distance LOD: split while the eye is within `distance_factor` node sides of the node's
    /// box; a node split last frame stays split until 10 % beyond, an unsplit one splits only
    /// 10 % inside (hysteresis).
    fn wants_distance_split(&self, level: u32, tx: u32, ty: u32, was_split: bool) -> bool {
        let side = (self.grid.q as f64) * (1u64 << level) as f64 * self.grid.spacing.max_element();
        let d = self
            .views
            .iter()
            .map(|v| {
                let p = v.camera.position;
                let aabb = self.aabb(level, tx, ty, p);
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
        let Some(NodeEval {
            eps: e,
            rho_px: rho,
            rho_norm,
        }) = self.evaluate(level, tx, ty, true)
        else {
            return 0;
        };
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
        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let (cx, cy) = (2 * tx + dx, 2 * ty + dy);
            if has_terrain(self.bake, level - 1, cx, cy) {
                missed += self.subdivide(level - 1, cx, cy, finest, out);
            }
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
    out.items.clear();
    out.levels.clear();
    out.levels.resize(placements.len(), LevelStats::default());
    out.unbounded = 0;
    if views.is_empty() {
        return;
    }
    let views: Vec<ViewCtx> = views
        .iter()
        .map(|v| {
            let (fx, fy) = v.camera.frustum.focal_px(v.viewport.0, v.viewport.1);
            ViewCtx {
                camera: v.camera,
                to_view: v.camera.world_to_view(),
                up: v.camera.world_to_view_rotation() * DVec3::Z,
                focal: fx.max(fy),
                vertical_gain: frustum_vertical_gain(v.camera),
                tau: v.tau_px,
            }
        })
        .collect();
    let split_prev = std::mem::take(&mut out.split);
    let split_now = std::cell::RefCell::new(std::collections::HashSet::new());
    let distance = params.mode == LodMode::Distance;
    let frame = Frame {
        split_prev: distance.then_some(&split_prev),
        split_now: distance.then_some(&split_now),
        bake,
        grid: Grid::of(bake),
        views,
        params,
    };

    if params.mode == LodMode::Bounded && params.coarsen {
        select_coarsest_first(&frame, placements, out);
        out.split = split_now.into_inner();
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
            let Some(NodeEval {
                eps,
                rho_px: rho,
                rho_norm,
            }) = frame.evaluate(level, tx, ty, true)
            else {
                out.levels[i].culled += 1;
                continue;
            };
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
            refine_ring_tile(&frame, level, tx, ty, i, &mut nodes, out);
        }
    }
    out.split = split_now.into_inner();
}

/// Draws ring tile (level, tx, ty) — which the finer levels do not cover — as a quadtree of
/// nodes from one pool slot (refinement up to the cap), each split while it misses τ.
fn refine_ring_tile(
    frame: &Frame,
    level: u32,
    tx: u32,
    ty: u32,
    level_index: usize,
    nodes: &mut Vec<(u32, u32, u32, f32, f32)>,
    out: &mut Selection,
) {
    let cap = frame.params.max_refinement.min(level).min(MAX_REFINEMENT);
    nodes.clear();
    out.unbounded += frame.subdivide(level, tx, ty, level - cap, nodes);
    let r = nodes.iter().map(|n| level - n.0).max().unwrap_or(0);
    let stats = &mut out.levels[level_index];
    stats.refined[r as usize] += 1;
    stats.nodes += nodes.len() as u32;
    for &(node_level, node_tx, node_ty, eps_m, rho_px) in nodes.iter() {
        out.items.push(DrawItem {
            level,
            tx,
            ty,
            refinement: r,
            node_level,
            node_tx,
            node_ty,
            eps_m,
            rho_px,
        });
    }
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
    let mut stack: Vec<(usize, u32, u32)> = (0..roots.tiles_y)
        .rev()
        .flat_map(|ty| (0..roots.tiles_x).rev().map(move |tx| (top, tx, ty)))
        .collect();
    while let Some((i, tx, ty)) = stack.pop() {
        let level = placements[i].level;
        if !has_terrain(frame.bake, level, tx, ty) {
            continue;
        }
        // A split node is not a tile of its own: `considered` counts drawn + culled.
        let Some(NodeEval {
            eps,
            rho_px: rho,
            rho_norm,
        }) = frame.evaluate(level, tx, ty, true)
        else {
            out.levels[i].considered += 1;
            out.levels[i].culled += 1;
            continue;
        };
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
        if i > 0 && inside_patch(&placements[i - 1], 2 * tx, 2 * ty) {
            // Children in the finer patch: descend (pushed so that they pop south-west first).
            for (dx, dy) in [(1, 1), (0, 1), (1, 0), (0, 0)] {
                stack.push((i - 1, 2 * tx + dx, 2 * ty + dy));
            }
            continue;
        }
        out.levels[i].considered += 1;
        out.levels[i].drawn += 1;
        refine_ring_tile(frame, level, tx, ty, i, &mut nodes, out);
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

/// For each drawn node (level, tx, ty, ε), the largest ε among itself and the nodes sharing
/// an edge with it — what its skirt must reach. Along an edge between nodes A and B both
/// surfaces are within their ε of the true one, so the edges differ by up to ε_A + ε_B, and
/// the higher edge's skirt must cover that: a skirt of ε + max(ε, neighbours' ε) closes every
/// crack, including T-junctions against a much rougher coarse neighbour, which 2ε alone does
/// not. Each fine–coarse pair is found from the finer node by walking up from the position
/// across its edge to the first drawn node (a same-level neighbour or a coarser ancestor) and
/// updates both.
pub fn neighbour_eps(nodes: &[(u32, u32, u32, f32)]) -> Vec<f32> {
    let mut index: std::collections::HashMap<(u32, u32, u32), usize, NodeHash> =
        std::collections::HashMap::with_capacity_and_hasher(nodes.len(), NodeHash::default());
    for (i, &(l, x, y, _)) in nodes.iter().enumerate() {
        index.insert((l, x, y), i);
    }
    let top = nodes.iter().map(|n| n.0).max().unwrap_or(0);
    let mut out: Vec<f32> = nodes.iter().map(|n| n.3).collect();
    for (i, &(l, x, y, e)) in nodes.iter().enumerate() {
        for (dx, dy) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
            let (nx, ny) = (x as i64 + dx, y as i64 + dy);
            if nx < 0 || ny < 0 {
                continue;
            }
            for k in 0..=(top - l) {
                let key = (l + k, (nx >> k) as u32, (ny >> k) as u32);
                if let Some(&j) = index.get(&key) {
                    if j != i {
                        out[i] = out[i].max(nodes[j].3);
                        out[j] = out[j].max(e);
                    }
                    break;
                }
            }
        }
    }
    out
}

/// A fast hasher for small integer keys (node lookups run thousands of times per frame).
#[derive(Default, Clone, Copy)]
struct NodeHasher(u64);

impl std::hash::Hasher for NodeHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_u32(&mut self, v: u32) {
        self.write_u64(v as u64);
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

type NodeHash = std::hash::BuildHasherDefault<NodeHasher>;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Attitude, Frustum};

    #[test]
    fn projected_error_is_monotonic_and_infinite_inside_the_error() {
        let f = 960.0;
        let c = 1.5;
        let a = projected_error_px(1.0, 1000.0, f, c);
        assert!((a - 1.0 * 960.0 * 1.5 / 999.0).abs() < 1e-12);
        assert!(projected_error_px(1.0, 2000.0, f, c) < a);
        assert!(projected_error_px(2.0, 1000.0, f, c) > a);
        assert_eq!(projected_error_px(5.0, 5.0, f, c), f64::INFINITY);
        assert_eq!(projected_error_px(0.0, 0.5, f, c), 0.0);
    }

    /// Distance LOD keeps its previous decision inside the ±10 % band: the same camera position
    /// selects different nodes when approached from near than from far.
    #[test]
    fn distance_mode_has_hysteresis() {
        use crate::bake::{bake, BakeParams};
        use crate::clipmap::place_levels;
        use crate::dataset::Dataset;
        use crate::Heightfield;
        let n = 257;
        let hf = Heightfield {
            width: n,
            height: n,
            spacing_x: 10.0,
            spacing_y: 10.0,
            heights: (0..n * n)
                .map(|k| ((k % n) as f32 * 0.3).sin() * 20.0)
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
        let desc = ClipmapDesc {
            tile_quads: 16,
            patch_tiles: 8,
            margin_tiles: 2,
            width: n as u32,
            height: n as u32,
        };
        let params = SelectParams {
            mode: LodMode::Distance,
            coarsen: false,
            ..SelectParams::default()
        };
        let run = |heights: &[f64]| {
            let mut sel = Selection::default();
            for &z in heights {
                let cam = Camera::new(
                    DVec3::new(1280.0, 1280.0, z),
                    Attitude::from_degrees(0.0, -89.0, 0.0),
                    Frustum::symmetric(170f64.to_radians(), 64, 64),
                );
                let placements = place_levels(&desc, [128.0, 128.0]);
                select_tiles(&b, &desc, &placements, &cam, (64, 64), &params, &mut sel);
            }
            sel.items.len()
        };
        // Level-1 ring tiles are 320 m wide: split below 3 × 320 = 960 m (± 10 %). The nearest
        // ones are 640 m away horizontally, so at 716 m up the eye is 960 m from them.
        let from_near = run(&[100.0, 700.0, 716.0]);
        let from_far = run(&[5000.0, 800.0, 716.0]);
        assert!(from_near > from_far, "near {from_near} vs far {from_far}");
        // Far outside the band, history does not matter.
        assert_eq!(run(&[100.0, 30_000.0]), run(&[30_000.0]));
    }

    /// The tightened factor is never above the direction-free obliquity, and the bound it gives
    /// holds by brute force: random cameras and boxes, random visible points in the box moved
    /// vertically by up to ε, the exact screen displacement never exceeds ε·f·g/(z_min − ε).
    #[test]
    fn vertical_gain_bounds_vertical_errors_on_screen() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (w, h) = (320u32, 180u32);
        let mut checked = 0;
        let mut tightest: f64 = 0.0;
        for _ in 0..400 {
            let cam = Camera::new(
                DVec3::new(0.0, 0.0, 1000.0),
                Attitude::from_degrees(rnd() * 360.0, rnd() * 180.0 - 90.0, rnd() * 360.0 - 180.0),
                Frustum::symmetric((20.0 + rnd() * 140.0).to_radians(), w, h),
            );
            let lo = DVec3::new(
                rnd() * 8000.0 - 4000.0,
                rnd() * 8000.0 - 4000.0,
                rnd() * 900.0,
            );
            let size = DVec3::new(50.0 + rnd() * 2000.0, 50.0 + rnd() * 2000.0, rnd() * 300.0);
            let aabb = Aabb {
                min: lo,
                max: lo + size,
            };
            let g = box_vertical_gain(&cam, &aabb);
            // The per-frame fast path agrees with the public functions.
            let corners = aabb
                .corners()
                .map(|c| cam.world_to_view().transform_point3(c));
            assert_eq!(
                outside_of(&corners, &cam.frustum, cam.near),
                crate::tiles::outside_frustum(&cam, &aabb)
            );
            assert!(g <= box_obliquity_reference(&cam, &aabb) + 1e-12);
            let (fx, fy) = cam.frustum.focal_px(w, h);
            let eps = 1.0 + rnd() * 20.0;
            let z_min = min_view_depth(&cam, &aabb);
            let bound = projected_error_px(eps, z_min, fx.max(fy), g);
            for _ in 0..50 {
                let p = aabb.min + (aabb.max - aabb.min) * DVec3::new(rnd(), rnd(), rnd());
                let Some((s0, _)) = cam.project_px(p, w, h) else {
                    continue;
                };
                if !(0.0..=w as f64).contains(&s0.x) || !(0.0..=h as f64).contains(&s0.y) {
                    continue;
                }
                let e = eps * (2.0 * rnd() - 1.0);
                let q = p + DVec3::new(0.0, 0.0, e);
                let Some((s1, _)) = cam.project_px(q, w, h) else {
                    continue;
                };
                let moved = (s1 - s0).length();
                assert!(
                    moved <= bound * (1.0 + 1e-9),
                    "moved {moved} px > bound {bound} px"
                );
                tightest = tightest.max(moved / bound);
                checked += 1;
            }
        }
        assert!(checked > 1000, "only {checked} visible samples");
        // Not vacuous: some samples come close to the bound.
        assert!(tightest > 0.5, "tightest {tightest}");
    }

    /// The direction-free factor sqrt(1 + a² + b²) over the box's clamped (a, b) ranges.
    fn box_obliquity_reference(camera: &Camera, aabb: &Aabb) -> f64 {
        let f = camera.frustum;
        let m = camera.world_to_view();
        let (mut a, mut b) = (0.0f64, 0.0f64);
        for c in aabb.corners() {
            let v = m.transform_point3(c);
            if v.z <= 1e-9 {
                return f.max_obliquity();
            }
            a = a.max((v.x / v.z).clamp(f.tan_left, f.tan_right).abs());
            b = b.max((v.y / v.z).clamp(-f.tan_up, -f.tan_down).abs());
        }
        (1.0 + a * a + b * b).sqrt()
    }

    #[test]
    fn skirts_reach_the_roughest_neighbour() {
        // Level 1 node (0, 0) covers level-0 (0..2, 0..2); two level-0 nodes east of it at
        // (2, 0) and (2, 1), and a level-0 node (3, 0) east of those; one far away.
        let nodes = [
            (1, 0, 0, 8.0),
            (0, 2, 0, 1.0),
            (0, 2, 1, 0.5),
            (0, 3, 0, 2.0),
            (0, 9, 9, 0.25),
        ];
        let m = neighbour_eps(&nodes);
        assert_eq!(m[0], 8.0, "the coarse node is the roughest itself");
        assert_eq!(m[1], 8.0, "fine next to coarse: T-junction");
        assert_eq!(m[2], 8.0);
        assert_eq!(m[3], 2.0, "same-level neighbour (2, 0) has less");
        assert_eq!(m[4], 0.25, "no neighbours");
        // A fine node rougher than its coarse neighbour raises the coarse one.
        let m = neighbour_eps(&[(1, 0, 0, 1.0), (0, 2, 1, 5.0)]);
        assert_eq!(m, vec![5.0, 5.0]);
    }

    #[test]
    fn curvature_lowers_the_box_by_the_far_drop() {
        let eye = DVec3::new(0.0, 0.0, 1000.0);
        let lo = DVec2::new(10_000.0, -500.0);
        let hi = DVec2::new(20_000.0, 500.0);
        let flat = tile_aabb(lo, hi, 100.0, 200.0, eye, false, 10.0);
        let curved = tile_aabb(lo, hi, 100.0, 200.0, eye, true, 10.0);
        assert_eq!(flat.min.z, 100.0);
        let far = (20_000f64.powi(2) + 500f64.powi(2)) / (2.0 * EARTH_RADIUS_M);
        let near = 10_000f64.powi(2) / (2.0 * EARTH_RADIUS_M);
        assert!((curved.min.z - (100.0 - far - 100.0 / (8.0 * EARTH_RADIUS_M))).abs() < 1e-9);
        assert!((curved.max.z - (200.0 - near)).abs() < 1e-9);
        // Eye above the tile: nearest distance is 0, the top does not move.
        let above = tile_aabb(
            lo,
            hi,
            100.0,
            200.0,
            DVec3::new(15_000.0, 0.0, 900.0),
            true,
            10.0,
        );
        assert_eq!(above.max.z, 200.0);
    }
}
