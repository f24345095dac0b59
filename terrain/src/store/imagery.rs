//! A store's imagery layer (`<name>.aerie-imagery`, beside `<name>.aerie`): draped imagery
//! (issue 17) cut into the same pages as the heights, so the streamer reads a page's imagery
//! with its samples and the renderer uploads it with the level strips. Texel geometry in
//! [`crate::drape::levels`]; the layer is bound to its store by the store's source checksum
//! and sizes, and refused (naming the field) against any other.
//!
//! **File** (little-endian; written front to back, the index last):
//!
//! ```text
//! offset size  field
//!      0    8  magic "AERIEIMG"
//!      8    4  u32 format version (1)
//!     12    4  u32 header size H (= the first page's offset)
//!     16    4  u32 texels per sample k (1, 2 or 4)
//!     20   28  u32 tile size m, page tiles P, levels, width, height (padded), valid width,
//!              valid height — the store's
//!     48    4  u32 the store's source checksum
//!     52    4  u32 page count (= the store's)
//!     56    4  reserved (0)
//!     60    4  u32 CRC-32 of bytes 0..60
//!     64       u32 source count, strings (u32 length + UTF-8): the imagery files
//!  H − 4    4  u32 CRC-32 of bytes 0..H−4
//!      H       pages back to back in the store's index order, each one zstd frame of the
//!              page's RGBA8 texels (straight alpha, sRGB), south row first; a page over
//!              padding only is 0 bytes
//!      I       index, 32 bytes a page: u32 level, px, py, texel columns, texel rows, stored
//!              length; u64 offset (CRC-32 of the stored bytes in the trailer's table below)
//!      C       u32 CRC-32 of each page's stored bytes, in index order
//! size−32  32  trailer: magic "AERIEIMX", u64 index offset I, u32 page count, u32 CRC-32
//!              of the index and its CRC table, u32 reserved (0), u32 CRC-32 of the
//!              trailer's first 28 bytes
//! ```

use std::path::{Path, PathBuf};
use std::sync::Arc;

use aerie_io::{FileSystem, InFile};

use super::error::{PageError, PageId, StoreError};
use super::format::{Layout, StoreHeader};
use super::page_io::read_verified;
use crate::drape::{level_extent, TerrainGrid};

pub const IMAGERY_MAGIC: &[u8; 8] = b"AERIEIMG";
pub const IMAGERY_VERSION: u32 = 1;
const TRAILER_MAGIC: &[u8; 8] = b"AERIEIMX";
const FIXED: usize = 64;
/// Bytes of one index entry.
pub const IMAGERY_ENTRY: usize = 32;
const TRAILER: usize = 32;
const MAX_HEADER: usize = 1 << 20;

/// The layer's file beside a store: `region.aerie` → `region.aerie-imagery`.
pub fn imagery_path(store: &Path) -> PathBuf {
    let mut s = store.as_os_str().to_owned();
    s.push("-imagery");
    PathBuf::from(s)
}

/// What the layer's header says.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageryHeader {
    pub header_size: u32,
    pub texels_per_sample: u32,
    pub tile_size: u32,
    pub page_tiles: u32,
    pub levels: u32,
    pub width: u32,
    pub height: u32,
    pub valid_width: u32,
    pub valid_height: u32,
    pub store_checksum: u32,
    pub page_count: u32,
    pub sources: Vec<String>,
}

impl ImageryHeader {
    /// The header of a layer for `store` at `k` texels per sample.
    pub fn for_store(store: &StoreHeader, k: u32, sources: Vec<String>) -> Self {
        let mut h = Self {
            header_size: 0,
            texels_per_sample: k,
            tile_size: store.tile_size,
            page_tiles: store.page_tiles,
            levels: store.levels,
            width: store.width,
            height: store.height,
            valid_width: store.valid_width,
            valid_height: store.valid_height,
            store_checksum: store.source_checksum,
            page_count: store.page_count,
            sources,
        };
        h.header_size = encode_header(&h).len() as u32;
        h
    }

    /// `Err` naming the first field (and its byte offset) that disagrees with `store`.
    pub fn check_against(&self, store: &StoreHeader) -> Result<(), (u64, &'static str, String)> {
        let fields: [(u64, &'static str, u32, u32); 9] = [
            (20, "tile size", self.tile_size, store.tile_size),
            (24, "page tiles", self.page_tiles, store.page_tiles),
            (28, "levels", self.levels, store.levels),
            (32, "width", self.width, store.width),
            (36, "height", self.height, store.height),
            (40, "valid width", self.valid_width, store.valid_width),
            (44, "valid height", self.valid_height, store.valid_height),
            (
                48,
                "store checksum",
                self.store_checksum,
                store.source_checksum,
            ),
            (52, "page count", self.page_count, store.page_count),
        ];
        for (offset, field, got, want) in fields {
            if got != want {
                return Err((
                    offset,
                    field,
                    format!("{got:#x} here, {want:#x} in the store: this imagery was made for another store (re-run `aerie import --imagery`)"),
                ));
            }
        }
        Ok(())
    }
}

fn put(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_le_bytes());
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}

fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
}

/// The header's bytes (its size field as given: [`ImageryHeader::for_store`] sets it).
pub fn encode_header(h: &ImageryHeader) -> Vec<u8> {
    let mut out = Vec::with_capacity(FIXED + 64);
    out.extend_from_slice(IMAGERY_MAGIC);
    for v in [
        IMAGERY_VERSION,
        h.header_size,
        h.texels_per_sample,
        h.tile_size,
        h.page_tiles,
        h.levels,
        h.width,
        h.height,
        h.valid_width,
        h.valid_height,
        h.store_checksum,
        h.page_count,
        0,
    ] {
        put(&mut out, v);
    }
    let crc = crc32fast::hash(&out);
    put(&mut out, crc);
    put(&mut out, h.sources.len() as u32);
    for s in &h.sources {
        put(&mut out, s.len() as u32);
        out.extend_from_slice(s.as_bytes());
    }
    let crc = crc32fast::hash(&out);
    put(&mut out, crc);
    out
}

/// One page's entry in the index.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImageryEntry {
    pub id: PageId,
    pub cols: u32,
    pub rows: u32,
    pub offset: u64,
    pub len: u32,
    pub crc: u32,
}

pub fn encode_entry(e: &ImageryEntry, out: &mut Vec<u8>) {
    for v in [e.id.level, e.id.px, e.id.py, e.cols, e.rows, e.len] {
        put(out, v);
    }
    out.extend_from_slice(&e.offset.to_le_bytes());
}

/// The trailer: index offset, page count and the CRC-32 of the index with its CRC table.
pub fn encode_trailer(index_offset: u64, pages: u32, index_crc: u32) -> Vec<u8> {
    let mut out = Vec::with_capacity(TRAILER);
    out.extend_from_slice(TRAILER_MAGIC);
    out.extend_from_slice(&index_offset.to_le_bytes());
    put(&mut out, pages);
    put(&mut out, index_crc);
    put(&mut out, 0);
    let crc = crc32fast::hash(&out);
    put(&mut out, crc);
    out
}

/// Texel columns and rows of page `id` of a layer with `k` texels per sample over `grid`
/// (see [`crate::drape::levels`]): the first texel and the counts.
pub fn page_texels(
    layout: &Layout,
    grid: &TerrainGrid,
    k: u32,
    id: PageId,
) -> ([usize; 2], [usize; 2]) {
    let r = layout.rect(id.level, id.px, id.py);
    let (w, h) = level_extent(grid, k, id.level);
    let per = layout.q as usize * k as usize;
    let span = |t0: u32, n: u32, limit: usize| {
        let a = (t0 as usize * per).min(limit);
        let b = ((t0 + n) as usize * per).min(limit);
        (a, b - a)
    };
    let (x0, nx) = span(r.tx0, r.ntx, w);
    let (y0, ny) = span(r.ty0, r.nty, h);
    ([x0, y0], [nx, ny])
}

/// An opened imagery layer: header and index in memory, the file open for page reads.
pub struct ImageryLayer {
    path: PathBuf,
    file: Box<dyn InFile>,
    header: ImageryHeader,
    index: Vec<ImageryEntry>,
    crcs: Vec<u32>,
    layout: Layout,
    grid: TerrainGrid,
}

impl std::fmt::Debug for ImageryLayer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ImageryLayer")
            .field("path", &self.path)
            .field("k", &self.header.texels_per_sample)
            .finish()
    }
}

/// One page's texels, decoded.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageryPage {
    /// The first texel of the level's raster the page holds, and its columns and rows.
    pub origin: [usize; 2],
    pub size: [usize; 2],
    /// RGBA8, row 0 south.
    pub rgba: Vec<u8>,
}

impl ImageryPage {
    pub fn bytes(&self) -> u64 {
        (std::mem::size_of::<Self>() + self.rgba.len()) as u64
    }
}

