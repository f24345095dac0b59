//! The index: one 32-byte entry per page, in layout order, checked against the header.

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

/// Index entries from their bytes (`b` = entries followed by the index CRC; `base` = the
/// index's byte offset in the file, for messages), each checked against the layout: at its
/// position, inside the page area, the pages back to back.
pub fn decode_index(
    b: &[u8],
    base: u64,
    h: &StoreHeader,
    layout: &Layout,
) -> Result<Vec<PageEntry>, FieldError> {
    let n = h.page_count as usize;
    debug_assert_eq!(b.len(), n * INDEX_ENTRY + 4);
    let at = |k: usize| (base + k as u64) as usize;
    let want = u32::from_le_bytes(b[n * INDEX_ENTRY..].try_into().expect("4"));
    let got = crc32fast::hash(&b[..n * INDEX_ENTRY]);
    if got != want {
        return Err(field_err(
            at(n * INDEX_ENTRY),
            "index CRC-32",
            format!("the index has CRC-32 {got:#010x}, its trailer says {want:#010x}: the index is corrupt"),
        ));
    }
    let mut out = Vec::with_capacity(n);
    let mut next = h.data_offset;
    for (i, e) in b[..n * INDEX_ENTRY].chunks_exact(INDEX_ENTRY).enumerate() {
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
        if next > h.file_size {
            return Err(field_err(
                off + 24,
                "page length",
                format!(
                    "entry {i} ends at byte {next}, past the header's file size {}",
                    h.file_size
                ),
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
    if next != h.file_size {
        return Err(field_err(
            96,
            "file size",
            format!(
                "the pages end at byte {next}, the header says the file is {} bytes",
                h.file_size
            ),
        ));
    }
    Ok(out)
}
