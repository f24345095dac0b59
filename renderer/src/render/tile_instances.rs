//! The frame plan's draw records (pure): where a node lies in its pool slot, one
//! `TileInstance` per drawn node (relative to the eye, grouped by refinement, whole nodes
//! first, then quadrants drawn at their parent's resolution, then sixteenths drawn at their
//! grandparent's) and one indexed indirect command per group: whole nodes with the tile's
//! mesh, quadrants with its coarse mesh (the parent's quarter mesh:
//! `mesh::skirted_coarse_tile_indices`), sixteenths with every fourth vertex
//! (`mesh::skirted_sixteenth_tile_indices`).

use bytemuck::Zeroable;
use glam::DVec3;

use aerie_terrain::geodesy::GeoGrid;
use aerie_terrain::select::{neighbour_eps, DrawItem};

use crate::render::geo_instances::{GeoEye, GeoNodeCache};
use crate::render::gpu::{DrawIndexedIndirect, TileInstance};
use crate::render::pool_atlas::PoolSlots;
use crate::render::stats::RESOLUTIONS;

/// Instance groups, each one indirect command: per refinement the whole nodes, then per
/// refinement the quadrants drawn at their parent's resolution, then per refinement the
/// sixteenths drawn at their grandparent's.
pub const DRAW_GROUPS: usize = 3 * RESOLUTIONS;

/// Where a tile's three meshes lie in the shared index buffer, (first index, index count)
/// each: the whole tile, its coarse mesh for quadrants drawn at their parent's resolution, and
/// its sixteenth mesh for sixteenths drawn at their grandparent's (empty when the tile's
/// quads a side are not a multiple of 4). One vertex layout serves all three
/// (`mesh::skirted_vertex_count`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TileMeshes {
    pub whole: (u32, u32),
    pub coarse: (u32, u32),
    pub sixteenth: (u32, u32),
    /// Each mesh's grid indices (whole, coarse, sixteenth): its first indices, before its
    /// skirt's.
    pub grid: [u32; 3],
}

impl TileMeshes {
    /// The index buffer of a tile of `side` vertices a side — the whole mesh, the coarse one,
    /// the sixteenth one — and where each lies in it.
    pub fn indices(side: u32) -> (Vec<u32>, TileMeshes) {
        use aerie_terrain::mesh::{
            skirted_coarse_tile_indices, skirted_sixteenth_tile_indices, skirted_tile_indices,
        };
        let mut v = skirted_tile_indices(side);
        let whole = (0, v.len() as u32);
        v.extend(skirted_coarse_tile_indices(side));
        let coarse = (whole.1, v.len() as u32 - whole.1);
        let sixteenths = side >= 5 && (side - 1).is_multiple_of(4);
        if sixteenths {
            v.extend(skirted_sixteenth_tile_indices(side));
        }
        let end = coarse.0 + coarse.1;
        let sixteenth = (end, v.len() as u32 - end);
        // A strided mesh lists its grid's 6 indices a cell, then its skirt's.
        let cells = |stride: u32| ((side - 1) / stride).pow(2) * 6;
        let grid = [cells(1), cells(2), if sixteenths { cells(4) } else { 0 }];
        (
            v,
            TileMeshes {
                whole,
                coarse,
                sixteenth,
                grid,
            },
        )
    }

    /// The same meshes without their skirts (each mesh's grid indices alone): CDLOD draws so,
    /// as Strugar's paper does — its morph closes the seams between levels.
    pub fn without_skirts(self) -> Self {
        let [w, c, s] = self.grid;
        Self {
            whole: (self.whole.0, w),
            coarse: (self.coarse.0, c),
            sixteenth: (self.sixteenth.0, s),
            ..self
        }
    }

    /// Group `g`'s mesh ([`DRAW_GROUPS`]).
    fn of_group(&self, g: usize) -> (u32, u32) {
        match g / RESOLUTIONS {
            0 => self.whole,
            1 => self.coarse,
            _ => self.sixteenth,
        }
    }
}

