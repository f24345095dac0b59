//! Clipmap level placement, ring tiles and the toroidal level-texture cache (DESIGN.md, "The
//! terrain technique"). Pure CPU: this module decides *where* each level is and *which* vertex
//! rectangles must be uploaded; the renderer does the uploads.
//!
//! Unlike the document's free-floating patches, tiles sit on a fixed global grid per level
//! (tile `(tx, ty)` of level L spans level-L vertices `[tx·q, (tx+1)·q]`), because the offline
//! error bake is per such tile. Patch origins snap to even tile indices so that the hole a patch
//! cuts in the next coarser level is made of whole coarser tiles.

/// Viewer coordinates are clamped to ±2^40 samples before placement: far beyond any dataset
/// (and any flight), small enough that tile arithmetic in f64 and i64 stays exact.
const VIEWER_LIMIT: f64 = (1u64 << 40) as f64;

/// Sizes that define the clipmap of one dataset.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ClipmapDesc {
    /// q = m − 1 quads per tile side (a power of two).
    pub tile_quads: u32,
    /// P tiles per patch side (even, ≥ 8: the patch centre falls on a tile corner).
    pub patch_tiles: u32,
    /// Cache margin per side in tiles (even, ≥ 2: the document's 2i(m−1) vertices, i ≥ 1).
    pub margin_tiles: u32,
    /// Dataset samples along x (east).
    pub width: u32,
    /// Dataset samples along y (north).
    pub height: u32,
}

/// Why a [`ClipmapDesc`] cannot be used.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ClipmapDescError {
    #[error("tile quads {0} must be a power of two ≥ 1 (m = 2^j + 1 vertices)")]
    TileQuads(u32),
    #[error("patch tiles {0} must be even and ≥ 8 (the patch centre falls on a tile corner)")]
    PatchTiles(u32),
    #[error("margin tiles {0} must be even and ≥ 2 (2i(m−1) vertices per side, i ≥ 1)")]
    MarginTiles(u32),
    #[error("dataset of {0}×{1} samples: need at least 2×2")]
    Dataset(u32, u32),
    #[error("level texture side of {0} texels is unreasonably large (over 2^20)")]
    TextureSide(u64),
}

impl ClipmapDesc {
    /// Checks the constraints every other function here assumes.
    pub fn validate(&self) -> Result<(), ClipmapDescError> {
        if !self.tile_quads.is_power_of_two() {
            return Err(ClipmapDescError::TileQuads(self.tile_quads));
        }
        if self.patch_tiles < 8 || self.patch_tiles % 2 == 1 {
            return Err(ClipmapDescError::PatchTiles(self.patch_tiles));
        }
        if self.margin_tiles < 2 || self.margin_tiles % 2 == 1 {
            return Err(ClipmapDescError::MarginTiles(self.margin_tiles));
        }
        if self.width < 2 || self.height < 2 {
            return Err(ClipmapDescError::Dataset(self.width, self.height));
        }
        let side =
            (self.patch_tiles as u64 + 2 * self.margin_tiles as u64) * self.tile_quads as u64;
        if side > (1 << 20) {
            return Err(ClipmapDescError::TextureSide(side));
        }
        Ok(())
    }

    /// Side of each level texture in texels: the patch plus `margin_tiles` whole tiles on each
    /// side, the cache that lets a level move without re-uploading (DESIGN.md).
    pub fn texture_side(&self) -> u32 {
        (self.patch_tiles + 2 * self.margin_tiles) * self.tile_quads
    }

    /// Samples per tile side at `level`.
    pub fn tile_samples(&self, level: u32) -> u64 {
        (self.tile_quads as u64) << level
    }

    /// Level-`level` tiles per axis that overlap the dataset's area (tiles 0..n are those whose
    /// cells intersect `[0, W−1]×[0, H−1]`).
    pub fn dataset_tiles(&self, level: u32) -> [u32; 2] {
        let t = self.tile_samples(level);
        [self.width, self.height].map(|s| (s as u64 - 1).div_ceil(t).max(1) as u32)
    }

    /// Number of levels NL: the smallest such that the coarsest level's whole grid fits in one
    /// level texture, so that level caches the entire dataset and never moves.
    ///
    /// "Whole grid" is taken as the vertices of the coarsest level's tiles that overlap the
    /// dataset (⌈(W−1)/(q·2^L)⌉·q + 1 per axis), not just ⌈(W−1)/2^L⌉ + 1: a tile that sticks out
    /// past the dataset's east/north edge is still drawn whole and its last vertex must not wrap
    /// onto texel 0. For datasets padded to 2^K + 1 the two definitions agree.
    pub fn level_count(&self) -> u32 {
        let side = self.texture_side() as u64;
        let mut level = 0;
        loop {
            // n·q + 1 vertices per axis must fit in `side` texels.
            let q = self.tile_quads as u64;
            let fits = self
                .dataset_tiles(level)
                .iter()
                .all(|&n| (n as u64) * q < side);
            if fits || level >= 62 {
                return level + 1;
            }
            level += 1;
        }
    }
}

