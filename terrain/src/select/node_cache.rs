//! What the selection knows of a node before any camera looks at it — ε with its curvature
//! slack, the box inputs and, on the ellipsoid, the node's box, normal and normal spread — kept
//! across frames: on geographic data computing them (a lattice of sines and cosines per node)
//! was most of a frame's selection, and none of it changes while the dataset stays the same.
//! On the flat plane the values are two table reads and the curvature slack, cheaper than a
//! lookup here: that path computes them each time (16385², τ = 1, 720p: 229 → 194 µs).

use std::collections::HashMap;

use glam::DVec2;

use crate::bake::ErrorBake;
use crate::fast_hash::FastHash;
use crate::geodesy::{GeoGrid, NodeGeometry};

/// The camera-independent part of a node (level, tx, ty).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct NodeFixed {
    /// ε of the level-ℓ surface over the node, curvature slack included (metres).
    pub eps: f64,
    /// On the ellipsoid: the normals' turn plus the cell slack relative to ε (the gain's
    /// `slack`); 0 on the plane.
    pub slack: f64,
    /// What ε holds beyond the bake's: the curvature slack (metres; the drawn cell's sag on
    /// the ellipsoid, the curvature interpolation on the plane).
    pub sag: f64,
    /// On the ellipsoid: the normals' turn over the node (radians); 0 on the plane.
    pub spread: f64,
    /// The node on the ellipsoid; `None` on the flat plane.
    pub geo: Option<NodeGeometry>,
    /// Horizontal rectangle (metres, clipped to the valid data) and baked height range: the
    /// flat box's inputs (its curvature drop depends on the eye).
    pub lo: DVec2,
    pub hi: DVec2,
    pub min_h: f32,
    pub max_h: f32,
}

/// What the cached values depend on besides the node: a different bake, grid or curvature
/// setting starts the cache afresh.
#[derive(Debug, Clone, Copy, PartialEq)]
struct CacheKey {
    bake: usize,
    checksum: u32,
    dims: [u32; 6],
    spacing: [u64; 2],
    earth: Option<GeoGrid>,
    curvature: bool,
}

impl CacheKey {
    fn of(bake: &ErrorBake, earth: Option<&GeoGrid>, curvature: bool) -> Self {
        Self {
            bake: bake as *const ErrorBake as usize,
            checksum: bake.source_checksum,
            dims: [
                bake.width,
                bake.height,
                bake.valid_width,
                bake.valid_height,
                bake.params.tile_size,
                bake.levels.len() as u32,
            ],
            spacing: [bake.spacing_x.to_bits(), bake.spacing_y.to_bits()],
            earth: earth.copied(),
            // Only the plane's ε uses it.
            curvature: earth.is_none() && curvature,
        }
    }
}

/// Nodes kept at most; beyond it the cache starts afresh (a flight across a continent would
/// otherwise keep every node it ever saw: ~170 bytes each, so this is ~45 MB).
const CAPACITY: usize = 1 << 18;

/// Sibling blocks room is made for at the start (a frame on Sierra Nevada at 720p asks for
/// ~2,900 nodes, ~730 blocks): past it the blocks grow by doubling, each time copying them once.
const BLOCKS_RESERVED: usize = 1024;

/// A node's four siblings (children of one parent), in [`super::walk::child_of`]'s order.
type SiblingBlock = [Option<NodeFixed>; 4];

/// Per-node fixed values, kept in the [`Selection`](super::Selection) across frames.
///
/// Siblings are kept together: the walk asks for a node's four children one after the other
/// (`Frame::quadrants`, `quadrants_within`), and one table entry per parent with the four
/// values side by side makes that one lookup and ~670 contiguous bytes instead of four lookups
/// of ~170 scattered bytes each (Sierra Nevada follow: the lookups and the copies out of them
/// were a fifth of the selection's samples, most of it waiting on memory).
///
/// Not part of a selection's value: a clone starts empty and `clone_from` keeps the target's
/// own nodes, so copying a selection (the renderer shares one among channels every frame)
/// never copies up to [`CAPACITY`] nodes.
#[derive(Debug, Default)]
pub struct NodeCache {
    key: Option<CacheKey>,
    /// Each parent's block in `blocks`, by the parent's packed (level, x, y).
    index: HashMap<u64, u32, FastHash>,
    blocks: Vec<SiblingBlock>,
    /// The last block looked up (its parent key and index): siblings come in a row.
    last: Option<(u64, u32)>,
    /// Nodes held (filled entries of `blocks`).
    nodes: usize,
}

impl Clone for NodeCache {
    fn clone(&self) -> Self {
        Self::default()
    }

    fn clone_from(&mut self, _source: &Self) {}
}

impl NodeCache {
    /// Starts the frame: forgets everything when the dataset or the grid changed (or the cache
    /// is full).
    pub(super) fn begin(&mut self, bake: &ErrorBake, earth: Option<&GeoGrid>, curvature: bool) {
        let key = CacheKey::of(bake, earth, curvature);
        if self.key != Some(key) || self.nodes > CAPACITY {
            self.index.clear();
            self.blocks.clear();
            self.index.reserve(BLOCKS_RESERVED);
            self.blocks.reserve(BLOCKS_RESERVED);
            self.last = None;
            self.nodes = 0;
            self.key = Some(key);
        }
    }

