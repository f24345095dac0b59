//! The frame plan's draw records (pure): where a node lies in its pool slot, one
//! `TileInstance` per drawn node (relative to the eye, grouped by refinement, whole nodes
//! first, then quadrants drawn at their parent's resolution, then sixteenths drawn at their
//! grandparent's) and one indexed indirect command per group: whole nodes with the tile's
//! mesh, quadrants with its coarse mesh (the parent's quarter mesh:
//! `mesh::skirted_coarse_tile_indices`), sixteenths with every fourth vertex
//! (`mesh::skirted_sixteenth_tile_indices`). Within a group the records are sorted by the
//! edges that need a skirt (`select::node_skirts`): the group's grid is one command, and
//! each set of edges one more (two for opposite edges) drawing only those edges' skirts.

use glam::DVec3;

use aerie_terrain::geodesy::GeoGrid;
use aerie_terrain::select::{DrawItem, LodMode, NodeSkirts, SkirtMemo, ALL_EDGES};

use crate::render::geo_instances::{GeoEye, GeoNodeCache};
use crate::render::gpu::{DrawIndexedIndirect, GeoPolynomial, TileInstance};
use crate::render::jobs::{FIXED_SLACK_BYTES, OVERLAY_SLACK_BYTES};
use crate::render::pool_atlas::PoolSlots;
use crate::render::stats::RESOLUTIONS;

/// Instance groups, each one indirect command: per refinement the whole nodes, then per
/// refinement the quadrants drawn at their parent's resolution, then per refinement the
/// sixteenths drawn at their grandparent's.
pub const DRAW_GROUPS: usize = 3 * RESOLUTIONS;

/// The sets of a node's edges that may need a skirt (`select::ALL_EDGES`' bits).
pub const EDGE_SETS: usize = 16;

/// The instance records' sort keys: a draw group's, then the node's skirted edges.
pub const INSTANCE_KEYS: usize = DRAW_GROUPS * EDGE_SETS;

/// The most commands a frame's terrain draw issues: per group its grid, and a command for
/// each of the 15 non-empty edge sets, two for each of the 2 sets of opposite edges.
pub const MAX_TERRAIN_DRAWS: usize = DRAW_GROUPS * (1 + 15 + 2);

/// Which edges of the drawn nodes get a skirt.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SkirtRule {
    /// None: CDLOD (Strugar 2009), whose morph closes the seams between its levels.
    None,
    /// Every edge of every node.
    Everywhere,
    /// The edges shared with a node drawn at another resolution (`select::node_skirts`), not
    /// those shared with one at the same resolution nor those facing a place where nothing
    /// is drawn — culled — inside the grid; the edges on or past the grid's first and last
    /// samples; between two nodes that reach past the last sample (their vertices there fold
    /// onto the first vertex at or past it, each node by its own step) unless both are of one
    /// level and resolution; and every edge of every node of a projected grid (its nodes'
    /// polynomials meet within their fit error, not exactly).
    #[default]
    WhereResolutionsDiffer,
}

impl SkirtRule {
    /// The rule a frame drawn in `mode` follows: CDLOD draws no skirts (Strugar 2009: the
    /// morph closes its seams); every other mode's hide the cracks between neighbours drawn
    /// at different resolutions.
    pub fn for_mode(self, mode: LodMode) -> SkirtRule {
        match mode {
            LodMode::Cdlod => SkirtRule::None,
            _ => self,
        }
    }
}

/// Skirt segments of one edge each mesh's skirt list repeats after its four edges, so that
/// every run of edges around the tile — south, east, north, west, south, east — is one range
/// of indices.
const REPEATED_EDGES: u32 = 2;

/// Where a tile's three meshes lie in the shared index buffer, (first index, index count)
/// each: the whole tile, its coarse mesh for quadrants drawn at their parent's resolution, and
/// its sixteenth mesh for sixteenths drawn at their grandparent's (empty when the tile's
/// quads a side are not a multiple of 4). One vertex layout serves all three
/// (`mesh::skirted_vertex_count`). Each range is the mesh's grid, then its four edges'
/// skirts (`mesh::skirt_edge_indices`, south, east, north, west), followed in the buffer by
/// the south and east skirts again ([`REPEATED_EDGES`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TileMeshes {
    pub whole: (u32, u32),
    pub coarse: (u32, u32),
    pub sixteenth: (u32, u32),
    /// Each mesh's grid indices (whole, coarse, sixteenth): its first indices, before its
    /// skirt's.
    pub grid: [u32; 3],
    /// Each mesh's indices of one edge's skirt.
    pub edge: [u32; 3],
}