/// A draw item's group: its refinement, offset by [`RESOLUTIONS`] for each level it is drawn
/// coarser than its own (a quadrant, a sixteenth).
fn group_of(item: &DrawItem) -> usize {
    item.refinement as usize + item.morph.levels_up() as usize * RESOLUTIONS
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
/// 1.., then the quadrants likewise, then the sixteenths): node origin relative to the eye (f64 → f32), sample
/// origin, vertex step, level, pool slot and the node's place in it, skirt depth. Returns the
/// concatenated records and each group's size.
pub fn build_instances(
    f: &InstanceFrame,
    draw_list: &[(DrawItem, u32)],
    geo_cache: &mut GeoNodeCache,
) -> (Vec<TileInstance>, [u32; DRAW_GROUPS]) {
    let q = f.tile_quads;
    let eye = f.eye;
    let nodes: Vec<(u32, u32, u32, f32)> = draw_list
        .iter()
        .map(|(i, _)| (i.node_level, i.node_tx, i.node_ty, i.eps_m))
        .collect();
    let reach = neighbour_eps(&nodes);
    let geo = f.earth.map(|g| {
        geo_cache.begin(g);
        GeoEye::new(g, eye)
    });
    // The records are written once, in their final place: a counting sort of the draw list by
    // refinement (stable, so each group keeps the list's order) into one vector of the exact
    // size (records are ~450 bytes: growing and concatenating per-group vectors copied each
    // several times).
    let mut sizes = [0u32; DRAW_GROUPS];
    for (item, _) in draw_list {
        sizes[group_of(item)] += 1;
    }
    let mut next = [0usize; DRAW_GROUPS];
    for g in 1..DRAW_GROUPS {
        next[g] = next[g - 1] + sizes[g - 1] as usize;
    }
    let mut order = vec![0u32; draw_list.len()];
    for (k, (item, _)) in draw_list.iter().enumerate() {
        let at = &mut next[group_of(item)];
        order[*at] = k as u32;
        *at += 1;
    }
    // Zeroed records filled in place: the ~450-byte records are not built aside and copied,
    // and the fields a node does not use (the ellipsoid's on the plane, a UTM node's
    // polynomials on a geographic grid) stay zero without being written.
    let mut instances = vec![TileInstance::zeroed(); draw_list.len()];
    for (t, &k) in instances.iter_mut().zip(&order) {
        let (item, slot) = draw_list[k as usize];
        let reach_m = reach[k as usize];
        let node = (q as i64) << item.node_level;
        let origin = [item.node_tx as i64 * node, item.node_ty as i64 * node];
        let (slot_x, slot_y, slot_stride) = slot_placement(&item, q);
        t.origin_rel = [
            (origin[0] as f64 * f.spacing[0] - eye.x) as f32,
            (origin[1] as f64 * f.spacing[1] - eye.y) as f32,
        ];
        t.origin_sample = [origin[0] as i32, origin[1] as i32];
        t.step = 1 << item.node_level;
        t.level = item.level;
        t.refinement = item.refinement;
        // A refined node names its slot's layer and its south-west vertex's texel in that
        // layer (the slot's cell + the node's place in the slot): `terrain.vert` finds the cell
        // again from it (`PoolAtlas::read_texel`).
        let (slot_x, slot_y) = if item.refinement > 0 {
            let place = f.pools[item.refinement as usize - 1].atlas.place(slot);
            t.slot = place.layer;
            (slot_x + place.x, slot_y + place.y)
        } else {
            t.slot = slot;
            (slot_x, slot_y)
        };
        // ε + max(ε, neighbours' ε) at the default factor 2 (see neighbour_eps).
        t.skirt_m = 0.5 * f.skirt_factor * (item.eps_m + reach_m) + f.skirt_min_m;
        (t.slot_x, t.slot_y, t.slot_stride) = (slot_x, slot_y, slot_stride);
        t.morph = item.morph.to_gpu();
        if let Some(e) = &geo {
            let (g, rel) = e.node_fields_in(geo_cache, origin, 1 << item.node_level, q);
            t.geo_origin = [rel[0], rel[1], rel[2], g.geo_origin[3]];
            t.geo_axis_r = g.geo_axis_r;
            t.geo_axis_t = g.geo_axis_t;
            t.geo_axis_z = g.geo_axis_z;
            t.geo_radius = g.geo_radius;
            if e.projected() {
                t.geo_s = g.geo_s;
                t.geo_n = g.geo_n;
            }
        }
    }
    (instances, sizes)
}

/// Triangles of a skirted tile of `q` quads a side (grid 2q², skirt 2 per perimeter edge).
pub fn skirted_tile_triangles(q: u32) -> u64 {
    let q = q as u64;
    2 * q * q + 8 * q
}

/// What one quadrant drawn at its parent's resolution draws fewer than a whole tile of `q`
/// quads: it is drawn with the tile's coarse mesh, the parent's quarter mesh of q/2 quads a
/// side.
pub fn quarter_mesh_saving(q: u32) -> u64 {
    skirted_tile_triangles(q) - skirted_tile_triangles(q / 2)
}

/// One indexed indirect command per group ([`DRAW_GROUPS`]), each starting where the previous
/// ended, and the triangles they draw: whole nodes with the tile's mesh, quadrants with its
/// coarse one, sixteenths with the stride-4 one. A mesh without indices draws nothing.
pub fn indirect_draws(
    group_sizes: &[u32; DRAW_GROUPS],
    meshes: TileMeshes,
) -> ([DrawIndexedIndirect; DRAW_GROUPS], u64) {
    let mut draws = [DrawIndexedIndirect::default(); DRAW_GROUPS];
    let mut first_instance = 0u32;
    let mut triangles = 0u64;
    for (g, (draw, &n)) in draws.iter_mut().zip(group_sizes).enumerate() {
        let (first_index, index_count) = meshes.of_group(g);
        *draw = DrawIndexedIndirect {
            index_count,
            instance_count: if index_count == 0 { 0 } else { n },
            first_index,
            vertex_offset: 0,
            first_instance,
        };
        first_instance += n;
        triangles += n as u64 * (index_count as u64 / 3);
    }
    (draws, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let f = InstanceFrame {
            tile_quads: 16,
            spacing: [10.0, 10.0],
            earth: None,
            eye: DVec3::ZERO,
            skirt_factor: 2.0,
            skirt_min_m: 0.0,
            pools: &pools,
        };
        let (instances, sizes) = build_instances(&f, &list, &mut GeoNodeCache::default());
        let mut want = [0u32; DRAW_GROUPS];
        want[..3].copy_from_slice(&[2, 1, 2]);
        want[RESOLUTIONS] = 2;
        want[RESOLUTIONS + 2] = 1;
        want[2 * RESOLUTIONS] = 1;
        assert_eq!(sizes, want);
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
        let (placed, _) = build_instances(&g, &list, &mut GeoNodeCache::default());
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

    /// Whole nodes draw the tile's range, quadrants the coarse one, sixteenths the stride-4
    /// one, each group's instances after the previous group's; the triangles are the ranges'
    /// per instance.
    #[test]
    fn quadrant_groups_draw_the_coarse_range() {
        use aerie_terrain::mesh::{
            skirted_coarse_tile_indices, skirted_sixteenth_tile_indices, skirted_tile_indices,
        };
        let (buffer, meshes) = TileMeshes::indices(17);
        let whole = skirted_tile_indices(17).len() as u32;
        let coarse = skirted_coarse_tile_indices(17).len() as u32;
        let sixteenth = skirted_sixteenth_tile_indices(17).len() as u32;
        assert_eq!(
            meshes,
            TileMeshes {
                whole: (0, whole),
                coarse: (whole, coarse),
                sixteenth: (whole + coarse, sixteenth),
                grid: [16 * 16 * 6, 8 * 8 * 6, 4 * 4 * 6],
            }
        );
        assert_eq!(buffer.len() as u32, whole + coarse + sixteenth);
        let mut sizes = [0u32; DRAW_GROUPS];
        sizes[0] = 3;
        sizes[1] = 1;
        sizes[RESOLUTIONS] = 2;
        sizes[2 * RESOLUTIONS] = 5;
        let (draws, tris) = indirect_draws(&sizes, meshes);
        assert_eq!((draws[0].first_index, draws[0].index_count), (0, whole));
        assert_eq!(draws[RESOLUTIONS].first_index, whole);
        assert_eq!(draws[RESOLUTIONS].index_count, coarse);
        assert_eq!(draws[RESOLUTIONS].first_instance, 4);
        assert_eq!(draws[RESOLUTIONS].instance_count, 2);
        let s = &draws[2 * RESOLUTIONS];
        assert_eq!((s.first_index, s.index_count), (whole + coarse, sixteenth));
        assert_eq!((s.first_instance, s.instance_count), (6, 5));
        assert_eq!(
            tris,
            4 * skirted_tile_triangles(16)
                + 2 * skirted_tile_triangles(8)
                + 5 * skirted_tile_triangles(4)
        );
        // Without skirts (CDLOD): each mesh's grid indices, which come first, 2q² triangles.
        let (bare, _) = indirect_draws(&sizes, meshes.without_skirts());
        for (b, d) in bare.iter().zip(&draws) {
            assert_eq!(
                (b.first_index, b.first_instance),
                (d.first_index, d.first_instance)
            );
        }
        let grid_of = |r: std::ops::Range<usize>| {
            let (a, b) = (r.start, r.end);
            let tri = &buffer[a..b];
            // Every grid triangle's vertices lie on the tile's grid (index < 17²).
            tri.iter().all(|&i| i < 17 * 17)
        };
        let m = meshes.without_skirts();
        for (first, count) in [m.whole, m.coarse, m.sixteenth] {
            assert!(grid_of(first as usize..(first + count) as usize));
            // … and the next index after them is a skirt's.
            assert!(buffer[(first + count) as usize..]
                .iter()
                .take(6)
                .any(|&i| i >= 17 * 17));
        }
        assert_eq!(bare[0].index_count / 3, 2 * 16 * 16);
        // A tile whose quads a side are not a multiple of 4 has no sixteenth mesh.
        assert_eq!(TileMeshes::indices(7).1.sixteenth.1, 0);
        assert_eq!(TileMeshes::indices(7).1.grid[2], 0);
        assert_eq!(
            skirted_tile_triangles(16) - quarter_mesh_saving(16),
            coarse as u64 / 3
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
