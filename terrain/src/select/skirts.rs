//! Each drawn node's seams: how far its skirts must reach (the roughest of its edge
//! neighbours), which of its edges are laid onto a coarser neighbour's (stitched) and which
//! need a skirt at all.

use crate::fast_hash::FastHash;

/// [`node_skirts`]' reach alone, every node drawn at its own level (the tests' entry).
#[cfg(test)]
pub(crate) fn neighbour_eps(nodes: &[(u32, u32, u32, f32)]) -> Vec<f32> {
    let levels: Vec<u32> = nodes.iter().map(|n| n.0).collect();
    node_skirts(nodes, &levels, &vec![SeamLimit::default(); nodes.len()]).reach
}

/// What a drawn node's own vertices allow at its edges ([`node_skirts`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SeamLimit {
    /// The largest stride (log2, in the node's vertex steps) it can stitch an edge at: its
    /// tile's quads a side, or 0 where it cannot stitch at all (stitching off, a projected
    /// grid's nodes, which meet only within their fit).
    pub stitch_max: u8,
    /// Its vertices past the grid's last sample fold onto the first vertex at or past it, by
    /// its own step: it never stitches, and against another such node of another level or
    /// resolution both edges keep a skirt (their folds differ).
    pub folds: bool,
}

/// The edges of a node in the perimeter walk's order (`mesh::perimeter_vertex`): bit e set
/// for edge e (0 south, 1 east, 2 north, 3 west).
pub const ALL_EDGES: u8 = 0b1111;

/// Bits per edge in [`NodeSkirts::stitch`].
pub const STITCH_BITS: u32 = 4;

/// Each drawn node's seams ([`node_skirts`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct NodeSkirts {
    /// Per node, the largest ε among itself and the nodes sharing an edge with it: what its
    /// skirt must reach ([`node_skirts`]).
    pub reach: Vec<f32>,
    /// Per node, the edges that need a skirt ([`ALL_EDGES`]' bits).
    pub edges: Vec<u8>,
    /// Per node, per edge e (bits `STITCH_BITS·e..`), s > 0 when the edge is stitched: its
    /// vertices between every 2^s-th (in the node's own vertex steps) are laid on the straight
    /// line between those, which is the edge of the coarser node across; 0 when not.
    pub stitch: Vec<u16>,
}

impl NodeSkirts {
    /// Edge `edge`'s stitch of node `i`: log2 of the stride, 0 when not stitched.
    pub fn stitch_of(&self, i: usize, edge: u32) -> u32 {
        (self.stitch[i] >> (STITCH_BITS * edge)) as u32 & ((1 << STITCH_BITS) - 1)
    }
}