impl TileMeshes {
    /// The index buffer of a tile of `side` vertices a side — the whole mesh, the coarse one,
    /// the sixteenth one — and where each lies in it.
    pub fn indices(side: u32) -> (Vec<u32>, TileMeshes) {
        use aerie_terrain::mesh::{
            skirt_edge_indices, skirted_coarse_tile_indices, skirted_sixteenth_tile_indices,
            skirted_tile_indices,
        };
        let sixteenths = side >= 5 && (side - 1).is_multiple_of(4);
        let mut v = Vec::new();
        let mut mesh = |stride: u32, skirted: Vec<u32>| {
            let first = v.len() as u32;
            let count = skirted.len() as u32;
            v.extend(skirted);
            for edge in 0..REPEATED_EDGES {
                v.extend(skirt_edge_indices(side, stride, edge));
            }
            (first, count)
        };
        let whole = mesh(1, skirted_tile_indices(side));
        let coarse = mesh(2, skirted_coarse_tile_indices(side));
        let sixteenth = if sixteenths {
            mesh(4, skirted_sixteenth_tile_indices(side))
        } else {
            (v.len() as u32, 0)
        };
        // A strided mesh lists its grid's 6 indices a cell, then each edge's skirt.
        let n = side - 1;
        let cells = |stride: u32| (n / stride).pow(2) * 6;
        let skirt = |stride: u32| aerie_terrain::mesh::skirt_edge_triangles(n / stride) * 3;
        let grid = [cells(1), cells(2), if sixteenths { cells(4) } else { 0 }];
        let edge = [skirt(1), skirt(2), if sixteenths { skirt(4) } else { 0 }];
        (
            v,
            TileMeshes {
                whole,
                coarse,
                sixteenth,
                grid,
                edge,
            },
        )
    }

    /// Group `g`'s mesh ([`DRAW_GROUPS`]): its first index, its grid's indices and one
    /// edge's skirt's.
    fn of_group(&self, g: usize) -> (u32, u32, u32) {
        let k = (g / RESOLUTIONS).min(2);
        let first = [self.whole.0, self.coarse.0, self.sixteenth.0][k];
        (first, self.grid[k], self.edge[k])
    }
}

/// The runs of consecutive edges (around the tile, south → east → north → west → south) that
/// make up an edge set, (first edge, edges) each: one run, or two for opposite edges.
fn edge_runs(set: u8) -> ([(u32, u32); 2], usize) {
    if set & ALL_EDGES == ALL_EDGES {
        return ([(0, 4), (0, 0)], 1);
    }
    let has = |e: u32| set & (1 << (e % 4)) != 0;
    let mut runs = [(0, 0); 2];
    let mut n = 0;
    for e in 0..4 {
        if has(e) && !has(e + 3) {
            let mut len = 1;
            while has(e + len) {
                len += 1;
            }
            runs[n] = (e, len);
            n += 1;
        }
    }
    (runs, n)
}

/// A draw item's group: its refinement, offset by [`RESOLUTIONS`] for each level it is drawn
/// coarser than its own (a quadrant, a sixteenth).
fn group_of(item: &DrawItem) -> usize {
    item.refinement as usize + item.morph.levels_up() as usize * RESOLUTIONS
}

/// Each drawn node's skirt: how far it reaches and the edges that get one under `f.skirts`
/// (see [`SkirtRule`]), in the list's order; one walk over the nodes gives both.
fn skirts_of(f: &InstanceFrame, draw_list: &[(DrawItem, u32)], memo: &mut SkirtMemo) -> NodeSkirts {
    let n = draw_list.len();
    if f.skirts == SkirtRule::None {
        return NodeSkirts {
            reach: vec![0.0; n],
            edges: vec![0; n],
        };
    }
    let q = f.tile_quads as u64;
    let projected = f.earth.is_some_and(|g| g.projected.is_some());
    let [last_x, last_y] = f.valid_samples.map(|v| (v as u64).saturating_sub(1));
    // A node's far corner in samples, east and north.
    let ends = |item: &DrawItem| {
        let end = |t: u32| (t as u64 + 1) * (q << item.node_level);
        [item.node_tx, item.node_ty].map(end)
    };
    // Every edge of every node keeps a skirt under these rules (a projected grid's nodes'
    // polynomials meet only within their fit).
    let all_edges = f.skirts == SkirtRule::Everywhere || projected;
    let mut nodes = Vec::with_capacity(n);
    let mut resolution = Vec::with_capacity(n);
    let mut folds = Vec::with_capacity(n);
    let mut on_last = Vec::with_capacity(n);
    for (i, _) in draw_list {
        nodes.push((i.node_level, i.node_tx, i.node_ty, i.eps_m));
        resolution.push(i.node_level + i.morph.levels_up());
        let [east, north] = ends(i);
        // A node reaching past the grid's last sample folds its vertices there by its own step.
        folds.push(east > last_x || north > last_y);
        // The grid's last sample: an edge on it or past it keeps the skirt its first one keeps.
        on_last.push(((east >= last_x) as u8) << 1 | ((north >= last_y) as u8) << 2);
    }
    let mut skirts = memo.skirts(&nodes, &resolution, &folds).clone();
    for (e, last) in skirts.edges.iter_mut().zip(on_last) {
        *e |= if all_edges { ALL_EDGES } else { last };
    }
    skirts
}