/// Where one level is this frame, in level-L tile coordinates (may be negative or beyond the
/// dataset near its edges; [`ring_tiles`] clips).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LevelPlacement {
    pub level: u32,
    /// South-west tile of the patch; even for every level but the coarsest.
    pub patch_origin: [i64; 2],
    /// Tiles per patch side (for the coarsest level: enough to cover the dataset on both axes).
    pub patch_tiles: u32,
    pub is_coarsest: bool,
}

/// Places every level around the viewer (in samples). Each finer patch is P×P tiles with an even
/// origin, as centred on the viewer as that allows (centre within one level-L tile of the
/// viewer); the coarsest level is the whole dataset. Centring gives ≥ P/4 − 1.5 (so ≥ 1 whole)
/// level-(L+1) tiles between consecutive finer patches. Patches are not clamped to the dataset:
/// near or beyond its edge they simply lose the tiles [`ring_tiles`] clips away, which keeps the
/// finest levels where the eye is. NaN is treated as 0 and coordinates are clamped to ±2^40.
pub fn place_levels(desc: &ClipmapDesc, viewer_samples: [f64; 2]) -> Vec<LevelPlacement> {
    debug_assert_eq!(desc.validate(), Ok(()));
    let count = desc.level_count();
    let viewer = viewer_samples.map(|v| {
        if v.is_nan() {
            0.0
        } else {
            v.clamp(-VIEWER_LIMIT, VIEWER_LIMIT)
        }
    });
    let quarter = desc.patch_tiles as f64 / 4.0;
    let mut levels = Vec::with_capacity(count as usize);
    for level in 0..count - 1 {
        let pair = 2.0 * desc.tile_samples(level) as f64;
        // Origin 2k with k = round(v/(2t) − P/4): the centre (origin + P/2) is within one tile.
        let patch_origin = viewer.map(|v| 2 * (v / pair - quarter + 0.5).floor() as i64);
        levels.push(LevelPlacement {
            level,
            patch_origin,
            patch_tiles: desc.patch_tiles,
            is_coarsest: false,
        });
    }
    let coarsest = count - 1;
    let [nx, ny] = desc.dataset_tiles(coarsest);
    levels.push(LevelPlacement {
        level: coarsest,
        patch_origin: [0, 0],
        patch_tiles: nx.max(ny),
        is_coarsest: true,
    });
    levels
}

/// Writes into `out` (cleared first) the tiles of `level`'s ring: inside its patch, outside the
/// footprint of the next finer patch `finer` (None for the finest level, whose ring is its whole
/// patch), and overlapping the dataset's area. Row-major from the south-west.
pub fn ring_tiles(
    desc: &ClipmapDesc,
    level: &LevelPlacement,
    finer: Option<&LevelPlacement>,
    out: &mut Vec<[u32; 2]>,
) {
    out.clear();
    let limit = desc.dataset_tiles(level.level);
    let span = |a: usize| {
        let lo = level.patch_origin[a].max(0);
        let hi = (level.patch_origin[a] + level.patch_tiles as i64).min(limit[a] as i64);
        (lo, hi)
    };
    let ((x0, x1), (y0, y1)) = (span(0), span(1));
    // The finer patch in this level's tiles; empty when there is none.
    let hole = match finer {
        Some(f) => {
            debug_assert_eq!(
                f.level + 1,
                level.level,
                "finer must be the next finer level"
            );
            debug_assert!(f.patch_origin.iter().all(|o| o % 2 == 0) && f.patch_tiles % 2 == 0);
            let o = f.patch_origin.map(|o| o.div_euclid(2));
            let n = (f.patch_tiles / 2) as i64;
            [o[0], o[0] + n, o[1], o[1] + n]
        }
        None => [0, 0, 0, 0],
    };
    for ty in y0..y1 {
        let in_hole_y = ty >= hole[2] && ty < hole[3];
        for tx in x0..x1 {
            if in_hole_y && tx >= hole[0] && tx < hole[1] {
                continue;
            }
            out.push([tx as u32, ty as u32]);
        }
    }
}

/// The vertices a level texture currently holds: `[origin, origin + side)` per axis, in level-L
/// vertex coordinates; vertex v lives at texel [`toroidal_texel`]`(v, side)`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CacheRegion {
    pub origin: [i64; 2],
    pub side: u32,
}

/// A rectangle of level-L vertices `[origin, origin + size)`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VertexRect {
    pub origin: [i64; 2],
    pub size: [u32; 2],
}

/// One non-wrapping piece of a [`VertexRect`] in a toroidal texture.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TexturePiece {
    /// Offset of the piece inside the rect (the source of the copy).
    pub src_offset: [u32; 2],
    /// Texel of the piece's first vertex.
    pub texel: [u32; 2],
    pub size: [u32; 2],
}

