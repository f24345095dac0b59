//! The streamed import against the in-memory one: for raw grids of every sample format, both
//! row orders, padding on both axes and several bands, the streamed bake equals `bake()` and
//! the store file is byte for byte the one `write_store` writes; a bad sample found mid-way is
//! an error naming it, and nothing is left under the store's name.

use std::path::Path;

use super::*;
use crate::bake::{bake, BakeParams};
use crate::dataset::load_dataset;
use crate::load::RawRows;

/// A rough surface with fractional heights (f32) or integer steps (u16 with scale/offset).
fn height(c: usize, r: usize) -> f64 {
    let (x, y) = (c as f64, r as f64);
    800.0
        + 300.0 * (x * 0.031).sin() * (y * 0.017).cos()
        + 40.0 * ((x * 0.7 + y * 1.3).sin())
        + if (c * 7 + r * 13).is_multiple_of(97) {
            150.0
        } else {
            0.0
        }
}

/// Writes `<name>` (w × h in file order) and its sidecar into `dir`.
fn write_raw(
    dir: &Path,
    name: &str,
    w: usize,
    h: usize,
    format: &str,
    north_up: bool,
) -> std::path::PathBuf {
    let path = dir.join(name);
    let mut bytes = Vec::new();
    for r in 0..h {
        for c in 0..w {
            let v = height(c, r);
            match format {
                "f32le" => bytes.extend_from_slice(&(v as f32).to_le_bytes()),
                "f32be" => bytes.extend_from_slice(&(v as f32).to_be_bytes()),
                "u16le" => bytes.extend_from_slice(&((v * 4.0) as u16).to_le_bytes()),
                _ => unreachable!(),
            }
        }
    }
    std::fs::write(&path, bytes).unwrap();
    let scale = if format == "u16le" {
        ", \"scale\": 0.25, \"offset\": -12.5"
    } else {
        ""
    };
    std::fs::write(
        dir.join(format!("{name}.json")),
        format!(
            "{{\"width\": {w}, \"height\": {h}, \"format\": \"{format}\", \"spacing_x\": 25, \"spacing_y\": 30, \"north_up\": {north_up}{scale}}}"
        ),
    )
    .unwrap();
    path
}

fn params(path: &Path) -> ImportParams {
    ImportParams {
        sources: vec![path.display().to_string()],
        page_tiles: 4,
        zstd_level: 3,
    }
}

#[test]
fn streamed_import_writes_the_in_memory_import_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    // 600 rows padded to 1025: five bands of 256 rows; 300 columns padded to 513.
    for (name, w, h, format, north_up, m) in [
        ("a.f32", 300, 600, "f32le", true, 17),
        ("b.raw", 257, 700, "f32be", false, 9),
        ("c.u16", 513, 260, "u16le", true, 33),
    ] {
        let path = write_raw(dir.path(), name, w, h, format, north_up);
        let ds = load_dataset(&path).unwrap();
        let rows = RawRows::open(&path).unwrap().expect("a raw grid");
        assert_eq!(rows.padded_size(), (ds.hf.width, ds.hf.height), "{name}");
        let levels = BakeParams {
            tile_size: m,
            levels: 0,
        }
        .resolve_levels(&ds)
        .unwrap();
        let p = BakeParams {
            tile_size: m,
            levels,
        };
        let whole = bake(&ds, p, &|_, _| {});
        let streamed = bake_rows(&rows, p, &|_, _| {}).unwrap();
        assert_eq!(streamed, whole, "{name}: the streamed bake");
        assert_eq!(streamed.source_checksum, ds.checksum(), "{name}");

        let a = dir.path().join(format!("{name}.memory.aerie"));
        let b = dir.path().join(format!("{name}.rows.aerie"));
        let sa = write_store(&a, &ds, &whole, &params(&path), &|_, _| {}).unwrap();
        let sb = write_store_rows(&b, &rows, &streamed, &params(&path), &|_, _| {}).unwrap();
        assert_eq!(sb, sa, "{name}: summaries");
        let (ba, bb) = (std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
        assert_eq!(ba.len(), bb.len(), "{name}: file sizes");
        assert!(ba == bb, "{name}: the two stores differ");
        // And it reads back as its source.
        let (ds2, bake2) = load_store(&b).unwrap();
        assert_eq!(ds2.hf.heights, ds.hf.heights, "{name}");
        assert_eq!(bake2, whole, "{name}");
    }
}

#[test]
fn a_bad_sample_met_mid_import_names_its_row_and_leaves_no_store() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_raw(dir.path(), "bad.f32", 100, 400, "f32le", false);
    // Sample (col 7, row 333) of the file: 2e5 m.
    let mut bytes = std::fs::read(&path).unwrap();
    let at = (333 * 100 + 7) * 4;
    bytes[at..at + 4].copy_from_slice(&2e5f32.to_le_bytes());
    std::fs::write(&path, bytes).unwrap();
    let rows = RawRows::open(&path).unwrap().unwrap();
    let p = BakeParams {
        tile_size: 17,
        levels: 3,
    };
    let e = bake_rows(&rows, p, &|_, _| {}).unwrap_err().to_string();
    assert!(
        e.contains("bad.f32") && e.contains("(col 7, row 333)") && e.contains("out of range"),
        "{e}"
    );
    // A bake of good rows, then the pages meet the bad one: an error, and no store.
    let good = write_raw(dir.path(), "good.f32", 100, 400, "f32le", false);
    let b = bake_rows(&RawRows::open(&good).unwrap().unwrap(), p, &|_, _| {}).unwrap();
    let out = dir.path().join("bad.aerie");
    let e = write_store_rows(&out, &rows, &b, &params(&path), &|_, _| {})
        .unwrap_err()
        .to_string();
    assert!(e.contains("(col 7, row 333)"), "{e}");
    assert!(!out.exists());
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("aerie"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

#[test]
fn only_raw_grids_are_read_by_rows() {
    let dir = tempfile::tempdir().unwrap();
    let tif = dir.path().join("x.tif");
    std::fs::write(&tif, b"not read").unwrap();
    assert!(RawRows::open(&tif).unwrap().is_none());
    // A raw grid without its sidecar is the loader's error.
    let raw = dir.path().join("y.f32");
    std::fs::write(&raw, [0u8; 16]).unwrap();
    let e = RawRows::open(&raw).err().expect("no sidecar").to_string();
    assert!(e.contains("y.f32"), "{e}");
}