/// What [`build_instances`] keeps across frames: the drawn nodes' eye-independent ellipsoid
/// fields and the last node list's skirts.
#[derive(Default)]
pub struct InstanceCaches {
    pub geo: GeoNodeCache,
    pub skirts: SkirtMemo,
}

/// What the instance records need from the frame: the clipmap's tile size, the grid spacing,
/// the ellipsoid placement of a geographic or UTM grid, the eye and the skirt rule.
pub struct InstanceFrame<'a> {
    pub tile_quads: u32,
    pub spacing: [f64; 2],
    pub earth: Option<&'a GeoGrid>,
    pub eye: DVec3,
    pub skirt_factor: f32,
    pub skirt_min_m: f32,
    /// Which edges get a skirt.
    pub skirts: SkirtRule,
    /// The grid's samples east and north (a node reaching past the last folds its vertices
    /// there; the edges on or past it keep their skirts).
    pub valid_samples: [u32; 2],
    /// The pools r = 1.. (index r − 1): where each slot lies in its image.
    pub pools: &'a [PoolSlots],
}

/// Where a node lies in its pool slot: the slot holds the ring tile at level L − r, so a node
/// at `node_level` starts `(slot_x, slot_y)` slot texels in and steps `slot_stride` texels per
/// vertex. Unrefined nodes (r = 0) read the clipmap: (0, 0, 1).
pub fn slot_placement(item: &DrawItem, tile_quads: u32) -> (u32, u32, u32) {
    let r = item.refinement;
    if r == 0 {
        return (0, 0, 1);
    }
    let q = tile_quads as i64;
    let node = q << item.node_level;
    let origin = [item.node_tx as i64 * node, item.node_ty as i64 * node];
    let tile = q << item.level;
    let slot_step = 1i64 << (item.level - r);
    (
        ((origin[0] - item.tx as i64 * tile) / slot_step) as u32,
        ((origin[1] - item.ty as i64 * tile) / slot_step) as u32,
        1u32 << (item.node_level - (item.level - r)),
    )
}

