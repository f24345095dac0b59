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
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn desc(q: u32, p: u32, m: u32, w: u32, h: u32) -> ClipmapDesc {
        ClipmapDesc {
            tile_quads: q,
            patch_tiles: p,
            margin_tiles: m,
            width: w,
            height: h,
        }
    }

    /// The definition of the brief, computed independently: smallest NL whose coarsest level's
    /// vertex grid (⌈(W−1)/2^(NL−1)⌉ + 1 per axis) fits in (P + 2·margin)·q texels.
    fn level_count_by_definition(q: u64, p: u64, m: u64, w: u64, h: u64) -> u32 {
        let side = (p + 2 * m) * q;
        (1..64u32)
            .find(|&nl| {
                let step = 1u64 << (nl - 1);
                (w - 1).div_ceil(step) < side && (h - 1).div_ceil(step) < side
            })
            .unwrap()
    }

    #[test]
    fn level_count_matches_definition_for_real_sizes() {
        for (n, expected) in [(1201, 4), (4097, 6), (16385, 8)] {
            let d = desc(16, 8, 2, n, n);
            assert_eq!(d.texture_side(), 192);
            assert_eq!(
                d.level_count(),
                level_count_by_definition(16, 8, 2, n as u64, n as u64),
                "{n}²"
            );
            assert_eq!(d.level_count(), expected, "{n}²");
        }
        // Non-square: the larger axis decides.
        let d = desc(16, 8, 2, 2401, 3601);
        assert_eq!(
            d.level_count(),
            level_count_by_definition(16, 8, 2, 2401, 3601)
        );
        // A dataset that already fits one texture has a single, whole-dataset level.
        let d = desc(16, 8, 2, 100, 150);
        assert_eq!(d.level_count(), 1);
        let levels = place_levels(&d, [50.0, 50.0]);
        assert_eq!(levels.len(), 1);
        assert!(levels[0].is_coarsest);
    }

    #[test]
    fn validate_rejects_bad_sizes() {
        assert_eq!(desc(16, 8, 2, 10, 10).validate(), Ok(()));
        assert_eq!(
            desc(12, 8, 2, 10, 10).validate(),
            Err(ClipmapDescError::TileQuads(12))
        );
        assert_eq!(
            desc(16, 6, 2, 10, 10).validate(),
            Err(ClipmapDescError::PatchTiles(6))
        );
        assert_eq!(
            desc(16, 9, 2, 10, 10).validate(),
            Err(ClipmapDescError::PatchTiles(9))
        );
        assert_eq!(
            desc(16, 8, 1, 10, 10).validate(),
            Err(ClipmapDescError::MarginTiles(1))
        );
        assert_eq!(
            desc(16, 8, 2, 1, 10).validate(),
            Err(ClipmapDescError::Dataset(1, 10))
        );
    }

    #[test]
    fn finest_ring_is_the_whole_patch_inside_the_dataset() {
        let d = desc(16, 8, 2, 4097, 4097);
        let levels = place_levels(&d, [2000.0, 2000.0]);
        let mut out = Vec::new();
        ring_tiles(&d, &levels[0], None, &mut out);
        assert_eq!(out.len(), 64);
        // Centred: the viewer (tile 125 of 16 samples) is within one tile of the centre.
        let centre = levels[0].patch_origin[0] as f64 + 4.0;
        assert!((centre - 2000.0 / 16.0).abs() <= 1.0);
        // A middle level's ring: 8×8 minus the 4×4 hole.
        ring_tiles(&d, &levels[1], Some(&levels[0]), &mut out);
        assert_eq!(out.len(), 64 - 16);
    }

    #[test]
    fn non_finite_viewer_does_not_panic_and_still_nests() {
        let d = desc(16, 8, 2, 16385, 16385);
        for v in [
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MAX,
            f64::MIN,
        ] {
            let levels = place_levels(&d, [v, -v]);
            check_nesting(&d, &levels);
            let mut out = Vec::new();
            for l in 0..levels.len() {
                ring_tiles(
                    &d,
                    &levels[l],
                    l.checked_sub(1).map(|f| &levels[f]),
                    &mut out,
                );
            }
        }
    }

    #[test]
    fn update_cache_first_fill_strips_jumps_and_coarsest() {
        let d = desc(16, 8, 2, 16385, 16385);
        let side = d.texture_side(); // 192
        let place = |o: [i64; 2]| LevelPlacement {
            level: 0,
            patch_origin: o,
            patch_tiles: 8,
            is_coarsest: false,
        };
        // First fill: the whole region, margin of 2 tiles before the patch.
        let (r0, up) = update_cache(&d, None, &place([10, 20]));
        assert_eq!(r0.origin, [160 - 32, 320 - 32]);
        assert_eq!(up, vec![whole(&r0)]);
        // Moving 2 tiles west stays inside the margin: nothing to upload.
        let (r1, up) = update_cache(&d, Some(&r0), &place([8, 20]));
        assert_eq!(r1, r0);
        assert!(up.is_empty());
        // Moving 2 tiles east leaves the region on x only: one vertical strip 2 tiles wide.
        let (r2, up) = update_cache(&d, Some(&r0), &place([12, 20]));
        assert_eq!(r2.origin, [192 - 32, r0.origin[1]]);
        assert_eq!(
            up,
            vec![VertexRect {
                origin: [r0.origin[0] + side as i64, r0.origin[1]],
                size: [32, side]
            }]
        );
        // Diagonal: one vertical band over the full height, one horizontal band beside it.
        let (r3, up) = update_cache(&d, Some(&r0), &place([12, 22]));
        assert_eq!(up.len(), 2);
        assert_eq!(up[0].size, [32, side]);
        assert_eq!(up[1].size, [side - 32, 32]);
        assert_eq!(r3.origin, [160, 352 - 32]);
        // A jump beyond the region re-uploads everything.
        let (r4, up) = update_cache(&d, Some(&r0), &place([100, 20]));
        assert_eq!(up, vec![whole(&r4)]);
        // The coarsest level: filled once, never again.
        let coarsest = place_levels(&d, [0.0, 0.0]).pop().unwrap();
        let (c0, up) = update_cache(&d, None, &coarsest);
        assert_eq!(c0.origin, [0, 0]);
        assert_eq!(up.len(), 1);
        let (c1, up) = update_cache(&d, Some(&c0), &coarsest);
        assert_eq!(c1, c0);
        assert!(up.is_empty());
    }

    #[test]
    fn toroidal_pieces_split_at_the_wrap() {
        let rect = VertexRect {
            origin: [-3, 10],
            size: [8, 4],
        };
        let pieces = toroidal_pieces(&rect, 16);
        assert_eq!(
            pieces,
            vec![
                TexturePiece {
                    src_offset: [0, 0],
                    texel: [13, 10],
                    size: [3, 4]
                },
                TexturePiece {
                    src_offset: [3, 0],
                    texel: [0, 10],
                    size: [5, 4]
                },
            ]
        );
        assert!(toroidal_pieces(
            &VertexRect {
                origin: [5, 5],
                size: [0, 7]
            },
            16
        )
        .is_empty());
    }

    /// Nesting invariants of one placement (shared by the property tests).
    fn check_nesting(d: &ClipmapDesc, levels: &[LevelPlacement]) {
        let count = d.level_count() as usize;
        assert_eq!(levels.len(), count);
        for (i, l) in levels.iter().enumerate() {
            assert_eq!(l.level as usize, i);
            assert_eq!(l.is_coarsest, i + 1 == count);
        }
        let coarsest = levels.last().unwrap();
        assert_eq!(coarsest.patch_origin, [0, 0]);
        // The coarsest patch covers the dataset and its tiles' vertices fit one texture.
        let t = d.tile_samples(coarsest.level);
        let covered = coarsest.patch_tiles as u64 * t;
        assert!(covered >= (d.width - 1) as u64 && covered >= (d.height - 1) as u64);
        for n in d.dataset_tiles(coarsest.level) {
            assert!(n * d.tile_quads < d.texture_side());
        }
        for l in &levels[..count - 1] {
            assert_eq!(l.patch_tiles, d.patch_tiles);
            assert!(l.patch_origin.iter().all(|o| o % 2 == 0), "{l:?}");
        }
        for pair in levels.windows(2) {
            let (fine, coarse) = (&pair[0], &pair[1]);
            // The finer patch in coarse tiles.
            let lo = fine.patch_origin.map(|o| o / 2);
            let hi = lo.map(|o| o + fine.patch_tiles as i64 / 2);
            if coarse.is_coarsest {
                // Its footprint, clipped to the dataset, lies inside the coarsest grid.
                let n = d.dataset_tiles(coarse.level);
                for a in 0..2 {
                    let (clo, chi) = (lo[a].max(0), hi[a].min(n[a] as i64));
                    assert!(clo >= chi || (clo >= 0 && chi <= coarse.patch_tiles as i64));
                }
            } else {
                for a in 0..2 {
                    assert!(
                        lo[a] > coarse.patch_origin[a], // ≥ 1 whole tile of margin
                        "{fine:?} in {coarse:?}"
                    );
                    assert!(
                        hi[a] < coarse.patch_origin[a] + coarse.patch_tiles as i64,
                        "{fine:?} in {coarse:?}"
                    );
                }
            }
        }
    }

    fn desc_strategy(max_side: u32) -> impl Strategy<Value = ClipmapDesc> {
        (
            prop::sample::select(vec![1u32, 2, 4, 8, 16]),
            prop::sample::select(vec![8u32, 10, 12, 16]),
            prop::sample::select(vec![2u32, 4]),
            2..=max_side,
            2..=max_side,
        )
            .prop_map(|(q, p, m, w, h)| desc(q, p, m, w, h))
    }

    /// Viewer coordinates: inside, on the edges, just outside, far outside and absurd.
    fn coord(extent: u32) -> impl Strategy<Value = f64> {
        let e = extent as f64;
        prop_oneof![
            4 => -0.5 * e..1.5 * e,
            1 => prop::sample::select(vec![0.0, e - 1.0, e, -1e-9, e - 1.0 + 1e-9]),
            1 => -1e9..1e9f64,
            1 => prop::sample::select(vec![1e15, -1e15, 1e300, -1e300, f64::MAX, -f64::MAX]),
        ]
    }

    fn desc_and_viewer(max_side: u32) -> impl Strategy<Value = (ClipmapDesc, [f64; 2])> {
        desc_strategy(max_side).prop_flat_map(|d| {
            let (w, h) = (d.width, d.height);
            (Just(d), coord(w), coord(h)).prop_map(|(d, x, y)| (d, [x, y]))
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        #[test]
        fn levels_nest_snap_and_centre((d, viewer) in desc_and_viewer(40_000)) {
            let levels = place_levels(&d, viewer);
            check_nesting(&d, &levels);
            // Centred within one level-L tile, hence within one level-(L+1) tile.
            if viewer.iter().all(|v| v.abs() <= VIEWER_LIMIT) {
                for l in &levels[..levels.len() - 1] {
                    let t = d.tile_samples(l.level) as f64;
                    for a in 0..2 {
                        let centre = (l.patch_origin[a] as f64 + l.patch_tiles as f64 / 2.0) * t;
                        prop_assert!((centre - viewer[a]).abs() <= t * (1.0 + 1e-9),
                            "level {} axis {a}: centre {centre} viewer {}", l.level, viewer[a]);
                    }
                }
            }
        }

        #[test]
        fn level_count_is_minimal(d in desc_strategy(70_000)) {
            let nl = d.level_count();
            let side = d.texture_side();
            let fits = |level: u32| d.dataset_tiles(level).iter().all(|&n| n * d.tile_quads < side);
            prop_assert!(fits(nl - 1));
            prop_assert!(nl == 1 || !fits(nl - 2));
            // Never fewer levels than the literal definition (equal for 2^K + 1 datasets).
            let lit = level_count_by_definition(
                d.tile_quads as u64, d.patch_tiles as u64, d.margin_tiles as u64,
                d.width as u64, d.height as u64);
            prop_assert!(nl >= lit);
            let k = 32 - (d.width.max(d.height) - 1).leading_zeros();
            let padded = desc(d.tile_quads, d.patch_tiles, d.margin_tiles, (1 << k) + 1, (1 << k) + 1);
            prop_assert_eq!(padded.level_count(), level_count_by_definition(
                d.tile_quads as u64, d.patch_tiles as u64, d.margin_tiles as u64,
                (1 << k) + 1, (1 << k) + 1));
        }

        #[test]
        fn rings_cover_the_dataset_exactly_once(
            (d, viewer) in desc_strategy(400)
                .prop_filter("cells", |d| d.tile_quads <= 4)
                .prop_flat_map(|d| {
                    let (w, h) = (d.width, d.height);
                    (Just(d), coord(w), coord(h)).prop_map(|(d, x, y)| (d, [x, y]))
                })
        ) {
            let levels = place_levels(&d, viewer);
            let (w, h) = ((d.width - 1) as i64, (d.height - 1) as i64);
            let mut count = vec![0u8; (w * h) as usize];
            let mut tiles = Vec::new();
            for (i, l) in levels.iter().enumerate() {
                let finer = if i == 0 { None } else { Some(&levels[i - 1]) };
                ring_tiles(&d, l, finer, &mut tiles);
                let t = d.tile_samples(l.level) as i64;
                for &[tx, ty] in &tiles {
                    let (x0, y0) = (tx as i64 * t, ty as i64 * t);
                    // Every returned tile overlaps the dataset.
                    prop_assert!(x0 < w && y0 < h, "tile {tx},{ty} of level {} outside", l.level);
                    for y in y0..(y0 + t).min(h) {
                        for x in x0..(x0 + t).min(w) {
                            count[(y * w + x) as usize] += 1;
                        }
                    }
                }
            }
            if let Some(i) = count.iter().position(|&c| c != 1) {
                prop_assert!(false, "cell ({}, {}) covered {} times", i as i64 % w, i as i64 / w, count[i]);
            }
        }

        #[test]
        fn toroidal_pieces_cover_rect_once(
            side in 1u32..40,
            ox in -1_000_000i64..1_000_000,
            oy in prop::sample::select(vec![i64::MIN / 4, -17, 0, 3, 1 << 40]),
            fw in 0.0..=1.0f64,
            fh in 0.0..=1.0f64,
        ) {
            let size = [(fw * side as f64) as u32, (fh * side as f64) as u32];
            let rect = VertexRect { origin: [ox, oy], size };
            let pieces = toroidal_pieces(&rect, side);
            prop_assert!(pieces.len() <= 4);
            let mut seen = vec![0u8; (side * side) as usize];
            for p in &pieces {
                prop_assert!(p.size[0] > 0 && p.size[1] > 0);
                for a in 0..2 {
                    prop_assert!(p.texel[a] + p.size[a] <= side, "wraps: {p:?}");
                    prop_assert!(p.src_offset[a] + p.size[a] <= size[a], "outside rect: {p:?}");
                }
                for dy in 0..p.size[1] {
                    for dx in 0..p.size[0] {
                        let texel = [p.texel[0] + dx, p.texel[1] + dy];
                        let vertex = [
                            ox + (p.src_offset[0] + dx) as i64,
                            oy + (p.src_offset[1] + dy) as i64,
                        ];
                        prop_assert_eq!(toroidal_texel(vertex, side), texel);
                        seen[(texel[1] * side + texel[0]) as usize] += 1;
                    }
                }
            }
            // Each texel at most once, and as many as the rect has vertices: exactly once.
            prop_assert!(seen.iter().all(|&c| c <= 1));
            let total: u64 = seen.iter().map(|&c| c as u64).sum();
            prop_assert_eq!(total, size[0] as u64 * size[1] as u64);
        }

        #[test]
        fn toroidal_texel_round_trips(
            side in 1u32..5000,
            origin in -(1i64 << 50)..(1i64 << 50),
            du in 0.0..1.0f64,
            dv in 0.0..1.0f64,
        ) {
            // Any vertex of a region [origin, origin + side) is recovered from its texel.
            let v = [origin + (du * side as f64) as i64, origin - 7 + (dv * side as f64) as i64];
            let region = [origin, origin - 7];
            let t = toroidal_texel(v, side);
            for a in 0..2 {
                prop_assert!(t[a] < side);
                let base = toroidal_texel([region[a], 0], side)[0] as i64;
                let back = region[a] + (t[a] as i64 - base).rem_euclid(side as i64);
                prop_assert_eq!(back, v[a]);
            }
        }
    }

    /// One level texture simulated texel by texel: which vertex each texel holds.
    struct SimTexture {
        side: u32,
        texels: Vec<Option<[i64; 2]>>,
    }

    impl SimTexture {
        fn apply(&mut self, rect: &VertexRect) {
            for p in toroidal_pieces(rect, self.side) {
                for dy in 0..p.size[1] {
                    for dx in 0..p.size[0] {
                        let t = ((p.texel[1] + dy) * self.side + p.texel[0] + dx) as usize;
                        self.texels[t] = Some([
                            rect.origin[0] + (p.src_offset[0] + dx) as i64,
                            rect.origin[1] + (p.src_offset[1] + dy) as i64,
                        ]);
                    }
                }
            }
        }
    }

    fn contains(region: &CacheRegion, v: [i64; 2]) -> bool {
        (0..2).all(|a| v[a] >= region.origin[a] && v[a] < region.origin[a] + region.side as i64)
    }

    fn flight_strategy() -> impl Strategy<Value = (ClipmapDesc, [f64; 2], Vec<[f64; 2]>)> {
        (
            prop::sample::select(vec![2u32, 4]),
            prop::sample::select(vec![8u32, 12]),
            prop::sample::select(vec![2u32, 4]),
            50u32..700,
            50u32..700,
        )
            .prop_flat_map(|(q, p, m, w, h)| {
                let d = desc(q, p, m, w, h);
                let step = q as f64; // at most one level-0 tile per frame
                (
                    Just(d),
                    (-(w as f64)..2.0 * w as f64, -(h as f64)..2.0 * h as f64),
                    prop::collection::vec((-step..=step, -step..=step), 1..40),
                )
                    .prop_map(|(d, (x, y), steps)| {
                        (d, [x, y], steps.into_iter().map(|(a, b)| [a, b]).collect())
                    })
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(96))]

        /// A flight of small steps: every level's texture, updated only through the uploaded
        /// rects, holds exactly the vertices of its new region; only strips are uploaded, exactly
        /// the part of the new region the old one did not hold; levels that did not move and the
        /// coarsest level upload nothing.
        #[test]
        fn flight_uploads_exactly_the_exposed_strips((d, start, steps) in flight_strategy()) {
            let side = d.texture_side();
            let q = d.tile_quads as i64;
            let mut viewer = start;
            let mut state: Vec<(LevelPlacement, CacheRegion, SimTexture)> = Vec::new();
            for frame in 0..=steps.len() {
                if frame > 0 {
                    viewer = [viewer[0] + steps[frame - 1][0], viewer[1] + steps[frame - 1][1]];
                }
                let levels = place_levels(&d, viewer);
                for (i, l) in levels.iter().enumerate() {
                    let old = state.get(i).map(|s| s.1.clone());
                    let (region, uploads) = update_cache(&d, old.as_ref(), l);
                    prop_assert_eq!(region.side, side);
                    // The patch lies inside the region.
                    for a in 0..2 {
                        let lo = l.patch_origin[a] * q;
                        let hi = lo + l.patch_tiles as i64 * q;
                        prop_assert!(lo >= region.origin[a] && hi < region.origin[a] + side as i64);
                    }
                    if l.is_coarsest {
                        prop_assert_eq!(region.origin, [0, 0]);
                    }
                    match &old {
                        None => {
                            prop_assert_eq!(uploads.clone(), vec![whole(&region)]);
                            state.push((l.clone(), region.clone(), SimTexture {
                                side,
                                texels: vec![None; (side * side) as usize],
                            }));
                        }
                        Some(old) => {
                            if state[i].0 == *l {
                                prop_assert!(uploads.is_empty(), "level {} did not move", i);
                                prop_assert_eq!(&region, old);
                            }
                            if l.is_coarsest {
                                prop_assert!(uploads.is_empty());
                            }
                            // Strips only: ≤ 2 rects, inside the new region, outside the old,
                            // disjoint, and together exactly new − old.
                            prop_assert!(uploads.len() <= 2);
                            let overlap: u64 = (0..2)
                                .map(|a| (side as i64 - (region.origin[a] - old.origin[a]).abs()).max(0) as u64)
                                .product();
                            // Small steps never force a full re-upload.
                            prop_assert!(overlap > 0, "level {} re-uploaded whole", i);
                            let mut area = 0u64;
                            for (k, r) in uploads.iter().enumerate() {
                                area += r.size[0] as u64 * r.size[1] as u64;
                                for dy in 0..r.size[1] as i64 {
                                    for dx in 0..r.size[0] as i64 {
                                        let v = [r.origin[0] + dx, r.origin[1] + dy];
                                        prop_assert!(contains(&region, v) && !contains(old, v));
                                        for other in &uploads[k + 1..] {
                                            prop_assert!(!(0..2).all(|a| v[a] >= other.origin[a]
                                                && v[a] < other.origin[a] + other.size[a] as i64));
                                        }
                                    }
                                }
                            }
                            prop_assert_eq!(area, (side as u64).pow(2) - overlap);
                            state[i].0 = l.clone();
                        }
                    }
                    state[i].1 = region.clone();
                    let tex = &mut state[i].2;
                    for r in &uploads {
                        tex.apply(r);
                    }
                    for y in region.origin[1]..region.origin[1] + side as i64 {
                        for x in region.origin[0]..region.origin[0] + side as i64 {
                            let t = toroidal_texel([x, y], side);
                            let held = tex.texels[(t[1] * side + t[0]) as usize];
                            prop_assert_eq!(held, Some([x, y]), "level {} frame {}", i, frame);
                        }
                    }
                }
            }
        }
    }
}
