//! Damaged stores: every failure is refused at open or named by page, never a panic, never
//! other data; failed writes leave nothing.

use std::path::Path;

use aerie_io::{Faults, FaultyFs};

use super::tests::{
    baked, check_round_trip, dataset, import, names, params, small_store, srtm_like,
};
use super::*;

fn open_err(p: &Path) -> String {
    Store::open(p).unwrap_err().to_string()
}

pub(super) const T: usize = super::index::TRAILER;

/// Byte offset of the index, from the trailer.
pub(super) fn index_at(bytes: &[u8]) -> usize {
    let t = bytes.len() - T;
    u64::from_le_bytes(bytes[t + 8..t + 16].try_into().unwrap()) as usize
}

/// Byte offset of the bake section, from the trailer.
pub(super) fn bake_at(bytes: &[u8]) -> usize {
    let t = bytes.len() - T;
    u64::from_le_bytes(bytes[t + 24..t + 32].try_into().unwrap()) as usize
}

/// Rewrites the trailer's own CRC after a trailer field was changed.
fn fix_trailer_crc(b: &mut [u8]) {
    let t = b.len() - T;
    let c = crc32fast::hash(&b[t..t + T - 4]);
    b[t + T - 4..].copy_from_slice(&c.to_le_bytes());
}

/// Rewrites the trailer's index CRC (and the trailer's own) after an index entry was
/// changed, so the entry check is reached.
fn fix_index_crc(bytes: &mut [u8], h: &StoreHeader) {
    let at = index_at(bytes);
    let end = at + INDEX_ENTRY * h.page_count as usize;
    let crc = crc32fast::hash(&bytes[at..end]);
    bytes[end + 20..end + 24].copy_from_slice(&crc.to_le_bytes());
    fix_trailer_crc(bytes);
}

#[test]
fn a_corrupt_page_is_an_error_naming_it_and_the_others_still_read() {
    let dir = tempfile::tempdir().unwrap();
    let (p, _, _) = small_store(dir.path());
    let store = Store::open(&p).unwrap();
    let e = store.pages()[3];
    drop(store);
    let mut bytes = std::fs::read(&p).unwrap();
    bytes[(e.offset + u64::from(e.len) / 2) as usize] ^= 0x40;
    std::fs::write(&p, &bytes).unwrap();
    let store = Store::open(&p).unwrap();
    let id = PageId {
        level: e.level,
        px: e.px,
        py: e.py,
    };
    let err = store.read_page(id).unwrap_err();
    assert!(matches!(err, PageError::Checksum { .. }), "{err}");
    let msg = err.to_string();
    assert!(
        msg.contains(&id.to_string()) && msg.contains("checksum mismatch"),
        "{msg}"
    );
    assert!(msg.contains(&format!("bytes {}..", e.offset)), "{msg}");
    for (i, o) in store.pages().iter().enumerate() {
        if i != 3 {
            store
                .read_page(PageId {
                    level: o.level,
                    px: o.px,
                    py: o.py,
                })
                .unwrap();
        }
    }
    // A page asked outside the layout is named too.
    let err = store
        .read_page(PageId {
            level: 9,
            px: 0,
            py: 0,
        })
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("level 9 page (0, 0)") && err.contains("levels"),
        "{err}"
    );
}

/// The file with its pages replaced by `pages` (in index order): offsets, lengths, CRCs,
/// index and trailer rewritten, so only the pages' content is wrong.
pub(super) fn with_pages(bytes: &[u8], h: &StoreHeader, pages: &[Vec<u8>]) -> Vec<u8> {
    let ix = index_at(bytes);
    let section = &bytes[bake_at(bytes)..ix];
    let mut index = bytes[ix..bytes.len() - T].to_vec();
    let mut out = bytes[..h.data_offset as usize].to_vec();
    for (i, p) in pages.iter().enumerate() {
        let at = INDEX_ENTRY * i;
        index[at + 16..at + 24].copy_from_slice(&(out.len() as u64).to_le_bytes());
        index[at + 24..at + 28].copy_from_slice(&(p.len() as u32).to_le_bytes());
        index[at + 28..at + 32].copy_from_slice(&crc32fast::hash(p).to_le_bytes());
        out.extend_from_slice(p);
    }
    let bake_offset = out.len() as u64;
    out.extend_from_slice(section);
    let trailer = super::index::Trailer {
        index_offset: out.len() as u64,
        index_crc: crc32fast::hash(&index),
        bake_offset,
        bake_len: section.len() as u64,
        bake_crc: crc32fast::hash(section),
    };
    out.extend_from_slice(&index);
    out.extend_from_slice(&super::index::encode_trailer(&trailer, h.page_count));
    out
}

