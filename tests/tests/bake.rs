//! The error bake against an independent brute-force oracle, the bake file's round trip and
//! rejections, and `aerie gen-dem` / `aerie bake` through the CLI entry point.
//!
//! The oracle below is written from DESIGN.md's definition, not from the bake's code: for a
//! level-L tile it walks every full-resolution sample, finds the level-L cell it lies in, and
//! interpolates the cell's corners with its own barycentric weights on the SW–NE triangles
//! (checked once against `mesh::quad_surface`). Stored ε are rounded up to f32, so "equal" means
//! `oracle ≤ stored ≤ oracle + 1 f32 ulp` (plus 1e-9 m for f64 evaluation order).

use std::path::{Path, PathBuf};

use aerie::terrain::bake::{
    bake, bake_path_for, load_or_bake, read_bake, write_bake, BakeError, BakeOutcome, BakeParams,
    ErrorBake, BAKE_VERSION,
};
use aerie::terrain::dataset::{load_dataset, Dataset};
use aerie::terrain::mesh::{quad_surface, Diagonal, TILE_DIAGONAL};
use aerie::terrain::Heightfield;
use proptest::prelude::*;

// ---------------------------------------------------------------------------------------------
// The oracle
// ---------------------------------------------------------------------------------------------

/// Height of the SW–NE split quad at (u, v) from barycentric weights.
fn barycentric(sw: f64, se: f64, nw: f64, ne: f64, u: f64, v: f64) -> f64 {
    if u >= v {
        // Triangle sw (0,0), se (1,0), ne (1,1).
        (1.0 - u) * sw + (u - v) * se + v * ne
    } else {
        // Triangle sw (0,0), ne (1,1), nw (0,1).
        (1.0 - v) * sw + u * ne + (v - u) * nw
    }
}

/// Level-`level` surface at full-resolution sample (c, r) of `ds`.
fn level_surface(ds: &Dataset, level: u32, c: usize, r: usize) -> f64 {
    let s = 1usize << level;
    let (w, h) = (ds.hf.width, ds.hf.height);
    let cx = (c / s).min((w - 1) / s - 1);
    let cy = (r / s).min((h - 1) / s - 1);
    let (c0, r0) = (cx * s, cy * s);
    let at = |c: usize, r: usize| f64::from(ds.hf.at(c, r));
    let u = (c - c0) as f64 / s as f64;
    let v = (r - r0) as f64 / s as f64;
    barycentric(
        at(c0, r0),
        at(c0 + s, r0),
        at(c0, r0 + s),
        at(c0 + s, r0 + s),
        u,
        v,
    )
}

/// (ε in f64, min, max, holds a real sample) of the samples of tile (tx, ty) of tile side
/// `t` samples − 1, against the level-`surface_level` surface.
fn oracle_tile(
    ds: &Dataset,
    t: usize,
    tx: usize,
    ty: usize,
    surface_level: u32,
) -> (f64, f32, f32, bool) {
    let (mut e, mut lo, mut hi, mut real) = (0f64, f32::INFINITY, f32::NEG_INFINITY, false);
    for r in ty * t..=(ty + 1) * t {
        for c in tx * t..=(tx + 1) * t {
            let hgt = ds.hf.at(c, r);
            lo = lo.min(hgt);
            hi = hi.max(hgt);
            real |= !ds.is_padding(c, r);
            if surface_level > 0 {
                e = e.max((f64::from(hgt) - level_surface(ds, surface_level, c, r)).abs());
            }
        }
    }
    (e, lo, hi, real)
}

fn assert_eps_matches(stored: f32, oracle: f64, what: &str) {
    let s = f64::from(stored);
    let ulp = f64::from(f32::EPSILON) * oracle.max(f64::from(f32::MIN_POSITIVE));
    assert!(
        s >= oracle - 1e-9 && s <= oracle + ulp + 1e-9,
        "{what}: stored ε {stored} vs oracle {oracle}"
    );
}

