//! Each drawn node's skirt: how far it must reach (the roughest of its edge neighbours), which
//! of its edges need one at all (those shared with a node drawn at another resolution), and
//! along which it fills the crack itself instead (the one node across drawn one resolution
//! coarser).

use crate::fast_hash::FastHash;

/// [`node_skirts`]' reach alone, every node drawn at its own level (the tests' entry).
#[cfg(test)]
pub(crate) fn neighbour_eps(nodes: &[(u32, u32, u32, f32)]) -> Vec<f32> {
    let levels: Vec<u32> = nodes.iter().map(|n| n.0).collect();
    node_skirts(nodes, &levels, &vec![false; nodes.len()], false).reach
}

/// The edges of a node in the perimeter walk's order (`mesh::perimeter_vertex`): bit e set
/// for edge e (0 south, 1 east, 2 north, 3 west).
pub const ALL_EDGES: u8 = 0b1111;

/// Each drawn node's skirt ([`node_skirts`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct NodeSkirts {
    /// Per node, the largest ε among itself and the nodes sharing an edge with it: what its
    /// skirt must reach ([`node_skirts`]).
    pub reach: Vec<f32>,
    /// Per node, the edges that need a skirt ([`ALL_EDGES`]' bits).
    pub edges: Vec<u8>,
    /// Per node, the edges along which it fills the crack to the one node across, drawn one
    /// resolution coarser, with a triangle per two segments of its edge
    /// (`mesh::fill_edge_indices`); neither side hangs a skirt there. Disjoint from `edges`.
    pub fills: Vec<u8>,
}

/// For each drawn node (level, tx, ty, ε), the largest ε among itself and the nodes sharing
/// an edge with it — what its skirt must reach —, and the edges that need a skirt at all.
///
/// Reach: along an edge between nodes A and B both surfaces are within their ε of the true
/// one, so the edges differ by up to ε_A + ε_B, and the higher edge's skirt must cover that: a
/// skirt of ε + max(ε, neighbours' ε) closes every crack, including T-junctions against a much
/// rougher coarse neighbour, which 2ε alone does not. Each fine–coarse pair is found from the
/// finer node by walking up from the position across its edge to the first drawn node (a
/// same-level neighbour or a coarser ancestor) and updates both.
///
/// Edges: `resolution[i]` is the level whose grid node i is drawn at (its own level, one more
/// for a quadrant drawn at its parent's resolution, two for a sixteenth). Levels are
/// subsamplings (DESIGN.md "The terrain technique"), so two nodes drawn at the same resolution
/// put the same vertices — the same samples, the same heights — along an edge they share: no
/// crack opens there. Every edge starts bare, and each pair of nodes sharing an edge at
/// different resolutions (a T-junction) gives both edges a skirt (the higher edge's covers
/// the crack, whichever it is); so does a pair of nodes that both fold their vertices at the
/// grid's end (`folds[i]`: the node reaches past the grid's last sample, where its vertices
/// fold onto the first vertex at or past it, by its own step) unless they are of one level
/// and resolution (folding alike). An edge with nothing drawn across it needs none: the
/// neighbour was culled — its box, which holds the strip between the two edges, is outside
/// every view or hidden — or holds no terrain; nor does a coarse edge whose finer neighbours
/// are all drawn at its resolution. Edges on the grid's first sample keep theirs (the renderer
/// keeps those on its last).
///
/// Tried and dropped: *stitching* a finer node's edge to the one coarser node across it (its
/// edge vertices between the coarse ones moved onto them, no skirt on either side). On the
/// suite it drew 0.90× the triangles configuration by configuration but changed CDLOD's ratio
/// only from 0.66× to 0.65×, and its strip triangles, as wide as the coarse node's vertex
/// step, put the generated `mixed` set's cliffs up to 76 px past τ.
///
/// The nodes are looked up in a dense grid per level over the box its nodes and their
/// ancestors span (a frame's nodes of one level lie in that level's clipmap patch), where the
/// ancestors of drawn nodes are marked split: a walk that meets a split node stops there — no
/// node above it is drawn. Nodes too scattered for the grids (more than
/// `GRID_CELLS_PER_NODE` cells a node) take a hash table; both give the same values (tests).
/// `nodes` must not overlap (no selection draws a place twice); where they do, every edge
/// keeps its skirt.
///
/// Fills (`fill`): where a node's whole edge faces one node drawn exactly one resolution
/// coarser (the same size or larger, neither folding), the coarse edge's vertices are every
/// other vertex of the fine edge — the same samples, the same heights —, so the crack between
/// them is, per coarse segment, exactly the triangle of the fine edge's three vertices over it,
/// whichever side of the coarse segment its middle vertex lies (DESIGN.md "The terrain
/// technique": levels are subsamplings). The finer node draws those triangles (a third of a
/// skirt's: one per two segments against three) and neither edge gets a skirt from the pair.
/// Two or more resolutions apart the fine polyline between two coarse vertices has interior
/// vertices on both sides of the coarse segment and no fixed triangulation of the gap is safe
/// (a fan pokes above both surfaces): both sides keep their skirts. The caller asks for fills
/// only where every drawn stride puts an even number of segments on an edge.
pub fn node_skirts(
    nodes: &[(u32, u32, u32, f32)],
    resolution: &[u32],
    folds: &[bool],
    fill: bool,
) -> NodeSkirts {
    assert_eq!(nodes.len(), resolution.len(), "a resolution per node");
    assert_eq!(nodes.len(), folds.len(), "a fold flag per node");
    let rule = Rule {
        pairs_once: true,
        fill,
    };
    match LevelGrids::of(nodes) {
        Some(grids) => walk_neighbours(
            nodes,
            resolution,
            folds,
            |l, x, y| grids.get(l, x, y),
            grids.overlap,
            rule,
        ),
        None => node_skirts_hashed(nodes, resolution, folds, rule),
    }
}