    /// The node's fixed values, computed by `compute` the first time they are asked for; by
    /// reference, so the caller reads the fields it needs in place instead of copying all ~170
    /// bytes.
    pub(super) fn get(
        &mut self,
        level: u32,
        tx: u32,
        ty: u32,
        compute: impl FnOnce() -> NodeFixed,
    ) -> &NodeFixed {
        // The parent (level + 1, tx / 2, ty / 2), packed as the node keys were: 29 bits a
        // coordinate is 5·10⁸ tiles, far beyond any grid a bake holds.
        let parent = (((level + 1) as u64) << 58) | (((tx >> 1) as u64) << 29) | (ty >> 1) as u64;
        let block = match self.last {
            Some((key, block)) if key == parent => block,
            _ => {
                let next = self.blocks.len() as u32;
                let block = *self.index.entry(parent).or_insert(next);
                if block == next {
                    self.blocks.push([None; 4]);
                }
                self.last = Some((parent, block));
                block
            }
        };
        let slot = &mut self.blocks[block as usize][((tx & 1) | ((ty & 1) << 1)) as usize];
        if slot.is_none() {
            self.nodes += 1;
        }
        slot.get_or_insert_with(compute)
    }

    /// Nodes held.
    pub fn len(&self) -> usize {
        self.nodes
    }

    /// Whether it holds none.
    pub fn is_empty(&self) -> bool {
        self.nodes == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::{bake, BakeParams};
    use crate::dataset::Dataset;
    use crate::gen::{generate, DemKind, GenParams};

    fn small_bake(seed: u64) -> ErrorBake {
        let hf = generate(&GenParams {
            size: 129,
            spacing: 30.0,
            kind: DemKind::Ridged,
            seed,
        });
        let ds = Dataset::from_heightfield(hf, "cache test".into());
        bake(&ds, BakeParams::default(), &|_, _| {})
    }

    /// A distinct value per node, so a value handed to the wrong node shows.
    fn value_of(level: u32, tx: u32, ty: u32) -> NodeFixed {
        let v = (level * 1_000_000 + tx * 1000 + ty) as f64;
        NodeFixed {
            eps: v,
            slack: v + 0.25,
            sag: v + 0.5,
            spread: 0.0,
            geo: None,
            lo: DVec2::splat(v),
            hi: DVec2::splat(v + 1.0),
            min_h: 0.0,
            max_h: 1.0,
        }
    }

    /// Each node's value is computed once and handed back for that node only, whichever order
    /// siblings and strangers are asked for in (the block of the last lookup is not taken for
    /// a node of another parent); `len` counts nodes, not blocks.
    #[test]
    fn each_node_computed_once_and_kept_apart_from_its_siblings() {
        let b = small_bake(3);
        let mut cache = NodeCache::default();
        cache.begin(&b, None, true);
        // Siblings of parent (1, 3, 4) interleaved with nodes of other parents and levels,
        // one node with the same (tx, ty) on another level, and the coordinates' high bits.
        let order = [
            (0, 6, 8),
            (0, 7, 8),
            (1, 6, 8),
            (0, 6, 9),
            (0, 40, 2),
            (0, 7, 9),
            (2, 0, 0),
            (0, 6, 8),
            (0, 1 << 20, 5),
            (0, (1 << 20) + 1, 5),
            (1, 6, 8),
        ];
        let mut computed = Vec::new();
        for &(l, x, y) in &order {
            let got = *cache.get(l, x, y, || {
                computed.push((l, x, y));
                value_of(l, x, y)
            });
            assert_eq!(got, value_of(l, x, y), "node ({l}, {x}, {y})");
            assert_eq!(*cache.get(l, x, y, || unreachable!()), got);
        }
        let distinct: std::collections::HashSet<_> = order.iter().collect();
        assert_eq!(computed.len(), distinct.len(), "computed: {computed:?}");
        assert_eq!(cache.len(), distinct.len());
        // A second pass computes nothing.
        for &(l, x, y) in order.iter().rev() {
            let got = cache.get(l, x, y, || panic!("({l}, {x}, {y}) computed again"));
            assert_eq!(*got, value_of(l, x, y));
        }
    }

    /// Another bake (or the curvature setting the plane's ε depends on) starts afresh; the
    /// same one keeps what it holds.
    #[test]
    fn another_dataset_starts_afresh() {
        let (b1, b2) = (small_bake(3), small_bake(4));
        let mut cache = NodeCache::default();
        cache.begin(&b1, None, true);
        cache.get(0, 1, 1, || value_of(0, 1, 1));
        cache.begin(&b1, None, true);
        assert_eq!(cache.len(), 1);
        cache.get(0, 1, 1, || panic!("kept"));
        cache.begin(&b1, None, false);
        assert!(cache.is_empty());
        cache.get(0, 1, 1, || value_of(0, 1, 1));
        cache.begin(&b2, None, false);
        assert!(cache.is_empty());
        let mut again = 0;
        cache.get(0, 1, 1, || {
            again += 1;
            value_of(0, 1, 1)
        });
        assert_eq!((again, cache.len()), (1, 1));
    }
}