impl ImageryLayer {
    /// Opens the layer at `path` for `store` (header, index, trailer; nothing proportional to
    /// the texels). Refuses, naming the byte offset and field: not a layer, another version,
    /// corrupt header, index or trailer, a layer made for another store, pages whose sizes
    /// disagree with the store's layout.
    pub fn open_in(
        fs: Arc<dyn FileSystem>,
        path: &Path,
        store: &StoreHeader,
        layout: &Layout,
        grid: &TerrainGrid,
    ) -> Result<Self, StoreError> {
        let io = |e: std::io::Error| StoreError::Io {
            path: path.to_path_buf(),
            reason: e.to_string(),
        };
        let fmt = |offset: u64, field: &'static str, reason: String| StoreError::Format {
            path: path.to_path_buf(),
            offset,
            field,
            reason,
        };
        let file = fs.open(path).map_err(io)?;
        let len = file.len().map_err(io)?;
        if len < (FIXED + TRAILER) as u64 {
            return Err(fmt(
                0,
                "header",
                format!("{len} bytes: not an imagery layer (truncated)"),
            ));
        }
        let mut fixed = vec![0u8; FIXED];
        file.read_exact_at(&mut fixed, 0).map_err(io)?;
        if &fixed[..8] != IMAGERY_MAGIC {
            return Err(fmt(0, "magic", "not an aerie imagery layer".into()));
        }
        let version = u32_at(&fixed, 8);
        if version != IMAGERY_VERSION {
            return Err(fmt(
                8,
                "version",
                format!("version {version}; this aerie reads {IMAGERY_VERSION}"),
            ));
        }
        if crc32fast::hash(&fixed[..60]) != u32_at(&fixed, 60) {
            return Err(fmt(60, "header CRC", "the fixed header is corrupt".into()));
        }
        let size = u32_at(&fixed, 12) as usize;
        if !(FIXED + 8..=MAX_HEADER).contains(&size) || size as u64 + TRAILER as u64 > len {
            return Err(fmt(
                12,
                "header size",
                format!("{size} bytes in a {len}-byte file"),
            ));
        }
        let mut hb = vec![0u8; size];
        file.read_exact_at(&mut hb, 0).map_err(io)?;
        if crc32fast::hash(&hb[..size - 4]) != u32_at(&hb, size - 4) {
            return Err(fmt(
                size as u64 - 4,
                "header CRC",
                "the source list is corrupt".into(),
            ));
        }
        let mut at = FIXED;
        let count = u32_at(&hb, at) as usize;
        at += 4;
        let mut sources = Vec::new();
        for _ in 0..count {
            let n = if at + 4 <= size - 4 {
                u32_at(&hb, at) as usize
            } else {
                usize::MAX
            };
            if n > size - 4 - (at + 4) {
                return Err(fmt(
                    at as u64,
                    "sources",
                    "a source name runs past the header".into(),
                ));
            }
            sources.push(String::from_utf8_lossy(&hb[at + 4..at + 4 + n]).into_owned());
            at += 4 + n;
        }
        let header = ImageryHeader {
            header_size: size as u32,
            texels_per_sample: u32_at(&fixed, 16),
            tile_size: u32_at(&fixed, 20),
            page_tiles: u32_at(&fixed, 24),
            levels: u32_at(&fixed, 28),
            width: u32_at(&fixed, 32),
            height: u32_at(&fixed, 36),
            valid_width: u32_at(&fixed, 40),
            valid_height: u32_at(&fixed, 44),
            store_checksum: u32_at(&fixed, 48),
            page_count: u32_at(&fixed, 52),
            sources,
        };
        let k = header.texels_per_sample;
        if !k.is_power_of_two() || k > crate::drape::MAX_STORE_TEXELS_PER_SAMPLE {
            return Err(fmt(16, "texels per sample", format!("{k} (1, 2 or 4)")));
        }
        header
            .check_against(store)
            .map_err(|(o, f, r)| fmt(o, f, r))?;
        let mut tb = [0u8; TRAILER];
        file.read_exact_at(&mut tb, len - TRAILER as u64)
            .map_err(io)?;
        let t_at = len - TRAILER as u64;
        if &tb[..8] != TRAILER_MAGIC || crc32fast::hash(&tb[..28]) != u32_at(&tb, 28) {
            return Err(fmt(
                t_at,
                "trailer",
                "no intact trailer at the end: truncated or corrupt".into(),
            ));
        }
        let index_at = u64_at(&tb, 8);
        let pages = u32_at(&tb, 16) as usize;
        let index_len = (IMAGERY_ENTRY + 4) * pages;
        if pages != store.page_count as usize
            || index_at.checked_add(index_len as u64) != Some(t_at)
        {
            return Err(fmt(
                t_at + 8,
                "index offset",
                format!("{pages} pages at byte {index_at} do not end at the trailer (byte {t_at})"),
            ));
        }
        let mut ib = vec![0u8; index_len];
        file.read_exact_at(&mut ib, index_at).map_err(io)?;
        if crc32fast::hash(&ib) != u32_at(&tb, 20) {
            return Err(fmt(
                index_at,
                "index",
                "checksum mismatch: the index is corrupt".into(),
            ));
        }
        let mut index = Vec::with_capacity(pages);
        let mut crcs = Vec::with_capacity(pages);
        let mut next = u64::from(header.header_size);
        for i in 0..pages {
            let b = &ib[i * IMAGERY_ENTRY..];
            let e = ImageryEntry {
                id: PageId {
                    level: u32_at(b, 0),
                    px: u32_at(b, 4),
                    py: u32_at(b, 8),
                },
                cols: u32_at(b, 12),
                rows: u32_at(b, 16),
                len: u32_at(b, 20),
                offset: u64_at(b, 24),
                crc: u32_at(&ib, IMAGERY_ENTRY * pages + 4 * i),
            };
            let off = index_at + (i * IMAGERY_ENTRY) as u64;
            let (l, px, py) = layout.page_at(i).expect("page count checked");
            if (e.id.level, e.id.px, e.id.py) != (l, px, py) {
                return Err(fmt(
                    off,
                    "page",
                    format!(
                        "entry {i} is {}, the store's is level {l} page ({px}, {py})",
                        e.id
                    ),
                ));
            }
            let (_, [nx, ny]) = page_texels(layout, grid, k, e.id);
            if (e.cols as usize, e.rows as usize) != (nx, ny) {
                return Err(fmt(
                    off + 12,
                    "texels",
                    format!(
                        "{}: {}×{} texels, the layout says {nx}×{ny}",
                        e.id, e.cols, e.rows
                    ),
                ));
            }
            if e.offset != next {
                return Err(fmt(
                    off + 24,
                    "offset",
                    format!("{}: at byte {}, expected {next}", e.id, e.offset),
                ));
            }
            next += u64::from(e.len);
            crcs.push(e.crc);
            index.push(e);
        }
        if next != index_at {
            return Err(fmt(
                index_at,
                "index",
                format!("the pages end at byte {next}, the index starts at {index_at}"),
            ));
        }
        Ok(Self {
            path: path.to_path_buf(),
            file,
            header,
            index,
            crcs,
            layout: layout.clone(),
            grid: grid.clone(),
        })
    }

    pub fn header(&self) -> &ImageryHeader {
        &self.header
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    pub fn texels_per_sample(&self) -> u32 {
        self.header.texels_per_sample
    }

    /// The store's page layout the layer follows.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The store's level-0 grid the layer is draped on.
    pub fn grid(&self) -> &TerrainGrid {
        &self.grid
    }

    /// Pages in the layer (the store's page count).
    pub fn page_count(&self) -> usize {
        self.index.len()
    }

    /// Bytes of every page as stored (compressed).
    pub fn stored_bytes(&self) -> u64 {
        self.index.iter().map(|e| u64::from(e.len)).sum()
    }

    /// Bytes of every page's decoded texels.
    pub fn texel_bytes(&self) -> u64 {
        self.index
            .iter()
            .map(|e| 4 * u64::from(e.cols) * u64::from(e.rows))
            .sum()
    }

    /// Bytes the decoded page `id` will hold ([`ImageryPage::bytes`]).
    pub fn page_bytes(&self, id: PageId) -> u64 {
        let (_, [nx, ny]) = page_texels(&self.layout, &self.grid, self.texels_per_sample(), id);
        (std::mem::size_of::<ImageryPage>() + 4 * nx * ny) as u64
    }

    /// Reads, verifies (CRC-32, size) and decodes page `id` (its index position is the
    /// store's); errors name the layer, the page and its bytes.
    pub fn read_page(&self, id: PageId) -> Result<ImageryPage, PageError> {
        let e = self
            .layout
            .position(id.level, id.px, id.py)
            .and_then(|i| self.index.get(i).map(|e| (i, *e)))
            .ok_or_else(|| PageError::NoSuchPage {
                path: self.path.clone(),
                page: id,
                reason: "not in the imagery index".into(),
            });
        let (i, e) = e?;
        let (origin, _) = page_texels(&self.layout, &self.grid, self.texels_per_sample(), id);
        let (offset, end) = (e.offset, e.offset + u64::from(e.len));
        let size = [e.cols as usize, e.rows as usize];
        let want = 4 * size[0] * size[1];
        if e.len == 0 {
            return Ok(ImageryPage {
                origin,
                size,
                rgba: vec![0; want],
            });
        }
        let buf = read_verified(&*self.file, &self.path, id, offset, e.len, self.crcs[i])?;
        let content = |reason: String| PageError::Content {
            path: self.path.clone(),
            page: id,
            offset,
            end,
            reason,
        };
        let rgba = zstd::bulk::decompress(&buf, want)
            .map_err(|err| content(format!("cannot decompress: {err}")))?;
        if rgba.len() != want {
            return Err(content(format!(
                "{} bytes of texels, the index says {}×{} texels ({want} bytes)",
                rgba.len(),
                size[0],
                size[1]
            )));
        }
        Ok(ImageryPage { origin, size, rgba })
    }
}
