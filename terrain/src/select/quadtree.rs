//! The selection itself: each level's ring tiles, culled and refined until the bound holds,
//! or (coarsening) a quadtree over the levels from the coarsest down.

use glam::DVec3;

use crate::bake::ErrorBake;
use crate::camera::Camera;
use crate::clipmap::{ring_tiles, ClipmapDesc, LevelPlacement};

use super::bound::{frustum_gain_floor, frustum_vertical_gain};
use super::carry::{Carry, CarryKey, FrustumPlanes, Optics, RingNormal, Taken, ViewNow};
use super::cdlod_morph::Morph;
use super::parts::{choose_parts, MeshCosts, NodeEval, Parts, Quadrant, Upgrade};
use super::selection::{
    AllReady, DrawItem, LevelStats, LodMode, SelectParams, Selection, TileReadiness, View,
    MAX_REFINEMENT,
};
use super::walk::{child_of, has_terrain, Frame, Grid, TryParts, ViewCtx};

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
    select_tiles_multi_ready(bake, desc, placements, views, params, &AllReady, out);
}

/// [`select_tiles_multi`] over level textures that may not hold every tile yet (a streamed
/// source): a level tile is drawn from its texture only when `ready` says its texels are
/// there; elsewhere the quadtree stops at the coarser level (refined from the pools where their
/// samples are resident) and the tile counts in [`Selection::stream_late`]. Outside the
/// quadtree (other modes, `coarsen` off) a ring tile not ready is not drawn and counts late.
pub fn select_tiles_multi_ready(
    bake: &ErrorBake,
    desc: &ClipmapDesc,
    placements: &[LevelPlacement],
    views: &[View],
    params: &SelectParams,
    ready: &dyn TileReadiness,
    out: &mut Selection,
) {
    out.items.clear();
    out.levels.clear();
    out.levels.resize(placements.len(), LevelStats::default());
    out.unbounded = 0;
    out.stream_late = 0;
    out.wants.clear();
    out.hidden = 0;
    if views.is_empty() {
        return;
    }
    if params.mode == LodMode::Cdlod {
        out.split.clear();
        return super::cdlod::select_cdlod(bake, placements, views, params, out);
    }
    let views: Vec<ViewCtx> = views
        .iter()
        .map(|v| {
            let (fx, fy) = v.camera.frustum.focal_px(v.viewport.0, v.viewport.1);
            ViewCtx {
                camera: v.camera,
                to_view: v.camera.world_to_view(),
                rotation: v.camera.world_to_view_rotation(),
                up: v.camera.world_to_view_rotation() * DVec3::Z,
                focal: fx.max(fy),
                vertical_gain: frustum_vertical_gain(v.camera),
                tau: v.tau_px,
                inv_tau: 1.0 / v.tau_px,
                focal_per_tau: fx.max(fy) / v.tau_px,
            }
        })
        .collect();
    let split_prev = std::mem::take(&mut out.split);
    let mut cache = std::mem::take(&mut out.node_cache);
    cache.begin(bake, params.earth.as_ref(), params.curvature);
    let split_now = std::cell::RefCell::new(std::collections::HashSet::new());
    let distance = params.mode == LodMode::Distance;
    let mut horizon = std::mem::take(&mut out.horizon);
    let cull_hidden = params.horizon_cull && params.mode == LodMode::Bounded;
    if cull_hidden {
        let eyes: Vec<DVec3> = views.iter().map(|v| v.camera.position).collect();
        horizon.build(bake, params.earth.as_ref(), params.curvature, &eyes);
    }
    let grid = Grid::of(bake);
    let tau_max = views.iter().map(|v| v.tau).fold(0.0, f64::max);
    let gain_floor = match views.as_slice() {
        [v] if params.earth.is_none() && !cull_hidden => {
            Some(frustum_gain_floor(&v.camera.frustum, v.up) * v.focal_per_tau)
        }
        _ => None,
    };
    #[cfg(test)]
    let gain_floor = gain_floor.filter(|_| !super::walk::reference::every_hybrid());
    let mut carry = std::mem::take(&mut out.carry);
    let v = &views[0];
    let f = v.camera.frustum;
    let optics = [
        v.focal,
        v.tau,
        v.camera.near,
        f.tan_left,
        f.tan_right,
        f.tan_down,
        f.tan_up,
    ];
    let key = carry_key(bake, params, views.len(), optics);
    #[cfg(test)]
    let key = key.filter(|_| !super::walk::reference::active());
    // On the plane every record shares the frustum's least gain, which must be positive; on
    // the ellipsoid each record forms its own (`carry.rs`).
    let floor = frustum_gain_floor(&f, v.up);
    let key = key.filter(|_| params.earth.is_some() || floor > 0.0);
    let now = ViewNow {
        eye: v.camera.position,
        rotation: v.rotation,
    };
    carry.begin(key, key.map(|_| now));
    let carrying = key.map(|_| Carrying {
        now,
        optics: {
            let a = f.tan_left.abs().max(f.tan_right.abs());
            let b = f.tan_up.abs().max(f.tan_down.abs());
            Optics {
                tau: v.tau,
                focal: v.focal,
                near: v.camera.near,
                turn: (2.0 + a * a + b * b).sqrt(),
                up: v.up,
                w_z: v.up.z.abs(),
                frustum: f,
            }
        },
        planes: FrustumPlanes::of(&f, v.camera.near),
    });
    let frame = Frame {
        split_prev: distance.then_some(&split_prev),
        split_now: distance.then_some(&split_now),
        bake,
        grid,
        diagonals: (0..=bake.levels.len() as u32)
            .map(|l| grid.cell_diagonal(l))
            .collect(),
        views,
        params,
        ready,
        cache: std::cell::RefCell::new(&mut cache),
        #[cfg(test)]
        reference: super::walk::reference::active(),
        horizon: cull_hidden.then_some(&horizon),
        hidden: std::cell::Cell::new(0),
        quadrants: std::cell::RefCell::new(Vec::new()),
        culled: carrying
            .as_ref()
            .map(|_| std::cell::RefCell::new(Vec::new())),
        costs: MeshCosts::of(grid.q),
        tau_max,
        gain_floor,
    };

    if params.mode == LodMode::Bounded && params.coarsen {
        let mut carried = carrying.map(|c| (c, &mut carry));
        select_coarsest_first(&frame, placements, carried.as_mut(), out);
        out.hidden = frame.hidden.get();
        drop(frame);
        out.split = split_now.into_inner();
        out.node_cache = cache;
        out.horizon = horizon;
        carry.end();
        out.carry = carry;
        return;
    }
    carry.end();
    out.carry = carry;
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
            let Some(eval) = frame.evaluate(level, tx, ty, true) else {
                out.levels[i].culled += 1;
                continue;
            };
            let NodeEval {
                eps,
                rho_px: rho,
                rho_norm,
                ..
            } = eval;
            if !frame.ready.is_ready(level, tx, ty) {
                // Not drawn rather than drawn stale (only the quadtree can fall back coarser).
                out.stream_late += 1;
                out.wants.push((level, tx, ty, rho as f32));
                continue;
            }
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
            out.unbounded +=
                refine_ring_tile(&frame, level, tx, ty, eval, None, i, &mut nodes, out);
        }
    }
    out.hidden = frame.hidden.get();
    drop(frame);
    out.split = split_now.into_inner();
    out.node_cache = cache;
    out.horizon = horizon;
}

