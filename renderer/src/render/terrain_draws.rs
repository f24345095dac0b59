//! The terrain draw's commands (pure): the shared index buffer's meshes (`TileMeshes`: the
//! whole tile, its coarse mesh for quadrants drawn at their parent's resolution, its sixteenth
//! mesh, each followed by its edges' skirts and fills), the instance records' sort keys — a
//! draw group, then the node's skirted and filled edges (`edge_combo`) — and the indexed
//! indirect commands of a frame's records (`indirect_draws`): per group one command for the
//! grids, per set of skirted edges one more (two for opposite edges) and per set of filled
//! edges within it one more. `tile_instances` sorts the records in this order.

use aerie_terrain::select::ALL_EDGES;

use crate::render::gpu::DrawIndexedIndirect;
use crate::render::stats::RESOLUTIONS;

/// Instance groups, each one indirect command: per refinement the whole nodes, then per
/// refinement the quadrants drawn at their parent's resolution, then per refinement the
/// sixteenths drawn at their grandparent's.
pub const DRAW_GROUPS: usize = 3 * RESOLUTIONS;

/// The sets of a node's edges that may need a skirt (`select::ALL_EDGES`' bits).
pub const EDGE_SETS: usize = 16;

/// A node's edges as (skirted, filled): two disjoint edge sets, 3⁴ pairs, numbered by the
/// skirted set, then the filled set ([`edge_combo`]).
pub const EDGE_COMBOS: usize = 81;

/// The pairs in [`edge_combo`]'s order, and where each skirted set's pairs start.
const COMBOS: ([(u8, u8); EDGE_COMBOS], [usize; EDGE_SETS + 1]) = {
    let mut list = [(0u8, 0u8); EDGE_COMBOS];
    let mut start = [0usize; EDGE_SETS + 1];
    let mut n = 0;
    let mut skirted = 0;
    while skirted < EDGE_SETS {
        start[skirted] = n;
        let mut filled = 0;
        while filled < EDGE_SETS {
            if skirted & filled == 0 {
                list[n] = (skirted as u8, filled as u8);
                n += 1;
            }
            filled += 1;
        }
        skirted += 1;
    }
    start[EDGE_SETS] = n;
    assert!(n == EDGE_COMBOS);
    (list, start)
};

/// Each pair's number, at skirted · 16 + filled (pairs that are not disjoint: none).
const COMBO_NUMBER: [u8; EDGE_SETS * EDGE_SETS] = {
    let mut number = [u8::MAX; EDGE_SETS * EDGE_SETS];
    let mut c = 0;
    while c < EDGE_COMBOS {
        let (skirted, filled) = COMBOS.0[c];
        number[skirted as usize * EDGE_SETS + filled as usize] = c as u8;
        c += 1;
    }
    number
};

/// The number of a node's (skirted, filled) edges among [`EDGE_COMBOS`]; the sets must be
/// disjoint.
pub fn edge_combo(skirted: u8, filled: u8) -> usize {
    let c = COMBO_NUMBER[(skirted as usize & 0xf) * EDGE_SETS + (filled as usize & 0xf)];
    assert!(
        c != u8::MAX,
        "edges {skirted:#06b} both skirted and filled: {filled:#06b}"
    );
    c as usize
}

/// The instance records' sort keys: a draw group's, then the node's (skirted, filled)
/// edges ([`edge_combo`]).
pub const INSTANCE_KEYS: usize = DRAW_GROUPS * EDGE_COMBOS;

/// Commands an edge set's runs take: none for no edge, two for opposite edges, else one.
const fn run_commands(set: usize) -> usize {
    match set {
        0 => 0,
        0b0101 | 0b1010 => 2,
        _ => 1,
    }
}

/// The most commands a frame's terrain draw issues: per group its grid, a command for each
/// of the 15 non-empty skirted sets, two for each of the 2 sets of opposite edges, and the
/// filled sets' commands over every (skirted, filled) pair.
pub const MAX_TERRAIN_DRAWS: usize = DRAW_GROUPS
    * (1 + 15 + 2 + {
        let mut fills = 0;
        let mut c = 0;
        while c < EDGE_COMBOS {
            fills += run_commands(COMBOS.0[c].1 as usize);
            c += 1;
        }
        fills
    });

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
/// the south and east skirts again ([`REPEATED_EDGES`]), then the four edges' fills
/// (`mesh::fill_edge_indices`) and the south and east fills again.
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
    /// Each mesh's indices of one edge's fill.
    pub fill: [u32; 3],
}

