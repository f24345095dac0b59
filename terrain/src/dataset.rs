//! A dataset: a loaded heightfield padded by edge extension to the `2^K + 1` grid the clipmap
//! and the error bake need, with the padding marked so it is never reported as terrain.
//!
//! **Padding rule.** Each axis is padded on its own to the smallest `2^K + 1 ≥ n` samples
//! (`K` may differ between x and y: 1197 × 643 becomes 2049 × 1025, the 2401 × 3601 mosaic
//! 4097 × 4097, 16385² stays as it is). Padding columns are added on the **east** side and
//! padding rows on the **north** side, so the origin (sample (0, 0), the south-west sample) and
//! the geo-reference do not move. A padding sample repeats the nearest real sample
//! (`h(min(col, valid_width−1), min(row, valid_height−1))`), so padded tiles are flat
//! extensions and every tile that holds a real sample has the same min/max as its real part.
//! `col ≥ valid_width || row ≥ valid_height` ⇔ padding.

use std::path::{Path, PathBuf};

use super::load::stitch::{stitch_folder, stitch_tiles};
use super::load::{load_dem, DemError};
use super::Heightfield;

/// A heightfield padded to `(2^Kx + 1) × (2^Ky + 1)` samples; see the module documentation.
#[derive(Debug, Clone)]
pub struct Dataset {
    /// The padded heightfield (`hf.width`, `hf.height` are the padded sizes).
    pub hf: Heightfield,
    /// Real samples per row; columns `>= valid_width` are padding (east side).
    pub valid_width: usize,
    /// Real rows; rows `>= valid_height` are padding (north side).
    pub valid_height: usize,
    /// Where the data came from, one line (a path, plus what stitching did for folders).
    pub source: String,
}

/// Smallest `2^K + 1 ≥ n` (n ≥ 2 → ≥ 2).
pub fn padded_side(n: usize) -> usize {
    if n <= 2 {
        return 2;
    }
    (n - 1).next_power_of_two() + 1
}

impl Dataset {
    /// Pads `hf` in place (no second copy of the samples is held) as the module says.
    pub fn from_heightfield(mut hf: Heightfield, source: String) -> Self {
        let (w, h) = (hf.width, hf.height);
        assert!(w >= 2 && h >= 2, "heightfield {w}×{h} is below 2×2");
        assert_eq!(hf.heights.len(), w * h, "heights length vs {w}×{h}");
        let (pw, ph) = (padded_side(w), padded_side(h));
        if (pw, ph) != (w, h) {
            let v = &mut hf.heights;
            v.resize(pw * ph, 0.0);
            // Move rows up to their padded positions, last row first: the destination of row r
            // (r·pw..) never overlaps the sources of rows below it (..r·w).
            for r in (0..h).rev() {
                v.copy_within(r * w..r * w + w, r * pw);
                let edge = v[r * pw + w - 1];
                v[r * pw + w..(r + 1) * pw].fill(edge);
            }
            // North padding rows repeat the last real row.
            let (real, pad) = v.split_at_mut(h * pw);
            let last = &real[(h - 1) * pw..h * pw];
            for row in pad.chunks_exact_mut(pw) {
                row.copy_from_slice(last);
            }
            hf.width = pw;
            hf.height = ph;
        }
        Dataset {
            hf,
            valid_width: w,
            valid_height: h,
            source,
        }
    }

    /// True when (col, row) is a padding sample (east or north of the real grid).
    #[inline]
    pub fn is_padding(&self, col: usize, row: usize) -> bool {
        col >= self.valid_width || row >= self.valid_height
    }

    /// `K` per axis: `hf.width = 2^kx + 1`, `hf.height = 2^ky + 1`.
    pub fn log2_sides(&self) -> (u32, u32) {
        (
            (self.hf.width - 1).trailing_zeros(),
            (self.hf.height - 1).trailing_zeros(),
        )
    }

    /// CRC-32 (IEEE) of the padded samples as little-endian f32, row 0 first. This is what a
    /// bake file records to tell whether it still belongs to this data.
    pub fn checksum(&self) -> u32 {
        samples_crc32(&self.hf.heights)
    }

    /// One line: "4097×4097 samples (2401×3601 real, padded east/north), 62.7 m × 92.6 m".
    pub fn summary(&self) -> String {
        let pad = if (self.valid_width, self.valid_height) == (self.hf.width, self.hf.height) {
            "no padding".to_string()
        } else {
            format!(
                "{}×{} real, padded east/north by edge extension",
                self.valid_width, self.valid_height
            )
        };
        format!(
            "{}×{} samples ({pad}), {:.2} m E-W × {:.2} m N-S",
            self.hf.width, self.hf.height, self.hf.spacing_x, self.hf.spacing_y
        )
    }
}

