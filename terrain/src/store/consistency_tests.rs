//! Stores whose header, bake section and pages disagree, each part valid on its own (every
//! CRC right): refused at open by [`Store::check_consistency`], naming the byte and reason.

use std::path::Path;

use super::damage_tests::with_pages;
use super::pages::{cut_samples, cut_tables, encode_payload};
use super::tests::{dataset, small_store, srtm_like};
use super::*;

/// Opens `p` and runs the check the streamed and whole-store paths run.
fn check(p: &Path) -> Result<(), String> {
    let store = Store::open(p).map_err(|e| e.to_string())?;
    let bake = store.read_bake().map_err(|e| e.to_string())?;
    store.check_consistency(&bake).map_err(|e| e.to_string())
}

/// Rewrites both header CRCs after a header field was changed, so only the field is wrong.
fn fix_header(b: &mut [u8], header_size: usize) {
    let c = crc32fast::hash(&b[..FIXED_HEADER - 4]);
    b[FIXED_HEADER - 4..FIXED_HEADER].copy_from_slice(&c.to_le_bytes());
    let c = crc32fast::hash(&b[..header_size - 4]);
    b[header_size - 4..header_size].copy_from_slice(&c.to_le_bytes());
}

#[test]
fn an_imported_store_is_consistent() {
    let dir = tempfile::tempdir().unwrap();
    let (p, _, _) = small_store(dir.path());
    check(&p).unwrap();
}

#[test]
fn header_fields_that_disagree_with_the_pages_or_the_bake_are_refused_at_open() {
    let dir = tempfile::tempdir().unwrap();
    let (p, _, _) = small_store(dir.path());
    let good = std::fs::read(&p).unwrap();
    let h = Store::open(&p).unwrap().header().clone();
    let n = h.header_size as usize;
    let q = dir.path().join("bad.aerie");
    let case = |f: &dyn Fn(&mut Vec<u8>)| -> String {
        let mut b = good.clone();
        f(&mut b);
        fix_header(&mut b, n);
        std::fs::write(&q, &b).unwrap();
        // Each part is valid alone: the file opens, the bake section reads.
        let store = Store::open(&q).unwrap();
        store.read_bake().unwrap();
        check(&q).unwrap_err()
    };
    let e = case(&|b| b[88..96].copy_from_slice(&(h.raw_sample_bytes + 4).to_le_bytes()));
    assert!(
        e.contains("byte 88 (raw sample bytes)") && e.contains("does not describe these pages"),
        "{e}"
    );
    let real = u64::from(h.valid_width) * u64::from(h.valid_height);
    let e = case(&|b| b[72..80].copy_from_slice(&(real + 1).to_le_bytes()));
    assert!(
        e.contains("byte 72 (voids filled)") && e.contains(&format!("{real} real samples")),
        "{e}"
    );
    // Level 1's max ε, as a header of another import of the same grid would have it.
    let at = n - 4 - 4 * h.levels as usize + 4;
    let e = case(&|b| b[at..at + 4].copy_from_slice(&(h.max_eps[1] + 0.5).to_le_bytes()));
    assert!(
        e.contains(&format!("byte {at} (max ε)"))
            && e.contains("level 1")
            && e.contains("the bake section is not this store's"),
        "{e}"
    );
    // The same bytes with the CRCs rewritten and nothing changed pass.
    std::fs::write(&q, &good).unwrap();
    check(&q).unwrap();
}

/// Changes a page's samples and its tables (ε, min, max).
type PageEdit = dyn Fn(&mut Vec<f32>, &mut [Vec<f32>; 3]);

/// The small store's pages re-encoded, `edit` changing the samples or tables of `target`,
/// every CRC valid; returns the check's message and the edited page's offset.
fn with_page_edited(dir: &Path, target: PageId, edit: &PageEdit) -> (String, u64) {
    let ds = dataset(65, 65, srtm_like);
    let (p, _, bake) = small_store(dir);
    let store = Store::open(&p).unwrap();
    let h = store.header().clone();
    let layout = store.layout().clone();
    let entries = store.pages().to_vec();
    drop(store);
    let bytes = std::fs::read(&p).unwrap();
    let mut offset = 0;
    let pages: Vec<Vec<u8>> = entries
        .iter()
        .map(|e| {
            let id = PageId {
                level: e.level,
                px: e.px,
                py: e.py,
            };
            let stored = bytes[e.offset as usize..(e.offset + u64::from(e.len)) as usize].to_vec();
            if id != target {
                return stored;
            }
            let mut samples = cut_samples(&ds, &layout, id);
            let mut tables = cut_tables(&bake, &layout, id);
            edit(&mut samples, &mut tables);
            let (coding, raw) =
                encode_payload(id, layout.rect(id.level, id.px, id.py), &samples, &tables);
            assert_eq!(coding, e.coding, "the edit keeps the page's coding");
            offset = e.offset;
            zstd::bulk::compress(&raw, 3).unwrap()
        })
        .collect();
    let q = dir.join("edited.aerie");
    std::fs::write(&q, with_pages(&bytes, &h, &pages)).unwrap();
    // Opens (header, index, trailer) and the edited page reads (CRC, decoding).
    let store = Store::open(&q).unwrap();
    store.read_page(target).unwrap();
    (check(&q).unwrap_err(), offset)
}

#[test]
fn pages_that_disagree_with_the_header_or_the_bake_are_refused_at_open() {
    let dir = tempfile::tempdir().unwrap();
    let levels = {
        let (p, _, _) = small_store(dir.path());
        Store::open(&p).unwrap().header().levels
    };
    assert!(levels > 1, "the case needs a level above level 0");
    let base = PageId {
        level: 0,
        px: 0,
        py: 0,
    };
    let top = PageId {
        level: levels - 1,
        px: 0,
        py: 0,
    };
    // Tables of another bake: the page and the bake section disagree.
    let (e, at) = with_page_edited(dir.path(), base, &|_, t| t[0][0] += 1.0);
    assert!(
        e.contains(&format!("byte {at} (page)"))
            && e.contains("level 0 page (0, 0)")
            && e.contains("in the bake section"),
        "{e}"
    );
    // A level-0 sample above its tile's maximum (its tables kept): the samples are not the
    // ones the bake measured. Sample (12, 1) lies in the page's tile (1, 0), 9-vertex tiles.
    let (e, at) = with_page_edited(dir.path(), base, &|s, t| s[17 + 12] = t[2][1] + 1.0);
    assert!(
        e.contains(&format!("byte {at} (page)")) && e.contains("outside its tile's"),
        "{e}"
    );
    // The coarsest level is not level 0 subsampled: its first sample moved within its
    // tile's bounds (so neither the tables nor the bounds catch it).
    let (e, at) = with_page_edited(dir.path(), top, &|s, t| {
        s[0] = if s[0] == t[1][0] { t[2][0] } else { t[1][0] };
    });
    assert!(
        e.contains(&format!("byte {at} (page)"))
            && e.contains(&format!(
                "level {} is not the subsampling of level 0",
                levels - 1
            )),
        "{e}"
    );
}