/// New cache region for a level and the vertex rects to upload into it. Per axis, the old
/// region is kept while the patch (P·q + 1 vertices) lies inside it, else re-placed with
/// `margin_tiles` whole tiles before the patch — the margin is the cache of DESIGN.md, so a level
/// that did not leave it uploads nothing. Uploads are the whole region on a first fill, a size
/// change or a jump with no overlap; otherwise only the newly exposed strips (≤ one vertical band
/// spanning the new region and one horizontal band, disjoint). Vertices outside the dataset are
/// included; the uploader clamps them to the edge. The coarsest level always holds the whole
/// dataset at origin 0, so only its first fill uploads.
pub fn update_cache(
    desc: &ClipmapDesc,
    old: Option<&CacheRegion>,
    placement: &LevelPlacement,
) -> (CacheRegion, Vec<VertexRect>) {
    let side = desc.texture_side();
    let old = old.filter(|o| o.side == side);
    let new = if placement.is_coarsest {
        CacheRegion {
            origin: [0, 0],
            side,
        }
    } else {
        let q = desc.tile_quads as i64;
        let extent = desc.patch_tiles as i64 * q; // last patch vertex, relative
        let origin = [0, 1].map(|a| {
            let lo = placement.patch_origin[a] * q;
            match old {
                Some(o) if o.origin[a] <= lo && lo + extent < o.origin[a] + side as i64 => {
                    o.origin[a]
                }
                _ => lo - desc.margin_tiles as i64 * q,
            }
        });
        CacheRegion { origin, side }
    };
    let uploads = match old {
        Some(o) => exposed(o, &new),
        None => vec![whole(&new)],
    };
    (new, uploads)
}

fn whole(region: &CacheRegion) -> VertexRect {
    VertexRect {
        origin: region.origin,
        size: [region.side; 2],
    }
}

/// `new − old` for two regions of the same side, as at most two disjoint bands.
fn exposed(old: &CacheRegion, new: &CacheRegion) -> Vec<VertexRect> {
    let s = new.side as i64;
    let d = [0, 1].map(|a| new.origin[a] - old.origin[a]);
    if d[0].abs() >= s || d[1].abs() >= s {
        return vec![whole(new)];
    }
    // The part of the new range on one axis that the old range does not hold.
    let fresh = |a: usize| -> (i64, i64) {
        if d[a] > 0 {
            (old.origin[a] + s, new.origin[a] + s)
        } else {
            (new.origin[a], old.origin[a])
        }
    };
    let mut out = Vec::with_capacity(2);
    if d[0] != 0 {
        let (x0, x1) = fresh(0);
        out.push(VertexRect {
            origin: [x0, new.origin[1]],
            size: [(x1 - x0) as u32, new.side],
        });
    }
    if d[1] != 0 {
        let (y0, y1) = fresh(1);
        let x0 = new.origin[0].max(old.origin[0]);
        let x1 = new.origin[0].min(old.origin[0]) + s;
        out.push(VertexRect {
            origin: [x0, y0],
            size: [(x1 - x0) as u32, (y1 - y0) as u32],
        });
    }
    out
}

/// Texel of vertex `vertex` in a toroidally addressed `side`×`side` texture.
pub fn toroidal_texel(vertex: [i64; 2], side: u32) -> [u32; 2] {
    vertex.map(|v| v.rem_euclid(side as i64) as u32)
}

/// Splits `rect` into the ≤ 4 non-wrapping pieces it occupies in a toroidal `side`×`side`
/// texture, so each piece is one plain buffer-to-image copy. Panics if the rect is wider than
/// the texture (it would overwrite itself).
pub fn toroidal_pieces(rect: &VertexRect, side: u32) -> Vec<TexturePiece> {
    assert!(side > 0, "toroidal texture of side 0");
    assert!(
        rect.size[0] <= side && rect.size[1] <= side,
        "rect {:?} larger than the {side}² texture",
        rect.size
    );
    let start = toroidal_texel(rect.origin, side);
    // Per axis: (offset in rect, texel, length) of the part before and after the wrap.
    let split = |a: usize| {
        let first = rect.size[a].min(side - start[a]);
        [(0, start[a], first), (first, 0, rect.size[a] - first)]
    };
    let (xs, ys) = (split(0), split(1));
    let mut out = Vec::with_capacity(4);
    for &(sy, ty, h) in &ys {
        for &(sx, tx, w) in &xs {
            if w > 0 && h > 0 {
                out.push(TexturePiece {
                    src_offset: [sx, sy],
                    texel: [tx, ty],
                    size: [w, h],
                });
            }
        }
    }
    out
}

#[cfg(test)]
#[path = "clipmap_tests.rs"]
mod tests;