#[test]
fn a_page_whose_content_disagrees_with_the_index_is_named() {
    // Valid zstd and valid CRCs, but what is inside is not what the index says: pages
    // shuffled, a page cut short, bytes that are not zstd.
    let dir = tempfile::tempdir().unwrap();
    let (p, _, _) = small_store(dir.path());
    let store = Store::open(&p).unwrap();
    let h = store.header().clone();
    let entries = store.pages().to_vec();
    drop(store);
    let bytes = std::fs::read(&p).unwrap();
    let pages: Vec<Vec<u8>> = entries
        .iter()
        .map(|e| bytes[e.offset as usize..(e.offset + u64::from(e.len)) as usize].to_vec())
        .collect();
    let first = PageId {
        level: 0,
        px: 0,
        py: 0,
    };
    let case = |f: &dyn Fn(&mut Vec<Vec<u8>>)| -> String {
        let mut pg = pages.clone();
        f(&mut pg);
        std::fs::write(&p, with_pages(&bytes, &h, &pg)).unwrap();
        let store = Store::open(&p).unwrap();
        let e = store.read_page(first).unwrap_err();
        assert!(matches!(e, PageError::Content { .. }), "{e}");
        e.to_string()
    };
    let e = case(&|pg| pg[0] = pg[1].clone());
    assert!(
        e.contains("level 0 page (0, 0)") && e.contains("names level 0 page (1, 0)"),
        "{e}"
    );
    let e = case(&|pg| pg[0] = zstd::bulk::compress(&[0u8; 40], 3).unwrap());
    assert!(
        e.contains("level 0 page (0, 0)") && e.contains("decompressed to 40 bytes"),
        "{e}"
    );
    let e = case(&|pg| pg[0] = vec![1, 2, 3, 4, 5]);
    assert!(
        e.contains("level 0 page (0, 0)") && e.contains("cannot decompress"),
        "{e}"
    );
    // The untouched pages rebuilt the same way read: the helper itself changes nothing else.
    std::fs::write(&p, with_pages(&bytes, &h, &pages)).unwrap();
    Store::open(&p).unwrap().read_page(first).unwrap();
}

