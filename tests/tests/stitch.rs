//! Stitching adjacent SRTM tiles against the mosaic SHA-256 sums in
//! `../shared/data/dem/SOURCES.md` ("How to stitch the SRTM3 tiles": the mosaic as big-endian
//! int16, row-major, north at the top), the mosaic's spacing against the WGS84 formula at its
//! centre latitude, and voids filled and counted over a stitched set. Skips (with a note) when
//! `../shared` is absent.

use std::path::{Path, PathBuf};

use aerie::terrain::dataset::{load_dataset, load_dataset_tiles, Dataset};
use aerie::terrain::load::stitch::stitch_folder;
use aerie::terrain::{load_dem, GeoReference};
use sha2::{Digest, Sha256};

fn dem_dir() -> Option<PathBuf> {
    let d = aerie_tests::shared_dem_dir();
    if d.is_none() {
        eprintln!("skipping: ../shared/data/dem not found (fresh clone without ../shared)");
    }
    d
}

/// The real part of the dataset as SOURCES.md hashes it: north row first, big-endian i16.
fn mosaic_sha256(ds: &Dataset) -> String {
    let mut bytes = Vec::with_capacity(ds.valid_width * ds.valid_height * 2);
    for r in (0..ds.valid_height).rev() {
        for c in 0..ds.valid_width {
            let h = ds.hf.at(c, r);
            assert_eq!(
                h,
                h.round(),
                "SRTM sample ({c},{r}) = {h} is not an integer"
            );
            bytes.extend_from_slice(&(h as i16).to_be_bytes());
        }
    }
    let digest = Sha256::digest(&bytes);
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

/// Independent WGS84 spacing (radii from a and b) for a 3" grid at `lat`.
fn expected_spacing(lat: f64) -> (f64, f64) {
    let a = 6_378_137.0_f64;
    let b = a * (1.0 - 1.0 / 298.257_223_563);
    let p = lat.to_radians();
    let q = (a * a * p.cos().powi(2) + b * b * p.sin().powi(2)).sqrt();
    let m = (a * b).powi(2) / q.powi(3);
    let n = a * a / q;
    let d = (1.0f64 / 1200.0).to_radians();
    (d * n * p.cos(), d * m)
}

fn tiles(dir: &Path, folder: &str, names: &[&str]) -> Vec<PathBuf> {
    names
        .iter()
        .map(|n| dir.join(folder).join(format!("{n}.hgt")))
        .collect()
}

fn check_mosaic(
    ds: &Dataset,
    rows: usize,
    cols: usize,
    range: (f32, f32),
    sha: &str,
    centre_lat: f64,
) {
    assert_eq!((ds.valid_width, ds.valid_height), (cols, rows));
    assert_eq!(ds.hf.voids_filled, 0);
    assert_eq!(mosaic_sha256(ds), sha);
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for r in 0..rows {
        for c in 0..cols {
            lo = lo.min(ds.hf.at(c, r));
            hi = hi.max(ds.hf.at(c, r));
        }
    }
    assert_eq!((lo, hi), range);
    let (ew, ns) = expected_spacing(centre_lat);
    assert!(
        (ds.hf.spacing_x - ew).abs() < 1e-6,
        "{} vs {ew}",
        ds.hf.spacing_x
    );
    assert!(
        (ds.hf.spacing_y - ns).abs() < 1e-6,
        "{} vs {ns}",
        ds.hf.spacing_y
    );
    assert!(
        ds.hf.spacing_note.contains(&format!("{centre_lat:.3}°N")),
        "{}",
        ds.hf.spacing_note
    );
}

#[test]
fn sierra_nevada_folder_2x3_matches_sources_checksum() {
    let Some(dir) = dem_dir() else { return };
    let ds = load_dataset(&dir.join("srtm3_sierra_nevada_es")).unwrap();
    check_mosaic(
        &ds,
        2401,
        3601,
        (-14.0, 3460.0),
        "f402db54d14754df29d7183e88d8351ff9d581faa1925049ffa6b42d9a61c28c",
        37.0,
    );
    // Padded to 4097 × 4097, origin and geo-reference unchanged (south-west tile corner).
    assert_eq!((ds.hf.width, ds.hf.height), (4097, 4097));
    assert!(matches!(
        ds.hf.geo,
        Some(GeoReference::Geographic { south_lat_deg, west_lon_deg, .. })
            if south_lat_deg == 36.0 && west_lon_deg == -5.0
    ));
    assert!(
        ds.source.contains("2×3 SRTM3 tiles") && ds.source.contains("0 seam mismatches"),
        "{}",
        ds.source
    );
}

#[test]
fn sierra_nevada_east_2x2_list_matches_sources_checksum() {
    let Some(dir) = dem_dir() else { return };
    let list = tiles(
        &dir,
        "srtm3_sierra_nevada_es",
        &["N36W004", "N37W003", "N36W003", "N37W004"],
    );
    let ds = load_dataset_tiles(&list).unwrap();
    check_mosaic(
        &ds,
        2401,
        2401,
        (-14.0, 3460.0),
        "3ac41719ab28db8e11e0dd3237b921907fbc28b8406314f9a25b645ae6d23a8b",
        37.0,
    );
}

#[test]
fn northern_england_mosaics_match_sources_checksums() {
    let Some(dir) = dem_dir() else { return };
    let (ds, info) = stitch_folder(&dir.join("srtm3_northern_england")).unwrap();
    assert_eq!(info.seam_mismatches, 0);
    let ds = Dataset::from_heightfield(ds, "n-england".into());
    check_mosaic(
        &ds,
        2401,
        3601,
        (-49.0, 1059.0),
        "c897cb1f5b3f792a54c5ff32e2246138581e37a086b10213e5f5ab8dfd798db2",
        54.0,
    );
    let list = tiles(
        &dir,
        "srtm3_northern_england",
        &["N54W003", "N54W002", "N53W003", "N53W002"],
    );
    let ds = load_dataset_tiles(&list).unwrap();
    check_mosaic(
        &ds,
        2401,
        2401,
        (-49.0, 891.0),
        "eec0cc283f0061aaebda2f0ac6102a72ec9093cd833ccc88482e679a3ffef99b",
        54.0,
    );
}

#[test]
fn stitched_voids_are_filled_and_counted() {
    let Some(dir) = dem_dir() else { return };
    // A folder holding the voided Alps tile: the same fill and count as loading it alone.
    let tmp = tempfile::tempdir().unwrap();
    let zip = dir.join("srtm3_single/N47E011.hgt.zip");
    std::fs::copy(&zip, tmp.path().join("N47E011.hgt.zip")).unwrap();
    let ds = load_dataset(tmp.path()).unwrap();
    let alone = load_dem(&zip).unwrap();
    assert_eq!(ds.hf.voids_filled, 54_278);
    assert_eq!((ds.valid_width, ds.valid_height), (1201, 1201));
    for r in (0..1201).step_by(7) {
        for c in (0..1201).step_by(5) {
            assert_eq!(ds.hf.at(c, r), alone.at(c, r), "({c},{r})");
        }
    }
}

#[test]
fn gaps_and_wrong_sets_are_clear_errors() {
    let Some(dir) = dem_dir() else { return };
    // Diagonal neighbours only: a gap.
    let list = tiles(&dir, "srtm3_sierra_nevada_es", &["N36W005", "N37W004"]);
    let msg = load_dataset_tiles(&list).unwrap_err().to_string();
    assert!(
        msg.contains("full rectangle") && msg.contains("N37W005") && msg.contains("N36W004"),
        "{msg}"
    );
    // Tiles from two regions far apart.
    let list = vec![
        dir.join("srtm3_sierra_nevada_es/N36W005.hgt"),
        dir.join("srtm3_northern_england/N53W004.hgt"),
    ];
    let msg = load_dataset_tiles(&list).unwrap_err().to_string();
    assert!(msg.contains("missing"), "{msg}");
}