/// Draws ring tile (level, tx, ty) — which the finer levels do not cover, and which `eval`
/// says a view sees — as a quadtree of nodes from one pool slot (refinement up to the cap),
/// each split while it misses τ.
#[allow(clippy::too_many_arguments)]
fn refine_ring_tile(
    frame: &Frame,
    level: u32,
    tx: u32,
    ty: u32,
    eval: NodeEval,
    retry: Option<TryParts<'_>>,
    level_index: usize,
    nodes: &mut Vec<(u32, u32, u32, f32, f32)>,
    out: &mut Selection,
) -> u32 {
    let cap = frame.params.max_refinement.min(level).min(MAX_REFINEMENT);
    nodes.clear();
    frame.quadrants.borrow_mut().clear();
    let missed = frame.subdivide_seen(level, tx, ty, eval, level - cap, retry, nodes);
    let first = out.items.len();
    out.push_refined(level_index, level, tx, ty, nodes);
    for &(k, morph) in frame.quadrants.borrow().iter() {
        out.items[first + k].morph = morph;
    }
    missed
}

/// A carried ring tile's `nodes` drawn, with their `morphs` (indices into `nodes`).
fn push_carried(
    out: &mut Selection,
    i: usize,
    (level, tx, ty): (u32, u32, u32),
    nodes: &[(u32, u32, u32, f32, f32)],
    morphs: &[(usize, Morph)],
) {
    let first = out.items.len();
    out.push_refined(i, level, tx, ty, nodes);
    for &(k, morph) in morphs {
        out.items[first + k].morph = morph;
    }
}

