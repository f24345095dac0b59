//! The exact offline error bake (DESIGN.md, "The terrain technique", **Error**).
//!
//! For every clipmap level `L` (0 = finest) and every tile of `m × m` level-`L` vertices
//! (`m = 2^j + 1`), the bake stores
//!
//! ```text
//! ε(L, tile) = max |h(p) − ĥ_L(p)|   over every full-resolution sample p of the tile, edges included
//! ```
//!
//! where `ĥ_L` is the piecewise-linear surface of the level-`L` triangles: level-`L` vertices are
//! every `2^L` samples, each level-`L` cell (`2^L × 2^L` samples) is split by
//! [`mesh::TILE_DIAGONAL`](super::mesh::TILE_DIAGONAL) and evaluated with
//! [`mesh::quad_surface`](super::mesh::quad_surface) — the same function that defines the GPU
//! mesh's triangles — at `u = i / 2^L`, `v = j / 2^L` (exact binary fractions). It measures ε
//! over each of the tile's four quadrants (the level-(L−1) tiles it covers, edges included):
//! a quadrant drawn at its parent's resolution has that error
//! ([`LevelTable::coarse_eps`]), and the tile's ε is the largest of the four. At levels
//! L ≥ 2 it measures ε over each of the tile's 16 blocks (4 × 4, the level-(L−2) tiles it
//! covers, edges included: a sample on a block boundary belongs to both blocks): a block
//! drawn at its grandparent's resolution has that error ([`LevelTable::fine_eps`]), and a
//! quadrant's ε is the largest of its 2 × 2 blocks' (exactly: the same samples, the same
//! values). It also stores the min/max full-resolution height per tile (for culling boxes)
//! and whether the tile holds any real (non-padding) sample.
//!
//! **Padding.** Padding samples are part of the surface and of every tile that also holds a
//! real sample (their ε includes them). Tiles made only of padding are not terrain
//! (`terrain = false`): their ε is not measured and is stored as 0, and so are their quadrants'
//! and blocks'. Every real sample lies in a
//! terrain tile at every level, so [`ErrorBake::eps_refined`] still bounds the error at every
//! real sample; it ignores the error over padding-only subtiles.
//!
//! **Tiles.** Level-`L` tile `(tx, ty)` covers samples `cols tx·(m−1)·2^L ..= (tx+1)·(m−1)·2^L`
//! and the same for rows; neighbouring tiles share their edge samples. The dataset is padded to
//! `(2^Kx+1) × (2^Ky+1)` ([`Dataset`](crate::dataset::Dataset)), so every level has whole tiles:
//! `tiles_x = 2^Kx / ((m−1)·2^L)`. Levels `0 ..= min(Kx, Ky) − j` fit.
//!
//! **Numbers.** Heights are f32; `quad_surface` and the differences are evaluated in f64 and
//! each tile's maximum is rounded **up** to the next f32, so a stored ε is never below the f64
//! value and exceeds it by at most one f32 ulp. The f64 value is exact for heights on a coarse
//! grid (integer metres: SRTM, int16 GeoTIFF) and otherwise within a few f64 ulps of max |h|
//! (≈ 1e-12 m), far below the f32 rounding step. Level-0 ε is 0 (the surface is the samples).
//! The loops are written for speed (row-wise, AVX2 when the CPU has it) but perform the same
//! IEEE operations as calling `quad_surface` per sample, bit for bit (unit-tested).
//!
//! **File** (`<dataset name>.aerie-bake`, little-endian, [`write_bake`] / [`read_bake`]):
//!
//! ```text
//! offset size  field
//!      0    8  magic "AERIEBAK"
//!      8    4  u32 format version (3; version 2 kept only the quadrants, version 1 one ε
//!              per tile: an older file is replaced on first use, saying why)
//!     12    4  u32 header size in bytes (96)
//!     16    4  u32 m, tile side in vertices (2^j + 1)
//!     20    4  u32 number of levels
//!     24    4  u32 width  (padded samples per row)
//!     28    4  u32 height (padded rows)
//!     32    4  u32 valid_width  (real samples per row; columns ≥ it are padding)
//!     36    4  u32 valid_height (real rows; rows ≥ it are padding)
//!     40    8  f64 spacing_x, metres
//!     48    8  f64 spacing_y, metres
//!     56    4  u32 source checksum: CRC-32 of the padded samples as f32 LE (Dataset::checksum)
//!     60    4  u32 flags (0)
//!     64    8  u64 file size in bytes, trailing CRC included
//!     72   20  reserved (0)
//!     92    4  u32 CRC-32 of bytes 0..92
//!     96       level sections, level 0 first; n = tiles_x · tiles_y, arrays row-major by tile
//!              (index ty · tiles_x + tx):
//!              +0 u32 level (= L)     +4 u32 tiles_x     +8 u32 tiles_y     +12 u32 0
//!              level 0:  +16 f32[n] min height    +16+4n f32[n] max height
//!              level 1:  +16 f32[4n] ε of the level-1 surface over each level-0 tile,
//!                        row-major over level 0's tiles (each tile's quadrants)
//!              level ≥2: +16 f32[16n] ε of the level-L surface over each level-(L−2) tile,
//!                        row-major over level L−2's tiles (each tile's 4 × 4 blocks)
//! size−4    4  u32 CRC-32 of bytes 0..size−4
//! ```
//!
//! Only what is measured is stored: level-0 ε is 0, a quadrant's ε at levels ≥ 2 is the
//! largest of its blocks', a level-L tile's ε the largest of its quadrants', its min/max is
//! that of its 2×2 level-(L−1) children, and the terrain flag follows from the real size, so
//! the reader derives those. Per level-0 tile that is 8 B of min/max, 4 B of level-1
//! quadrants and ≈ 16/3 B of blocks over all levels ≥ 2: at m = 17 (a level-0 tile is 1 KiB
//! of f32 samples) the file is ≈ 1.7 % of the (padded) dataset's f32 size (format 2: 1.3 %).
//! Reading checks magic, version, sizes, both CRCs, that every ε is a finite number ≥ 0 (naming
//! the level, the tile and the byte offset), then the dataset (sizes, spacing, checksum):
//! every failure names the file, the field or byte offset and the reason, and says to re-run
//! `aerie bake`.

mod error;
pub(crate) mod exact;
mod file;
mod format;
mod table;

pub use error::BakeError;
pub use exact::{bake, round_up_f32};
pub use file::{
    bake_path_for, check_existing, load_or_bake, read_bake, read_bake_file, write_bake,
    write_bake_in, BakeOutcome, Existing,
};
pub use format::{BAKE_EXTENSION, BAKE_MAGIC, BAKE_VERSION, HEADER_SIZE};
pub use table::{
    report_csv, BakeParams, ErrorBake, LevelStats, LevelTable, MeasuredBake, MeasuredEps,
    REPORT_CSV_HEADER,
};

#[cfg(test)]
mod file_tests;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod write_tests;