impl TileMeshes {
    /// The index buffer of a tile of `side` vertices a side — the whole mesh, the coarse one,
    /// the sixteenth one — and where each lies in it.
    pub fn indices(side: u32) -> (Vec<u32>, TileMeshes) {
        use aerie_terrain::mesh::{
            fill_edge_indices, skirt_edge_indices, skirted_coarse_tile_indices,
            skirted_sixteenth_tile_indices, skirted_tile_indices,
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
            for edge in 0..4 + REPEATED_EDGES {
                v.extend(fill_edge_indices(side, stride, edge % 4));
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
        let fill = |stride: u32| aerie_terrain::mesh::fill_edge_triangles(n / stride) * 3;
        let grid = [cells(1), cells(2), if sixteenths { cells(4) } else { 0 }];
        let edge = [skirt(1), skirt(2), if sixteenths { skirt(4) } else { 0 }];
        let fill = [fill(1), fill(2), if sixteenths { fill(4) } else { 0 }];
        (
            v,
            TileMeshes {
                whole,
                coarse,
                sixteenth,
                grid,
                edge,
                fill,
            },
        )
    }

    /// Group `g`'s mesh ([`DRAW_GROUPS`]): its first index, its grid's indices, one edge's
    /// skirt's, where its fills start and one edge's fill's.
    fn of_group(&self, g: usize) -> GroupMesh {
        let k = (g / RESOLUTIONS).min(2);
        let first = [self.whole.0, self.coarse.0, self.sixteenth.0][k];
        let (grid, edge) = (self.grid[k], self.edge[k]);
        GroupMesh {
            first,
            grid,
            edge,
            fills: first + grid + (4 + REPEATED_EDGES) * edge,
            fill: self.fill[k],
        }
    }
}

/// One draw group's mesh in the index buffer ([`TileMeshes::of_group`]).
struct GroupMesh {
    first: u32,
    grid: u32,
    edge: u32,
    fills: u32,
    fill: u32,
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

/// The most commands [`indirect_draws`] issues for `nodes` instances: per group its grid, and
/// per instance's key at most two runs of skirted edges and two of filled ones; never more
/// than [`MAX_TERRAIN_DRAWS`].
pub fn terrain_draws_bound(nodes: usize) -> usize {
    MAX_TERRAIN_DRAWS.min(DRAW_GROUPS + 4 * nodes)
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
/// edges' skirts (two for opposite edges) for the instances of that set, and within it per
/// set of filled edges one command drawing those edges' fills (two for opposite edges). Only
/// commands that draw something are listed; a mesh without indices draws nothing.
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
    let (combos, starts) = &COMBOS;
    for (g, sizes) in key_sizes.chunks_exact(EDGE_COMBOS).enumerate() {
        // Most groups and sets are empty: skip them before working out their runs.
        let in_group: u32 = sizes.iter().sum();
        if in_group == 0 {
            continue;
        }
        let m = meshes.of_group(g);
        push(m.first, m.grid, first_instance, in_group);
        for skirted in 0..EDGE_SETS {
            let of_set = starts[skirted]..starts[skirted + 1];
            let n: u32 = sizes[of_set.clone()].iter().sum();
            if n == 0 {
                continue;
            }
            let (runs, count) = edge_runs(skirted as u8);
            for &(from, len) in &runs[..count] {
                let at = m.first + m.grid + from * m.edge;
                push(at, len * m.edge, first_instance, n);
            }
            for c in of_set {
                let n = sizes[c];
                if n == 0 {
                    continue;
                }
                let (runs, count) = edge_runs(combos[c].1);
                for &(from, len) in &runs[..count] {
                    push(m.fills + from * m.fill, len * m.fill, first_instance, n);
                }
                first_instance += n;
            }
        }
    }
    debug_assert!(draws.len() <= terrain_draws_bound(key_sizes.iter().sum::<u32>() as usize));
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
        // Each edge's fill: one triangle per two segments (`mesh::fill_edge_indices`).
        let fill = [8 * 3, 4 * 3, 2 * 3];
        let after = |k: usize| REPEATED_EDGES * edge[k] + (4 + REPEATED_EDGES) * fill[k];
        assert_eq!(
            meshes,
            TileMeshes {
                whole: (0, whole),
                coarse: (whole + after(0), coarse),
                sixteenth: (whole + after(0) + coarse + after(1), sixteenth),
                grid: [16 * 16 * 6, 8 * 8 * 6, 4 * 4 * 6],
                edge,
                fill,
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
        let all = edge_combo(ALL_EDGES, 0);
        let mut sizes = [0u32; INSTANCE_KEYS];
        sizes[all] = 3;
        sizes[EDGE_COMBOS + all] = 1;
        sizes[RESOLUTIONS * EDGE_COMBOS + all] = 2;
        sizes[2 * RESOLUTIONS * EDGE_COMBOS + all] = 5;
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

    /// For every (skirted, filled) pair of edge sets and every mesh, the commands draw exactly
    /// those edges' skirt segments and fills (each once) and the grid, in one command per run
    /// of edges; the numbering is one-to-one over the disjoint pairs, and no frame's commands
    /// can outnumber [`MAX_TERRAIN_DRAWS`].
    #[test]
    fn each_edge_set_draws_exactly_its_edges_skirts_and_fills() {
        use aerie_terrain::mesh::{fill_edge_indices, skirt_edge_indices};
        let pairs: Vec<(u8, u8)> = (0..16u8)
            .flat_map(|s| (0..16u8).map(move |f| (s, f)))
            .filter(|&(s, f)| s & f == 0)
            .collect();
        let mut numbers: Vec<usize> = pairs.iter().map(|&(s, f)| edge_combo(s, f)).collect();
        numbers.sort();
        assert_eq!(numbers, (0..EDGE_COMBOS).collect::<Vec<_>>());
        for side in [5u32, 9, 17] {
            let (buffer, meshes) = TileMeshes::indices(side);
            let mut every = [0u32; INSTANCE_KEYS];
            for (k, stride) in [(0usize, 1u32), (1, 2), (2, 4)] {
                let first = [meshes.whole.0, meshes.coarse.0, meshes.sixteenth.0][k];
                for &(skirted, filled) in &pairs {
                    let mut sizes = [0u32; INSTANCE_KEYS];
                    let key = k * RESOLUTIONS * EDGE_COMBOS + edge_combo(skirted, filled);
                    sizes[key] = 1;
                    every[key] = 1;
                    let (draws, tris) = indirect_draws(&sizes, meshes);
                    let extra: Vec<&[u32]> = draws
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
                    let mut drawn = triangles(&extra.concat());
                    let edges = |set: u8, indices: fn(u32, u32, u32) -> Vec<u32>| {
                        (0..4)
                            .filter(|e| set & (1 << e) != 0)
                            .flat_map(|e| indices(side, stride, e))
                            .collect::<Vec<_>>()
                    };
                    let mut want = triangles(
                        &[
                            edges(skirted, skirt_edge_indices),
                            edges(filled, fill_edge_indices),
                        ]
                        .concat(),
                    );
                    drawn.sort();
                    want.sort();
                    let what = format!("side {side}, stride {stride}, {skirted:04b} {filled:04b}");
                    assert_eq!(drawn, want, "{what}");
                    let grid = (side - 1) / stride;
                    let grid = if k == 2 && (side - 1) % 4 != 0 {
                        0
                    } else {
                        grid * grid * 2
                    };
                    if grid > 0 {
                        assert_eq!(tris, grid as u64 + want.len() as u64, "{what}");
                        // A fill of one segment draws nothing (no coarse segment spans it).
                        let fills = meshes.fill[k] > 0;
                        let runs = run_commands(skirted as usize)
                            + fills as usize * run_commands(filled as usize);
                        assert_eq!(draws.len(), 1 + runs, "{what}");
                    }
                }
            }
            // Every pair of every group at once: within the bound.
            for g in 0..DRAW_GROUPS {
                for c in 0..EDGE_COMBOS {
                    every[g * EDGE_COMBOS + c] = 1;
                }
            }
            assert!(indirect_draws(&every, meshes).0.len() <= MAX_TERRAIN_DRAWS);
        }
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
