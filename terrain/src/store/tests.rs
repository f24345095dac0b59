//! The store against its sources: every sample of every level and every baked number read
//! back equal; damaged files refused or reported with the reason; a failed write leaves no
//! store; queries on a store answer as the in-memory source does.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use aerie_io::{Faults, FaultyFs};
use glam::DVec3;

use super::*;
use crate::bake::{bake, BakeParams, ErrorBake};
use crate::dataset::Dataset;
use crate::query::{first_hit, height_of_terrain, InMemorySource, Lookup, Ray, SurfaceSource};
use crate::Heightfield;

fn dataset(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Dataset {
    let heights = (0..h)
        .flat_map(|r| (0..w).map(move |c| (r, c)))
        .map(|(r, c)| f(c, r))
        .collect();
    Dataset::from_heightfield(
        Heightfield {
            width: w,
            height: h,
            spacing_x: 30.0,
            spacing_y: 20.0,
            heights,
            geo: Some(crate::GeoReference::Geographic {
                south_lat_deg: 47.0,
                west_lon_deg: 11.0,
                dlat_deg: 1.0 / 1200.0,
                dlon_deg: 1.0 / 1200.0,
            }),
            voids_filled: 3,
            spacing_note: "test grid".into(),
        },
        "test".into(),
    )
}

/// A hash in [0, 1): terrain with detail at every scale, nothing a coder could guess.
fn noise(c: usize, r: usize) -> f32 {
    let mut x = (c as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (r as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
    x ^= x >> 29;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x ^= x >> 32;
    (x % 10_000) as f32 / 10_000.0
}

/// Integer metres, the i16 extremes included (the wrapping predictor must survive them).
fn srtm_like(c: usize, r: usize) -> f32 {
    match (c, r) {
        (5, 7) => -32768.0,
        (6, 7) => 32767.0,
        _ => (((c as f32 * 0.05).sin() * 800.0 + r as f32 * 3.0) + noise(c, r) * 40.0).round(),
    }
}

/// Integer metres with a few filled-void-like fractional samples, one -0.0 and one value
/// beyond i16 among them (each must come back exactly).
fn mostly_integer(c: usize, r: usize) -> f32 {
    match (c, r) {
        (9, 9) => -0.0,
        (10, 9) => 40_000.25,
        (11, 9) => -1e9,
        _ if (c * 7 + r * 3).is_multiple_of(41) => srtm_like(c, r) + 0.375,
        _ => srtm_like(c, r),
    }
}

/// Fractional heights and one -0.0 (which an i16 coding would turn into +0.0).
fn fractional(c: usize, r: usize) -> f32 {
    if (c, r) == (3, 3) {
        return -0.0;
    }
    (c as f32 * 0.7).cos() * 120.5 + noise(c, r) * 3.3
}

fn baked(ds: &Dataset, tile_size: u32) -> ErrorBake {
    let p = BakeParams {
        tile_size,
        levels: 0,
    };
    let p = BakeParams {
        levels: p.resolve_levels(ds).unwrap(),
        ..p
    };
    bake(ds, p, &|_, _| {})
}

fn params(page_tiles: u32) -> ImportParams {
    ImportParams {
        sources: vec!["a.hgt".into(), "b.hgt".into()],
        page_tiles,
        zstd_level: 3,
    }
}

fn import(dir: &Path, ds: &Dataset, b: &ErrorBake, page_tiles: u32) -> (PathBuf, StoreSummary) {
    let p = dir.join("t.aerie");
    let s = write_store(&p, ds, b, &params(page_tiles), &|_, _| {}).unwrap();
    (p, s)
}

/// Every page read back: its samples are the level's subsampling of the dataset, its tables
/// the bake's; and every sample of every level lies in some page.
fn check_round_trip(ds: &Dataset, b: &ErrorBake, store: &Store) {
    let layout = store.layout().clone();
    let q = layout.q;
    for (l, lev) in layout.levels.iter().enumerate() {
        let l = l as u32;
        let step = 1usize << l;
        let (cols, rows) = ((ds.hf.width - 1) / step + 1, (ds.hf.height - 1) / step + 1);
        let mut seen = vec![false; cols * rows];
        for py in 0..lev.pages_y {
            for px in 0..lev.pages_x {
                let page = store.read_page(PageId { level: l, px, py }).unwrap();
                let r = page.rect;
                for j in 0..r.rows {
                    for i in 0..r.cols {
                        let (c, rr) = ((r.tx0 * q + i) as usize, (r.ty0 * q + j) as usize);
                        let want = ds.hf.at(c * step, rr * step);
                        let got = page.at(i, j);
                        assert_eq!(
                            got.to_bits(),
                            want.to_bits(),
                            "level {l} sample ({c}, {rr})"
                        );
                        seen[rr * cols + c] = true;
                    }
                }
                for j in 0..r.nty {
                    for i in 0..r.ntx {
                        let (tx, ty) = (r.tx0 + i, r.ty0 + j);
                        let k = (j * r.ntx + i) as usize;
                        assert_eq!(
                            page.eps[k].to_bits(),
                            b.eps(l, tx, ty).to_bits(),
                            "ε L{l} ({tx},{ty})"
                        );
                        let (mn, mx) = b.bounds(l, tx, ty);
                        assert_eq!(
                            (page.min[k], page.max[k]),
                            (mn, mx),
                            "min/max L{l} ({tx},{ty})"
                        );
                    }
                }
            }
        }
        assert!(seen.iter().all(|&s| s), "level {l}: a sample is in no page");
    }
}

#[test]
fn every_sample_and_every_baked_number_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    // 150×70 pads to 257×129: pages cut at the east/north edges of every level.
    for (f, coding) in [
        (srtm_like as fn(usize, usize) -> f32, Coding::I16Gradient),
        (fractional, Coding::F32Xor),
        (mostly_integer, Coding::I16Exceptions),
    ] {
        let ds = dataset(150, 70, f);
        let b = baked(&ds, 9);
        assert!(b.levels.len() >= 4);
        let (p, s) = import(dir.path(), &ds, &b, 2);
        let store = Store::open(&p).unwrap();
        assert_eq!(store.pages().len() as u32, s.pages);
        // Level-0 page (0, 0) holds the special samples; every page is coded as its samples
        // allow (exact i16 pages of the mostly-integer set stay plain i16).
        assert_eq!(store.pages()[0].coding, coding, "{coding:?}");
        if coding != Coding::I16Exceptions {
            assert!(
                store.pages().iter().all(|e| e.coding == coding),
                "{coding:?}"
            );
        }
        check_round_trip(&ds, &b, &store);
        let h = store.header();
        assert_eq!(
            (h.width, h.height, h.valid_width, h.valid_height),
            (257, 129, 150, 70)
        );
        assert_eq!((h.spacing_x, h.spacing_y, h.voids_filled), (30.0, 20.0, 3));
        assert_eq!(h.geo, ds.hf.geo);
        assert_eq!(h.sources, ["a.hgt", "b.hgt"]);
        assert_eq!(h.source_checksum, ds.checksum());
        assert_eq!(h.file_size, std::fs::metadata(&p).unwrap().len());
        // Open reads the header and the index, nothing else.
        assert_eq!(store.open_bytes(), h.data_offset);
        assert!(s.ratio() > 1.0, "ratio {}", s.ratio());
    }
}

#[test]
fn page_sizes_from_one_tile_to_the_whole_level_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dataset(65, 33, srtm_like);
    let b = baked(&ds, 5);
    for pt in [1, 4, 64] {
        let (p, _) = import(dir.path(), &ds, &b, pt);
        check_round_trip(&ds, &b, &Store::open(&p).unwrap());
    }
}

fn small_store(dir: &Path) -> (PathBuf, Dataset, ErrorBake) {
    let ds = dataset(65, 65, srtm_like);
    let b = baked(&ds, 9);
    let (p, _) = import(dir, &ds, &b, 2);
    (p, ds, b)
}

fn open_err(p: &Path) -> String {
    Store::open(p).unwrap_err().to_string()
}

/// Rewrites the index CRC after an index entry was changed, so the entry check is reached.
fn fix_index_crc(bytes: &mut [u8], h: &StoreHeader) {
    let at = h.header_size as usize;
    let end = at + INDEX_ENTRY * h.page_count as usize;
    let crc = crc32fast::hash(&bytes[at..end]);
    bytes[end..end + 4].copy_from_slice(&crc.to_le_bytes());
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
/// file size and both header CRCs rewritten, so only the pages' content is wrong.
fn with_pages(bytes: &[u8], h: &StoreHeader, pages: &[Vec<u8>]) -> Vec<u8> {
    let mut out = bytes[..h.data_offset as usize].to_vec();
    let mut offset = h.data_offset;
    for (i, p) in pages.iter().enumerate() {
        let at = h.header_size as usize + INDEX_ENTRY * i;
        out[at + 16..at + 24].copy_from_slice(&offset.to_le_bytes());
        out[at + 24..at + 28].copy_from_slice(&(p.len() as u32).to_le_bytes());
        out[at + 28..at + 32].copy_from_slice(&crc32fast::hash(p).to_le_bytes());
        offset += p.len() as u64;
    }
    fix_index_crc(&mut out, h);
    out[96..104].copy_from_slice(&offset.to_le_bytes());
    let c = crc32fast::hash(&out[..124]);
    out[124..128].copy_from_slice(&c.to_le_bytes());
    let n = h.header_size as usize;
    let c = crc32fast::hash(&out[..n - 4]);
    out[n - 4..n].copy_from_slice(&c.to_le_bytes());
    for p in pages {
        out.extend_from_slice(p);
    }
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
    let e = case(&|b| b[8..12].copy_from_slice(&2u32.to_le_bytes()));
    assert!(
        e.contains("byte 8 (format version)") && e.contains("version 2 is newer"),
        "{e}"
    );
    let e = case(&|b| b[50] ^= 1);
    assert!(
        e.contains("byte 124 (header CRC-32)") && e.contains("corrupt"),
        "{e}"
    );
    let e = case(&|b| b.truncate(100));
    assert!(e.contains("shorter than the 128-byte header"), "{e}");
    // Truncated inside the index.
    let e = case(&|b| b.truncate(h.header_size as usize + 40));
    assert!(
        e.contains(&format!("byte {} (index)", h.header_size)) && e.contains("truncated index"),
        "{e}"
    );
    // Truncated inside the pages: refused at open (the file size says so).
    let e = case(&|b| b.truncate(b.len() - 10));
    assert!(
        e.contains("byte 96 (file size)") && e.contains("truncated"),
        "{e}"
    );
    // A corrupt index entry (CRC).
    let e = case(&|b| b[h.header_size as usize + 5] ^= 1);
    assert!(e.contains("index CRC-32") && e.contains("corrupt"), "{e}");
    // An entry whose page runs past the end of the file.
    let e = case(&|b| {
        let at = h.header_size as usize + INDEX_ENTRY * (h.page_count as usize - 1) + 24;
        b[at..at + 4].copy_from_slice(&1_000_000u32.to_le_bytes());
        fix_index_crc(b, &h);
    });
    assert!(
        e.contains("(page length)") && e.contains("past the header's file size"),
        "{e}"
    );
    // An entry naming another page than its position.
    let e = case(&|b| {
        let at = h.header_size as usize + INDEX_ENTRY * 2;
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

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn a_failed_write_leaves_no_store_and_no_temporary() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dataset(65, 65, srtm_like);
    let b = baked(&ds, 9);
    let p = dir.path().join("t.aerie");
    let full = write_store(&p, &ds, &b, &params(2), &|_, _| {})
        .unwrap()
        .header
        .file_size;
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

#[test]
fn a_bake_of_other_data_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dataset(65, 65, srtm_like);
    let other = dataset(65, 65, fractional);
    let b = baked(&other, 9);
    let err =
        write_store(&dir.path().join("t.aerie"), &ds, &b, &params(2), &|_, _| {}).unwrap_err();
    assert!(
        err.to_string().contains("not made from this dataset"),
        "{err}"
    );
    assert!(names(dir.path()).is_empty());
}

#[test]
fn queries_on_a_store_answer_as_in_memory() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dataset(150, 110, fractional);
    let b = baked(&ds, 9);
    let (p, _) = import(dir.path(), &ds, &b, 2);
    let store = Store::open(&p).unwrap();
    let mem = InMemorySource::new(Arc::new(ds.clone()), Arc::new(b.clone())).unwrap();
    let mut src = StoreSource::new(&store);
    let (nx, ny) = src.grid().tiles(0);
    // Nothing resident: every question over terrain is pending.
    assert!(matches!(
        height_of_terrain(&src, 100.0, 100.0),
        Lookup::Pending { .. }
    ));
    // The south-west quarter resident: answers there equal, elsewhere pending, never wrong.
    let read = src
        .load_tiles(
            &store,
            (0..nx / 2).flat_map(|x| (0..ny / 2).map(move |y| (x, y))),
        )
        .unwrap();
    assert!(read > 0 && src.resident_tiles() > 0);
    let (ex, ny_m) = (149.0 * 30.0, 109.0 * 20.0);
    let mut k = 0usize;
    let mut next = || {
        k += 1;
        f64::from(noise(k, 7 * k + 1))
    };
    let (mut ready, mut pending) = (0, 0);
    for _ in 0..400 {
        let (x, y) = (next() * ex * 1.1 - 20.0, next() * ny_m * 1.1 - 20.0);
        let want = height_of_terrain(&mem, x, y);
        match height_of_terrain(&src, x, y) {
            Lookup::Pending { .. } => pending += 1,
            got => {
                assert_eq!(got, want, "HOT at ({x}, {y})");
                ready += 1;
            }
        }
    }
    assert!(
        ready > 50 && pending > 50,
        "{ready} ready, {pending} pending"
    );
    let rays: Vec<Ray> = (0..300)
        .map(|_| {
            let o = DVec3::new(next() * ex, next() * ny_m, 150.0 + next() * 200.0);
            let d = DVec3::new(next() - 0.5, next() - 0.5, -next() * 0.3);
            Ray::new(o, d, 0.0, 5000.0).unwrap()
        })
        .collect();
    let (mut ready, mut pending) = (0, 0);
    for r in &rays {
        match first_hit(&src, r) {
            Lookup::Pending { .. } => pending += 1,
            got => {
                assert_eq!(got, first_hit(&mem, r), "{r:?}");
                ready += 1;
            }
        }
    }
    assert!(
        ready > 20 && pending > 20,
        "{ready} ready, {pending} pending"
    );
    // Every tile resident: every answer equal.
    src.load_tiles(&store, (0..nx).flat_map(|x| (0..ny).map(move |y| (x, y))))
        .unwrap();
    assert_eq!(src.resident_tiles(), (nx * ny) as usize);
    for r in &rays {
        assert_eq!(first_hit(&src, r), first_hit(&mem, r), "{r:?}");
    }
    for _ in 0..300 {
        let (x, y) = (next() * ex, next() * ny_m);
        assert_eq!(height_of_terrain(&src, x, y), height_of_terrain(&mem, x, y));
    }
}

#[test]
fn a_projected_geo_reference_and_no_geo_reference_round_trip_through_the_header() {
    use super::format::{check_fixed, decode_header, encode_header, header_len};
    let dir = tempfile::tempdir().unwrap();
    let (p, _, _) = small_store(dir.path());
    let base = Store::open(&p).unwrap().header().clone();
    for geo in [
        None,
        Some(crate::GeoReference::Projected {
            crs: "EPSG:32611".into(),
            easting: 500_000.5,
            northing: 4_100_000.25,
        }),
    ] {
        let mut h = StoreHeader {
            geo,
            ..base.clone()
        };
        h.header_size = header_len(&h) as u32;
        let b = encode_header(&h);
        assert_eq!(check_fixed(&b).unwrap() as usize, b.len());
        assert_eq!(decode_header(&b).unwrap(), h);
    }
}

/// Every page of the store read back, or the first error (as text).
fn read_all(p: &Path) -> Result<Vec<Page>, String> {
    let store = Store::open(p).map_err(|e| e.to_string())?;
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

/// One value of a page: integers (the i16 extremes among them), -0.0, fractions, values past
/// i16, subnormals, huge magnitudes.
fn any_height() -> impl proptest::strategy::Strategy<Value = f32> {
    use proptest::prelude::*;
    prop_oneof![
        6 => (-32768i32..=32767).prop_map(|v| v as f32),
        1 => Just(-0.0f32),
        1 => -1e4f32..1e4,
        1 => (32768i32..1_000_000).prop_map(|v| v as f32),
        1 => any::<f32>().prop_filter("finite", |v| v.is_finite()),
    ]
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(200))]

    /// Whatever the samples, the page decodes to the same bits (every coding is lossless).
    #[test]
    fn any_finite_samples_code_and_decode_bit_for_bit(
        ntx in 1u32..4,
        nty in 1u32..4,
        seed in proptest::collection::vec(any_height(), 1..64),
        tables in proptest::collection::vec(-1e4f32..1e4, 1..8),
        mix in 0usize..3,
    ) {
        let q = 4u32;
        let layout = Layout::new(ntx * q + 1, nty * q + 1, q, 1, 4).unwrap();
        let id = PageId { level: 0, px: 0, py: 0 };
        let rect = layout.rect(0, 0, 0);
        // mix 0: as drawn (mostly f32 pages); 1: integers but one sample in 16 (i16 with
        // exceptions); 2: all integers (plain i16). `+ 0.0` turns -0.0 into 0.0.
        let samples: Vec<f32> = (0..rect.samples())
            .map(|k| {
                let v = seed[(k * 7 + k / 3) % seed.len()];
                match mix {
                    1 if k % 16 != 5 => v.round().clamp(-32768.0, 32767.0) + 0.0,
                    2 => v.round().clamp(-32768.0, 32767.0) + 0.0,
                    _ => v,
                }
            })
            .collect();
        let t: Vec<f32> = (0..rect.tiles()).map(|k| tables[k % tables.len()]).collect();
        let tabs = [t.clone(), t.clone(), t];
        let (coding, raw) = super::pages::encode_payload(id, rect, &samples, &tabs);
        if mix == 2 {
            proptest::prop_assert_eq!(coding, Coding::I16Gradient);
        }
        if mix == 1 {
            proptest::prop_assert!(coding != Coding::F32Xor);
        }
        proptest::prop_assert!(raw.len() <= layout.raw_len(0, 0, 0, coding));
        let page = super::pages::decode_payload(&raw, &layout, id, coding).unwrap();
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        proptest::prop_assert_eq!(bits(&page.samples), bits(&samples));
        proptest::prop_assert_eq!(bits(&page.eps), bits(&tabs[0]));
        proptest::prop_assert_eq!(bits(&page.max), bits(&tabs[2]));
    }
}

#[test]
fn a_store_can_be_shared_by_reader_threads() {
    fn shared<T: Send + Sync>() {}
    shared::<Store>();
    let dir = tempfile::tempdir().unwrap();
    let (p, ds, b) = small_store(dir.path());
    let store = Store::open(&p).unwrap();
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| check_round_trip(&ds, &b, &store));
        }
    });
}
