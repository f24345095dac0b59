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
pub const TRAILER: usize = 32;
/// First 8 bytes of the trailer.
pub const TRAILER_MAGIC: &[u8; 8] = b"AERIEIDX";

/// The trailer: magic, index offset, page count, CRC-32 of the index entries, its own CRC.
pub fn encode_trailer(index_offset: u64, pages: u32, index_crc: u32) -> Vec<u8> {
    let mut p = Put(TRAILER_MAGIC.to_vec());
    p.u64(index_offset);
    p.u32(pages);
    p.u32(index_crc);
    p.u32(0);
    let crc = crc32fast::hash(&p.0);
    p.u32(crc);
    p.0
}

/// The index offset and the entries' CRC from the trailer (the last [`TRAILER`] bytes of a
/// `len`-byte file), checked against the header: the index ends where the trailer starts.
pub fn decode_trailer(b: &[u8], len: u64, h: &StoreHeader) -> Result<(u64, u32), FieldError> {
    let at = (len - TRAILER as u64) as usize;
    let u32_at = |k: usize| u32::from_le_bytes(b[k..k + 4].try_into().expect("4"));
    if &b[..8] != TRAILER_MAGIC || crc32fast::hash(&b[..28]) != u32_at(28) {
        return Err(field_err(
            at,
            "trailer",
            "the last 32 bytes are not a store trailer: the file is truncated or was not completely written",
        ));
    }
    let index_offset = u64::from_le_bytes(b[8..16].try_into().expect("8"));
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
    if index_offset < h.data_offset || index_offset.checked_add(index_len) != Some(at as u64) {
        return Err(field_err(
            at + 8,
            "index offset",
            format!(
                "an index of {pages} pages at byte {index_offset} does not end at the trailer (byte {at}) after the header ({} bytes)",
                h.data_offset
            ),
        ));
    }
    Ok((index_offset, u32_at(20)))
}

/// Index entries from their bytes (`b`, at byte `base` of the file, the trailer's CRC
/// `want`), each checked against the layout: at its position, the pages back to back from
/// the header's end to the index.
pub fn decode_index(
    b: &[u8],
    base: u64,
    want: u32,
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
        if next > base {
            return Err(field_err(
                off + 24,
                "page length",
                format!("entry {i} ends at byte {next}, past the start of the index ({base})"),
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
    if next != base {
        return Err(field_err(
            at(0),
            "index",
            format!("the pages end at byte {next}, the index starts at {base}"),
        ));
    }
    Ok(out)
}
