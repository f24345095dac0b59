//! The frame plan's draw records (pure): where a node lies in its pool slot, each drawn node's
//! skirts and fills (`SkirtRule`, `select::node_skirts`), and one `TileInstance` per drawn node
//! (relative to the eye), grouped by refinement — whole nodes first, then quadrants drawn at
//! their parent's resolution, then sixteenths drawn at their grandparent's — and within a
//! group sorted by the edges that need a skirt, then by those the node fills: the order
//! `terrain_draws::indirect_draws` issues its commands in, one per group's grids and one per
//! set of skirted or filled edges.

use glam::DVec3;

use aerie_terrain::geodesy::GeoGrid;
use aerie_terrain::select::{DrawItem, LodMode, NodeSkirts, SkirtMemo, ALL_EDGES};

use crate::render::geo_instances::{GeoEye, GeoNodeCache};
use crate::render::gpu::{DrawIndexedIndirect, GeoPolynomial, TileInstance};
use crate::render::jobs::{FIXED_SLACK_BYTES, OVERLAY_SLACK_BYTES};
use crate::render::pool_atlas::PoolSlots;
use crate::render::stats::RESOLUTIONS;
use crate::render::terrain_draws::{edge_combo, terrain_draws_bound, EDGE_COMBOS, INSTANCE_KEYS};

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

/// A draw item's group: its refinement, offset by [`RESOLUTIONS`] for each level it is drawn
/// coarser than its own (a quadrant, a sixteenth).
fn group_of(item: &DrawItem) -> usize {
    item.refinement as usize + item.morph.levels_up() as usize * RESOLUTIONS
}

/// Each drawn node's skirt: how far it reaches, the edges that get one under `f.skirts`
/// (see [`SkirtRule`]) and those it fills instead, in the list's order; one walk over the
/// nodes gives all three.
fn skirts_of(f: &InstanceFrame, draw_list: &[(DrawItem, u32)], memo: &mut SkirtMemo) -> NodeSkirts {
    let n = draw_list.len();
    if f.skirts == SkirtRule::None {
        return NodeSkirts {
            reach: vec![0.0; n],
            edges: vec![0; n],
            fills: vec![0; n],
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
    // Fills need an even number of segments on every edge at every drawn stride (1, 2, 4).
    let fill = !all_edges && q.is_multiple_of(8);
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
    let mut skirts = memo.skirts(&nodes, &resolution, &folds, fill).clone();
    for ((e, filled), last) in skirts.edges.iter_mut().zip(&mut skirts.fills).zip(on_last) {
        *e |= if all_edges { ALL_EDGES } else { last };
        *filled &= !*e;
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
    let NodeSkirts {
        reach,
        edges,
        fills,
    } = skirts_of(f, draw_list, &mut caches.skirts);
    let geo_cache = &mut caches.geo;
    let key_of =
        |k: usize| group_of(&draw_list[k].0) * EDGE_COMBOS + edge_combo(edges[k], fills[k]);
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
        + (std::mem::size_of::<DrawIndexedIndirect>() * terrain_draws_bound(selected_nodes)) as u64
        + (selected_nodes * (std::mem::size_of::<TileInstance>() + polynomial)) as u64
        + overlay
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::terrain_draws::{indirect_draws, TileMeshes, DRAW_GROUPS};

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
        let per_group: Vec<u32> = sizes.chunks(EDGE_COMBOS).map(|c| c.iter().sum()).collect();
        assert_eq!(per_group, want);
        // Skirts everywhere: every node in its group's set of all four edges.
        for (key, &n) in sizes.iter().enumerate() {
            let all = edge_combo(ALL_EDGES, 0);
            assert!(n == 0 || key % EDGE_COMBOS == all, "key {key}");
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

    /// The skirt rule on a small frame: two tiles side by side at one level share an edge
    /// without skirts; a finer node north of one fills the crack against the coarser tile
    /// (one resolution apart: neither keeps a skirt there; without fills both do), keeps its
    /// skirt on the grid's first samples, and goes without them against the holes east and
    /// north of it (nothing drawn there: culled); a quadrant drawn at its parent's resolution goes
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
        let skirts = skirts_of(&f, &list, &mut SkirtMemo::default());
        assert_eq!(skirts.edges, [s | w, s | e, w, 0]);
        assert_eq!(skirts.fills, [0, 0, s, 0]);
        // Tiles of 12 quads (odd segments at stride 4): no fills, both sides skirted.
        let twelve = InstanceFrame {
            tile_quads: 12,
            valid_samples: [75, 1000],
            ..f
        };
        let skirts = skirts_of(&twelve, &list, &mut SkirtMemo::default());
        assert_eq!(skirts.edges, [s | n | w, s | e, s | w, 0]);
        assert_eq!(skirts.fills, [0; 4]);
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
            let skirts = skirts_of(&g, &list, &mut SkirtMemo::default());
            assert_eq!(skirts.edges, want);
            assert_eq!(skirts.fills, [0; 4]);
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
        // Bare: the first tile's east and north edges and the second's west and north (96
        // triangles), the finer tile's east and north (48), the quadrant's four (48); the
        // finer tile's south filled instead (8 triangles for its 24).
        assert_eq!(
            tris(SkirtRule::WhereResolutionsDiffer),
            grids + 3 * 96 + 48 - 96 - 48 - 48 - 24 + 8
        );
    }
}