#[test]
fn damaged_headers_and_indexes_are_refused_with_offset_and_reason() {
    let dir = tempfile::tempdir().unwrap();
    let (p, _, _) = small_store(dir.path());
    let good = std::fs::read(&p).unwrap();
    let h = Store::open(&p).unwrap().header().clone();
    let q = dir.path().join("bad.aerie");
    let case = |f: &dyn Fn(&mut Vec<u8>)| -> String {
        let mut b = good.clone();
        f(&mut b);
        std::fs::write(&q, &b).unwrap();
        open_err(&q)
    };
    let e = case(&|b| b[0] = b'X');
    assert!(
        e.contains("byte 0 (magic)") && e.contains("not an aerie store"),
        "{e}"
    );
    let e = case(&|b| b[8..12].copy_from_slice(&(STORE_VERSION + 1).to_le_bytes()));
    assert!(
        e.contains("byte 8 (format version)")
            && e.contains(&format!("version {} is newer", STORE_VERSION + 1)),
        "{e}"
    );
    // A version-1 store (no bake section) is refused with what to do.
    let e = case(&|b| {
        b[8..12].copy_from_slice(&1u32.to_le_bytes());
        let c = crc32fast::hash(&b[..FIXED_HEADER - 4]);
        b[FIXED_HEADER - 4..FIXED_HEADER].copy_from_slice(&c.to_le_bytes());
    });
    assert!(
        e.contains("byte 8 (format version)")
            && e.contains("version 1 is older")
            && e.contains("re-import"),
        "{e}"
    );
    let e = case(&|b| b[50] ^= 1);
    assert!(
        e.contains("byte 124 (header CRC-32)") && e.contains("corrupt"),
        "{e}"
    );
    let e = case(&|b| b.truncate(100));
    assert!(e.contains("shorter than the 128-byte header"), "{e}");
    // Cut right after the header, inside the index, inside the pages: no trailer at the end.
    let e = case(&|b| b.truncate(h.header_size as usize + 10));
    assert!(e.contains("(trailer)") && e.contains("no index"), "{e}");
    let ix = index_at(&good);
    for cut in [ix + 40, ix - 10, good.len() - 10] {
        let e = case(&|b| b.truncate(cut));
        assert!(
            e.contains(&format!("byte {} (trailer)", cut - T))
                && e.contains("truncated or was not completely written"),
            "cut at {cut}: {e}"
        );
    }
    // Trailing bytes after the trailer: the end is not a trailer either.
    let e = case(&|b| b.extend_from_slice(&[0; 7]));
    assert!(e.contains("(trailer)"), "{e}");
    // A trailer whose index does not end at the trailer, or whose page count disagrees.
    let t = good.len() - T;
    let e = case(&|b| {
        b[t + 8..t + 16].copy_from_slice(&(ix as u64 - 32).to_le_bytes());
        fix_trailer_crc(b);
    });
    assert!(
        e.contains(&format!("byte {} (index offset)", t + 8))
            && e.contains("does not end at the trailer"),
        "{e}"
    );
    let e = case(&|b| {
        b[t + 16..t + 20].copy_from_slice(&(h.page_count - 1).to_le_bytes());
        fix_trailer_crc(b);
    });
    assert!(e.contains("(trailer page count)"), "{e}");
    // A bake section that does not end at the index.
    let e = case(&|b| {
        let len = u64::from_le_bytes(b[t + 32..t + 40].try_into().unwrap());
        b[t + 32..t + 40].copy_from_slice(&(len + 1).to_le_bytes());
        fix_trailer_crc(b);
    });
    assert!(
        e.contains(&format!("byte {} (bake section)", t + 24))
            && e.contains("does not end at the index"),
        "{e}"
    );
    // A corrupt index entry (CRC).
    let e = case(&|b| b[ix + 5] ^= 1);
    assert!(
        e.contains(&format!("byte {ix} (index CRC-32)")) && e.contains("corrupt"),
        "{e}"
    );
    // An entry whose page runs into the index.
    let e = case(&|b| {
        let at = ix + INDEX_ENTRY * (h.page_count as usize - 1) + 24;
        b[at..at + 4].copy_from_slice(&1_000_000u32.to_le_bytes());
        fix_index_crc(b, &h);
    });
    assert!(
        e.contains("(page length)") && e.contains("past the start of the bake section"),
        "{e}"
    );
    // An entry naming another page than its position.
    let e = case(&|b| {
        let at = ix + INDEX_ENTRY * 2;
        b[at + 4..at + 8].copy_from_slice(&7u32.to_le_bytes());
        fix_index_crc(b, &h);
    });
    assert!(e.contains("entry 2 names level 0 page (7, 0)"), "{e}");
    // A header whose sizes disagree with the rest (both header CRCs made valid).
    let fix_header = |b: &mut Vec<u8>| {
        let c = crc32fast::hash(&b[..124]);
        b[124..128].copy_from_slice(&c.to_le_bytes());
        let n = h.header_size as usize;
        let c = crc32fast::hash(&b[..n - 4]);
        b[n - 4..n].copy_from_slice(&c.to_le_bytes());
    };
    let e = case(&|b| {
        b[44..48].copy_from_slice(&(h.page_count + 1).to_le_bytes());
        fix_header(b);
    });
    assert!(
        e.contains("byte 44 (page count)") && e.contains("the grid and levels make"),
        "{e}"
    );
    let e = case(&|b| {
        b[24..28].copy_from_slice(&(h.levels - 1).to_le_bytes());
        fix_header(b);
    });
    assert!(
        e.contains("(max ε count)")
            && e.contains(&format!("{} values for {} levels", h.levels, h.levels - 1)),
        "{e}"
    );
    let e = case(&|b| {
        b[28..32].copy_from_slice(&(h.width + 2).to_le_bytes());
        fix_header(b);
    });
    assert!(
        e.contains("byte 24 (levels)") && e.contains("do not tile"),
        "{e}"
    );
    // The untouched file still opens.
    std::fs::write(&q, &good).unwrap();
    Store::open(&q).unwrap();
}

#[test]
fn a_file_cut_after_open_makes_page_errors_not_panics() {
    let dir = tempfile::tempdir().unwrap();
    let (p, _, _) = small_store(dir.path());
    let store = Store::open(&p).unwrap();
    let last = *store.pages().last().unwrap();
    let f = std::fs::OpenOptions::new().write(true).open(&p).unwrap();
    f.set_len(last.offset + 1).unwrap();
    let id = PageId {
        level: last.level,
        px: last.px,
        py: last.py,
    };
    let err = store.read_page(id).unwrap_err();
    assert!(matches!(err, PageError::Read { .. }), "{err}");
    assert!(err.to_string().contains(&id.to_string()), "{err}");
    store
        .read_page(PageId {
            level: 0,
            px: 0,
            py: 0,
        })
        .unwrap();
}