/// Per-instance data grouped as [`DRAW_GROUPS`] says (unrefined whole nodes first, then r =
/// 1.., then the quadrants likewise, then the sixteenths), each group sorted by the edges its
/// nodes skirt ([`INSTANCE_KEYS`]): node origin relative to the eye (f64 → f32), sample
/// origin, vertex step, level, pool slot and the node's place in it, skirt depth. Returns the
/// concatenated records, on a projected grid each record's polynomials in the same order (else
/// none), and each key's count.
pub fn build_instances(
    f: &InstanceFrame,
    draw_list: &[(DrawItem, u32)],
    caches: &mut InstanceCaches,
) -> (Vec<TileInstance>, Vec<GeoPolynomial>, [u32; INSTANCE_KEYS]) {
    let q = f.tile_quads;
    let eye = f.eye;
    let NodeSkirts { reach, edges } = skirts_of(f, draw_list, &mut caches.skirts);
    let geo_cache = &mut caches.geo;
    let key_of = |k: usize| group_of(&draw_list[k].0) * EDGE_SETS + edges[k] as usize;
    let geo = f.earth.map(|g| {
        geo_cache.begin(g);
        GeoEye::new(g, eye)
    });
    // The records are written once, in their final place: a counting sort of the draw list by
    // key (stable, so each key keeps the list's order) into one vector of the exact size
    // (records are 144 bytes: growing and concatenating per-group vectors copied each
    // several times).
    let mut sizes = [0u32; INSTANCE_KEYS];
    for k in 0..draw_list.len() {
        sizes[key_of(k)] += 1;
    }
    let mut next = [0usize; INSTANCE_KEYS];
    for g in 1..INSTANCE_KEYS {
        next[g] = next[g - 1] + sizes[g - 1] as usize;
    }
    let mut order = vec![0u32; draw_list.len()];
    for k in 0..draw_list.len() {
        let at = &mut next[key_of(k)];
        order[*at] = k as u32;
        *at += 1;
    }
    // Each record built whole and pushed once, in its final place (no zeroed vector written
    // over: 200 KB a frame on the dense flights); the ellipsoid's fields are zero on the plane.
    let mut instances = Vec::with_capacity(draw_list.len());
    let projected = geo.as_ref().is_some_and(GeoEye::projected);
    let mut polynomials = Vec::with_capacity(if projected { draw_list.len() } else { 0 });
    for &k in &order {
        let (item, slot) = draw_list[k as usize];
        let reach_m = reach[k as usize];
        let node = (q as i64) << item.node_level;
        let origin = [item.node_tx as i64 * node, item.node_ty as i64 * node];
        let (slot_x, slot_y, slot_stride) = slot_placement(&item, q);
        // A refined node names its slot's layer and its south-west vertex's texel in that
        // layer (the slot's cell + the node's place in the slot): `terrain.vert` finds the cell
        // again from it (`PoolAtlas::read_texel`).
        let (slot, slot_x, slot_y) = if item.refinement > 0 {
            let place = f.pools[item.refinement as usize - 1].atlas.place(slot);
            (place.layer, slot_x + place.x, slot_y + place.y)
        } else {
            (slot, slot_x, slot_y)
        };
        let mut t = TileInstance {
            origin_rel: [
                (origin[0] as f64 * f.spacing[0] - eye.x) as f32,
                (origin[1] as f64 * f.spacing[1] - eye.y) as f32,
            ],
            origin_sample: [origin[0] as i32, origin[1] as i32],
            step: 1 << item.node_level,
            level: item.level,
            refinement: item.refinement,
            slot,
            // ε + max(ε, neighbours' ε) at the default factor 2 (see select::node_skirts).
            skirt_m: 0.5 * f.skirt_factor * (item.eps_m + reach_m) + f.skirt_min_m,
            slot_x,
            slot_y,
            slot_stride,
            morph: item.morph.to_gpu(),
            geo_origin: [0.0; 4],
            geo_axis_r: [0.0; 4],
            geo_axis_t: [0.0; 4],
            geo_axis_z: [0.0; 4],
            geo_radius: [0.0; 4],
        };
        if let Some(e) = &geo {
            let (g, poly, rel) = e.node_fields_in(geo_cache, origin, 1 << item.node_level, q);
            t.geo_origin = [rel[0], rel[1], rel[2], g.geo_origin[3]];
            t.geo_axis_r = g.geo_axis_r;
            t.geo_axis_t = g.geo_axis_t;
            t.geo_axis_z = g.geo_axis_z;
            t.geo_radius = g.geo_radius;
            if let Some(p) = poly {
                polynomials.push(*p);
            }
        }
        instances.push(t);
    }
    (instances, polynomials, sizes)
}

/// Bytes the frame's fixed pushes need besides the uploads: indirect commands, one instance (and
/// on a `projected` grid one polynomial) per selected node (coarsening only lowers the count),
/// the overlay, and their slack.
pub fn fixed_reserve(selected_nodes: usize, projected: bool, overlay_bytes: Option<u64>) -> u64 {
    let overlay = overlay_bytes.map_or(0, |b| b + OVERLAY_SLACK_BYTES);
    let polynomial = projected as usize * std::mem::size_of::<GeoPolynomial>();
    FIXED_SLACK_BYTES
        + (std::mem::size_of::<DrawIndexedIndirect>() * MAX_TERRAIN_DRAWS) as u64
        + (selected_nodes * (std::mem::size_of::<TileInstance>() + polynomial)) as u64
        + overlay
}

/// Triangles of a skirted tile of `q` quads a side (grid 2q², each edge's skirt three per two
/// segments: `mesh::skirt_edge_triangles`).
pub fn skirted_tile_triangles(q: u32) -> u64 {
    let skirt = aerie_terrain::mesh::skirt_edge_triangles(q) as u64;
    let q = q as u64;
    2 * q * q + 4 * skirt
}

/// What one quadrant drawn at its parent's resolution draws fewer than a whole tile of `q`
/// quads: it is drawn with the tile's coarse mesh, the parent's quarter mesh of q/2 quads a
/// side.
pub fn quarter_mesh_saving(q: u32) -> u64 {
    skirted_tile_triangles(q) - skirted_tile_triangles(q / 2)
}

