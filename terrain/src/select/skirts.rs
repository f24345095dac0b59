//! How far each drawn node's skirt must reach: the roughest of its edge neighbours.

use crate::fast_hash::FastHash;

/// For each drawn node (level, tx, ty, ε), the largest ε among itself and the nodes sharing
/// an edge with it — what its skirt must reach. Along an edge between nodes A and B both
/// surfaces are within their ε of the true one, so the edges differ by up to ε_A + ε_B, and
/// the higher edge's skirt must cover that: a skirt of ε + max(ε, neighbours' ε) closes every
/// crack, including T-junctions against a much rougher coarse neighbour, which 2ε alone does
/// not. Each fine–coarse pair is found from the finer node by walking up from the position
/// across its edge to the first drawn node (a same-level neighbour or a coarser ancestor) and
/// updates both.
pub fn neighbour_eps(nodes: &[(u32, u32, u32, f32)]) -> Vec<f32> {
    let mut index: std::collections::HashMap<(u32, u32, u32), usize, FastHash> =
        std::collections::HashMap::with_capacity_and_hasher(nodes.len(), FastHash::default());
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