/// For each drawn node (level, tx, ty, ε), the largest ε among itself and the nodes sharing
/// an edge with it — what its skirt must reach —, which of its edges are stitched to a
/// coarser neighbour and which need a skirt.
///
/// Reach: along an edge between nodes A and B both surfaces are within their ε of the true
/// one, so the edges differ by up to ε_A + ε_B, and the higher edge's skirt must cover that: a
/// skirt of ε + max(ε, neighbours' ε) closes every crack, including T-junctions against a much
/// rougher coarse neighbour, which 2ε alone does not. Each fine–coarse pair is found from the
/// finer node by walking up from the position across its edge to the first drawn node (a
/// same-level neighbour or a coarser ancestor) and updates both.
///
/// Seams: `resolution[i]` is the level whose grid node i is drawn at (its own level, one more
/// for a quadrant drawn at its parent's resolution, two for a sixteenth). Levels are
/// subsamplings (DESIGN.md "The terrain technique"), so two nodes drawn at the same resolution
/// put the same vertices along an edge they share: no crack opens there. Where they differ,
/// the node drawn finer may be *stitched* when the one node across its whole edge (found by
/// its walk: as large or larger) is drawn coarser, as far as `limits[i]` allows
/// ([`SeamLimit`]): its edge is drawn through the coarse node's vertices only (each vertex in
/// between moved onto the nearer of them, `terrain.vert`), so both draw the same line and
/// neither needs a skirt. Every other pair drawn at different resolutions keeps a skirt on
/// both edges — one whose stride is too coarse, and one whose finer-drawn node faces several
/// nodes (a coarser-level node drawn finer than the finer-level nodes across it) —, as does
/// a pair that both fold at the grid's end unless of one level and resolution (folding
/// alike). An edge with nothing drawn across it needs none: the neighbour was culled — its
/// box, which holds the strip between the two edges, is outside every view or hidden — or
/// holds no terrain; nor does one whose finer neighbours are all drawn at its resolution or
/// stitched to it. Edges on the grid's first sample keep theirs (the renderer keeps those on
/// its last).
///
/// Stitching changes the fine node's surface in the strip of one vertex step along the edge:
/// there it is drawn by triangles from its own vertices to the coarse node's, whose distance
/// from the true surface neither node's ε bounds (the image error measures it). Skirts keep
/// every node's surface its own, within its ε: the default rule stitches nothing.
///
/// The nodes are looked up in a dense grid per level over the box its nodes and their
/// ancestors span (a frame's nodes of one level lie in that level's clipmap patch), where the
/// ancestors of drawn nodes are marked split: a walk that meets a split node stops there — no
/// node above it is drawn. Nodes too scattered for the grids (more than
/// `GRID_CELLS_PER_NODE` cells a node) take a hash table; both give the same values (tests).
/// `nodes` must not overlap (no selection draws a place twice); where they do, every edge
/// keeps its skirt and none is stitched.
pub fn node_skirts(
    nodes: &[(u32, u32, u32, f32)],
    resolution: &[u32],
    limits: &[SeamLimit],
) -> NodeSkirts {
    assert_eq!(nodes.len(), resolution.len(), "a resolution per node");
    assert_eq!(nodes.len(), limits.len(), "a seam limit per node");
    match LevelGrids::of(nodes) {
        Some(grids) => walk_neighbours(
            nodes,
            resolution,
            limits,
            |l, x, y| grids.get(l, x, y),
            grids.overlap,
        ),
        None => node_skirts_hashed(nodes, resolution, limits),
    }
}

/// [`node_skirts`] through a hash table of the drawn nodes.
fn node_skirts_hashed(
    nodes: &[(u32, u32, u32, f32)],
    resolution: &[u32],
    limits: &[SeamLimit],
) -> NodeSkirts {
    let mut index: std::collections::HashMap<(u32, u32, u32), usize, FastHash> =
        std::collections::HashMap::with_capacity_and_hasher(nodes.len(), FastHash::default());
    for (i, &(l, x, y, _)) in nodes.iter().enumerate() {
        index.insert((l, x, y), i);
    }
    // The drawn nodes' ancestors, where drawn nodes lie below, marked as the grids mark them
    // (up to the first marked already; none once a drawn node lies inside another).
    let top = nodes.iter().map(|n| n.0).max().unwrap_or(0);
    let mut split: std::collections::HashSet<(u32, u32, u32), FastHash> =
        std::collections::HashSet::with_capacity_and_hasher(nodes.len(), FastHash::default());
    let mut overlap = false;
    'nodes: for &(l, x, y, _) in nodes {
        for k in 1..=top - l {
            let up = (l + k, x >> k, y >> k);
            if index.contains_key(&up) {
                overlap = true;
                break 'nodes;
            }
            if !split.insert(up) {
                continue 'nodes;
            }
        }
    }
    walk_neighbours(
        nodes,
        resolution,
        limits,
        |l, x, y| match index.get(&(l, x, y)) {
            Some(&j) => Cell::Drawn(j),
            None if !overlap && split.contains(&(l, x, y)) => Cell::Split,
            None => Cell::Empty,
        },
        overlap,
    )
}

/// What a lookup finds at (level, x, y).
#[derive(Clone, Copy, PartialEq, Debug)]
enum Cell {
    /// No drawn node, none below.
    Empty,
    /// Node `j` of the list.
    Drawn(usize),
    /// Not drawn, and drawn nodes lie below it (nothing above it is drawn, unless drawn
    /// nodes overlap).
    Split,
}