/// Ring tile `key`'s record made at this frame's view from `nodes`, `morphs` and the parts
/// found outside the frustum, `culled` ([`Carry::record`]; on the ellipsoid with the tile's
/// normal).
fn record_ring_tile(
    frame: &Frame,
    c: &Carrying,
    carry: &mut Carry<SelectParams>,
    key: (u32, u32, u32),
    nodes: &[(u32, u32, u32, f32, f32)],
    morphs: &[(usize, Morph)],
    culled: &[(u32, u32, u32)],
) {
    let normal = frame.fixed(key.0, key.1, key.2).geo.map(|g| RingNormal {
        up: g.up,
        spread: g.spread,
    });
    carry.record(
        key,
        &c.now,
        &c.optics,
        normal,
        nodes,
        morphs,
        culled,
        &c.planes,
        |l, x, y| frame.carried_box(l, x, y),
    );
}

/// The one node of a ring tile's carried record that no longer holds (`failing`, drawn as
/// `morph`: at its own resolution, its parent's or its grandparent's), walked afresh as
/// [`refine_ring_tile`] walks a ring tile's nodes, with the options a fresh walk reaching it
/// would weigh: a sixteenth that fails is tried as its parent's quadrant first, and any node
/// below the ring tile is split with its children tried as sixteenths of its parent (the node
/// missed τ at its parent's resolution, or it would not be failing at a finer one). The ground
/// it covered is covered again, each part meeting τ or split to the cap, culled parts dropped.
/// Its nodes are appended to `nodes` and their morphs to `morphs` (indices into `nodes`);
/// returns how many miss τ.
fn repair_node(
    frame: &Frame,
    ring_level: u32,
    failing: (u32, u32, u32, f32, f32),
    morph: Morph,
    nodes: &mut Vec<(u32, u32, u32, f32, f32)>,
    morphs: &mut Vec<(usize, Morph)>,
) -> u32 {
    let cap = frame
        .params
        .max_refinement
        .min(ring_level)
        .min(MAX_REFINEMENT);
    let finest = ring_level - cap;
    let (l, x, y) = (failing.0, failing.1, failing.2);
    frame.quadrants.borrow_mut().clear();
    // Its parent within the ring tile, where its children may be that parent's sixteenths.
    let parent =
        (l < ring_level && frame.params.parent_quadrants).then(|| frame.fixed(l + 1, x / 2, y / 2));
    let own = match &parent {
        Some(p) if morph == Morph::SIXTEENTH => match frame.evaluate_quadrant(p, None, l, x, y) {
            None => None,
            Some((q, _, _)) if q.rho_norm <= 1.0 => {
                nodes.push((l, x, y, q.eps as f32, q.rho_px as f32));
                morphs.push((nodes.len() - 1, Morph::QUADRANT));
                return 0;
            }
            Some((_, own, _)) => Some(own),
        },
        _ => frame.evaluate(l, x, y, true),
    };
    let missed = match own {
        None => {
            frame.note_culled(l, x, y);
            0
        }
        Some(eval) => {
            let retry = parent
                .as_ref()
                .map(|parent| TryParts { parent, kids: None });
            frame.subdivide_seen(l, x, y, eval, finest, retry, nodes)
        }
    };
    // `subdivide_seen` indexes its morphs into the list it appends to.
    morphs.extend_from_slice(&frame.quadrants.borrow());
    missed
}

