//! Fuzz target bodies for aerie's file parsers: the DEM loaders (`dem`), bake files (`bake`),
//! tile stores (`store`) and TOML configs (`config`). Each takes arbitrary bytes, must not panic, checks what must
//! hold for any input (a loaded grid is consistent, an error names its file on one line) and
//! returns whether the input was accepted, so the replay test can check that the corpus gets
//! past the first checks.
//!
//! The DEM and bake readers take paths (they choose the format from the file name and read a
//! `<file>.json` sidecar next to it), so the bytes are written to a scratch folder first: in
//! `/dev/shm` where it exists, to keep a run of millions of inputs off the disk.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use aerie_terrain::bake::read_bake_file;
use aerie_terrain::load_dem;
use aerie_terrain::store::{PageId, Store};

/// The file names the DEM input's first byte chooses between: one per loader (`load_dem`
/// dispatches on the name; HGT tiles also need a tile name for their placement).
pub const DEM_NAMES: [&str; 8] = [
    "N47E011.hgt",
    "N47E011.hgt.zip",
    "dem.tif",
    "dem.png",
    "dem.f32",
    "dem.u16",
    "dem.npy",
    "dem.npz",
];

/// This thread's scratch folder: one per process and thread (the replay tests run on several
/// threads of one process, and a fuzzer may run beside them; two bodies writing the same
/// `dem.f32` at once would read each other's bytes). Left behind on exit, each holds at most
/// two small files.
fn scratch() -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    thread_local! {
        static DIR: PathBuf = {
            let shm = Path::new("/dev/shm");
            let base = if shm.is_dir() {
                shm.to_path_buf()
            } else {
                std::env::temp_dir()
            };
            let n = COUNTER.fetch_add(1, Ordering::Relaxed);
            let dir = base.join(format!("aerie-fuzz-{}-{n}", std::process::id()));
            std::fs::create_dir_all(&dir).expect("scratch folder");
            dir
        };
    }
    DIR.with(PathBuf::clone)
}

/// A DEM input's parts: file name, sidecar (if any), file bytes.
pub type DemParts<'a> = (&'static str, Option<&'a [u8]>, &'a [u8]);

/// Splits a DEM input: byte 0 picks the file name (`DEM_NAMES`), byte 1 is the sidecar's
/// length (0: no sidecar), then the sidecar JSON, then the DEM file itself.
pub fn split_dem_input(b: &[u8]) -> Option<DemParts<'_>> {
    let (&kind, rest) = b.split_first()?;
    let (&n, rest) = rest.split_first()?;
    let n = usize::from(n).min(rest.len());
    let (sidecar, dem) = rest.split_at(n);
    let name = DEM_NAMES[usize::from(kind) % DEM_NAMES.len()];
    Some((name, (n > 0).then_some(sidecar), dem))
}

/// Builds a DEM input (the inverse of [`split_dem_input`]; the seed writer uses it).
pub fn dem_input(name: &str, sidecar: Option<&str>, dem: &[u8]) -> Vec<u8> {
    let kind = DEM_NAMES
        .iter()
        .position(|n| *n == name)
        .expect("a DEM name") as u8;
    let side = sidecar.unwrap_or("").as_bytes();
    assert!(side.len() <= 255, "sidecar over 255 bytes");
    let mut v = vec![kind, side.len() as u8];
    v.extend_from_slice(side);
    v.extend_from_slice(dem);
    v
}

/// A DEM file (any format, with or without a sidecar): it loads into a consistent grid of
/// finite heights and positive finite spacings, or the error is one line naming the file.
pub fn dem(b: &[u8]) -> bool {
    let Some((name, sidecar, bytes)) = split_dem_input(b) else {
        return false;
    };
    let path = scratch().join(name);
    let side = scratch().join(format!("{name}.json"));
    std::fs::write(&path, bytes).expect("scratch write");
    match sidecar {
        Some(s) => std::fs::write(&side, s).expect("scratch write"),
        None => match std::fs::remove_file(&side) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => panic!("{}: {e}", side.display()),
        },
    }
    match load_dem(&path) {
        Ok(hf) => {
            assert!(
                hf.width >= 2 && hf.height >= 2,
                "{}×{}",
                hf.width,
                hf.height
            );
            assert_eq!(hf.heights.len(), hf.width * hf.height);
            // The loaders' plausibility limits: spacings 1 mm ..= 100 km (a subnormal GeoTIFF
            // ModelPixelScale once loaded and void filling turned its heights into NaN).
            for s in [hf.spacing_x, hf.spacing_y] {
                assert!((1e-3..=1e5).contains(&s), "spacing {s}");
            }
            assert!(
                hf.heights.iter().all(|h| h.is_finite()),
                "non-finite height"
            );
            true
        }
        Err(e) => {
            let msg = e.to_string();
            assert!(!msg.contains('\n'), "multi-line error: {msg:?}");
            assert!(msg.contains(name), "error does not name {name}: {msg}");
            false
        }
    }
}