/// The walk itself, over any lookup (a `Split` cell ends the walk); `overlap`: drawn nodes
/// overlap (every edge keeps its skirt, none is stitched).
fn walk_neighbours(
    nodes: &[(u32, u32, u32, f32)],
    resolution: &[u32],
    limits: &[SeamLimit],
    find: impl Fn(u32, u32, u32) -> Cell,
    overlap: bool,
) -> NodeSkirts {
    let top = nodes.iter().map(|n| n.0).max().unwrap_or(0);
    let mut reach: Vec<f32> = nodes.iter().map(|n| n.3).collect();
    // Edges start bare and are given a skirt by the pairs that need one.
    let mut edges = vec![0u8; nodes.len()];
    let mut stitch = vec![0u16; nodes.len()];
    // The perimeter walk's edges: south, east, north, west.
    const ACROSS: [(i64, i64); 4] = [(0, -1), (1, 0), (0, 1), (-1, 0)];
    for (i, &(l, x, y, e)) in nodes.iter().enumerate() {
        for (edge, (dx, dy)) in ACROSS.into_iter().enumerate() {
            let (nx, ny) = (x as i64 + dx, y as i64 + dy);
            if nx < 0 || ny < 0 {
                // The grid's first sample.
                edges[i] |= 1 << edge;
                continue;
            }
            for k in 0..=(top - l) {
                match find(l + k, (nx >> k) as u32, (ny >> k) as u32) {
                    Cell::Empty => continue,
                    Cell::Split => break,
                    Cell::Drawn(j) => {
                        if j != i {
                            reach[i] = reach[i].max(nodes[j].3);
                            reach[j] = reach[j].max(e);
                            // Node j covers the whole strip across this edge (it is the
                            // neighbour or its ancestor): its edge there is straight between
                            // its vertices, every 2^resolution[j] samples.
                            let (ri, rj) = (resolution[i], resolution[j]);
                            let opposite = 1 << ((edge + 2) % 4);
                            let (li, lj) = (limits[i], limits[j]);
                            if li.folds && lj.folds && (ri != rj || nodes[j].0 != l) {
                                // Folded each by its own step.
                                edges[i] |= 1 << edge;
                                edges[j] |= opposite;
                            } else if rj > ri && !li.folds && rj - l <= li.stitch_max as u32 {
                                stitch[i] |= ((rj - l) as u16) << (STITCH_BITS as usize * edge);
                            } else if rj > ri || (rj < ri && nodes[j].0 > l) {
                                // Too coarse a stride (or a folding node), or j drawn finer
                                // but its edge facing several nodes (it cannot stitch to
                                // this one alone).
                                edges[i] |= 1 << edge;
                                edges[j] |= opposite;
                            }
                            // rj < ri at the same level: j's own walk finds this node and
                            // stitches to it or gives both edges a skirt.
                        }
                        break;
                    }
                }
            }
        }
    }
    if overlap {
        edges.fill(ALL_EDGES);
        stitch.fill(0);
    }
    NodeSkirts {
        reach,
        edges,
        stitch,
    }
}

/// Grid cells allowed per node before [`node_skirts`] takes the hash table instead (a
/// frame's nodes fill their levels' boxes far more densely).
const GRID_CELLS_PER_NODE: u64 = 64;

/// One level's grid: cells over `[x0, x0 + w) × [y0, y0 + h)`.
struct LevelGrid {
    x0: u32,
    y0: u32,
    w: u32,
    h: u32,
    cells: Vec<u32>,
}

/// Cell values: a node's index, or one of these.
const EMPTY: u32 = u32::MAX;
const SPLIT: u32 = u32::MAX - 1;

struct LevelGrids {
    levels: Vec<LevelGrid>,
    /// A drawn node lies inside another: walks go on through split cells.
    overlap: bool,
}