/// Checks every tile of the given levels (all when `tiles` is None) against the oracle.
fn check_tiles(ds: &Dataset, b: &ErrorBake, pick: &dyn Fn(u32, u32, u32) -> bool) -> usize {
    let q = (b.params.tile_size - 1) as usize;
    let mut checked = 0;
    for t in &b.levels {
        let l = t.level;
        let side = q << l;
        for ty in 0..t.tiles_y {
            for tx in 0..t.tiles_x {
                if !pick(l, tx, ty) {
                    continue;
                }
                let (e, lo, hi, real) = oracle_tile(ds, side, tx as usize, ty as usize, l);
                let what = format!("level {l} tile ({tx},{ty})");
                if l == 0 || !real {
                    // Level 0 is the samples themselves; all-padding tiles are not measured.
                    assert_eq!(b.eps(l, tx, ty), 0.0, "{what}");
                } else {
                    assert_eps_matches(b.eps(l, tx, ty), e, &what);
                }
                assert_eq!(b.bounds(l, tx, ty), (lo, hi), "{what}: min/max");
                assert_eq!(b.is_terrain(l, tx, ty), real, "{what}: terrain flag");
                checked += 1;
            }
        }
    }
    checked
}

fn dataset(w: usize, h: usize, heights: Vec<f32>, spacing: f64) -> Dataset {
    Dataset::from_heightfield(
        Heightfield {
            width: w,
            height: h,
            spacing_x: spacing,
            spacing_y: spacing * 1.5,
            heights,
            geo: None,
            voids_filled: 0,
            spacing_note: String::new(),
        },
        "proptest".into(),
    )
}

#[test]
fn oracle_surface_is_the_mesh_surface() {
    // The oracle's own interpolation agrees with the one function the GPU mesh and the bake use.
    assert_eq!(TILE_DIAGONAL, Diagonal::SouthWestToNorthEast);
    let corners = [
        (0.0, 0.0, 0.0, 10.0),
        (3.5, -7.25, 120.0, 44.0),
        (1e3, 2e3, -5e2, 7.0),
    ];
    for &(sw, se, nw, ne) in &corners {
        for s in [2u32, 4, 16] {
            for i in 0..=s {
                for j in 0..=s {
                    let (u, v) = (f64::from(i) / f64::from(s), f64::from(j) / f64::from(s));
                    let a = barycentric(sw, se, nw, ne, u, v);
                    let b = quad_surface(sw, se, nw, ne, u, v);
                    assert!(
                        (a - b).abs() <= 1e-9 * (1.0 + a.abs()),
                        "({u},{v}): {a} vs {b}"
                    );
                }
            }
        }
    }
}