/// The indexed indirect commands of the instances counted per key ([`INSTANCE_KEYS`],
/// as [`build_instances`] lays them out), and the triangles they draw. Per group: one
/// command for every instance's grid — whole nodes the tile's mesh, quadrants its coarse one,
/// sixteenths the stride-4 one —, then per set of skirted edges one command drawing those
/// edges' skirts (two for opposite edges) for the instances of that set. Only commands that
/// draw something are listed; a mesh without indices draws nothing.
pub fn indirect_draws(
    key_sizes: &[u32; INSTANCE_KEYS],
    meshes: TileMeshes,
) -> (Vec<DrawIndexedIndirect>, u64) {
    let mut draws = Vec::new();
    let mut triangles = 0u64;
    let mut push = |first_index: u32, index_count: u32, first_instance: u32, n: u32| {
        if index_count > 0 && n > 0 {
            draws.push(DrawIndexedIndirect {
                index_count,
                instance_count: n,
                first_index,
                vertex_offset: 0,
                first_instance,
            });
            triangles += n as u64 * (index_count as u64 / 3);
        }
    };
    let mut first_instance = 0u32;
    for (g, sets) in key_sizes.chunks_exact(EDGE_SETS).enumerate() {
        let (first, grid, edge) = meshes.of_group(g);
        push(first, grid, first_instance, sets.iter().sum());
        for (set, &n) in sets.iter().enumerate() {
            let (runs, count) = edge_runs(set as u8);
            for &(from, len) in &runs[..count] {
                push(first + grid + from * edge, len * edge, first_instance, n);
            }
            first_instance += n;
        }
    }
    debug_assert!(draws.len() <= MAX_TERRAIN_DRAWS);
    (draws, triangles)
}