/// A bake file: it reads into tables of the sizes its header claims, or the error is one line
/// naming the file.
pub fn bake(b: &[u8]) -> bool {
    let path = scratch().join("dem.aerie-bake");
    std::fs::write(&path, b).expect("scratch write");
    match read_bake_file(&path) {
        Ok(bake) => {
            assert!(bake.valid_width <= bake.width && bake.valid_height <= bake.height);
            for s in [bake.spacing_x, bake.spacing_y] {
                assert!(s.is_finite() && s > 0.0, "spacing {s}");
            }
            assert_eq!(
                bake.file_size(),
                b.len() as u64,
                "every byte is accounted for"
            );
            true
        }
        Err(e) => {
            let msg = e.to_string();
            assert!(!msg.contains('\n'), "multi-line error: {msg:?}");
            assert!(
                msg.contains("dem.aerie-bake"),
                "error does not name the file: {msg}"
            );
            false
        }
    }
}

/// Pages a `store` input reads at most (a fuzzed index may claim millions).
const STORE_PAGES: usize = 64;

/// A tile store: it opens (header, trailer, index), its bake section reads into tables of the
/// grid's sizes, and its first pages read into samples of their layout's sizes — or each
/// error is one line naming the file. Never a panic, whatever the bytes.
pub fn store(b: &[u8]) -> bool {
    let path = scratch().join("dem.aerie");
    std::fs::write(&path, b).expect("scratch write");
    let one_line = |msg: String| {
        assert!(!msg.contains('\n'), "multi-line error: {msg:?}");
        assert!(
            msg.contains("dem.aerie"),
            "error does not name the file: {msg}"
        );
    };
    let store = match Store::open(&path) {
        Ok(s) => s,
        Err(e) => {
            one_line(e.to_string());
            return false;
        }
    };
    let h = store.header().clone();
    assert!(h.valid_width <= h.width && h.valid_height <= h.height);
    match store.read_bake() {
        Ok(bake) => {
            assert_eq!((bake.width, bake.height), (h.width, h.height));
            assert_eq!(bake.levels.len() as u32, h.levels);
            for (l, t) in bake.levels.iter().enumerate() {
                let g = store.layout().levels[l];
                assert_eq!((t.tiles_x, t.tiles_y), (g.tiles_x, g.tiles_y));
                assert_eq!(t.eps.len(), (g.tiles_x * g.tiles_y) as usize);
            }
        }
        Err(e) => one_line(e.to_string()),
    }
    let mut ok = true;
    for e in store.pages().iter().take(STORE_PAGES) {
        let id = PageId {
            level: e.level,
            px: e.px,
            py: e.py,
        };
        match store.read_page(id) {
            Ok(p) => {
                let r = store.layout().rect(id.level, id.px, id.py);
                assert_eq!(p.rect, r);
                assert_eq!(p.samples.len(), r.samples());
                assert!(p.samples.iter().all(|v| v.is_finite()), "non-finite sample");
            }
            Err(err) => {
                one_line(err.to_string());
                ok = false;
            }
        }
    }
    ok
}

/// A config file (UTF-8 or not): it parses and writes back TOML that parses to an equal value,
/// or the error is one line starting with the file name.
pub fn config(b: &[u8]) -> bool {
    let Ok(text) = std::str::from_utf8(b) else {
        return false;
    };
    match aerie_config::parse(text, "fuzz.toml") {
        Ok(cfg) => {
            let again = cfg.to_toml().expect("a parsed config writes back");
            let back = aerie_config::parse(&again, "again.toml")
                .unwrap_or_else(|e| panic!("written config does not parse: {e}\n{again}"));
            assert_eq!(back, cfg, "round trip changed the config");
            true
        }
        Err(e) => {
            let msg = e.to_string();
            assert!(!msg.contains('\n'), "multi-line error: {msg:?}");
            assert!(
                msg.starts_with("fuzz.toml"),
                "error does not start with the file: {msg}"
            );
            false
        }
    }
}