/// A random heightfield with cliffs (a vertical step along a row and a column) and
/// single-sample spikes, of any size (padded by the dataset).
fn terrain_strategy() -> impl Strategy<Value = (usize, usize, Vec<f32>, u32)> {
    (2usize..=41, 2usize..=41)
        .prop_flat_map(|(w, h)| {
            (
                Just(w),
                Just(h),
                prop::collection::vec(-50.0f32..50.0, w * h),
                (0..w, 0..h, -800.0f32..800.0),
                prop::collection::vec((0..w, 0..h, 100.0f32..2000.0), 0..5),
                prop::sample::select(vec![3u32, 5, 9, 17]),
            )
        })
        .prop_map(|(w, h, mut hs, (cliff_c, cliff_r, step), spikes, m)| {
            for r in 0..h {
                for c in 0..w {
                    if c >= cliff_c {
                        hs[r * w + c] += step;
                    }
                    if r >= cliff_r {
                        hs[r * w + c] -= step / 2.0;
                    }
                }
            }
            for (c, r, up) in spikes {
                hs[r * w + c] += up;
            }
            (w, h, hs, m)
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 160, ..ProptestConfig::default() })]

    #[test]
    fn every_stored_eps_equals_the_brute_force_oracle((w, h, hs, m) in terrain_strategy()) {
        let ds = dataset(w, h, hs, 7.0);
        let params = BakeParams { tile_size: m, levels: 0 };
        // Too small for one m×m tile: the parameters are refused, never a wrong bake.
        let Ok(levels) = params.resolve_levels(&ds) else {
            prop_assert!(ds.hf.width.min(ds.hf.height) < m as usize);
            return Ok(());
        };
        let b = bake(&ds, params, &|_, _| {});
        prop_assert_eq!(b.levels.len() as u32, levels);
        prop_assert_eq!((b.width as usize, b.height as usize), (ds.hf.width, ds.hf.height));
        check_tiles(&ds, &b, &|_, _, _| true);
        // ε with refinement r = the level-(L−r) surface over the level-L tile's subtiles that
        // hold real samples (every real sample of the tile is in one of them).
        let q = (m - 1) as usize;
        for t in &b.levels {
            for r in 1..=t.level {
                let fine = q << (t.level - r);
                let k = 1usize << r;
                for ty in 0..t.tiles_y as usize {
                    for tx in 0..t.tiles_x as usize {
                        let mut e = 0f64;
                        for sy in ty * k..(ty + 1) * k {
                            for sx in tx * k..(tx + 1) * k {
                                let (se, _, _, real) = oracle_tile(&ds, fine, sx, sy, t.level - r);
                                if real {
                                    e = e.max(se);
                                }
                            }
                        }
                        let got = b.eps_refined(t.level, tx as u32, ty as u32, r);
                        assert_eps_matches(got, e, "refined");
                    }
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Real fixtures
// ---------------------------------------------------------------------------------------------

fn shared_dem(rel: &str) -> Option<PathBuf> {
    let p = aerie_tests::repo_root()
        .join("../shared/data/dem")
        .join(rel);
    if p.exists() {
        Some(p)
    } else {
        eprintln!(
            "skipping: {} not found (fresh clone without ../shared)",
            p.display()
        );
        None
    }
}

#[test]
fn alpine_npy_every_tile_every_level() {
    let Some(p) = shared_dem("forge3d_codec_corpus/alpine.npy") else {
        return;
    };
    let ds = load_dataset(&p).unwrap();
    assert_eq!((ds.valid_width, ds.valid_height), (256, 256));
    assert_eq!((ds.hf.width, ds.hf.height), (257, 257));
    for m in [9, 17] {
        let b = bake(
            &ds,
            BakeParams {
                tile_size: m,
                levels: 0,
            },
            &|_, _| {},
        );
        let n = check_tiles(&ds, &b, &|_, _, _| true);
        assert!(n > 100, "{n}");
        // Mount Rainier is steep: coarse levels have large errors, which grow with the level.
        let max = |l: usize| b.levels[l].eps.iter().fold(0f32, |a, &e| a.max(e));
        assert!(max(1) > 5.0 && max(b.levels.len() - 1) > max(1));
    }
}

#[test]
fn n47e011_subset_of_tiles() {
    let Some(p) = shared_dem("srtm3_single/N47E011.hgt.zip") else {
        return;
    };
    let ds = load_dataset(&p).unwrap();
    assert_eq!((ds.hf.width, ds.hf.height), (2049, 2049));
    let b = bake(&ds, BakeParams::default(), &|_, _| {});
    assert_eq!(b.levels.len(), 8); // 2048 = 2^11, m − 1 = 2^4 → levels 0..=7
                                   // Per level: a strided sample of tiles, the tile of the level's largest ε, and the tiles on
                                   // the real/padding boundary, within a budget of samples per level.
    let q = 16usize;
    let mut picks: Vec<Vec<(u32, u32)>> = Vec::new();
    for t in &b.levels {
        let side = (q << t.level) + 1;
        let budget = (300_000 / (side * side)).max(1);
        let argmax = (0..t.len())
            .max_by(|&a, &b| t.eps[a].total_cmp(&t.eps[b]))
            .unwrap() as u32;
        let mut v = vec![(argmax % t.tiles_x, argmax / t.tiles_x)];
        let boundary = ((1200 / (q << t.level)) as u32).min(t.tiles_x - 1);
        v.push((boundary, boundary));
        let stride = (t.len() / budget).max(1);
        for i in (0..t.len()).step_by(stride).take(budget) {
            v.push((i as u32 % t.tiles_x, i as u32 / t.tiles_x));
        }
        picks.push(v);
    }
    let n = check_tiles(&ds, &b, &|l, tx, ty| picks[l as usize].contains(&(tx, ty)));
    assert!(n >= 8 * 2, "{n}");
    // The Alps at 92 m × 63 m: tens of metres at level 1, hundreds at level 4.
    let max = |l: usize| b.levels[l].eps.iter().fold(0f32, |a, &e| a.max(e));
    assert!(max(1) > 20.0 && max(4) > 200.0, "{} {}", max(1), max(4));
    // Padding: 1201 real samples of 2049 → the north-east tiles are not terrain.
    // Level-0 tile 75 spans columns 1200..=1216: its west edge is the last real column.
    assert!(b.is_terrain(0, 75, 75) && !b.is_terrain(0, 76, 0) && !b.is_terrain(0, 127, 127));
}

// ---------------------------------------------------------------------------------------------
// The file
// ---------------------------------------------------------------------------------------------

fn small_ds(seed: u32) -> Dataset {
    let (w, h) = (40, 23);
    let hs = (0..w * h)
        .map(|i| ((i as u32).wrapping_mul(2_654_435_761) ^ seed) % 1000)
        .map(|v| v as f32 * 0.37)
        .collect();
    dataset(w, h, hs, 30.0)
}

fn fresh_bake(dir: &Path) -> (Dataset, ErrorBake, PathBuf) {
    let ds = small_ds(1);
    let b = bake(
        &ds,
        BakeParams {
            tile_size: 5,
            levels: 0,
        },
        &|_, _| {},
    );
    let p = dir.join("small.f32.aerie-bake");
    write_bake(&p, &b).unwrap();
    (ds, b, p)
}

fn assert_mentions(e: &BakeError, parts: &[&str]) {
    let msg = e.to_string();
    assert!(!msg.contains('\n'), "{msg}");
    for p in parts {
        assert!(msg.contains(p), "`{msg}` lacks `{p}`");
    }
}

#[test]
fn bake_file_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let (ds, b, p) = fresh_bake(dir.path());
    let len = std::fs::metadata(&p).unwrap().len();
    assert_eq!(len, b.file_size());
    let back = read_bake(&p, &ds).unwrap();
    assert_eq!(back, b);
    assert_eq!(&std::fs::read(&p).unwrap()[..8], b"AERIEBAK");
    // No temporary file is left behind.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn stale_truncated_other_version_bad_magic_and_corrupt_are_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let (ds, _, p) = fresh_bake(dir.path());
    let good = std::fs::read(&p).unwrap();
    let ps = p.display().to_string();

    // Stale: one sample changed.
    let mut other = ds.clone();
    other.hf.heights[77] += 1.0;
    let e = read_bake(&p, &other).unwrap_err();
    assert!(matches!(e, BakeError::Stale { .. }), "{e:?}");
    assert_mentions(&e, &[&ps, "stale", "checksum", "aerie bake"]);
    // Stale: another grid.
    let e = read_bake(&p, &small_ds(1).clone_with_spacing(31.0)).unwrap_err();
    assert_mentions(&e, &["stale", "spacing"]);

    // Truncated anywhere: inside the magic, the header, an array, the trailing CRC.
    for cut in [3usize, 10, 50, 96, 120, good.len() - 30, good.len() - 1] {
        std::fs::write(&p, &good[..cut]).unwrap();
        let e = read_bake(&p, &ds).unwrap_err();
        assert!(
            matches!(e, BakeError::Truncated { offset, .. } if offset == cut as u64),
            "cut {cut}: {e:?}"
        );
        assert_mentions(
            &e,
            &[
                &ps,
                &format!("truncated at byte offset {cut}"),
                "aerie bake",
            ],
        );
    }

    // Another version (the version is read before anything that could depend on it).
    let mut v = good.clone();
    v[8..12].copy_from_slice(&(BAKE_VERSION + 1).to_le_bytes());
    std::fs::write(&p, &v).unwrap();
    let e = read_bake(&p, &ds).unwrap_err();
    assert!(matches!(e, BakeError::Version { found, .. } if found == BAKE_VERSION + 1));
    assert_mentions(
        &e,
        &[
            &ps,
            &format!("version {}", BAKE_VERSION + 1),
            "byte offset 8",
            "aerie bake",
        ],
    );

    // Not a bake at all.
    std::fs::write(&p, b"P6\n320 200\n255\n and so on, an image").unwrap();
    let e = read_bake(&p, &ds).unwrap_err();
    assert!(matches!(e, BakeError::BadMagic { .. }), "{e:?}");
    assert_mentions(&e, &[&ps, "not an aerie bake file", "aerie bake"]);

    // A flipped bit in an ε array: the file CRC names the field and offset.
    let mut c = good.clone();
    c[96 + 16 + 5] ^= 0x40;
    std::fs::write(&p, &c).unwrap();
    let e = read_bake(&p, &ds).unwrap_err();
    assert!(
        matches!(e, BakeError::Corrupt { ref field, .. } if field == "file CRC-32"),
        "{e:?}"
    );
    assert_mentions(&e, &[&format!("byte offset {}", good.len() - 4)]);
    // A flipped bit in the header: the header CRC.
    let mut c = good.clone();
    c[17] ^= 1;
    std::fs::write(&p, &c).unwrap();
    let e = read_bake(&p, &ds).unwrap_err();
    assert_mentions(&e, &["header CRC-32", "byte offset 92"]);
    // Missing.
    let e = read_bake(&dir.path().join("none.aerie-bake"), &ds).unwrap_err();
    assert!(matches!(e, BakeError::NotFound { .. }));
}

trait WithSpacing {
    fn clone_with_spacing(&self, s: f64) -> Dataset;
}

impl WithSpacing for Dataset {
    fn clone_with_spacing(&self, s: f64) -> Dataset {
        let mut d = self.clone();
        d.hf.spacing_x = s;
        d
    }
}

#[test]
fn nothing_is_overwritten_silently() {
    let dir = tempfile::tempdir().unwrap();
    let ds = small_ds(2);
    let params = BakeParams {
        tile_size: 5,
        levels: 0,
    };
    let p = dir.path().join("x.aerie-bake");
    let noop = |_: u64, _: u64| {};

    // Missing → baked; again → up to date, file untouched.
    let (b, o) = load_or_bake(&ds, &p, params, false, &noop).unwrap();
    assert_eq!(o, BakeOutcome::Baked);
    let bytes = std::fs::read(&p).unwrap();
    let (b2, o) = load_or_bake(&ds, &p, params, false, &noop).unwrap();
    assert_eq!((o, &b2), (BakeOutcome::UpToDate, &b));
    assert_eq!(std::fs::read(&p).unwrap(), bytes);

    // Other parameters or stale data → replaced, and the outcome says why.
    let (_, o) = load_or_bake(
        &ds,
        &p,
        BakeParams {
            tile_size: 3,
            levels: 2,
        },
        false,
        &noop,
    )
    .unwrap();
    assert!(
        matches!(o, BakeOutcome::Replaced(ref why) if why.contains("m = 5")),
        "{o:?}"
    );
    let (_, o) = load_or_bake(&small_ds(3), &p, params, false, &noop).unwrap();
    assert!(
        matches!(o, BakeOutcome::Replaced(ref why) if why.contains("stale")),
        "{o:?}"
    );

    // Not a bake → refused, untouched; --force replaces it.
    std::fs::write(&p, b"my precious notes").unwrap();
    let e = load_or_bake(&ds, &p, params, false, &noop).unwrap_err();
    assert!(matches!(e, BakeError::Refused { .. }), "{e:?}");
    assert_mentions(&e, &["not an aerie bake file", "--force"]);
    assert_eq!(std::fs::read(&p).unwrap(), b"my precious notes");
    let (_, o) = load_or_bake(&ds, &p, params, true, &noop).unwrap();
    assert!(matches!(o, BakeOutcome::Replaced(_)));
    assert_eq!(read_bake(&p, &ds).unwrap(), b);

    // A newer version's bake → refused; an older one is replaced.
    let mut v = std::fs::read(&p).unwrap();
    v[8..12].copy_from_slice(&(BAKE_VERSION + 1).to_le_bytes());
    std::fs::write(&p, &v).unwrap();
    let e = load_or_bake(&ds, &p, params, false, &noop).unwrap_err();
    assert_mentions(&e, &["newer format version"]);
    assert_eq!(std::fs::read(&p).unwrap(), v);
    v[8..12].copy_from_slice(&0u32.to_le_bytes());
    std::fs::write(&p, &v).unwrap();
    let (_, o) = load_or_bake(&ds, &p, params, false, &noop).unwrap();
    assert!(
        matches!(o, BakeOutcome::Replaced(ref why) if why.contains("version 0")),
        "{o:?}"
    );
}

#[test]
fn bake_path_next_to_file_and_folder() {
    assert_eq!(
        bake_path_for(Path::new("/data/dem/alpine.npy")),
        Path::new("/data/dem/alpine.npy.aerie-bake")
    );
    assert_eq!(
        bake_path_for(Path::new("/data/srtm3_sierra_nevada_es")),
        Path::new("/data/srtm3_sierra_nevada_es.aerie-bake")
    );
}

// ---------------------------------------------------------------------------------------------
// The commands
// ---------------------------------------------------------------------------------------------

fn aerie(args: &[&str]) -> Result<(), aerie::app::failure::Failure> {
    use clap::Parser as _;
    let mut v = vec!["aerie"];
    v.extend_from_slice(args);
    let cli = aerie::app::cli::Cli::try_parse_from(v).expect("arguments parse");
    aerie::app::cli::run(cli)
}

fn gen(dir: &Path, name: &str, kind: &str, seed: u64, size: usize) -> PathBuf {
    let out = dir.join(name);
    aerie(&[
        "gen-dem",
        "--size",
        &size.to_string(),
        "--spacing",
        "10",
        "--kind",
        kind,
        "--seed",
        &seed.to_string(),
        "--out",
        out.to_str().unwrap(),
    ])
    .unwrap_or_else(|f| panic!("gen-dem: {}", f.message));
    out
}

#[test]
fn gen_dem_is_deterministic_and_loads() {
    let dir = tempfile::tempdir().unwrap();
    let a = gen(dir.path(), "a.f32", "mixed", 42, 129);
    let b = gen(dir.path(), "b.f32", "mixed", 42, 129);
    let c = gen(dir.path(), "c.f32", "mixed", 43, 129);
    let (ba, bb, bc) = (
        std::fs::read(&a).unwrap(),
        std::fs::read(&b).unwrap(),
        std::fs::read(&c).unwrap(),
    );
    assert_eq!(ba.len(), 129 * 129 * 4);
    assert_eq!(ba, bb, "same seed, different bytes");
    assert_ne!(ba, bc, "different seed, same bytes");
    let hf = aerie::terrain::load_dem(&a).unwrap();
    assert_eq!(
        (hf.width, hf.height, hf.spacing_x, hf.spacing_y),
        (129, 129, 10.0, 10.0)
    );
    let mem = aerie::terrain::gen::generate(&aerie::terrain::gen::GenParams {
        size: 129,
        spacing: 10.0,
        kind: aerie::terrain::gen::DemKind::Mixed,
        seed: 42,
    });
    assert_eq!(
        hf.heights, mem.heights,
        "file rows are south first, as generated"
    );
}

fn load(p: &Path) -> Heightfield {
    aerie::terrain::load_dem(p).unwrap()
}

/// Largest |Δh| between 4-neighbours.
fn max_step(hf: &Heightfield, skip: &dyn Fn(usize, usize) -> bool) -> f32 {
    let mut m = 0f32;
    for r in 0..hf.height {
        for c in 0..hf.width {
            if skip(c, r) {
                continue;
            }
            if c + 1 < hf.width && !skip(c + 1, r) {
                m = m.max((hf.at(c, r) - hf.at(c + 1, r)).abs());
            }
            if r + 1 < hf.height && !skip(c, r + 1) {
                m = m.max((hf.at(c, r) - hf.at(c, r + 1)).abs());
            }
        }
    }
    m
}

/// Samples higher than all 8 neighbours by at least `by` metres.
fn needles(hf: &Heightfield, by: f32) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    for r in 1..hf.height - 1 {
        for c in 1..hf.width - 1 {
            let h = hf.at(c, r);
            let all = (-1i64..=1).all(|dr| {
                (-1i64..=1).all(|dc| {
                    (dr, dc) == (0, 0)
                        || h - hf.at((c as i64 + dc) as usize, (r as i64 + dr) as usize) >= by
                })
            });
            if all {
                out.push((c, r));
            }
        }
    }
    out
}

#[test]
fn gen_dem_kinds_have_their_character() {
    let dir = tempfile::tempdir().unwrap();
    let n = 257;
    // Cliffs: vertical walls of ≥ 150 m between adjacent samples.
    let hf = load(&gen(dir.path(), "cliffs.f32", "cliffs", 5, n));
    let step = max_step(&hf, &|_, _| false);
    assert!(step >= 150.0, "largest adjacent step {step} m");
    // Spikes: isolated single-sample needles (≥ 300 m tall, so ≥ 250 m above all 8 neighbours
    // on hills that move < 20 m per sample); elsewhere smooth.
    let hf = load(&gen(dir.path(), "spikes.f32", "spikes", 5, n));
    let nd = needles(&hf, 250.0);
    assert!(nd.len() >= 50, "{} needles", nd.len());
    for (i, a) in nd.iter().enumerate() {
        for b in &nd[i + 1..] {
            assert!(
                a.0.abs_diff(b.0) > 1 || a.1.abs_diff(b.1) > 1,
                "needles {a:?} {b:?} touch"
            );
        }
    }
    let smooth = max_step(&hf, &|c, r| nd.contains(&(c, r)));
    assert!(smooth < 20.0, "hills between needles step {smooth} m");
    // Flat is flat.
    let hf = load(&gen(dir.path(), "flat.f32", "flat", 5, n));
    assert!(hf.heights.iter().all(|&h| h == hf.heights[0]));
    // Ridged: real relief, smooth at the sample scale.
    let hf = load(&gen(dir.path(), "ridged.f32", "ridged", 5, n));
    let (lo, hi) = hf.min_max();
    assert!(hi - lo > 100.0 && lo >= 0.0 && hi < 4000.0, "{lo}..{hi}");
    // Mixed: the flat quadrant is flat, the spikes quadrant has needles.
    let hf = load(&gen(dir.path(), "mixed.f32", "mixed", 5, n));
    let h0 = hf.at(n - 1, n - 1);
    assert!((n / 2..n).all(|r| (n / 2..n).all(|c| hf.at(c, r) == h0)));
    assert!(needles(&hf, 250.0)
        .iter()
        .any(|&(c, r)| c < n / 2 && r >= n / 2));
}

#[test]
fn bake_command_writes_reports_and_refuses() {
    let dir = tempfile::tempdir().unwrap();
    let dem = gen(dir.path(), "t.f32", "spikes", 9, 100);
    let d = dem.to_str().unwrap();
    aerie(&["bake", d, "--tile-size", "9", "--report"]).unwrap_or_else(|f| panic!("{}", f.message));
    let bake_file = bake_path_for(&dem);
    let ds = load_dataset(&dem).unwrap();
    let b = read_bake(&bake_file, &ds).unwrap();
    assert_eq!((b.params.tile_size, b.params.levels), (9, 5)); // 100 → 129 = 2^7+1; 7 − 3 + 1
    check_tiles(&ds, &b, &|l, _, _| l <= 2);
    let csv = std::fs::read_to_string(format!("{}.csv", bake_file.display())).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 1 + 5, "{csv}");
    assert!(lines[0].starts_with("level,") && lines[0].contains("p99_eps_m"));
    let l1: Vec<&str> = lines[2].split(',').collect();
    let max1 = b.levels[1].eps.iter().fold(0f32, |a, &e| a.max(e));
    assert_eq!(l1[6].parse::<f32>().unwrap(), max1, "{}", lines[2]);
    // Up to date: the file is not rewritten.
    let before = std::fs::read(&bake_file).unwrap();
    aerie(&["bake", d, "--tile-size", "9"]).unwrap();
    assert_eq!(std::fs::read(&bake_file).unwrap(), before);

    // Bad input exits 2: unknown dataset, bad tile size, too many levels, non-bake output.
    let code = |args: &[&str]| aerie(args).unwrap_err().code;
    assert_eq!(code(&["bake", "/nonexistent/x.hgt"]), 2);
    assert_eq!(code(&["bake", d, "--tile-size", "16"]), 2);
    assert_eq!(code(&["bake", d, "--levels", "40"]), 2);
    let notes = dir.path().join("notes.txt");
    std::fs::write(&notes, "keep me").unwrap();
    let f = aerie(&["bake", d, "--out", notes.to_str().unwrap()]).unwrap_err();
    assert_eq!(f.code, 2);
    assert!(
        f.message.contains("not an aerie bake file"),
        "{}",
        f.message
    );
    assert_eq!(std::fs::read_to_string(&notes).unwrap(), "keep me");
    aerie(&["bake", d, "--out", notes.to_str().unwrap(), "--force"]).unwrap();
    assert!(read_bake(&notes, &ds).is_ok());
    assert_eq!(code(&["gen-dem", "--size", "1", "--out", "/tmp/x.f32"]), 2);
    assert_eq!(code(&["gen-dem", "--size", "9", "--out", "/tmp/x.png"]), 2);
}