impl LevelGrids {
    /// The grids of `nodes`, or `None` when they would take more than
    /// [`GRID_CELLS_PER_NODE`] cells a node (or the list is too long for u32 indices).
    fn of(nodes: &[(u32, u32, u32, f32)]) -> Option<Self> {
        if nodes.is_empty() || nodes.len() >= SPLIT as usize {
            return None;
        }
        let top = nodes.iter().map(|n| n.0).max()? as usize;
        // Each level's box: its drawn nodes' and the finer level's box halved (the ancestors).
        let mut boxes: Vec<Option<[u32; 4]>> = vec![None; top + 1];
        for &(l, x, y, _) in nodes {
            let b = &mut boxes[l as usize];
            *b = Some(match *b {
                None => [x, y, x, y],
                Some([x0, y0, x1, y1]) => [x0.min(x), y0.min(y), x1.max(x), y1.max(y)],
            });
        }
        for l in 1..=top {
            if let Some([x0, y0, x1, y1]) = boxes[l - 1] {
                let half = [x0 >> 1, y0 >> 1, x1 >> 1, y1 >> 1];
                boxes[l] = Some(match boxes[l] {
                    None => half,
                    Some([a0, b0, a1, b1]) => [
                        a0.min(half[0]),
                        b0.min(half[1]),
                        a1.max(half[2]),
                        b1.max(half[3]),
                    ],
                });
            }
        }
        let area = |b: &Option<[u32; 4]>| {
            b.map_or(0, |[x0, y0, x1, y1]| {
                ((x1 - x0) as u64 + 1).saturating_mul((y1 - y0) as u64 + 1)
            })
        };
        let cells: u64 = boxes.iter().map(area).fold(0, u64::saturating_add);
        if cells > GRID_CELLS_PER_NODE.saturating_mul(nodes.len() as u64) {
            return None;
        }
        let mut levels: Vec<LevelGrid> = boxes
            .iter()
            .map(|b| match *b {
                Some([x0, y0, x1, y1]) => LevelGrid {
                    x0,
                    y0,
                    w: x1 - x0 + 1,
                    h: y1 - y0 + 1,
                    cells: vec![EMPTY; area(b) as usize],
                },
                None => LevelGrid {
                    x0: 0,
                    y0: 0,
                    w: 0,
                    h: 0,
                    cells: Vec::new(),
                },
            })
            .collect();
        // Drawn nodes (a repeated node: the last one, as the hash table keeps it).
        for (i, &(l, x, y, _)) in nodes.iter().enumerate() {
            let g = &mut levels[l as usize];
            let at = g.at(x, y).expect("inside its level's box");
            g.cells[at] = i as u32;
        }
        // Their ancestors marked split, up to the first one marked already.
        let mut overlap = false;
        'nodes: for &(l, x, y, _) in nodes {
            for m in l + 1..=top as u32 {
                let k = m - l;
                let g = &mut levels[m as usize];
                let at = g.at(x >> k, y >> k).expect("inside its level's box");
                match g.cells[at] {
                    EMPTY => g.cells[at] = SPLIT,
                    SPLIT => continue 'nodes,
                    _ => {
                        overlap = true;
                        break 'nodes;
                    }
                }
            }
        }
        Some(Self { levels, overlap })
    }

    fn get(&self, level: u32, x: u32, y: u32) -> Cell {
        let Some(g) = self.levels.get(level as usize) else {
            return Cell::Empty;
        };
        match g.at(x, y).map(|at| g.cells[at]) {
            None | Some(EMPTY) => Cell::Empty,
            Some(SPLIT) if self.overlap => Cell::Empty,
            Some(SPLIT) => Cell::Split,
            Some(j) => Cell::Drawn(j as usize),
        }
    }
}

