//! The store against its sources: every sample of every level and every baked number read
//! back equal, any samples coded losslessly, queries on a store answer as the in-memory
//! source does. Damaged stores and failed writes: `damage_tests.rs`.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DVec3;

use super::*;
use crate::bake::{bake, BakeParams, ErrorBake};
use crate::dataset::Dataset;
use crate::query::{first_hit, height_of_terrain, InMemorySource, Lookup, Ray, SurfaceSource};
use crate::Heightfield;

pub(super) fn dataset(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Dataset {
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
pub(super) fn srtm_like(c: usize, r: usize) -> f32 {
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
pub(super) fn fractional(c: usize, r: usize) -> f32 {
    if (c, r) == (3, 3) {
        return -0.0;
    }
    (c as f32 * 0.7).cos() * 120.5 + noise(c, r) * 3.3
}

pub(super) fn baked(ds: &Dataset, tile_size: u32) -> ErrorBake {
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

pub(super) fn params(page_tiles: u32) -> ImportParams {
    ImportParams {
        sources: vec!["a.hgt".into(), "b.hgt".into()],
        page_tiles,
        zstd_level: 3,
    }
}

pub(super) fn import(
    dir: &Path,
    ds: &Dataset,
    b: &ErrorBake,
    page_tiles: u32,
) -> (PathBuf, StoreSummary) {
    let p = dir.join("t.aerie");
    let s = write_store(&p, ds, b, &params(page_tiles), &|_, _| {}).unwrap();
    (p, s)
}

/// Every page read back: its samples are the level's subsampling of the dataset, its tables
/// the bake's; and every sample of every level lies in some page.
pub(super) fn check_round_trip(ds: &Dataset, b: &ErrorBake, store: &Store) {
    // The bake section alone gives the whole bake, table for table.
    assert_eq!(&store.read_bake().unwrap(), b);
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
        assert_eq!(s.file_bytes, std::fs::metadata(&p).unwrap().len());
        // Open reads the header and the index, nothing else.
        assert_eq!(
            store.open_bytes(),
            h.data_offset
                + INDEX_ENTRY as u64 * u64::from(h.page_count)
                + super::index::TRAILER as u64
        );
        // The bake section lies between the pages and the index.
        assert_eq!(s.bake_bytes, store.bake_bytes());
        assert_eq!(
            s.file_bytes,
            h.data_offset
                + s.page_bytes
                + s.bake_bytes
                + INDEX_ENTRY as u64 * u64::from(h.page_count)
                + super::index::TRAILER as u64
        );
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

pub(super) fn small_store(dir: &Path) -> (PathBuf, Dataset, ErrorBake) {
    let ds = dataset(65, 65, srtm_like);
    let b = baked(&ds, 9);
    let (p, _) = import(dir, &ds, &b, 2);
    (p, ds, b)
}

pub(super) fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
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
        h.data_offset = u64::from(h.header_size);
        let b = encode_header(&h);
        assert_eq!(check_fixed(&b).unwrap() as usize, b.len());
        assert_eq!(decode_header(&b).unwrap(), h);
    }
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

#[test]
fn a_page_whose_tables_differ_from_the_bake_section_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let (p, _, _) = small_store(dir.path());
    let store = Store::open(&p).unwrap();
    let bake = store.read_bake().unwrap();
    let id = PageId {
        level: 1,
        px: 0,
        py: 0,
    };
    let page = store.read_page(id).unwrap();
    page.check_tables(&bake).unwrap();
    for (t, what) in [(0, "ε"), (1, "min"), (2, "max")] {
        let mut bad = page.clone();
        match t {
            0 => bad.eps[1] += 0.5,
            1 => bad.min[1] -= 0.5,
            _ => bad.max[1] += 0.5,
        }
        let e = bad.check_tables(&bake).unwrap_err();
        assert!(
            e.contains("tile (1, 0)") && e.contains(what) && e.contains("bake section"),
            "{e}"
        );
    }
}

/// A bake section in an older format's payload, as that format's encoder wrote it: the
/// current encoder writes level 1's array from level 0's `coarse_eps` and each level L ≥ 2's
/// from level L−2's `fine_eps`, so putting there what the older format kept (version 3: the
/// quadrants, level L−1's `coarse_eps`; version 2: the tiles' ε) gives its bytes.
fn older_payload(b: &ErrorBake, version: u32) -> Vec<u8> {
    let mut shifted = b.clone();
    for l in 1..b.levels.len() {
        let kept = match version {
            3 => b.levels[l - 1].coarse_eps.clone(),
            _ => b.levels[l].eps.clone(),
        };
        match l {
            1 => shifted.levels[0].coarse_eps = kept,
            _ => shifted.levels[l - 2].fine_eps = kept,
        }
    }
    bake_section::encode(&shifted)
}

/// The store's bake section decoded as a store of `version` would hold it.
fn decode_older(store: &Store, b: &ErrorBake, version: u32) -> ErrorBake {
    let mut h = store.header().clone();
    h.version = version;
    let payload = older_payload(b, version);
    assert_eq!(
        payload.len(),
        bake_section::raw_len(store.layout(), version)
    );
    bake_section::decode(&payload, &h, store.layout()).unwrap()
}

/// Each level-L tile's `fine_eps` is its parent's `coarse_eps`: the bound a file without the
/// blocks gives.
fn assert_fine_is_parents_coarse(old: &ErrorBake, measured: &ErrorBake) {
    for l in 2..old.levels.len() {
        let (parent, child) = (&old.levels[l - 1], &old.levels[l - 2]);
        assert_eq!(child.fine_eps.len(), child.len());
        for (i, &f) in child.fine_eps.iter().enumerate() {
            let (cx, cy) = (i as u32 % child.tiles_x, i as u32 / child.tiles_x);
            let p = ((cy / 2) * parent.tiles_x + cx / 2) as usize;
            assert_eq!(
                f.to_bits(),
                parent.coarse_eps[p].to_bits(),
                "L{} {i}",
                l - 2
            );
            assert!(
                f >= measured.levels[l - 2].fine_eps[i],
                "a bound on the measured one"
            );
        }
    }
}

/// A version-2 bake section (one ε per tile) still decodes: the tiles' ε as stored, each
/// quadrant at its parent's ε and each tile at its grandparent's resolution at its parent's
/// there — bounds on the measured ε that version 4 keeps.
#[test]
fn a_version_2_bake_section_reads_with_quadrants_at_their_parents_eps() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dataset(150, 70, srtm_like);
    let b = baked(&ds, 9);
    let (p, _) = import(dir.path(), &ds, &b, 2);
    let store = Store::open(&p).unwrap();
    assert_eq!(store.header().version, STORE_VERSION);
    let old = decode_older(&store, &b, 2);
    let now = store.read_bake().unwrap();
    assert_eq!(now, b, "version 4 keeps the measured quadrants and blocks");
    for l in 1..b.levels.len() {
        let (parent, child) = (&b.levels[l], &old.levels[l - 1]);
        assert_eq!(
            old.levels[l].eps, parent.eps,
            "level {l}: tiles' ε as stored"
        );
        for (i, &c) in child.coarse_eps.iter().enumerate() {
            let (cx, cy) = (i as u32 % child.tiles_x, i as u32 / child.tiles_x);
            assert_eq!(c, parent.eps[((cy / 2) * parent.tiles_x + cx / 2) as usize]);
            assert!(
                c >= b.levels[l - 1].coarse_eps[i],
                "a bound on the measured one"
            );
        }
    }
    assert_fine_is_parents_coarse(&old, &b);
    // Measured quadrants are tighter somewhere on rough terrain, or the format would not pay.
    assert!((0..b.levels.len() - 1).any(|l| b.levels[l].coarse_eps != old.levels[l].coarse_eps));
}

/// A version-3 bake section (the quadrants of every level, no blocks) still decodes: the
/// tiles' ε and the quadrants' as measured, each tile at its grandparent's resolution at its
/// parent's ε there (the looser bound).
#[test]
fn a_version_3_bake_section_reads_with_blocks_at_their_parents_coarse_eps() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dataset(150, 70, srtm_like);
    let b = baked(&ds, 5);
    assert!(b.levels.len() >= 4, "{} levels", b.levels.len());
    let (p, _) = import(dir.path(), &ds, &b, 2);
    let store = Store::open(&p).unwrap();
    let old = decode_older(&store, &b, 3);
    for (o, n) in old.levels.iter().zip(&b.levels) {
        assert_eq!(o.eps, n.eps, "level {}: tiles' ε", n.level);
        assert_eq!(
            o.coarse_eps, n.coarse_eps,
            "level {}: quadrants' ε",
            n.level
        );
        assert_eq!((&o.min, &o.max, &o.terrain), (&n.min, &n.max, &n.terrain));
    }
    assert_fine_is_parents_coarse(&old, &b);
    // Measured blocks are tighter somewhere.
    assert!((0..b.levels.len() - 2).any(|l| b.levels[l].fine_eps != old.levels[l].fine_eps));
    // The version-3 payload is shorter: the quadrants of levels ≥ 2 are a quarter of blocks.
    assert!(bake_section::raw_len(store.layout(), 3) < bake_section::raw_len(store.layout(), 4));
}

/// A bake section value that is not an ε is refused naming the level, the tiles it is over
/// and the tile: a quadrant's (level 1) and a block's (levels ≥ 2).
#[test]
fn a_bake_section_value_that_is_not_an_eps_names_its_level_and_tile() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dataset(150, 70, srtm_like);
    let b = baked(&ds, 5);
    let (p, _) = import(dir.path(), &ds, &b, 2);
    let store = Store::open(&p).unwrap();
    let tx0 = b.levels[0].tiles_x as usize;
    let tx1 = b.levels[1].tiles_x as usize;
    for (level, of, k, v, what) in [
        (
            1,
            0,
            tx0 + 3,
            f32::NAN,
            "quadrant ε of level 1 over level 0's",
        ),
        (2, 0, 2 * tx0 + 1, -0.5, "block ε of level 2 over level 0's"),
        (
            3,
            1,
            tx1 + 2,
            f32::INFINITY,
            "block ε of level 3 over level 1's",
        ),
    ] {
        let mut bad = b.clone();
        let t = &mut bad.levels[of];
        match level {
            1 => t.coarse_eps[k] = v,
            _ => t.fine_eps[k] = v,
        }
        let tx = t.tiles_x as usize;
        let payload = bake_section::encode(&bad);
        let e = bake_section::decode(&payload, store.header(), store.layout()).unwrap_err();
        let want = format!("{what} tile ({}, {})", k % tx, k / tx);
        assert!(
            e.contains(&want) && e.contains("not a finite number"),
            "{e} lacks {want}"
        );
    }
}
