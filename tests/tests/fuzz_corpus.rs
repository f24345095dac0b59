//! Replays the checked-in fuzz corpora of the file parsers (`fuzz/corpus/<target>/`, grown and
//! minimised by `make fuzz`) through the fuzz target bodies on the stable toolchain: an input
//! that once crashed a parser stays a test. The pose-input corpora (`sim-bridge/fuzz/`) are
//! replayed by `aerie_sim_bridge::fuzzing`'s own tests.

#[path = "../../fuzz/src/bodies.rs"]
mod bodies;

use std::path::{Path, PathBuf};

/// A target body: arbitrary bytes in, "accepted" out.
type Body = fn(&[u8]) -> bool;

/// Target name (= `fuzz/fuzz_targets/<name>.rs`, `fuzz/corpus/<name>/`) and body.
const TARGETS: [(&str, Body); 4] = [
    ("dem", bodies::dem),
    ("bake", bodies::bake),
    ("store", bodies::store),
    ("config", bodies::config),
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

fn files(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .collect();
    v.sort();
    v
}

/// Every corpus input runs through its body without panicking; some are accepted (the corpus
/// reaches past the magic and size checks) and some refused.
#[test]
fn file_parser_corpora_replay_without_a_panic() {
    for (name, body) in TARGETS {
        let entries = files(&root().join("fuzz/corpus").join(name));
        assert!(entries.len() >= 3, "{name}: {} inputs", entries.len());
        let mut ok = 0;
        for path in &entries {
            let bytes = std::fs::read(path).unwrap();
            let r = std::panic::catch_unwind(|| body(&bytes));
            match r {
                Ok(true) => ok += 1,
                Ok(false) => {}
                Err(_) => panic!("{name}: {} panics", path.display()),
            }
        }
        assert!(
            ok >= 1 && ok < entries.len(),
            "{name}: {ok} of {} inputs accepted",
            entries.len()
        );
    }
}

/// Each DEM loader is reached by some accepted corpus input (the name byte is not stuck on one
/// format), so the replay exercises every file format.
#[test]
fn dem_corpus_loads_every_format() {
    let mut loaded = [false; bodies::DEM_NAMES.len()];
    for path in files(&root().join("fuzz/corpus/dem")) {
        let bytes = std::fs::read(&path).unwrap();
        if bodies::dem(&bytes) {
            let (name, _, _) = bodies::split_dem_input(&bytes).unwrap();
            loaded[bodies::DEM_NAMES.iter().position(|n| *n == name).unwrap()] = true;
        }
    }
    for (i, name) in bodies::DEM_NAMES.iter().enumerate() {
        // An HGT tile is 2.8 MB or more: too big for the corpus, so no `.hgt` input loads; the
        // zipped tile and the HGT sample decoding share `decode_tile`, which the unit tests cover.
        if name.ends_with(".hgt") || name.ends_with(".hgt.zip") {
            continue;
        }
        assert!(loaded[i], "no corpus input loads as {name}");
    }
}

/// The DEM input layout round-trips (the seed writer and the body agree on it).
#[test]
fn dem_input_layout_round_trips() {
    let b = bodies::dem_input("dem.f32", Some("{\"width\":2}"), b"abcd");
    let (name, side, dem) = bodies::split_dem_input(&b).unwrap();
    assert_eq!(name, "dem.f32");
    assert_eq!(side, Some(&b"{\"width\":2}"[..]));
    assert_eq!(dem, b"abcd");
    assert_eq!(bodies::split_dem_input(&[3]), None);
    let (_, side, dem) = bodies::split_dem_input(&[3, 200, b'x']).unwrap();
    assert_eq!((side, dem), (Some(&b"x"[..]), &b""[..]));
}

/// The corpora stay small enough to live in the repository: no input over 8 KiB, all of them
/// (both fuzz projects) under 2 MiB.
#[test]
fn fuzz_corpora_stay_small() {
    let mut total = 0u64;
    for project in ["fuzz/corpus", "sim-bridge/fuzz/corpus"] {
        for dir in files_and_dirs(&root().join(project)) {
            for f in files(&dir) {
                let n = std::fs::metadata(&f).unwrap().len();
                assert!(n <= 8192, "{}: {n} bytes", f.display());
                total += n;
            }
        }
    }
    assert!(total < 2 << 20, "corpora total {total} bytes");
}

fn files_and_dirs(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect()
}

/// The fuzz project declares exactly these targets, each calling its body.
#[test]
fn fuzz_project_declares_every_target() {
    let fuzz = root().join("fuzz");
    let manifest = std::fs::read_to_string(fuzz.join("Cargo.toml")).unwrap();
    for (name, _) in TARGETS {
        assert!(manifest.contains(&format!("name = \"{name}\"")), "{name}");
        let src = std::fs::read_to_string(fuzz.join(format!("fuzz_targets/{name}.rs"))).unwrap();
        assert!(src.contains(&format!("bodies::{name}(")), "{name}.rs");
    }
}