impl LevelGrid {
    #[inline]
    fn at(&self, x: u32, y: u32) -> Option<usize> {
        let (dx, dy) = (x.wrapping_sub(self.x0), y.wrapping_sub(self.y0));
        (dx < self.w && dy < self.h).then(|| dy as usize * self.w as usize + dx as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn xorshift(seed: &mut u64) -> u64 {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 7;
        *seed ^= *seed << 17;
        *seed
    }

    /// A random quadtree cover of `top` levels at (x, y) (level-`top` coordinates), with
    /// holes when `holes`.
    fn cover(seed: &mut u64, top: u32, x: u32, y: u32, holes: bool) -> Vec<(u32, u32, u32, f32)> {
        let mut nodes = Vec::new();
        let mut stack = vec![(top, x, y)];
        while let Some((l, x, y)) = stack.pop() {
            if l > 0 && !xorshift(seed).is_multiple_of(3) {
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    stack.push((l - 1, 2 * x + dx, 2 * y + dy));
                }
            } else if !holes || !xorshift(seed).is_multiple_of(5) {
                nodes.push((l, x, y, (xorshift(seed) % 1000) as f32 / 10.0));
            }
        }
        nodes
    }

    /// The grids give what the hash table and the full walk give, on covers with and without
    /// holes, several covers side by side, overlapping and repeated nodes (which take the
    /// full walk through split cells), and on covers whose split cells end walks early.
    #[test]
    fn the_grids_walk_as_the_hash_table_does() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut stopped_early = 0;
        for case in 0..200u32 {
            let top = 1 + case % 6;
            let base = (1u32 << (20 + case % 5)) + case;
            let mut nodes = cover(&mut seed, top, base, base + 3, case % 2 == 1);
            if case % 3 == 0 {
                nodes.extend(cover(&mut seed, top, base + 1, base + 3, case % 4 == 1));
            }
            if case % 5 == 0 && nodes.len() > 2 {
                // An overlap: a coarser node over one of the drawn ones.
                let (l, x, y, _) = nodes[nodes.len() / 2];
                if l < top {
                    nodes.push((l + 1, x / 2, y / 2, 55.5));
                }
            }
            if case % 7 == 0 {
                let again = nodes[0];
                nodes.push((again.0, again.1, again.2, again.3 + 1.0));
            }
            if nodes.is_empty() {
                continue; // every part culled
            }
            let grids = LevelGrids::of(&nodes).expect("a cover fills its boxes");
            let resolution: Vec<u32> = nodes.iter().map(|n| n.0 + (n.1 + n.2) % 2).collect();
            let limits: Vec<SeamLimit> = nodes
                .iter()
                .map(|n| SeamLimit {
                    stitch_max: ((n.1 ^ n.2) % 4) as u8,
                    folds: (n.1 + 2 * n.2) % 7 == 0,
                })
                .collect();
            let want = node_skirts_hashed(&nodes, &resolution, &limits);
            assert_eq!(
                node_skirts(&nodes, &resolution, &limits),
                want,
                "case {case}: {nodes:?}"
            );
            if !grids.overlap {
                stopped_early += grids
                    .levels
                    .iter()
                    .flat_map(|g| &g.cells)
                    .filter(|&&c| c == SPLIT)
                    .count();
            }
        }
        assert!(stopped_early > 0, "no split cell in any case");
    }