#[test]
fn a_failed_write_leaves_no_store_and_no_temporary() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dataset(65, 65, srtm_like);
    let b = baked(&ds, 9);
    let p = dir.path().join("t.aerie");
    let full = write_store(&p, &ds, &b, &params(2), &|_, _| {})
        .unwrap()
        .file_bytes;
    std::fs::remove_file(&p).unwrap();
    for faults in [
        Faults::full_after(full / 2),
        Faults {
            max_write: Some(64),
            eio_on_write: Some(5),
            ..Faults::default()
        },
        Faults {
            fail_rename: true,
            ..Faults::default()
        },
    ] {
        let fs = FaultyFs::new(faults.clone());
        let err = write_store_in(fs.shared(), &p, &ds, &b, &params(2), &|_, _| {}).unwrap_err();
        assert!(matches!(err, StoreError::Write(_)), "{err}");
        assert!(err.to_string().contains("t.aerie"), "{err}");
        assert!(
            names(dir.path()).is_empty(),
            "{faults:?}: {:?}",
            names(dir.path())
        );
        assert!(Store::open(&p).is_err());
    }
    // Short writes that all succeed make the same valid store.
    let fs = FaultyFs::new(Faults {
        max_write: Some(100),
        ..Faults::default()
    });
    write_store_in(fs.shared(), &p, &ds, &b, &params(2), &|_, _| {}).unwrap();
    check_round_trip(&ds, &b, &Store::open(&p).unwrap());
}

/// The bake section and every page of the store read back, or the first error (as text).
fn read_all(p: &Path) -> Result<Vec<Page>, String> {
    let store = Store::open(p).map_err(|e| e.to_string())?;
    store.read_bake().map_err(|e| e.to_string())?;
    store
        .pages()
        .iter()
        .map(|e| {
            store
                .read_page(PageId {
                    level: e.level,
                    px: e.px,
                    py: e.py,
                })
                .map_err(|e| e.to_string())
        })
        .collect()
}

#[test]
fn every_byte_is_checked_a_flip_anywhere_is_an_error_never_a_panic_or_other_data() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dataset(33, 33, srtm_like);
    let (p, _) = import(dir.path(), &ds, &baked(&ds, 5), 2);
    let good = std::fs::read(&p).unwrap();
    assert!(read_all(&p).is_ok());
    let q = dir.path().join("flipped.aerie");
    for at in 0..good.len() {
        let mut b = good.clone();
        b[at] ^= 0x10;
        std::fs::write(&q, &b).unwrap();
        assert!(
            read_all(&q).is_err(),
            "a flip at byte {at} of {} went unnoticed",
            good.len()
        );
    }
}

#[test]
fn a_store_cut_at_any_length_does_not_open() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dataset(33, 33, srtm_like);
    let (p, _) = import(dir.path(), &ds, &baked(&ds, 5), 2);
    let good = std::fs::read(&p).unwrap();
    let q = dir.path().join("cut.aerie");
    for len in 0..good.len() {
        std::fs::write(&q, &good[..len]).unwrap();
        let e = Store::open(&q).unwrap_err().to_string();
        assert!(e.contains("cut.aerie: "), "{e}");
    }
}

#[test]
fn a_bad_sector_fails_only_its_page_and_short_reads_change_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let (p, ds, b) = small_store(dir.path());
    let e = Store::open(&p).unwrap().pages()[5];
    let fs = FaultyFs::new(Faults {
        eio_at_read_offset: Some(e.offset + 1),
        ..Faults::default()
    });
    let store = Store::open_in(fs.shared(), &p).unwrap();
    let id = PageId {
        level: e.level,
        px: e.px,
        py: e.py,
    };
    let err = store.read_page(id).unwrap_err();
    assert!(matches!(err, PageError::Read { .. }), "{err}");
    let msg = err.to_string();
    assert!(
        msg.contains(&id.to_string()) && msg.contains("Input/output error"),
        "{msg}"
    );
    for o in store.pages().iter().filter(|o| o.offset != e.offset) {
        store
            .read_page(PageId {
                level: o.level,
                px: o.px,
                py: o.py,
            })
            .unwrap();
    }
    let short = FaultyFs::new(Faults {
        max_read: Some(7),
        ..Faults::default()
    });
    check_round_trip(&ds, &b, &Store::open_in(short.shared(), &p).unwrap());
}

#[test]
fn a_corrupt_bake_section_is_refused_by_read_bake_naming_its_offset() {
    let dir = tempfile::tempdir().unwrap();
    let (p, _, b) = small_store(dir.path());
    let mut bytes = std::fs::read(&p).unwrap();
    let at = bake_at(&bytes);
    assert_eq!(Store::open(&p).unwrap().read_bake().unwrap(), b);
    bytes[at + 3] ^= 0x08;
    std::fs::write(&p, &bytes).unwrap();
    // The store still opens (its pages are fine) but its bake is refused, with the reason.
    let store = Store::open(&p).unwrap();
    let e = store.read_bake().unwrap_err().to_string();
    assert!(
        e.contains(&format!("byte {at} (bake section)")) && e.contains("corrupt"),
        "{e}"
    );
}