/// How [`walk_neighbours`] treats pairs: `pairs_once`: a pair of same-level neighbours is
/// looked up from one side only (what every caller asks; the tests compare it with both);
/// `fill`: a pair one resolution apart is filled from the finer side ([`node_skirts`]).
#[derive(Clone, Copy, Debug)]
struct Rule {
    pairs_once: bool,
    fill: bool,
}

/// The skirts of the last node list given again while the list is the same: with a selection
/// carried across frames most frames draw the same nodes as the frame before (Sierra Nevada
/// follow at 720p, τ = 1: 69 % of frames), and [`node_skirts`] is the frame plan's dearest
/// step (~70 µs for 1,400 nodes). The result is [`node_skirts`]' for the list, whichever way
/// it came.
#[derive(Debug, Default)]
pub struct SkirtMemo {
    nodes: Vec<(u32, u32, u32, f32)>,
    resolution: Vec<u32>,
    folds: Vec<bool>,
    fill: bool,
    skirts: NodeSkirts,
    /// Lists answered from the memo, and formed afresh.
    pub hits: u64,
    pub misses: u64,
}

impl SkirtMemo {
    /// [`node_skirts`] of the list, from the memo when it is the last one given (every node,
    /// ε bit for bit, resolution and fold flag equal, in the same order, and the same `fill`).
    pub fn skirts(
        &mut self,
        nodes: &[(u32, u32, u32, f32)],
        resolution: &[u32],
        folds: &[bool],
        fill: bool,
    ) -> &NodeSkirts {
        let same_nodes = self.nodes.len() == nodes.len()
            && self
                .nodes
                .iter()
                .zip(nodes)
                .all(|(a, b)| (a.0, a.1, a.2, a.3.to_bits()) == (b.0, b.1, b.2, b.3.to_bits()));
        if same_nodes && self.fill == fill && self.resolution == resolution && self.folds == folds {
            self.hits += 1;
        } else {
            self.misses += 1;
            self.fill = fill;
            self.skirts = node_skirts(nodes, resolution, folds, fill);
            self.nodes.clear();
            self.nodes.extend_from_slice(nodes);
            self.resolution.clear();
            self.resolution.extend_from_slice(resolution);
            self.folds.clear();
            self.folds.extend_from_slice(folds);
        }
        &self.skirts
    }
}