    /// Against a brute force over every pair of nodes sharing an edge along a positive length:
    /// an edge is stitched exactly when the one node across all of it (as large or larger) is
    /// drawn coarser within the node's stride limit, at that resolution; it has a skirt
    /// exactly when it lies on the grid's first sample, or some node across it is drawn at
    /// another resolution and neither side of that pair can stitch (the finer-drawn side faces
    /// several nodes, or its stride limit is too small). Covers with holes, every resolution
    /// offset, every stride limit.
    #[test]
    fn an_edge_is_stitched_or_skirted_only_against_another_resolution() {
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let (mut bare, mut kept, mut stitched) = (0, 0, 0);
        for case in 0..160u32 {
            let top = 1 + case % 5;
            // Some covers on the grid's first sample (x = 0).
            let nodes = cover(
                &mut seed,
                top,
                (3 + case) * (case % 4 != 0) as u32,
                5,
                case % 2 == 1,
            );
            if nodes.is_empty() {
                continue;
            }
            // Drawn at its own level, or (a quadrant, a sixteenth) one or two above.
            let resolution: Vec<u32> = nodes
                .iter()
                .map(|n| n.0 + (xorshift(&mut seed) % 3) as u32 * (case % 3 != 0) as u32)
                .collect();
            let limits: Vec<SeamLimit> = nodes
                .iter()
                .map(|_| SeamLimit {
                    stitch_max: (xorshift(&mut seed) % 5) as u8 * (case % 5 != 0) as u8,
                    folds: xorshift(&mut seed).is_multiple_of(4),
                })
                .collect();
            let skirts = node_skirts(&nodes, &resolution, &limits);
            // Footprints in level-0 cells: [x0, x1) × [y0, y1).
            let fp =
                |&(l, x, y, _): &(u32, u32, u32, f32)| [x << l, (x + 1) << l, y << l, (y + 1) << l];
            // The nodes across edge `edge` of node `i` along a positive length.
            let across = |i: usize, edge: u32| -> Vec<usize> {
                let [x0, x1, y0, y1] = fp(&nodes[i]);
                (0..nodes.len())
                    .filter(|&j| {
                        let [a0, a1, b0, b1] = fp(&nodes[j]);
                        let along_x = a0 < x1 && x0 < a1;
                        let along_y = b0 < y1 && y0 < b1;
                        match edge {
                            0 => b1 == y0 && along_x,
                            1 => a0 == x1 && along_y,
                            2 => b0 == y1 && along_x,
                            _ => a1 == x0 && along_y,
                        }
                    })
                    .collect()
            };
            // Node i's stitch on `edge`: the one node across all of it drawn coarser, within
            // its limit.
            let stitch_of = |i: usize, edge: u32| -> u32 {
                let a = across(i, edge);
                let (l, r) = (nodes[i].0, resolution[i]);
                match a[..] {
                    [j] if nodes[j].0 >= l
                        && resolution[j] > r
                        && !limits[i].folds
                        && resolution[j] - l <= limits[i].stitch_max as u32 =>
                    {
                        resolution[j] - l
                    }
                    _ => 0,
                }
            };
            for (i, n) in nodes.iter().enumerate() {
                let [x0, _, y0, _] = fp(n);
                for edge in 0..4u32 {
                    let opposite = (edge + 2) % 4;
                    let want_stitch = stitch_of(i, edge);
                    let first_sample = (edge == 0 && y0 == 0) || (edge == 3 && x0 == 0);
                    let unsewn = across(i, edge).into_iter().any(|j| {
                        let folds_apart = limits[i].folds
                            && limits[j].folds
                            && (resolution[j] != resolution[i] || nodes[j].0 != n.0);
                        folds_apart
                            || (resolution[j] != resolution[i]
                                && stitch_of(i, edge) == 0
                                && stitch_of(j, opposite) == 0)
                    });
                    let want_skirt = first_sample || unsewn;
                    let has_skirt = skirts.edges[i] & (1 << edge) != 0;
                    let what = || {
                        format!(
                            "case {case}: node {n:?} (resolution {}, {:?}) edge {edge}, across {:?}",
                            resolution[i],
                            limits[i],
                            across(i, edge)
                                .iter()
                                .map(|&j| (nodes[j], resolution[j], limits[j]))
                                .collect::<Vec<_>>()
                        )
                    };
                    assert_eq!(has_skirt, want_skirt, "{}", what());
                    assert_eq!(skirts.stitch_of(i, edge), want_stitch, "{}", what());
                    if want_stitch > 0 {
                        assert!(!has_skirt || first_sample, "{}", what());
                        stitched += 1;
                    } else if has_skirt {
                        kept += 1;
                    } else {
                        bare += 1;
                    }
                }
            }
        }
        assert!(
            bare > 100 && kept > 100 && stitched > 100,
            "{bare} bare edges, {kept} skirted, {stitched} stitched"
        );
    }

    /// Nodes spread far apart (a box of more cells than the nodes can justify) take the hash
    /// table, with the same values; so do none.
    #[test]
    fn scattered_nodes_take_the_hash_table() {
        let nodes = [
            (0, 0, 0, 1.0),
            (0, 1, 0, 2.0),
            (0, 1 << 30, 1 << 30, 3.0),
            (3, 9, 9, 4.0),
        ];
        assert!(LevelGrids::of(&nodes).is_none());
        assert_eq!(neighbour_eps(&nodes), vec![2.0, 2.0, 3.0, 4.0]);
        assert!(neighbour_eps(&[]).is_empty());
    }
}