/// Each command's (first index, index count, first instance, instance count): what the
/// tests compare.
#[cfg(test)]
pub(crate) fn draw_ranges(draws: &[DrawIndexedIndirect]) -> Vec<(u32, u32, u32, u32)> {
    draws
        .iter()
        .map(|d| {
            (
                d.first_index,
                d.index_count,
                d.first_instance,
                d.instance_count,
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame of tiles of 17 at 10 m, the eye at the origin, no minimum skirt.
    fn frame(skirts: SkirtRule, valid_samples: [u32; 2], pools: &[PoolSlots]) -> InstanceFrame<'_> {
        InstanceFrame {
            tile_quads: 16,
            spacing: [10.0, 10.0],
            earth: None,
            eye: DVec3::ZERO,
            skirt_factor: 2.0,
            skirt_min_m: 0.0,
            skirts,
            valid_samples,
            pools,
        }
    }

    /// The records come grouped by refinement, unrefined first, whole nodes before the
    /// quadrants drawn at their parent's resolution and those before the sixteenths drawn at
    /// their grandparent's, each group in the draw list's order, and the sizes count the groups.
    #[test]
    fn instances_are_grouped_by_refinement_then_quadrants_in_list_order() {
        use aerie_terrain::select::cdlod_morph::Morph;
        let refined = |r: u32, k: u32, up: u32| DrawItem {
            refinement: r,
            node_level: 4 - r,
            node_tx: k << r,
            morph: [Morph::NONE, Morph::QUADRANT, Morph::SIXTEENTH][up as usize],
            ..DrawItem::whole(4, k, 0, 1.0, 0.5)
        };
        let list: Vec<(DrawItem, u32)> = [
            (2, 0, 0),
            (0, 1, 1),
            (0, 2, 0),
            (1, 3, 0),
            (2, 4, 1),
            (2, 5, 0),
            (0, 6, 0),
            (0, 7, 1),
            (0, 8, 2),
        ]
        .iter()
        .map(|&(r, k, q)| (refined(r, k, q), k))
        .collect();
        let pools: Vec<PoolSlots> = (1..=6).map(|r| PoolSlots::new((16 << r) + 1, 16)).collect();
        let f = frame(SkirtRule::Everywhere, [1 << 20, 1 << 20], &pools);
        let (instances, _, sizes) = build_instances(&f, &list, &mut InstanceCaches::default());
        let mut want = [0u32; DRAW_GROUPS];
        want[..3].copy_from_slice(&[2, 1, 2]);
        want[RESOLUTIONS] = 2;
        want[RESOLUTIONS + 2] = 1;
        want[2 * RESOLUTIONS] = 1;
        let per_group: Vec<u32> = sizes.chunks(EDGE_SETS).map(|c| c.iter().sum()).collect();
        assert_eq!(per_group, want);
        // Skirts everywhere: every node in its group's set of all four edges.
        for (key, &n) in sizes.iter().enumerate() {
            assert!(n == 0 || key % EDGE_SETS == ALL_EDGES as usize, "key {key}");
        }
        let slots: Vec<u32> = instances.iter().map(|i| i.slot).collect();
        assert_eq!(slots, [2, 6, 3, 0, 5, 1, 7, 4, 8]);
        // Packed 2 × 2 slots to a layer, a refined node names its slot's layer and its
        // south-west vertex's texel there: the slot's cell + its place in the slot.
        let limits = crate::render::pool_atlas::PoolLimits {
            max_layers: 4,
            max_side: 4096,
        };
        let packed: Vec<PoolSlots> = pools
            .iter()
            .map(|p| PoolSlots {
                atlas: crate::render::pool_atlas::PoolAtlas::new(p.side, 16, limits).unwrap(),
                ..p.clone()
            })
            .collect();
        let g = InstanceFrame {
            pools: &packed,
            ..f
        };
        let (placed, _, _) = build_instances(&g, &list, &mut InstanceCaches::default());
        for (t, o) in placed.iter().zip(&instances) {
            if t.refinement == 0 {
                assert_eq!(t, o);
                continue;
            }
            let atlas = &packed[t.refinement as usize - 1].atlas;
            assert_eq!(atlas.per_row, 2);
            let p = atlas.place(o.slot);
            assert_eq!(t.slot, p.layer, "{t:?}");
            assert_eq!([t.slot_x, t.slot_y], [p.x + o.slot_x, p.y + o.slot_y]);
            assert_eq!(atlas.read_texel([t.slot_x, t.slot_y], [-1, -1]), [p.x, p.y]);
        }
        // Quadrants and sixteenths alike are fully morphed onto the parent's grid.
        let quadrant: Vec<bool> = instances.iter().map(|i| i.morph[0] < 0.0).collect();
        assert_eq!(
            quadrant,
            [false, false, false, false, false, true, true, true, true]
        );
    }

    /// On a projected grid each record has its node's polynomials, in the records' order (the
    /// counting sort's, not the list's), and the record's tail is its node's frame; a
    /// geographic grid's records have none (nothing staged for them).
    #[test]
    fn polynomials_follow_the_records_on_a_projected_grid_only() {
        use aerie_terrain::GeoReference;
        let utm = GeoReference::Projected {
            crs: "EPSG:32632".into(),
            easting: 170_000.0,
            northing: 5_200_000.0,
        };
        let geographic = GeoReference::Geographic {
            south_lat_deg: 47.0,
            west_lon_deg: 11.0,
            dlat_deg: 1.0 / 1200.0,
            dlon_deg: 1.0 / 1200.0,
        };
        let pools: Vec<PoolSlots> = (1..=6).map(|r| PoolSlots::new((16 << r) + 1, 16)).collect();
        // Whole nodes at levels 3 and 2 here and there on the grid.
        let list: Vec<(DrawItem, u32)> = [(3u32, 0u32), (3, 1), (2, 5)]
            .iter()
            .map(|&(level, k)| (DrawItem::whole(level, k, 1, 1.0, 0.5), 0))
            .collect();
        for (geo, want_polys) in [(&utm, true), (&geographic, false)] {
            let g = GeoGrid::of(Some(geo), 30.0, 30.0).unwrap();
            let eye = g.world_of_grid(glam::DVec2::new(4_000.0, 6_000.0), 2_000.0);
            let f = InstanceFrame {
                earth: Some(&g),
                eye,
                spacing: [30.0, 30.0],
                ..frame(SkirtRule::Everywhere, [1 << 20, 1 << 20], &pools)
            };
            let (instances, polys, _) = build_instances(&f, &list, &mut InstanceCaches::default());
            assert_eq!(instances.len(), list.len());
            if !want_polys {
                assert!(polys.is_empty(), "a geographic grid stages no polynomials");
                continue;
            }
            assert_eq!(polys.len(), instances.len());
            let e = GeoEye::new(&g, eye);
            for (t, p) in instances.iter().zip(&polys) {
                let origin = [t.origin_sample[0] as i64, t.origin_sample[1] as i64];
                let fields = e.node_fields(origin, t.step, 16);
                assert_eq!(*p, GeoPolynomial::of(&fields), "{origin:?}");
                assert_ne!(*p, GeoPolynomial::default());
                assert_eq!(t.geo_axis_r, fields.geo_axis_r);
                assert_eq!(t.geo_radius, fields.geo_radius);
            }
        }
    }

    /// Whole nodes draw the tile's grid, quadrants the coarse one, sixteenths the stride-4
    /// one, each group's instances after the previous group's; all four skirts follow each
    /// grid as one range; the triangles are the ranges' per instance.
    #[test]
    fn quadrant_groups_draw_the_coarse_range() {
        use aerie_terrain::mesh::{
            skirted_coarse_tile_indices, skirted_sixteenth_tile_indices, skirted_tile_indices,
        };
        let (buffer, meshes) = TileMeshes::indices(17);
        let whole = skirted_tile_indices(17).len() as u32;
        let coarse = skirted_coarse_tile_indices(17).len() as u32;
        let sixteenth = skirted_sixteenth_tile_indices(17).len() as u32;
        // Each edge's skirt: three triangles per two segments (`mesh::skirt_edge_indices`).
        let edge = [8 * 9, 4 * 9, 2 * 9];
        let after = |k: usize| REPEATED_EDGES * edge[k];
        assert_eq!(
            meshes,
            TileMeshes {
                whole: (0, whole),
                coarse: (whole + after(0), coarse),
                sixteenth: (whole + after(0) + coarse + after(1), sixteenth),
                grid: [16 * 16 * 6, 8 * 8 * 6, 4 * 4 * 6],
                edge,
            }
        );
        assert_eq!(
            buffer.len() as u32,
            whole + coarse + sixteenth + after(0) + after(1) + after(2)
        );
        // Each range is the skirted mesh the mesh module makes.
        for (range, mesh) in [
            (meshes.whole, skirted_tile_indices(17)),
            (meshes.coarse, skirted_coarse_tile_indices(17)),
            (meshes.sixteenth, skirted_sixteenth_tile_indices(17)),
        ] {
            assert_eq!(
                &buffer[range.0 as usize..(range.0 + range.1) as usize],
                &mesh[..]
            );
        }
        let all = ALL_EDGES as usize;
        let mut sizes = [0u32; INSTANCE_KEYS];
        sizes[all] = 3;
        sizes[EDGE_SETS + all] = 1;
        sizes[RESOLUTIONS * EDGE_SETS + all] = 2;
        sizes[2 * RESOLUTIONS * EDGE_SETS + all] = 5;
        let (draws, tris) = indirect_draws(&sizes, meshes);
        let got = draw_ranges(&draws);
        let (g, c, s) = (meshes.grid, meshes.coarse.0, meshes.sixteenth.0);
        assert_eq!(
            got,
            [
                (0, g[0], 0, 3),
                (g[0], 4 * edge[0], 0, 3),
                (0, g[0], 3, 1),
                (g[0], 4 * edge[0], 3, 1),
                (c, g[1], 4, 2),
                (c + g[1], 4 * edge[1], 4, 2),
                (s, g[2], 6, 5),
                (s + g[2], 4 * edge[2], 6, 5),
            ]
        );
        assert_eq!(
            tris,
            4 * skirted_tile_triangles(16)
                + 2 * skirted_tile_triangles(8)
                + 5 * skirted_tile_triangles(4)
        );
        // Without skirts (CDLOD's set): each mesh's grid indices, 2q² triangles.
        let mut bare = [0u32; INSTANCE_KEYS];
        bare[0] = 3;
        let (draws, tris) = indirect_draws(&bare, meshes);
        assert_eq!(draws.len(), 1);
        assert_eq!(tris, 3 * 2 * 16 * 16);
        assert!(buffer[..g[0] as usize].iter().all(|&i| i < 17 * 17));
        // A tile whose quads a side are not a multiple of 4 has no sixteenth mesh.
        assert_eq!(TileMeshes::indices(7).1.sixteenth.1, 0);
        assert_eq!(TileMeshes::indices(7).1.grid[2], 0);
        assert_eq!(
            skirted_tile_triangles(16) - quarter_mesh_saving(16),
            coarse as u64 / 3
        );
    }

    /// For every set of edges and every mesh, the skirt commands draw exactly those edges'
    /// skirt segments (each once) and no grid triangle.
    #[test]
    fn each_edge_set_draws_exactly_its_edges_skirts() {
        use aerie_terrain::mesh::skirt_edge_indices;
        for side in [5u32, 9, 17] {
            let (buffer, meshes) = TileMeshes::indices(side);
            for (k, stride) in [(0usize, 1u32), (1, 2), (2, 4)] {
                for set in 0..EDGE_SETS {
                    let mut sizes = [0u32; INSTANCE_KEYS];
                    sizes[k * RESOLUTIONS * EDGE_SETS + set] = 1;
                    let (draws, _) = indirect_draws(&sizes, meshes);
                    let first = [meshes.whole.0, meshes.coarse.0, meshes.sixteenth.0][k];
                    let skirts: Vec<&[u32]> = draws
                        .iter()
                        .filter(|d| d.first_index != first)
                        .map(|d| {
                            let at = d.first_index as usize;
                            &buffer[at..at + d.index_count as usize]
                        })
                        .collect();
                    let triangles = |v: &[u32]| -> Vec<[u32; 3]> {
                        v.chunks(3).map(|c| c.try_into().unwrap()).collect()
                    };
                    let mut drawn = triangles(&skirts.concat());
                    let mut want = triangles(
                        &(0..4)
                            .filter(|e| set & (1 << e) != 0)
                            .flat_map(|e| skirt_edge_indices(side, stride, e))
                            .collect::<Vec<_>>(),
                    );
                    drawn.sort();
                    want.sort();
                    assert_eq!(drawn, want, "side {side}, stride {stride}, set {set:04b}");
                    let opposite = set == 0b0101 || set == 0b1010;
                    let runs = if set == 0 { 0 } else { 1 + opposite as usize };
                    assert_eq!(draws.len(), 1 + runs, "set {set:04b}");
                }
            }
        }
    }

    /// The skirt rule on a small frame: two tiles side by side at one level share an edge
    /// without skirts; a finer node north of one keeps its skirts against the coarser tile
    /// and the grid's first samples, and goes without them against the holes east and north
    /// of it (nothing drawn there: culled); a quadrant drawn at its parent's resolution goes
    /// without one against the tile of that resolution south of it and the holes around it; a
    /// tile reaching past the grid's last sample keeps the skirts on the grid's first and
    /// last samples, one ending on the last the skirt there; CDLOD's rule draws none, and the
    /// default fewer triangles than skirts everywhere.
    #[test]
    fn skirts_go_where_resolutions_differ() {
        use aerie_terrain::select::cdlod_morph::Morph;
        let tile = |l: u32, x: u32, y: u32, morph: Morph| {
            (
                DrawItem {
                    morph,
                    ..DrawItem::whole(l, x, y, 1.0, 0.5)
                },
                0,
            )
        };
        let list = [
            tile(2, 0, 0, Morph::NONE),
            tile(2, 1, 0, Morph::NONE),
            tile(1, 0, 2, Morph::NONE),
            tile(1, 2, 2, Morph::QUADRANT),
        ];
        // The second tile spans samples 64..=128: past the last one.
        let f = frame(SkirtRule::WhereResolutionsDiffer, [100, 1000], &[]);
        let (s, e, n, w) = (1u8, 2u8, 4u8, 8u8);
        assert_eq!(
            skirts_of(&f, &list, &mut SkirtMemo::default()).edges,
            [s | n | w, s | e, s | w, 0]
        );
        let inside = InstanceFrame {
            valid_samples: [1000, 1000],
            ..f
        };
        assert_eq!(
            skirts_of(&inside, &list, &mut SkirtMemo::default()).edges[1],
            s
        );
        let on_the_last = InstanceFrame {
            valid_samples: [129, 1000],
            ..f
        };
        assert_eq!(
            skirts_of(&on_the_last, &list, &mut SkirtMemo::default()).edges[1],
            s | e
        );
        for (rule, want) in [
            (SkirtRule::None, [0; 4]),
            (SkirtRule::Everywhere, [ALL_EDGES; 4]),
        ] {
            let g = InstanceFrame { skirts: rule, ..f };
            assert_eq!(skirts_of(&g, &list, &mut SkirtMemo::default()).edges, want);
        }
        let (_, meshes) = TileMeshes::indices(17);
        let tris = |rule| {
            let g = InstanceFrame { skirts: rule, ..f };
            let (_, _, sizes) = build_instances(&g, &list, &mut InstanceCaches::default());
            indirect_draws(&sizes, meshes).1
        };
        // A 16-quad edge's skirt is 24 triangles, an 8-quad one's 12 (three per two segments).
        let grids = 3 * 512 + 128;
        assert_eq!(tris(SkirtRule::None), grids);
        assert_eq!(tris(SkirtRule::Everywhere), grids + 3 * 96 + 48);
        // Bare: the first tile's east edge and the second's west and north (72 triangles),
        // the finer tile's east and north (48) and the quadrant's four (48).
        assert_eq!(
            tris(SkirtRule::WhereResolutionsDiffer),
            grids + 3 * 96 + 48 - 168
        );
    }

    #[test]
    fn a_quadrant_counts_as_the_parents_quarter_mesh() {
        use aerie_terrain::mesh::skirted_tile_indices;
        for q in [8u32, 16, 32] {
            let full = skirted_tile_indices(q + 1).len() as u64 / 3;
            let quarter = skirted_tile_indices(q / 2 + 1).len() as u64 / 3;
            assert_eq!(skirted_tile_triangles(q), full);
            assert_eq!(quarter_mesh_saving(q), full - quarter);
        }
    }
}