/// [`node_skirts`] through a hash table of the drawn nodes.
fn node_skirts_hashed(
    nodes: &[(u32, u32, u32, f32)],
    resolution: &[u32],
    folds: &[bool],
    rule: Rule,
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
        folds,
        |l, x, y| match index.get(&(l, x, y)) {
            Some(&j) => Cell::Drawn(j),
            None if !overlap && split.contains(&(l, x, y)) => Cell::Split,
            None => Cell::Empty,
        },
        overlap,
        rule,
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
/// overlap (every edge keeps its skirt, none fills).
fn walk_neighbours(
    nodes: &[(u32, u32, u32, f32)],
    resolution: &[u32],
    folds: &[bool],
    find: impl Fn(u32, u32, u32) -> Cell,
    overlap: bool,
    rule: Rule,
) -> NodeSkirts {
    let top = nodes.iter().map(|n| n.0).max().unwrap_or(0);
    let mut reach: Vec<f32> = nodes.iter().map(|n| n.3).collect();
    // Edges start bare and are given a skirt by the pairs that need one.
    let mut edges = vec![0u8; nodes.len()];
    let mut fills = vec![0u8; nodes.len()];
    // Per node, the edges whose same-level neighbour has been met from the other side
    // already: the pair's updates are symmetric (both reaches, both edges, `apart` the same
    // either way), so each such pair is looked up once instead of twice.
    let mut met = vec![0u8; nodes.len()];
    // The perimeter walk's edges: south, east, north, west.
    const ACROSS: [(i64, i64); 4] = [(0, -1), (1, 0), (0, 1), (-1, 0)];
    for (i, &(l, x, y, e)) in nodes.iter().enumerate() {
        // Whether the lookup finds this node at its own place (not a repeat of a later one):
        // only then does its neighbour's lookup across the shared edge find it in turn.
        let found_here = find(l, x, y) == Cell::Drawn(i);
        for (edge, (dx, dy)) in ACROSS.into_iter().enumerate() {
            if met[i] & (1 << edge) != 0 {
                continue;
            }
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
                            // neighbour or its ancestor); node i covers j's edge only when
                            // they are of one level.
                            let (ri, rj) = (resolution[i], resolution[j]);
                            let fill = rule.fill && !folds[i] && !folds[j];
                            let apart = rj != ri || (folds[i] && folds[j] && nodes[j].0 != l);
                            if fill && rj == ri + 1 {
                                fills[i] |= 1 << edge;
                            } else if fill && k == 0 && ri == rj + 1 {
                                fills[j] |= 1 << ((edge + 2) % 4);
                            } else if apart {
                                edges[i] |= 1 << edge;
                                edges[j] |= 1 << ((edge + 2) % 4);
                            }
                            if k == 0 && found_here && rule.pairs_once {
                                met[j] |= 1 << ((edge + 2) % 4);
                            }
                        }
                        break;
                    }
                }
            }
        }
    }
    if overlap {
        edges.fill(ALL_EDGES);
        fills.fill(0);
    }
    NodeSkirts {
        reach,
        edges,
        fills,
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

    /// The grids' walk looking each same-level pair up from both sides (the reference the
    /// one-sided walk must equal).
    fn walk_both_sides(
        grids: &LevelGrids,
        nodes: &[(u32, u32, u32, f32)],
        resolution: &[u32],
        folds: &[bool],
        fill: bool,
    ) -> NodeSkirts {
        let find = |l, x, y| grids.get(l, x, y);
        let rule = Rule {
            pairs_once: false,
            fill,
        };
        walk_neighbours(nodes, resolution, folds, find, grids.overlap, rule)
    }

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

    /// The grids give what the hash table and the full walk give — and the walk that looks
    /// each same-level pair up from both sides —, on covers with and without holes, several
    /// covers side by side, overlapping and repeated nodes (which take the full walk through
    /// split cells), and on covers whose split cells end walks early.
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
            let folds: Vec<bool> = nodes.iter().map(|n| (n.1 + 2 * n.2) % 7 == 0).collect();
            for fill in [false, true] {
                let rule = Rule {
                    pairs_once: true,
                    fill,
                };
                let want = node_skirts_hashed(&nodes, &resolution, &folds, rule);
                assert_eq!(
                    node_skirts(&nodes, &resolution, &folds, fill),
                    want,
                    "case {case}, fill {fill}: {nodes:?}"
                );
                // Each same-level pair looked up from both sides gives the same.
                let both_sides = walk_both_sides(&grids, &nodes, &resolution, &folds, fill);
                assert_eq!(both_sides, want, "case {case}, fill {fill}: {nodes:?}");
            }
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
    /// a node's reach is the largest ε of itself and the nodes across its edges. Without
    /// fills an edge has a skirt exactly when it lies on the grid's first sample, or some node
    /// across it is drawn at another resolution, or both fold at the grid's end and differ in
    /// level or resolution; so an edge facing nothing (culled), or only nodes at its own
    /// resolution, has none. With fills an edge fills exactly when one node across covers it
    /// whole, drawn one resolution coarser, and neither folds; and a pair so filled (from
    /// either side) gives neither edge a skirt. Covers with holes, every resolution offset,
    /// folding nodes.
    #[test]
    fn an_edge_has_a_skirt_only_against_another_resolution() {
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let (mut bare, mut kept, mut filled) = (0, 0, 0);
        for case in 0..320u32 {
            let fill = case % 2 == 1;
            let case = case / 2;
            let top = 1 + case % 5;
            // Some covers on the grid's first sample (x = 0).
            let x = (3 + case) * (case % 4 != 0) as u32;
            let nodes = cover(&mut seed, top, x, 5, case % 2 == 1);
            if nodes.is_empty() {
                continue;
            }
            // Drawn at its own level, or (a quadrant, a sixteenth) one or two above.
            let resolution: Vec<u32> = nodes
                .iter()
                .map(|n| n.0 + (xorshift(&mut seed) % 3) as u32 * (case % 3 != 0) as u32)
                .collect();
            let folds: Vec<bool> = nodes
                .iter()
                .map(|_| xorshift(&mut seed).is_multiple_of(4))
                .collect();
            let skirts = node_skirts(&nodes, &resolution, &folds, fill);
            // Footprints in level-0 cells: [x0, x1) × [y0, y1).
            let fp =
                |&(l, x, y, _): &(u32, u32, u32, f32)| [x << l, (x + 1) << l, y << l, (y + 1) << l];
            // The nodes across edge `edge` of node `i` along a positive length.
            let across_of = |i: usize, edge: u32| -> Vec<usize> {
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
            // Node i fills its edge: one node across, covering it whole, one resolution
            // coarser, neither folding.
            let fills_edge = |i: usize, edge: u32| -> bool {
                let across = across_of(i, edge);
                fill && across.len() == 1 && {
                    let j = across[0];
                    nodes[j].0 >= nodes[i].0
                        && resolution[j] == resolution[i] + 1
                        && !folds[i]
                        && !folds[j]
                }
            };
            for (i, n) in nodes.iter().enumerate() {
                let [x0, _, y0, _] = fp(n);
                let mut want_reach = n.3;
                for edge in 0..4u32 {
                    let across = across_of(i, edge);
                    // Reach: the roughest of itself and every node across any edge.
                    for &j in &across {
                        want_reach = want_reach.max(nodes[j].3);
                    }
                    let first_sample = (edge == 0 && y0 == 0) || (edge == 3 && x0 == 0);
                    let apart = across.iter().any(|&j| {
                        let filled = fills_edge(i, edge) || fills_edge(j, (edge + 2) % 4);
                        !filled
                            && (resolution[j] != resolution[i]
                                || (folds[i] && folds[j] && nodes[j].0 != n.0))
                    });
                    let has_skirt = skirts.edges[i] & (1 << edge) != 0;
                    let has_fill = skirts.fills[i] & (1 << edge) != 0;
                    let context = || {
                        format!(
                            "case {case}, fill {fill}: node {n:?} (resolution {}, folds {}) edge {edge}, across {:?}",
                            resolution[i],
                            folds[i],
                            across
                                .iter()
                                .map(|&j| (nodes[j], resolution[j], folds[j]))
                                .collect::<Vec<_>>()
                        )
                    };
                    assert_eq!(has_skirt, first_sample || apart, "{}", context());
                    assert_eq!(has_fill, fills_edge(i, edge), "{}", context());
                    assert!(!(has_fill && has_skirt), "{}", context());
                    match (has_skirt, has_fill) {
                        (true, _) => kept += 1,
                        (_, true) => filled += 1,
                        _ => bare += 1,
                    }
                }
                assert_eq!(
                    skirts.reach[i], want_reach,
                    "case {case}: node {n:?}'s reach"
                );
            }
        }
        assert!(
            bare > 100 && kept > 100 && filled > 100,
            "{bare} bare edges, {kept} skirted, {filled} filled"
        );
    }

    /// Nodes spread far apart (a box of more cells than the nodes can justify) take the hash
    /// table, with the same values; so do none.
    /// The memo gives `node_skirts`' result for every list: the same list again from the memo,
    /// a list differing in one node, one ε, one resolution or one fold flag formed afresh.
    #[test]
    fn the_memo_gives_what_node_skirts_gives() {
        let mut seed = 0x5eed_u64;
        let nodes = cover(&mut seed, 4, 3, 5, true);
        let resolution: Vec<u32> = nodes.iter().map(|n| n.0).collect();
        let folds = vec![false; nodes.len()];
        let mut memo = SkirtMemo::default();
        let fresh = node_skirts(&nodes, &resolution, &folds, false);
        assert_eq!(memo.skirts(&nodes, &resolution, &folds, false), &fresh);
        assert_eq!(memo.skirts(&nodes, &resolution, &folds, false), &fresh);
        assert_eq!((memo.hits, memo.misses), (1, 1));
        // A finer neighbour drawn at a coarser resolution: other edges.
        let k = (0..nodes.len())
            .find(|&i| {
                node_skirts(
                    &nodes,
                    &{
                        let mut r = resolution.clone();
                        r[i] += 1;
                        r
                    },
                    &folds,
                    false,
                ) != fresh
            })
            .expect("some node whose resolution changes the skirts");
        let mut other = resolution.clone();
        other[k] += 1;
        let changed = node_skirts(&nodes, &other, &folds, false);
        assert_eq!(memo.skirts(&nodes, &other, &folds, false), &changed);
        // The same list with fills: formed afresh, and some pair filled.
        let filled = node_skirts(&nodes, &other, &folds, true);
        assert_ne!(filled, changed);
        assert_eq!(memo.skirts(&nodes, &other, &folds, true), &filled);
        // One ε: another reach.
        let mut rougher = nodes.clone();
        rougher[k].3 += 7.0;
        assert_eq!(
            memo.skirts(&rougher, &resolution, &folds, false),
            &node_skirts(&rougher, &resolution, &folds, false)
        );
        // One fold flag, one node fewer.
        let mut folded = folds.clone();
        folded[k] = true;
        assert_eq!(
            memo.skirts(&rougher, &resolution, &folded, false),
            &node_skirts(&rougher, &resolution, &folded, false)
        );
        let n = nodes.len() - 1;
        assert_eq!(
            memo.skirts(&nodes[..n], &resolution[..n], &folds[..n], false),
            &node_skirts(&nodes[..n], &resolution[..n], &folds[..n], false)
        );
        assert_eq!((memo.hits, memo.misses), (1, 6));
    }

    /// A node repeated on both sides of an edge (no selection repeats one; the walk must
    /// still not lose a pair): in every order of the list, looking each same-level pair up
    /// once gives what looking from both sides gives.
    #[test]
    fn repeated_neighbours_lose_no_pair() {
        let base = [
            (0, 4, 4, 1.0),
            (0, 5, 4, 2.0),
            (0, 4, 4, 3.0),
            (0, 5, 4, 4.0),
            (1, 3, 2, 0.5),
        ];
        let mut orders = 0;
        for p in 0..(5 * 4 * 3 * 2) {
            // The p-th permutation (factorial number system).
            let mut pool: Vec<_> = base.to_vec();
            let mut nodes = Vec::new();
            let mut r = p;
            for n in (1..=5).rev() {
                nodes.push(pool.remove(r % n));
                r /= n;
            }
            let resolution: Vec<u32> = nodes.iter().map(|n| n.0 + (n.3 as u32) % 2).collect();
            let folds = vec![false; nodes.len()];
            let grids = LevelGrids::of(&nodes).expect("a small box");
            for fill in [false, true] {
                let both_sides = walk_both_sides(&grids, &nodes, &resolution, &folds, fill);
                assert_eq!(
                    node_skirts(&nodes, &resolution, &folds, fill),
                    both_sides,
                    "{nodes:?}"
                );
            }
            orders += 1;
        }
        assert_eq!(orders, 120);
    }

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