/// CRC-32 of f32 samples as little-endian bytes, computed on all cores in 16 MiB pieces.
pub fn samples_crc32(samples: &[f32]) -> u32 {
    const PIECE: usize = 4 << 20; // samples
    let pieces: Vec<&[f32]> = samples.chunks(PIECE).collect();
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
        .clamp(1, pieces.len().max(1));
    let per = pieces.len().div_ceil(threads);
    let hashers: Vec<crc32fast::Hasher> = std::thread::scope(|s| {
        let handles: Vec<_> = pieces
            .chunks(per.max(1))
            .map(|group| {
                s.spawn(move || {
                    let mut h = crc32fast::Hasher::new();
                    for p in group {
                        h.update(&le_bytes(p));
                    }
                    h
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("checksum thread"))
            .collect()
    });
    let mut total = crc32fast::Hasher::new();
    for h in &hashers {
        total.combine(h);
    }
    total.finalize()
}

pub(crate) fn le_bytes(s: &[f32]) -> std::borrow::Cow<'_, [u8]> {
    if cfg!(target_endian = "little") {
        std::borrow::Cow::Borrowed(bytemuck::cast_slice(s))
    } else {
        std::borrow::Cow::Owned(s.iter().flat_map(|v| v.to_le_bytes()).collect())
    }
}

/// Loads a dataset: a DEM file ([`load_dem`]) or a folder of SRTM `.hgt`/`.hgt.zip` tiles
/// (stitched), then padded ([`Dataset::from_heightfield`]).
pub fn load_dataset(path: &Path) -> Result<Dataset, DemError> {
    if path.is_dir() {
        let (hf, info) = stitch_folder(path)?;
        Ok(Dataset::from_heightfield(
            hf,
            format!("{} (stitched {})", path.display(), info.describe()),
        ))
    } else {
        let hf = load_dem(path)?;
        Ok(Dataset::from_heightfield(hf, path.display().to_string()))
    }
}

/// Loads and stitches a list of SRTM tiles into one padded dataset.
pub fn load_dataset_tiles(paths: &[PathBuf]) -> Result<Dataset, DemError> {
    let (hf, info) = stitch_tiles(paths)?;
    let first = paths.first().map(|p| p.display().to_string());
    Ok(Dataset::from_heightfield(
        hf,
        format!(
            "{} and {} more (stitched {})",
            first.unwrap_or_default(),
            paths.len().saturating_sub(1),
            info.describe()
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hf(w: usize, h: usize) -> Heightfield {
        Heightfield {
            width: w,
            height: h,
            spacing_x: 10.0,
            spacing_y: 20.0,
            heights: (0..w * h).map(|i| i as f32).collect(),
            geo: None,
            voids_filled: 0,
            spacing_note: String::new(),
        }
    }

    #[test]
    fn padded_sides() {
        assert_eq!(padded_side(2), 2);
        assert_eq!(padded_side(3), 3);
        assert_eq!(padded_side(4), 5);
        assert_eq!(padded_side(17), 17);
        assert_eq!(padded_side(18), 33);
        assert_eq!(padded_side(1201), 2049);
        assert_eq!(padded_side(3601), 4097);
        assert_eq!(padded_side(16385), 16385);
    }

    #[test]
    fn padding_extends_edges_east_and_north() {
        for (w, h) in [(3, 3), (4, 6), (7, 2), (2, 10), (6, 5)] {
            let orig = hf(w, h);
            let ds = Dataset::from_heightfield(orig.clone(), "t".into());
            let (pw, ph) = (padded_side(w), padded_side(h));
            assert_eq!((ds.hf.width, ds.hf.height), (pw, ph));
            assert_eq!(ds.hf.heights.len(), pw * ph);
            for r in 0..ph {
                for c in 0..pw {
                    let want = orig.at(c.min(w - 1), r.min(h - 1));
                    assert_eq!(ds.hf.at(c, r), want, "{w}×{h} at ({c},{r})");
                    assert_eq!(ds.is_padding(c, r), c >= w || r >= h);
                }
            }
            let (kx, ky) = ds.log2_sides();
            assert_eq!(((1 << kx) + 1, (1 << ky) + 1), (pw, ph));
        }
    }

    #[test]
    fn checksum_sees_every_sample() {
        let a = Dataset::from_heightfield(hf(9, 9), "a".into());
        let mut b = a.clone();
        assert_eq!(a.checksum(), b.checksum());
        b.hf.heights[80] += 0.5;
        assert_ne!(a.checksum(), b.checksum());
        // Independent: crc of the little-endian bytes in one go.
        let bytes: Vec<u8> = a.hf.heights.iter().flat_map(|v| v.to_le_bytes()).collect();
        assert_eq!(a.checksum(), crc32fast::hash(&bytes));
        // Many pieces (more than one thread's worth) combine to the same value.
        let big: Vec<f32> = (0..9_000_000).map(|i| (i % 977) as f32).collect();
        let bytes: Vec<u8> = big.iter().flat_map(|v| v.to_le_bytes()).collect();
        assert_eq!(samples_crc32(&big), crc32fast::hash(&bytes));
    }
}
