//! The index (one 32-byte entry per page, in layout order, checked against the header) and
//! the trailer at the end of the file that locates it.

use super::error::PageId;
use super::format::{
    field_err, Coding, FieldError, Layout, PageEntry, Put, StoreHeader, INDEX_ENTRY,
};

/// One index entry as bytes.
pub fn encode_entry(e: &PageEntry, out: &mut Vec<u8>) {
    let mut p = Put(std::mem::take(out));
    p.u32(e.level);
    p.u32(e.px);
    p.u32(e.py);
    p.u32(e.coding.code());
    p.u64(e.offset);
    p.u32(e.len);
    p.u32(e.crc);
    *out = p.0;
}

/// Bytes of the trailer that ends every store.
pub const TRAILER: usize = 48;
/// First 8 bytes of the trailer.
pub const TRAILER_MAGIC: &[u8; 8] = b"AERIEIDX";

/// Where the trailer says the index and the bake section are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Trailer {
    pub index_offset: u64,
    /// CRC-32 of the index entries.
    pub index_crc: u32,
    /// The bake section: first byte, stored (compressed) length, CRC-32 of the stored bytes.
    pub bake_offset: u64,
    pub bake_len: u64,
    pub bake_crc: u32,
}

/// The trailer: magic, index offset, page count, CRC-32 of the index entries, the bake
/// section's offset, length and CRC-32, its own CRC.
pub fn encode_trailer(t: &Trailer, pages: u32) -> Vec<u8> {
    let mut p = Put(TRAILER_MAGIC.to_vec());
    p.u64(t.index_offset);
    p.u32(pages);
    p.u32(t.index_crc);
    p.u64(t.bake_offset);
    p.u64(t.bake_len);
    p.u32(t.bake_crc);
    let crc = crc32fast::hash(&p.0);
    p.u32(crc);
    p.0
}

/// The trailer (the last [`TRAILER`] bytes of a `len`-byte file), checked against the
/// header: the pages, then the bake section, then the index, which ends where the trailer
/// starts.
pub fn decode_trailer(b: &[u8], len: u64, h: &StoreHeader) -> Result<Trailer, FieldError> {
    let at = (len - TRAILER as u64) as usize;
    let u32_at = |k: usize| u32::from_le_bytes(b[k..k + 4].try_into().expect("4"));
    let u64_at = |k: usize| u64::from_le_bytes(b[k..k + 8].try_into().expect("8"));
    if &b[..8] != TRAILER_MAGIC || crc32fast::hash(&b[..TRAILER - 4]) != u32_at(TRAILER - 4) {
        return Err(field_err(
            at,
            "trailer",
            "the last 48 bytes are not a store trailer: the file is truncated or was not completely written",
        ));
    }
    let t = Trailer {
        index_offset: u64_at(8),
        index_crc: u32_at(20),
        bake_offset: u64_at(24),
        bake_len: u64_at(32),
        bake_crc: u32_at(40),
    };
    let pages = u32_at(16);
    if pages != h.page_count {
        return Err(field_err(
            at + 16,
            "trailer page count",
            format!(
                "{pages} pages in the trailer, {} in the header",
                h.page_count
            ),
        ));
    }
    let index_len = INDEX_ENTRY as u64 * u64::from(pages);
    if t.index_offset < h.data_offset || t.index_offset.checked_add(index_len) != Some(at as u64) {
        return Err(field_err(
            at + 8,
            "index offset",
            format!(
                "an index of {pages} pages at byte {} does not end at the trailer (byte {at}) after the header ({} bytes)",
                t.index_offset, h.data_offset
            ),
        ));
    }
    if t.bake_offset < h.data_offset
        || t.bake_offset.checked_add(t.bake_len) != Some(t.index_offset)
    {
        return Err(field_err(
            at + 24,
            "bake section",
            format!(
                "a bake section of {} bytes at byte {} does not end at the index (byte {}) after the header ({} bytes)",
                t.bake_len, t.bake_offset, t.index_offset, h.data_offset
            ),
        ));
    }
    Ok(t)
}

/// Index entries from their bytes (`b`, at byte `base` of the file, the trailer's CRC
/// `want`), each checked against the layout: at its position, the pages back to back from
/// the header's end to `pages_end` (the bake section).
pub fn decode_index(
    b: &[u8],
    base: u64,
    want: u32,
    pages_end: u64,
    h: &StoreHeader,
    layout: &Layout,
) -> Result<Vec<PageEntry>, FieldError> {
    let n = h.page_count as usize;
    debug_assert_eq!(b.len(), n * INDEX_ENTRY);
    let at = |k: usize| (base + k as u64) as usize;
    let got = crc32fast::hash(b);
    if got != want {
        return Err(field_err(
            at(0),
            "index CRC-32",
            format!("the index has CRC-32 {got:#010x}, the trailer says {want:#010x}: the index is corrupt"),
        ));
    }
    let mut out = Vec::with_capacity(n);
    let mut next = h.data_offset;
    for (i, e) in b.chunks_exact(INDEX_ENTRY).enumerate() {
        let u = |k: usize| u32::from_le_bytes(e[k..k + 4].try_into().expect("4"));
        let (level, px, py) = (u(0), u(4), u(8));
        let off = at(i * INDEX_ENTRY);
        let (wl, wx, wy) = layout.page_at(i).expect("i < page count");
        if (level, px, py) != (wl, wx, wy) {
            return Err(field_err(
                off,
                "index entry",
                format!("entry {i} names level {level} page ({px}, {py}); the header's layout puts level {wl} page ({wx}, {wy}) there"),
            ));
        }
        let coding = Coding::from_code(u(12)).ok_or_else(|| {
            field_err(
                off + 12,
                "page coding",
                format!(
                    "entry {i}: coding {} is not 0 (i16), 1 (f32) or 2 (i16 + exceptions)",
                    u(12)
                ),
            )
        })?;
        let offset = u64::from_le_bytes(e[16..24].try_into().expect("8"));
        let len = u(24);
        if offset != next {
            return Err(field_err(
                off + 16,
                "page offset",
                format!(
                    "entry {i} ({}) starts at byte {offset}, the previous page ends at {next}",
                    PageId { level, px, py }
                ),
            ));
        }
        next = offset + u64::from(len);
        if next > pages_end {
            return Err(field_err(
                off + 24,
                "page length",
                format!("entry {i} ends at byte {next}, past the start of the bake section ({pages_end})"),
            ));
        }
        out.push(PageEntry {
            level,
            px,
            py,
            coding,
            offset,
            len,
            crc: u(28),
        });
    }
    if next != pages_end {
        return Err(field_err(
            at(0),
            "index",
            format!("the pages end at byte {next}, the bake section starts at {pages_end}"),
        ));
    }
    Ok(out)
}