/// `Bounded` with [`SelectParams::coarsen`]: a quadtree over the clipmap levels. Every
/// coarsest-level tile is a root; a node that meets τ is drawn from its own level's texture;
/// one that misses it is split into its four children when the next finer level's patch holds
/// them (the patches nest with even origins, so a tile is wholly inside or outside it), else it
/// is a ring tile of its level and is refined from the pools. The result covers the same ground
/// as the ring-by-ring selection, each part by one node meeting τ (or unbounded at the cap),
/// at the coarsest level that does.
fn select_coarsest_first(
    frame: &Frame,
    placements: &[LevelPlacement],
    mut carry: Option<&mut (Carrying, &mut Carry<SelectParams>)>,
    out: &mut Selection,
) {
    let mut morphs = Vec::new();
    let Some(coarsest) = placements.last() else {
        return;
    };
    let roots = &frame.bake.levels[coarsest.level as usize];
    let mut nodes = Vec::new();
    let top = placements.len() - 1;
    // Nodes to visit, with their evaluation when a quadrant test made it already, and whether
    // they may still be tried in parts (see `Frame::upgrade_quadrants`); the children that
    // test formed, by index.
    let mut stack: Vec<(usize, u32, u32, Option<NodeEval>, Retry)> = (0..roots.tiles_y)
        .rev()
        .flat_map(|ty| {
            (0..roots.tiles_x)
                .rev()
                .map(move |tx| (top, tx, ty, None, Retry::Yes))
        })
        .collect();
    let mut formed: Vec<[Quadrant; 4]> = Vec::new();
    let mut parts = Vec::new();
    let mut kept_culled = Vec::new();
    while let Some((i, tx, ty, known, retry)) = stack.pop() {
        let kids = match retry {
            Retry::Formed(k) => frame.formed(Some(&formed[k as usize])).copied(),
            _ => None,
        };
        let retry = !matches!(retry, Retry::No);
        let level = placements[i].level;
        if !has_terrain(frame.bake, level, tx, ty) {
            continue;
        }
        if i == top && !frame.ready.is_ready(level, tx, ty) {
            // The coarsest level is filled before the first frame; a root not there yet is not
            // drawn rather than drawn stale.
            out.stream_late += 1;
            out.wants.push((level, tx, ty, f32::MAX));
            continue;
        }
        // A split node is not a tile of its own: `considered` counts drawn + culled.
        let Some(eval) = known.or_else(|| frame.evaluate(level, tx, ty, true)) else {
            out.levels[i].considered += 1;
            out.levels[i].culled += 1;
            continue;
        };
        let NodeEval {
            eps,
            rho_px: rho,
            rho_norm,
            ..
        } = eval;
        let children = [(1, 1), (0, 1), (1, 0), (0, 0)].map(|(dx, dy)| (2 * tx + dx, 2 * ty + dy));
        let child_level = level.wrapping_sub(1);
        let missing = |&(cx, cy): &(u32, u32)| {
            has_terrain(frame.bake, child_level, cx, cy)
                && !frame.ready.is_ready(child_level, cx, cy)
        };
        // Children in the finer patch, all of them in its texture.
        let in_patch = i > 0 && inside_patch(&placements[i - 1], 2 * tx, 2 * ty);
        let children_ready = in_patch && !children.iter().any(missing);
        // A node that missed τ as a quadrant of its parent (`known`) may still be drawn in
        // fewer triangles than whole: its children as sixteenths of that parent.
        let grand = (known.is_some() && retry && children_ready && frame.sixteenths_below(level))
            .then(|| frame.fixed(level + 1, tx / 2, ty / 2));
        if rho_norm <= 1.0 && grand.is_none() {
            let coarser = (i == top)
                .then(|| frame.coarser_root(level, tx, ty))
                .flatten();
            // A root drawn as a sixteenth is the fewest triangles any of its seen parts
            // could be: those are not formed then.
            let sixteenth = coarser.is_some_and(|(item, _)| item.morph.sixteenth);
            let seen = !sixteenth && frame.seen_parts(&eval, level, tx, ty, &mut parts);
            // The root drawn coarser, unless its seen parts are fewer triangles and
            // instances still.
            let instance = frame.costs.instance;
            let parts_cost =
                seen.then(|| frame.parts_triangles(&parts) + instance * parts.len() as u32);
            if let Some((item, triangles)) = coarser {
                if parts_cost.is_none_or(|c| triangles + instance <= c) {
                    push_drawn(out, i, item);
                    continue;
                }
            }
            if seen {
                for &item in &parts {
                    push_drawn(out, i, item);
                }
            } else {
                push_drawn(
                    out,
                    i,
                    DrawItem::whole(level, tx, ty, eps as f32, rho as f32),
                );
            }
            continue;
        }
        let mut waiting = false;
        if in_patch {
            // Descend (pushed so that they pop south-west first) once all the children are in
            // the finer texture; until then this node stands for them.
            if children_ready {
                if !frame.params.parent_quadrants {
                    for (cx, cy) in children {
                        stack.push((i - 1, cx, cy, None, Retry::Yes));
                    }
                    continue;
                }
                // Each child as a quadrant at this node's resolution first (the child tile
                // fully morphed onto this node's grid), and as a sixteenth of the parent; then
                // the fewest triangles that meet τ.
                let parent = frame.fixed(level, tx, ty);
                let mut found = [Upgrade::Untried; 4];
                let quads = match &grand {
                    // Meeting τ itself: its children bounded from its box alone (or formed
                    // so already, by its parent's upgrade).
                    Some(g) if rho_norm <= 1.0 => kids.unwrap_or_else(|| {
                        frame.quadrants_meeting(&eval, &parent, g, level, tx, ty)
                    }),
                    _ => {
                        let mut quads = frame.quadrants(&parent, grand.as_ref(), level, tx, ty);
                        let grandchildren_ready = |cx: u32, cy: u32| {
                            i >= 2
                                && inside_patch(&placements[i - 2], 2 * cx, 2 * cy)
                                && (0..4).all(|k| {
                                    let (gx, gy) = child_of(cx, cy, k);
                                    !has_terrain(frame.bake, level - 2, gx, gy)
                                        || frame.ready.is_ready(level - 2, gx, gy)
                                })
                        };
                        frame.upgrade_quadrants(
                            &mut quads,
                            &parent,
                            level,
                            tx,
                            ty,
                            grandchildren_ready,
                            &mut found,
                        );
                        quads
                    }
                };
                match choose_parts(&quads, rho_norm <= 1.0, frame.costs) {
                    Parts::Whole(rho_px) => {
                        let rho_px = rho_px.unwrap_or(rho);
                        let item = DrawItem::whole(level, tx, ty, eps as f32, rho_px as f32);
                        push_drawn(out, i, item);
                        continue;
                    }
                    Parts::AsQuadrant { rho_px, .. } => {
                        let (peps, _) = frame.as_quadrant(grand.as_ref().unwrap(), level, tx, ty);
                        let item = DrawItem {
                            morph: Morph::QUADRANT,
                            ..DrawItem::whole(level, tx, ty, peps as f32, rho_px as f32)
                        };
                        push_drawn(out, i, item);
                        continue;
                    }
                    Parts::Children => {}
                }
                // North-east first, so that the stack pops them south-west first.
                for (k, quad) in quads.iter().enumerate().rev() {
                    let (cx, cy) = child_of(tx, ty, k);
                    let drawn = |q: NodeEval, morph: Morph| DrawItem {
                        morph,
                        ..DrawItem::whole(child_level, cx, cy, q.eps as f32, q.rho_px as f32)
                    };
                    match *quad {
                        Quadrant::NoTerrain => {}
                        Quadrant::Unseen => {
                            out.levels[i - 1].considered += 1;
                            out.levels[i - 1].culled += 1;
                        }
                        Quadrant::Seen { sub: Some(s), .. } if s.rho_norm <= 1.0 => {
                            push_drawn(out, i - 1, drawn(s, Morph::SIXTEENTH));
                        }
                        Quadrant::Seen { q, .. } if q.rho_norm <= 1.0 => {
                            push_drawn(out, i - 1, drawn(q, Morph::QUADRANT));
                        }
                        Quadrant::Seen { own, .. } => {
                            let retry = match &found[k] {
                                Upgrade::Whole => Retry::No,
                                Upgrade::Untried => Retry::Yes,
                                Upgrade::Children(kids) => {
                                    formed.push(*kids);
                                    Retry::Formed(formed.len() as u32 - 1)
                                }
                            };
                            stack.push((i - 1, cx, cy, Some(own), retry))
                        }
                    }
                }
                continue;
            }
            for &(cx, cy) in children.iter().filter(|c| missing(c)) {
                out.wants.push((child_level, cx, cy, rho as f32));
            }
            waiting = true;
        }
        out.levels[i].considered += 1;
        out.levels[i].drawn += 1;
        // Waiting for finer texels, the node is refined from the pools instead: beyond the
        // cap it is late for streaming, not a tile the cap leaves unbounded.
        // A node that missed τ as its parent's quadrant: its children may be that parent's
        // sixteenths, from the pools.
        let parent = (known.is_some() && retry && frame.sixteenths_below(level))
            .then(|| frame.fixed(level + 1, tx / 2, ty / 2));
        let retry = parent.as_ref().map(|parent| TryParts {
            parent,
            kids: kids.as_ref(),
        });
        let missed = match carry.as_deref_mut() {
            Some((c, carry)) if !waiting => {
                let key = (level, tx, ty);
                nodes.clear();
                morphs.clear();
                kept_culled.clear();
                let taken = carry.take(
                    key,
                    &c.now,
                    &c.optics,
                    &c.planes,
                    &mut nodes,
                    &mut morphs,
                    &mut kept_culled,
                );
                if let Some(culled) = &frame.culled {
                    culled.borrow_mut().clear();
                }
                match taken {
                    Taken::Whole => {
                        push_carried(out, i, key, &nodes, &morphs);
                        0
                    }
                    Taken::AllBut(failing, morph) => {
                        // The others drawn again, the one walked afresh, the record made again.
                        let missed =
                            repair_node(frame, level, failing, morph, &mut nodes, &mut morphs);
                        push_carried(out, i, key, &nodes, &morphs);
                        if missed == 0 {
                            if let Some(culled) = &frame.culled {
                                kept_culled.extend_from_slice(&culled.borrow());
                            }
                            record_ring_tile(frame, c, carry, key, &nodes, &morphs, &kept_culled);
                        }
                        missed
                    }
                    Taken::Walk => {
                        carry.stats.walked_tiles += 1;
                        let missed =
                            refine_ring_tile(frame, level, tx, ty, eval, retry, i, &mut nodes, out);
                        if missed == 0 {
                            let culled = frame.culled.as_ref().map(|c| c.borrow());
                            let culled = culled.as_deref().map_or(&[][..], |v| v.as_slice());
                            let morphs = frame.quadrants.borrow();
                            record_ring_tile(frame, c, carry, key, &nodes, &morphs, culled);
                        }
                        missed
                    }
                }
            }
            _ => refine_ring_tile(frame, level, tx, ty, eval, retry, i, &mut nodes, out),
        };
        if waiting {
            out.stream_late += (missed > 0) as u32;
        } else {
            out.unbounded += missed;
        }
    }
    let drawn_levels = out.levels.iter().position(|l| l.drawn > 0);
    out.finest_level = drawn_levels.unwrap_or(0) as u32;
    for s in out.levels.iter_mut() {
        s.skipped = s.drawn == 0;
    }
}

