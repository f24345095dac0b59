//! Opening a store (header + index only) and reading its pages with positioned reads.
//!
//! Positioned reads (`pread`), not a memory map: a page read that fails (a truncated or
//! damaged file, an I/O error) is an error value naming the page, where a mapped page would be
//! `SIGBUS`; pages are read once into the cache, so a map saves nothing; and worker threads can
//! share one descriptor without a seek position.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use aerie_io::{FileSystem, InFile};

use super::bake_section;
use super::error::{PageError, PageId, StoreError};
use super::format::{
    check_fixed, check_layout, decode_header, FieldError, Layout, PageEntry, StoreHeader,
    FIXED_HEADER, INDEX_ENTRY,
};
use super::index::{decode_index, decode_trailer, Trailer, TRAILER};
use super::page_io::read_verified;
use super::pages::{decode_payload, Page};
use crate::bake::ErrorBake;

/// An opened store: its header, layout and index in memory, the file open for page reads.
pub struct Store {
    path: PathBuf,
    file: Box<dyn InFile>,
    header: StoreHeader,
    layout: Layout,
    index: Vec<PageEntry>,
    trailer: Trailer,
    open_bytes: u64,
    file_len: u64,
}

impl std::fmt::Debug for Store {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Store")
            .field("path", &self.path)
            .field("pages", &self.index.len())
            .finish()
    }
}

impl Store {
    /// Opens `path`: reads and checks the header, the trailer and the index, nothing else (see
    /// [`Store::open_bytes`]). Refuses, naming the byte offset and the reason: not a store, a
    /// newer format version, a corrupt header, trailer or index, a truncated file (no
    /// trailer at its end), a header whose sizes disagree with its index.
    pub fn open(path: &Path) -> Result<Store, StoreError> {
        Self::open_in(aerie_io::real(), path)
    }

