//! The tile store end to end: real SRTM mosaics imported and read back page by page reproduce
//! the SHA-256 sums in `../shared/data/dem/SOURCES.md` (skipped without `../shared`); `aerie
//! import` and `aerie info` on the committed demo DEM (summary, JSON, refusals with exit 2
//! naming the file and the reason).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use aerie::terrain::bake::{bake, BakeParams};
use aerie::terrain::dataset::{load_dataset, load_dataset_tiles, Dataset};
use aerie::terrain::store::{write_store, ImportParams, PageId, Store};
use aerie_tests::aerie_bin;
use sha2::{Digest, Sha256};

fn aerie(args: &[&str]) -> Output {
    Command::new(aerie_bin())
        .args(args)
        .output()
        .expect("run aerie")
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// The store's level-0 real samples, read back page by page, as SOURCES.md hashes a mosaic:
/// north row first, big-endian i16.
fn mosaic_sha256_through_store(store: &Store) -> String {
    let h = store.header();
    let (w, vh) = (h.valid_width as usize, h.valid_height as usize);
    let mut grid = vec![i16::MIN; w * vh];
    let mut filled = 0usize;
    let l0 = store.layout().levels[0];
    let q = store.layout().q as usize;
    for py in 0..l0.pages_y {
        for px in 0..l0.pages_x {
            let page = store.read_page(PageId { level: 0, px, py }).unwrap();
            let r = page.rect;
            for j in 0..r.rows {
                for i in 0..r.cols {
                    let (c, row) = (
                        r.tx0 as usize * q + i as usize,
                        r.ty0 as usize * q + j as usize,
                    );
                    if c >= w || row >= vh {
                        continue;
                    }
                    let v = page.at(i, j);
                    assert_eq!(v, v.round(), "sample ({c}, {row}) = {v} is not an integer");
                    let k = row * w + c;
                    if grid[k] == i16::MIN {
                        filled += 1;
                    }
                    grid[k] = v as i16;
                }
            }
        }
    }
    assert_eq!(filled, w * vh, "every real sample is in a page");
    let mut bytes = Vec::with_capacity(w * vh * 2);
    for row in (0..vh).rev() {
        for c in 0..w {
            bytes.extend_from_slice(&grid[row * w + c].to_be_bytes());
        }
    }
    Sha256::digest(&bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

fn import(ds: &Dataset, out: &Path) -> Store {
    let p = BakeParams::default();
    let p = BakeParams {
        levels: p.resolve_levels(ds).unwrap(),
        ..p
    };
    let b = bake(ds, p, &|_, _| {});
    let params = ImportParams {
        sources: vec![ds.source.clone()],
        page_tiles: 8,
        zstd_level: 3,
    };
    write_store(out, ds, &b, &params, &|_, _| {}).unwrap();
    Store::open(out).unwrap()
}

#[test]
fn stitched_srtm_mosaics_reproduce_their_sources_checksums_through_the_store() {
    let Some(dir) = aerie_tests::shared_dem_dir() else {
        eprintln!("skipping: ../shared/data/dem not found (fresh clone without ../shared)");
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    for (folder, sha) in [
        (
            "srtm3_sierra_nevada_es",
            "f402db54d14754df29d7183e88d8351ff9d581faa1925049ffa6b42d9a61c28c",
        ),
        (
            "srtm3_northern_england",
            "c897cb1f5b3f792a54c5ff32e2246138581e37a086b10213e5f5ab8dfd798db2",
        ),
    ] {
        let ds = load_dataset(&dir.join(folder)).unwrap();
        let store = import(&ds, &tmp.path().join(format!("{folder}.aerie")));
        assert_eq!(
            (store.header().valid_width, store.header().valid_height),
            (3601, 2401)
        );
        assert_eq!(mosaic_sha256_through_store(&store), sha, "{folder}");
        assert_eq!(store.header().source_checksum, ds.checksum());
    }
    // A list of tiles (the 2×2 east block) as well as a folder.
    let list: Vec<PathBuf> = ["N36W004", "N37W003", "N36W003", "N37W004"]
        .iter()
        .map(|n| dir.join("srtm3_sierra_nevada_es").join(format!("{n}.hgt")))
        .collect();
    let ds = load_dataset_tiles(&list).unwrap();
    let store = import(&ds, &tmp.path().join("east.aerie"));
    assert_eq!(
        mosaic_sha256_through_store(&store),
        "3ac41719ab28db8e11e0dd3237b921907fbc28b8406314f9a25b645ae6d23a8b"
    );
}

/// A flat SRTM tile of side `n` (1201 = SRTM3, 3601 = SRTM1) named `name`.
fn write_tile(dir: &Path, name: &str, n: usize) -> PathBuf {
    let p = dir.join(name);
    let bytes: Vec<u8> = (0..n * n).flat_map(|_| 100i16.to_be_bytes()).collect();
    std::fs::write(&p, bytes).unwrap();
    p
}

#[test]
fn import_and_info_on_the_demo_dem() {
    let tmp = tempfile::tempdir().unwrap();
    let dem = tmp.path().join("N47E011.hgt.zip");
    std::fs::copy(aerie_tests::demo_dem(), &dem).unwrap();
    let out = tmp.path().join("stores/demo.aerie");
    let json = tmp.path().join("demo.json");
    let (dem_s, out_s, json_s) = (
        dem.to_str().unwrap(),
        out.to_str().unwrap(),
        json.to_str().unwrap(),
    );
    let o = aerie(&["import", dem_s, "--out", out_s, "--json", json_s]);
    assert!(o.status.success(), "{}", text(&o));
    let t = text(&o);
    assert!(
        t.contains("imported") && t.contains("8 levels") && t.contains("ratio"),
        "{t}"
    );
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(j["levels"], 8);
    assert_eq!(
        j["file_bytes"].as_u64().unwrap(),
        std::fs::metadata(&out).unwrap().len()
    );
    assert_eq!(j["max_eps_m"].as_array().unwrap().len(), 8);
    assert!(j["compression_ratio"].as_f64().unwrap() > 1.0);
    // What import says is what info reads back from the file.
    let o = aerie(&["info", out_s, "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let i: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for k in [
        "pages",
        "file_bytes",
        "raw_sample_bytes",
        "levels",
        "width",
        "valid_width",
    ] {
        assert_eq!(i[k], j[k], "{k}");
    }
    let eps: Vec<f64> = i["per_level"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["max_eps_m"].as_f64().unwrap())
        .collect();
    let want: Vec<f64> = j["max_eps_m"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(eps, want);
    let o = aerie(&["info", out_s]);
    assert!(
        o.status.success()
            && text(&o).contains(&format!(
                "format version {}",
                aerie::terrain::store::STORE_VERSION
            ))
            && !text(&o).contains("re-import"),
        "{}",
        text(&o)
    );
    assert_eq!(
        (i["quadrant_eps"].as_bool(), i["block_eps"].as_bool()),
        (Some(true), Some(true))
    );
    // --verify reads every page; a flipped byte in one is found, named, and exits 2.
    let o = aerie(&["info", out_s, "--verify"]);
    let pages = j["pages"].as_u64().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains(&format!("verified {pages} of {pages} pages")),
        "{}",
        text(&o)
    );
    let mut bytes = std::fs::read(&out).unwrap();
    let at = bytes.len() / 2; // inside the pages (the index and trailer are the last 11 kB)
    bytes[at] ^= 1;
    let bad = tmp.path().join("bad.aerie");
    std::fs::write(&bad, &bytes).unwrap();
    let o = aerie(&["info", bad.to_str().unwrap(), "--verify", "--json"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["verify"]["checksum_errors"], 1, "{v}");
    assert_eq!(v["verify"]["pages_ok"].as_u64().unwrap(), pages - 1);
    assert!(text(&o).contains("checksum mismatch"), "{}", text(&o));
    // An existing store is kept without --overwrite, replaced with it.
    let before = std::fs::read(&out).unwrap();
    let o = aerie(&["import", dem_s, "--out", out_s]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("--overwrite"), "{}", text(&o));
    assert_eq!(std::fs::read(&out).unwrap(), before);
    let o = aerie(&[
        "import",
        dem_s,
        "--out",
        out_s,
        "--overwrite",
        "--zstd-level",
        "1",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    // info on a file that is not a store names the byte and the reason.
    let o = aerie(&["info", dem_s]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("byte 0 (magic)"), "{}", text(&o));
}

/// Stores of the same 33×33 grid written by builds of format versions 2, 3 and 4 (the store
/// fuzz corpus's seeds): each opens; `info` says what an older bake section lacks, in text and
/// JSON; an older section reads with the looser bounds (a tile at its grandparent's resolution
/// at its parent's ε there), the measured ones as version 4 holds them.
#[test]
fn info_names_an_older_bake_section_and_older_stores_read_with_looser_bounds() {
    let tmp = tempfile::tempdir().unwrap();
    let corpus = aerie_tests::repo_root().join("fuzz/corpus/store");
    let mut bakes = Vec::new();
    for (seed, version, says) in [
        ("seed_v2_valid", 2, Some("format 2: one ε per tile")),
        (
            "seed_v3_valid",
            3,
            Some("format 3: ε over each tile's quadrants but not its 16 blocks"),
        ),
        ("seed_valid", 4, None),
    ] {
        let p = tmp.path().join(format!("{seed}.aerie"));
        std::fs::copy(corpus.join(seed), &p).unwrap();
        let ps = p.to_str().unwrap();
        let o = aerie(&["info", ps]);
        let t = text(&o);
        assert!(o.status.success(), "{t}");
        assert!(t.contains(&format!("format version {version}")), "{t}");
        match says {
            Some(s) => assert!(t.contains(s) && t.contains("re-import"), "{t}"),
            None => assert!(!t.contains("re-import"), "{t}"),
        }
        let o = aerie(&["info", ps, "--json"]);
        assert!(o.status.success(), "{}", text(&o));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(j["format_version"], version);
        assert_eq!(j["quadrant_eps"], version >= 3, "{j}");
        assert_eq!(j["block_eps"], version >= 4, "{j}");
        bakes.push(Store::open(&p).unwrap().read_bake().unwrap());
    }
    let [v2, v3, v4] = &bakes[..] else {
        unreachable!()
    };
    assert!(v4.levels.len() >= 3, "{} levels", v4.levels.len());
    for (l, t) in v4.levels.iter().enumerate() {
        assert_eq!(v2.levels[l].eps, t.eps, "level {l}");
        assert_eq!(v3.levels[l].eps, t.eps, "level {l}");
        assert_eq!(v3.levels[l].coarse_eps, t.coarse_eps, "level {l}");
        if l + 2 >= v4.levels.len() {
            continue;
        }
        let parent = &v4.levels[l + 1];
        for old in [v2, v3] {
            for (i, (&f, &measured)) in old.levels[l].fine_eps.iter().zip(&t.fine_eps).enumerate() {
                let (cx, cy) = (i as u32 % t.tiles_x, i as u32 / t.tiles_x);
                let p = ((cy / 2) * parent.tiles_x + cx / 2) as usize;
                assert_eq!(f, old.levels[l + 1].coarse_eps[p], "level {l} tile {i}");
                assert!(measured <= f, "level {l} tile {i}: {measured} > {f}");
            }
        }
    }
}

#[test]
fn import_refuses_inputs_that_do_not_make_one_grid_naming_files_and_reason() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let out = d.join("x.aerie");
    let out_s = out.to_str().unwrap();
    let a = write_tile(d, "N10E010.hgt", 1201);
    let b = write_tile(d, "N10E011.hgt", 3601);
    let c = write_tile(d, "N12E010.hgt", 1201);
    let tif = d.join("other.tif");
    std::fs::write(&tif, b"II*\0").unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let cases: [(Vec<String>, &[&str]); 4] = [
        (
            vec![s(&a), s(&b)],
            &["N10E011.hgt", "mixed resolutions", "N10E010.hgt"],
        ),
        (
            vec![s(&a), s(&c)],
            &["N10E010.hgt", "do not form a full rectangle", "N11E010"],
        ),
        (vec![s(&a), s(&tif)], &["other.tif", "only SRTM tiles"]),
        (vec![s(&a), s(&a)], &["N10E010.hgt", "given twice"]),
    ];
    for (inputs, words) in cases {
        let mut args = vec!["import".to_string()];
        args.extend(inputs);
        args.extend(["--out".to_string(), out_s.to_string()]);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = aerie(&args);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(2), "{t}");
        for w in words {
            assert!(t.contains(w), "{w:?} not in {t}");
        }
        assert!(!out.exists());
    }
    let o = aerie(&["import", &s(&a), "--out", &s(&d.join("x.bin"))]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("ends in .aerie"), "{}", text(&o));
}

/// `--dem region.aerie`: a store draws exactly what its source draws (the store is read whole
/// into the renderer's in-memory path, checked against its checksum), a store imported with
/// another tile size is refused naming both sizes, and so is a bench sweep over other sizes.
#[test]
fn render_from_a_store_draws_the_same_image_as_its_source() {
    let dir = tempfile::tempdir().unwrap();
    let dem = dir.path().join("N47E011.hgt.zip");
    std::fs::copy(aerie_tests::demo_dem(), &dem).unwrap();
    let store = dir.path().join("inn.aerie");
    let s = |p: &Path| p.display().to_string();
    let o = aerie(&["import", &s(&dem), "--out", &s(&store)]);
    assert!(o.status.success(), "{}", text(&o));
    let render = |input: &Path, out: &Path, extra: &[&str]| {
        let mut args = vec![
            "render".to_string(),
            "--dem".into(),
            s(input),
            "--camera".into(),
            "30500,12000,4500,0,-15,0".into(),
            "--size".into(),
            "96x54".into(),
            "--out".into(),
            s(out),
        ];
        args.extend(extra.iter().map(|a| a.to_string()));
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        aerie(&refs)
    };
    let (a, b) = (dir.path().join("src.png"), dir.path().join("store.png"));
    let o = render(&dem, &a, &[]);
    assert!(o.status.success(), "{}", text(&o));
    let o = render(&store, &b, &[]);
    assert!(o.status.success(), "{}", text(&o));
    let (ia, ib) = (
        image::open(&a).unwrap().to_rgba8(),
        image::open(&b).unwrap().to_rgba8(),
    );
    assert_eq!(ia.dimensions(), ib.dimensions());
    assert!(ia == ib, "the store's frame differs from its source's");
    let sky = ia.pixels().filter(|p| p.0 == ia.get_pixel(0, 0).0).count();
    assert!(sky < ia.pixels().len(), "the frame shows terrain");
    // The bench draws a store with the tiles it was imported with: a sweep over other tile
    // sizes is refused before anything is drawn, naming the flag and the store's size.
    let bench_out = dir.path().join("bench");
    let b = aerie(&[
        "bench",
        "--dem",
        &s(&store),
        "--tile-sizes",
        "17,9",
        "--frames",
        "1",
        "--out",
        &s(&bench_out),
    ]);
    assert_eq!(b.status.code(), Some(2), "{}", text(&b));
    let msg = text(&b);
    assert!(
        msg.contains("--tile-sizes 17,9") && msg.contains("(17)"),
        "{msg}"
    );
    assert!(
        !bench_out.exists(),
        "the refused bench wrote {}",
        bench_out.display()
    );
    // The renderer's tile size (17 by default) must be the store's.
    let other = dir.path().join("inn33.aerie");
    let o = aerie(&["import", &s(&dem), "--out", &s(&other), "--tile-size", "33"]);
    assert!(o.status.success(), "{}", text(&o));
    let c = render(&other, &dir.path().join("x.png"), &[]);
    assert_eq!(c.status.code(), Some(2), "{}", text(&c));
    let msg = text(&c);
    assert!(
        msg.contains("inn33.aerie") && msg.contains("17") && msg.contains("33"),
        "{msg}"
    );
}

/// The store-reader fuzz target's body, replayed on seeded random damage of the valid seed in
/// the normal test suite (the fuzzer itself needs cargo-fuzz; `fuzz_corpus.rs` replays the
/// corpus).
#[path = "../../fuzz/src/bodies.rs"]
#[allow(dead_code)]
mod bodies;

#[test]
fn the_store_reader_survives_random_damage_without_a_panic() {
    let seed = aerie_tests::repo_root().join("fuzz/corpus/store/seed_valid");
    let good = std::fs::read(&seed).unwrap();
    assert!(bodies::store(&good), "the valid seed reads");
    let mut x = 0x2545_f491_4f6c_dd1du64;
    let mut next = |n: usize| {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x % n as u64) as usize
    };
    let mut refused = 0;
    for k in 0..3000 {
        let mut b = good.clone();
        match k % 4 {
            // One to four flipped bytes anywhere.
            0 | 1 => {
                for _ in 0..1 + next(4) {
                    let at = next(b.len());
                    b[at] ^= 1 << next(8);
                }
            }
            // Cut anywhere.
            2 => b.truncate(next(good.len())),
            // A run of bytes overwritten with one value (sizes and offsets made huge or zero).
            _ => {
                let at = next(b.len());
                let v = [0u8, 0xff, 0x7f, 0x80][next(4)];
                for c in b.iter_mut().skip(at).take(1 + next(12)) {
                    *c = v;
                }
            }
        }
        let r = std::panic::catch_unwind(|| bodies::store(&b));
        match r {
            Ok(ok) => refused += usize::from(!ok),
            Err(_) => panic!("damage case {k} panics the store reader"),
        }
    }
    assert!(refused > 2500, "{refused} of 3000 damaged stores refused");
}

/// The demo DEM imported and streamed: every rectangle of every level gathered through a warm
/// `StreamedStore` equals the in-memory source of the file it was imported from.
#[test]
fn the_demo_dem_streamed_from_its_store_gathers_as_in_memory() {
    use aerie::terrain::source::{InMemoryTerrain, SampleRect, TerrainSource};
    use aerie::terrain::stream::{StreamParams, StreamedStore};
    let dir = tempfile::tempdir().unwrap();
    let ds = load_dataset(&aerie_tests::demo_dem()).unwrap();
    let out = dir.path().join("inn.aerie");
    let store = import(&ds, &out);
    let levels = store.header().levels;
    drop(store);
    let mem = InMemoryTerrain::new(std::sync::Arc::new(ds));
    let (s, bake_back) = StreamedStore::open(&out, StreamParams::default()).unwrap();
    assert_eq!(bake_back.levels.len() as u32, levels);
    let (w, h) = (mem.grid().width as i64, mem.grid().height as i64);
    let mut x = 88172645463325252u64;
    let mut next = |n: i64| {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x % n as u64) as i64
    };
    for k in 0..300 {
        let level = next(i64::from(levels)) as u32;
        let step = 1i64 << level;
        let origin = [
            (next(w + 64) - 32) & !(step - 1),
            (next(h + 64) - 32) & !(step - 1),
        ];
        let r = SampleRect {
            level,
            origin,
            size: [1 + next(130) as u32, 1 + next(20) as u32],
        };
        s.wait_resident(&[r], std::time::Duration::from_secs(30))
            .unwrap();
        let (mut a, mut b) = (vec![0f32; r.len()], vec![0f32; r.len()]);
        s.gather(&r, &mut a).unwrap();
        mem.gather(&r, &mut b).unwrap();
        assert!(
            a.iter().zip(&b).all(|(p, q)| p.to_bits() == q.to_bits()),
            "rect {k}: {r:?}"
        );
    }
    assert_eq!(s.stats().failed, 0);
}

/// A raw grid is imported a band of rows at a time (the summary says so), and the store holds
/// exactly its samples: read back whole it equals the grid loaded whole, and `info --verify`
/// finds every page sound.
#[test]
fn a_raw_grid_is_imported_by_rows() {
    let tmp = tempfile::tempdir().unwrap();
    let raw = tmp.path().join("gen.f32");
    let (raw_s, out_s, json_s) = (
        raw.to_str().unwrap().to_string(),
        tmp.path().join("gen.aerie").to_str().unwrap().to_string(),
        tmp.path().join("gen.json").to_str().unwrap().to_string(),
    );
    let o = aerie(&[
        "gen-dem",
        "--size",
        "700",
        "--spacing",
        "30",
        "--kind",
        "mixed",
        "--out",
        &raw_s,
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let o = aerie(&["import", &raw_s, "--out", &out_s, "--json", &json_s]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("by rows"), "{}", text(&o));
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json_s).unwrap()).unwrap();
    assert_eq!(j["streamed"], true, "{j:#}");
    assert_eq!(j["real_samples"], 700 * 700, "{j:#}");
    let (ds, stored) = aerie::terrain::store::load_store(Path::new(&out_s)).unwrap();
    let whole = load_dataset(&raw).unwrap();
    assert!(ds.hf.heights == whole.hf.heights, "the store's samples");
    let fresh = bake(&whole, stored.params, &|_, _| {});
    assert_eq!(stored, fresh, "the store's bake");
    let o = aerie(&["info", &out_s, "--verify"]);
    assert!(o.status.success(), "{}", text(&o));
}

/// A page cache too small for the first frame is refused at once, naming the flag, what the
/// frame needs and a budget that holds it — which then renders (before, start-up waited 30 s
/// for pages that evicted each other).
#[test]
fn a_cache_too_small_for_the_first_frame_is_refused_with_a_budget_that_fits() {
    let tmp = tempfile::tempdir().unwrap();
    let raw = tmp.path().join("g.f32");
    let store = tmp.path().join("g.aerie");
    let (raw_s, store_s) = (raw.to_str().unwrap(), store.to_str().unwrap());
    let o = aerie(&[
        "gen-dem",
        "--size",
        "1025",
        "--spacing",
        "30",
        "--kind",
        "ridged",
        "--out",
        raw_s,
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let o = aerie(&["import", raw_s, "--out", store_s, "--page-tiles", "2"]);
    assert!(o.status.success(), "{}", text(&o));
    let render = |cache: &str| {
        let png = tmp.path().join(format!("c{cache}.png"));
        aerie(&[
            "render",
            "--dem",
            store_s,
            "--cache-mb",
            cache,
            "--size",
            "64x36",
            "--camera",
            "15000,15000,4000,0,-30,0",
            "--out",
            png.to_str().unwrap(),
        ])
    };
    let o = render("2");
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let msg = text(&o);
    assert!(
        msg.contains("--cache-mb 2: the first frame needs") && msg.contains("give --cache-mb "),
        "{msg}"
    );
    let enough = msg
        .split("give --cache-mb ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .expect("a budget");
    let o = render(enough);
    assert!(o.status.success(), "--cache-mb {enough}: {}", text(&o));
}