/// [`CarryKey`] of a frame that may carry: one view (on the plane or the ellipsoid), no
/// horizon culling, the bounded quadtree with parts; `None` else.
fn carry_key(
    bake: &ErrorBake,
    params: &SelectParams,
    views: usize,
    optics: [f64; 7],
) -> Option<CarryKey<SelectParams>> {
    let fits = params.carry
        && views == 1
        && !params.horizon_cull
        && params.mode == LodMode::Bounded
        && params.coarsen
        && params.parent_quadrants;
    fits.then(|| CarryKey {
        bake: bake as *const ErrorBake as usize,
        checksum: bake.source_checksum,
        params: *params,
        optics: optics.map(f64::to_bits),
    })
}

/// What carrying ring tiles across frames reads of the one view (`carry.rs`).
struct Carrying {
    now: ViewNow,
    optics: Optics,
    planes: FrustumPlanes,
}

/// Whether a node on the coarsest-first walk's stack, evaluated as its parent's quadrant, may
/// still be tried in parts ([`Frame::upgrade_quadrants`]): no (found best drawn whole), yes,
/// or yes with its children formed already (by index in the walk's table of them).
#[derive(Clone, Copy)]
enum Retry {
    No,
    Yes,
    Formed(u32),
}

/// `item` drawn as a node of `out.levels[i]`: counted considered, drawn, unrefined.
fn push_drawn(out: &mut Selection, i: usize, item: DrawItem) {
    let stats = &mut out.levels[i];
    stats.considered += 1;
    stats.drawn += 1;
    stats.refined[0] += 1;
    stats.nodes += 1;
    out.items.push(item);
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
