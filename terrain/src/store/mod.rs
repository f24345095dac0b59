//! The tile store (`<name>.aerie`): a dataset imported once into pages of every clipmap
//! level, each with its tiles' baked ε and min/max, coded losslessly, compressed and
//! checksummed, so that terrain larger than memory can be read page by page.
//!
//! **Levels and pages.** Level `L` is the exact power-of-two subsampling of level 0 (sample
//! (c, r) of level L = level-0 sample (c·2^L, r·2^L)), cut like the bake's tiles (`m = 2^j + 1`
//! vertices, `q = m − 1` quads, neighbours share edges) into pages of `P × P` tiles (P a power
//! of two, default 8): page (px, py) of level L holds tiles `px·P ..` (fewer at the level's
//! east/north edge) and their `(ntx·q + 1) × (nty·q + 1)` samples, edges included, so a page
//! stands alone. Per tile it carries ε, min and max exactly as [`crate::bake::bake`] computes
//! them (the import bakes in memory and copies the tables; one implementation). Level-0 page
//! (px, py) lies in level-L page (px >> L, py >> L).
//!
//! **File** (little-endian; written front to back in one pass, the index last):
//!
//! ```text
//! offset size  field
//!      0    8  magic "AERIESTO"
//!      8    4  u32 format version (4; 3 and 2 are read too, their bake sections holding
//!              the quadrants' ε only or one ε per tile; version 1 had no bake section and
//!              is refused with a message to re-import; a newer one is refused)
//!     12    4  u32 header size H (= the first page's offset)
//!     16   32  u32 tile size m, page tiles P, levels, width, height (padded), valid width,
//!              valid height, page count
//!     48   16  f64 spacing x, spacing y (metres)
//!     64    4  u32 source checksum (CRC-32 of the padded level-0 samples, Dataset::checksum)
//!     68    4  u32 flags (0)
//!     72    8  u64 voids filled
//!     80    8  u64 data offset (= H)
//!     88    8  u64 bytes of the pages' samples as f32 (for the ratio)
//!     96   28  reserved (0)
//!    124    4  u32 CRC-32 of bytes 0..124
//!    128       geo-reference: u32 kind (0 none; 1 geographic: f64 south lat, west lon,
//!              dlat, dlon in degrees; 2 projected: string CRS, f64 easting, northing),
//!              string spacing note, u32 source count, strings (u32 length + UTF-8),
//!              u32 levels, f32 max ε per level (terrain tiles)
//!  H − 4    4  u32 CRC-32 of bytes 0..H−4
//!      H       pages back to back, in index order, each one zstd frame of:
//!              u32 level, px, py, coding; f32 ε[n], min[n], max[n] (n tiles, row-major);
//!              samples, south row first: coding 0 = i16 residuals of the gradient predictor
//!              (west + south − south-west, wrapping), zigzag, u16 each (every sample an
//!              exact i16, -0.0 excluded); coding 2 = the same of the samples rounded, then
//!              u32 k and k × (u32 index, u32 f32 bits) restoring the exact value of each
//!              sample that is not an exact i16 (chosen when k ≤ samples / 8); coding 1 = f32
//!              bits XOR the west neighbour's (south for column 0), as 4 byte planes.
//!      B       bake section, one zstd frame: per level L = 1 … L−1 the f32 ε of the
//!              level-L surface over each level-0 tile at L = 1 (its tiles' quadrants) and
//!              over each level-(L−2) tile at L ≥ 2 (its tiles' 16 blocks; version 3: over
//!              each level-(L−1) tile at every level; version 2: ε per level-L tile), then
//!              level 0's min and max per tile (row-major), each array as bits XOR the
//!              previous value, in 4 byte planes (`bake_section`)
//!      I       index, one 32-byte entry per page, level 0 first, pages row-major:
//!              u32 level, px, py, coding; u64 offset; u32 stored length; u32 CRC-32 of
//!              the stored bytes
//! size−48  48  trailer: magic "AERIEIDX", u64 index offset I, u32 page count, u32 CRC-32
//!              of the index entries, u64 bake offset B, u64 bake length, u32 CRC-32 of the
//!              bake section's stored bytes, u32 CRC-32 of the trailer's first 44 bytes
//! ```
//!
//! **Reading.** [`Store::open`] reads the header, the trailer and the index only (≈ 1/2000 of
//! the samples as f32); [`Store::read_bake`] the bake section only (≈ 1/75 of the file),
//! which is the whole [`crate::bake::ErrorBake`] the selection needs. Open refuses
//! (naming the byte offset and the reason) a bad magic, a newer version, a corrupt header,
//! trailer or index, a header whose sizes disagree with the index, a truncated file (its end
//! is not a trailer). [`Store::read_page`] reads
//! one page with a positioned read and verifies its CRC and content; a bad page is a
//! [`PageError`] naming it, never a panic. [`StoreSource`] serves the host's queries from the
//! resident pages.
//!
//! Files: `format` (bytes of the header, the page layout), `index` (the index entries and the
//! trailer), `bake_section`, `pages` (cutting and coding a page), `write` (the import
//! writer), `read` (open, the bake, page reads), `source` (queries);
//! tests in `tests` (round trips, queries) and `damage_tests` (damaged files, failed writes).

mod bake_section;
mod consistency;
mod error;
mod format;
mod imagery;
mod imagery_level;
mod imagery_rect;
mod imagery_write;
mod index;
mod load;
mod page_io;
mod pages;
mod read;
mod rows_import;
mod source;
mod write;

pub use error::{PageError, PageId, StoreError};
pub use format::{
    Coding, Layout, LevelLayout, PageEntry, PageRect, StoreHeader, DEFAULT_PAGE_TILES,
    FIXED_HEADER, INDEX_ENTRY, STORE_EXTENSION, STORE_MAGIC, STORE_VERSION,
};
pub use imagery::{imagery_path, ImageryHeader, ImageryLayer, ImageryPage, IMAGERY_MAGIC};
pub use imagery_level::{choose_level, open_imagery_beside, read_level, LevelImagery};
pub use imagery_rect::{copy_page_texels, imagery_rect, ImageryRect};
pub use imagery_write::{store_grid, write_imagery_in, ImagerySummary};
pub use load::load_store;
pub use pages::Page;
pub use read::Store;
pub use rows_import::{bake_rows, write_store_rows, write_store_rows_in};
pub use source::StoreSource;
pub use write::{write_store, write_store_in, ImportParams, StoreSummary};

#[cfg(test)]
mod consistency_tests;
#[cfg(test)]
mod damage_tests;
#[cfg(test)]
mod imagery_tests;
#[cfg(test)]
mod rows_import_tests;
#[cfg(test)]
mod tests;