    /// [`Store::open`] through `fs`.
    pub fn open_in(fs: Arc<dyn FileSystem>, path: &Path) -> Result<Store, StoreError> {
        let io = |e: std::io::Error| StoreError::Io {
            path: path.to_path_buf(),
            reason: e.to_string(),
        };
        let fmt = |e: FieldError| StoreError::Format {
            path: path.to_path_buf(),
            offset: e.offset,
            field: e.field,
            reason: e.reason,
        };
        let file = fs.open(path).map_err(io)?;
        let len = file.len().map_err(io)?;
        let mut fixed = vec![0u8; FIXED_HEADER.min(len as usize)];
        file.read_exact_at(&mut fixed, 0).map_err(io)?;
        let size = check_fixed(&fixed).map_err(fmt)? as u64;
        if len < size {
            return Err(fmt(FieldError {
                offset: 12,
                field: "header size",
                reason: format!("the header is {size} bytes, the file only {len}: truncated"),
            }));
        }
        let mut hb = vec![0u8; size as usize];
        file.read_exact_at(&mut hb, 0).map_err(io)?;
        let header = decode_header(&hb).map_err(fmt)?;
        let layout = check_layout(&header).map_err(fmt)?;
        if len < size + TRAILER as u64 {
            return Err(fmt(FieldError {
                offset: len,
                field: "trailer",
                reason: format!(
                    "the file ends at byte {len}, right after its {size}-byte header: truncated, no index"
                ),
            }));
        }
        let mut tb = [0u8; TRAILER];
        file.read_exact_at(&mut tb, len - TRAILER as u64)
            .map_err(io)?;
        let trailer = decode_trailer(&tb, len, &header).map_err(fmt)?;
        let index_at = trailer.index_offset;
        let index_len = INDEX_ENTRY as u64 * u64::from(header.page_count);
        let mut ib = vec![0u8; index_len as usize];
        file.read_exact_at(&mut ib, index_at).map_err(io)?;
        let index = decode_index(
            &ib,
            index_at,
            trailer.index_crc,
            trailer.bake_offset,
            &header,
            &layout,
        )
        .map_err(fmt)?;
        Ok(Store {
            path: path.to_path_buf(),
            file,
            header,
            layout,
            index,
            trailer,
            open_bytes: size + index_len + TRAILER as u64,
            file_len: len,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    pub fn header(&self) -> &StoreHeader {
        &self.header
    }

    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The index, in layout order (level 0 first, then row-major pages).
    pub fn pages(&self) -> &[PageEntry] {
        &self.index
    }

    /// Size of the file at open.
    pub fn file_len(&self) -> u64 {
        self.file_len
    }

    /// Bytes `open` read: the header, the index (32 bytes a page: ≈ 1/2000 of the f32
    /// samples at m = 17 with 8 × 8-tile pages) and the trailer, never a page.
    pub fn open_bytes(&self) -> u64 {
        self.open_bytes
    }

    /// Bytes of the bake section as stored (what [`Store::read_bake`] reads).
    pub fn bake_bytes(&self) -> u64 {
        self.trailer.bake_len
    }

    /// Reads, verifies (CRC-32) and decodes the bake section: every level's ε and level 0's
    /// min/max, the whole [`ErrorBake`] the selection needs, without reading a page. Refuses,
    /// naming the byte offset and the reason, a section whose bytes fail the checksum, do not
    /// decompress to the layout's size, or hold no bake numbers.
    pub fn read_bake(&self) -> Result<ErrorBake, StoreError> {
        let t = self.trailer;
        let fmt = |reason: String| StoreError::Format {
            path: self.path.clone(),
            offset: t.bake_offset,
            field: "bake section",
            reason,
        };
        let mut buf = vec![0u8; t.bake_len as usize];
        self.file
            .read_exact_at(&mut buf, t.bake_offset)
            .map_err(|e| StoreError::Io {
                path: self.path.clone(),
                reason: format!(
                    "bake section at bytes {}..{}: {e}",
                    t.bake_offset,
                    t.bake_offset + t.bake_len
                ),
            })?;
        let got = crc32fast::hash(&buf);
        if got != t.bake_crc {
            return Err(fmt(format!(
                "{} bytes with CRC-32 {got:#010x}, the trailer says {:#010x}: the bake section is corrupt",
                t.bake_len, t.bake_crc
            )));
        }
        let raw = zstd::bulk::decompress(
            &buf,
            bake_section::raw_len(&self.layout, self.header.version),
        )
        .map_err(|e| fmt(format!("cannot decompress: {e}")))?;
        bake_section::decode(&raw, &self.header, &self.layout).map_err(fmt)
    }

    /// The index entry of a page.
    pub fn entry(&self, id: PageId) -> Result<&PageEntry, PageError> {
        self.layout
            .position(id.level, id.px, id.py)
            .map(|i| &self.index[i])
            .ok_or_else(|| PageError::NoSuchPage {
                path: self.path.clone(),
                page: id,
                reason: match self.layout.levels.get(id.level as usize) {
                    None => format!("the store has {} levels", self.header.levels),
                    Some(l) => format!("level {} has {}×{} pages", id.level, l.pages_x, l.pages_y),
                },
            })
    }

    /// Reads, verifies (CRC-32) and decodes one page. Never panics on bad bytes: a short read,
    /// a checksum mismatch or content that disagrees with the index is an error naming the page.
    pub fn read_page(&self, id: PageId) -> Result<Page, PageError> {
        let e = *self.entry(id)?;
        let (offset, end) = (e.offset, e.offset + u64::from(e.len));
        let buf = read_verified(&*self.file, &self.path, id, offset, e.len, e.crc)?;
        let content = |reason: String| PageError::Content {
            path: self.path.clone(),
            page: id,
            offset,
            end,
            reason,
        };
        let raw_len = self.layout.raw_len(id.level, id.px, id.py, e.coding);
        let raw = zstd::bulk::decompress(&buf, raw_len)
            .map_err(|err| content(format!("cannot decompress: {err}")))?;
        decode_payload(&raw, &self.layout, id, e.coding).map_err(content)
    }
}
