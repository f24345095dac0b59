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
/// otherwise keep every node it ever saw: ~150 bytes each, so this is ~40 MB).
const CAPACITY: usize = 1 << 18;

/// Per-node fixed values, kept in the [`Selection`](super::Selection) across frames.
///
/// Not part of a selection's value: a clone starts empty and `clone_from` keeps the target's
/// own nodes, so copying a selection (the renderer shares one among channels every frame)
/// never copies up to [`CAPACITY`] nodes.
#[derive(Debug, Default)]
pub struct NodeCache {
    key: Option<CacheKey>,
    nodes: HashMap<u64, NodeFixed, FastHash>,
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
        if self.key != Some(key) || self.nodes.len() > CAPACITY {
            self.nodes.clear();
            self.key = Some(key);
        }
    }

    /// The node's fixed values, computed by `compute` the first time they are asked for.
    pub(super) fn get(
        &mut self,
        level: u32,
        tx: u32,
        ty: u32,
        compute: impl FnOnce() -> NodeFixed,
    ) -> NodeFixed {
        let key = ((level as u64) << 58) | ((tx as u64) << 29) | ty as u64;
        *self.nodes.entry(key).or_insert_with(compute)
    }

    /// Nodes held.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether it holds none.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }
}
