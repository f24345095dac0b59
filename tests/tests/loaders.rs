//! DEM loaders against the real elevation files in `../shared/data/dem` (see SOURCES.md there;
//! the expected numbers below are copied from its tables, which were produced with NumPy).
//! When that folder is absent (a fresh clone), each test prints a skip note and passes.

use std::path::{Path, PathBuf};
use std::time::Instant;

use aerie::terrain::{load_dem, DemError, GeoReference, Heightfield};

fn data_dir() -> Option<PathBuf> {
    let dir = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shared/data/dem"
    ));
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!(
            "skipping: real DEM folder {} not found (fresh clone without ../shared)",
            dir.display()
        );
        None
    }
}

fn load(path: &Path) -> Heightfield {
    load_dem(path).unwrap_or_else(|e| panic!("{e}"))
}

fn sw_corner(hf: &Heightfield) -> (f64, f64, f64, f64) {
    match hf.geo {
        Some(GeoReference::Geographic {
            south_lat_deg,
            west_lon_deg,
            dlat_deg,
            dlon_deg,
        }) => (south_lat_deg, west_lon_deg, dlat_deg, dlon_deg),
        ref other => panic!("expected a geographic reference, got {other:?}"),
    }
}

fn mean(hf: &Heightfield) -> f64 {
    hf.heights.iter().map(|&h| f64::from(h)).sum::<f64>() / hf.heights.len() as f64
}

#[test]
fn n47e011_zip_alps_with_voids() {
    let Some(dir) = data_dir() else { return };
    let t = Instant::now();
    let hf = load(&dir.join("srtm3_single/N47E011.hgt.zip"));
    eprintln!(
        "N47E011.hgt.zip loaded in {:?}: {}",
        t.elapsed(),
        hf.spacing_note
    );
    assert_eq!((hf.width, hf.height), (1201, 1201));
    assert_eq!(hf.heights.len(), 1201 * 1201);
    assert_eq!(hf.voids_filled, 54_278);
    assert!(hf.heights.iter().all(|h| h.is_finite()));
    let (lo, hi) = hf.min_max();
    assert!(lo >= 473.0 && hi <= 3461.0, "range after fill {lo}..{hi}");
    // The valid extremes are still there (fills never exceed them).
    assert_eq!((lo, hi), (473.0, 3461.0));
    assert!(
        (62.0..64.0).contains(&hf.spacing_x),
        "E-W spacing {}",
        hf.spacing_x
    );
    assert!(
        (hf.spacing_y - 92.6).abs() < 0.1,
        "N-S spacing {}",
        hf.spacing_y
    );
    let (lat, lon, dlat, dlon) = sw_corner(&hf);
    assert_eq!((lat, lon), (47.0, 11.0));
    assert!((dlat - 1.0 / 1200.0).abs() < 1e-15 && (dlon - 1.0 / 1200.0).abs() < 1e-15);
    assert!(hf.spacing_note.contains("47.500°N"), "{}", hf.spacing_note);
    // One degree of latitude is ~111 km; the extent follows from the spacing.
    let (x_ext, y_ext) = hf.extent_m();
    assert!((x_ext - 1200.0 * hf.spacing_x).abs() < 1e-6 && y_ext > 110_000.0);
}

#[test]
fn n40w074_new_york_western_hemisphere() {
    let Some(dir) = data_dir() else { return };
    let hf = load(&dir.join("srtm3_single/N40W074.hgt"));
    assert_eq!((hf.width, hf.height), (1201, 1201));
    assert_eq!(hf.voids_filled, 1051);
    let (lo, hi) = hf.min_max();
    assert!(lo >= -42.0 && hi <= 179.0, "range {lo}..{hi}");
    assert_eq!(sw_corner(&hf).0, 40.0);
    assert_eq!(sw_corner(&hf).1, -74.0);
    let at_or_below_zero = hf.heights.iter().filter(|&&h| h <= 0.0).count();
    // SOURCES.md: 1,030,801 valid samples <= 0; filled voids in water add a few more.
    assert!(
        (1_030_801..=1_030_801 + 1051).contains(&at_or_below_zero),
        "{at_or_below_zero}"
    );
}

/// (file, min, max, mean, samples <= 0) from SOURCES.md §1a/§1b; none of these tiles has voids.
const CLEAN_TILES: &[(&str, f32, f32, f64, usize)] = &[
    (
        "srtm3_sierra_nevada_es/N36W003.hgt",
        -14.0,
        2240.0,
        115.1,
        1_103_696,
    ),
    (
        "srtm3_sierra_nevada_es/N36W004.hgt",
        -2.0,
        2926.0,
        219.9,
        1_058_968,
    ),
    (
        "srtm3_sierra_nevada_es/N36W005.hgt",
        -9.0,
        2064.0,
        177.2,
        886_575,
    ),
    (
        "srtm3_sierra_nevada_es/N37W003.hgt",
        139.0,
        2602.0,
        1043.2,
        0,
    ),
    (
        "srtm3_sierra_nevada_es/N37W004.hgt",
        222.0,
        3460.0,
        959.8,
        0,
    ),
    ("srtm3_sierra_nevada_es/N37W005.hgt", 70.0, 1658.0, 444.0, 0),
    (
        "srtm3_northern_england/N53W002.hgt",
        -48.0,
        637.0,
        154.9,
        243,
    ),
    (
        "srtm3_northern_england/N53W003.hgt",
        -3.0,
        557.0,
        110.0,
        27_370,
    ),
    (
        "srtm3_northern_england/N53W004.hgt",
        -7.0,
        1059.0,
        71.1,
        941_473,
    ),
    (
        "srtm3_northern_england/N54W002.hgt",
        -49.0,
        702.0,
        126.5,
        163_198,
    ),
    (
        "srtm3_northern_england/N54W003.hgt",
        -2.0,
        891.0,
        282.8,
        37_663,
    ),
    (
        "srtm3_northern_england/N54W004.hgt",
        -1.0,
        969.0,
        73.6,
        786_854,
    ),
];

#[test]
fn clean_srtm3_tiles_match_sources_table() {
    let Some(dir) = data_dir() else { return };
    for &(file, min, max, avg, non_positive) in CLEAN_TILES {
        let hf = load(&dir.join(file));
        assert_eq!((hf.width, hf.height), (1201, 1201), "{file}");
        assert_eq!(hf.voids_filled, 0, "{file}");
        assert_eq!(hf.min_max(), (min, max), "{file}");
        let m = mean(&hf);
        assert!((m - avg).abs() < 0.06, "{file}: mean {m:.3} vs {avg}");
        let n = hf.heights.iter().filter(|&&h| h <= 0.0).count();
        assert_eq!(n, non_positive, "{file}: samples <= 0");
        // E-W spacing shrinks with latitude: ~74 m at 37°N, ~54 m at 54°N.
        let lat = sw_corner(&hf).0 + 0.5;
        let ratio = hf.spacing_x / hf.spacing_y;
        assert!(
            (ratio / lat.to_radians().cos() - 1.0).abs() < 0.01,
            "{file}: E-W/N-S {ratio}"
        );
    }
}

#[test]
fn neighbouring_tiles_share_edges_after_flip() {
    let Some(dir) = data_dir() else { return };
    let sn = dir.join("srtm3_sierra_nevada_es");
    let north = load(&sn.join("N37W004.hgt"));
    let south = load(&sn.join("N36W004.hgt"));
    let east = load(&sn.join("N37W003.hgt"));
    // Row 0 is the south edge: the north tile's first row is the south tile's last row.
    for c in 0..1201 {
        assert_eq!(north.at(c, 0), south.at(c, 1200), "col {c}");
    }
    // The last column of a tile is the first column of its east neighbour.
    for r in 0..1201 {
        assert_eq!(north.at(1200, r), east.at(0, r), "row {r}");
    }
    // Mulhacén (SRTM3 3460 m) is in N37W004, in its southern half (37.05°N).
    let (i, _) = north
        .heights
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .unwrap();
    assert!(
        i / 1201 < 600,
        "highest sample on row {} (should be south half)",
        i / 1201
    );
}

#[test]
fn forge3d_npy_fixtures() {
    let Some(dir) = data_dir() else { return };
    let d = dir.join("forge3d_codec_corpus");
    for (file, min, max) in [
        ("alpine.npy", 1309.0, 4302.0),
        ("canyon.npy", 1982.0, 2602.0),
        ("rolling.npy", 220.0, 1001.0),
    ] {
        let hf = load(&d.join(file));
        assert_eq!((hf.width, hf.height), (256, 256), "{file}");
        assert_eq!(hf.voids_filled, 0, "{file}");
        assert_eq!(hf.min_max(), (min, max), "{file}");
        assert_eq!((hf.spacing_x, hf.spacing_y), (30.0, 30.0), "{file}");
    }
    let hf = load(&d.join("coastal_flat_nodata.npy"));
    assert_eq!((hf.width, hf.height), (256, 256));
    assert_eq!(hf.voids_filled, 5093);
    assert!(hf.heights.iter().all(|h| h.is_finite()));
    let (lo, hi) = hf.min_max();
    assert!(lo >= 1.0 && hi <= 26.0, "range after fill {lo}..{hi}");
}

#[test]
fn matplotlib_npz_samples() {
    let Some(dir) = data_dir() else { return };
    let d = dir.join("matplotlib");
    let hf = load(&d.join("jacksboro_fault_dem.npz"));
    assert_eq!((hf.width, hf.height), (403, 344));
    assert_eq!(hf.min_max(), (236.0, 1076.0));
    assert_eq!(hf.voids_filled, 0);

    let hf = load(&d.join("topobathy.npz"));
    assert_eq!((hf.width, hf.height), (120, 91));
    assert_eq!(hf.min_max(), (-1437.0, 2205.0));
    let (lat, lon, _, _) = sw_corner(&hf);
    assert!(
        (lat - 48.016).abs() < 0.01 && (lon + 125.98).abs() < 0.01,
        "{lat} {lon}"
    );
}

#[test]
fn real_data_errors_name_the_file() {
    let Some(dir) = data_dir() else { return };
    // An unknown extension: the message lists what is accepted.
    let tmp = tempfile::tempdir().unwrap();
    let dem = tmp.path().join("bigtujunga.dem");
    std::fs::copy(dir.join("topotoolbox/bigtujunga.tif"), &dem).unwrap();
    let e = load_dem(&dem).unwrap_err();
    assert!(matches!(e, DemError::UnknownExtension { .. }), "{e:?}");
    let msg = e.to_string();
    assert!(
        msg.starts_with(&format!("{}: ", dem.display()))
            && msg.contains(".hgt")
            && msg.contains(".tif"),
        "{msg}"
    );

    let missing = dir.join("srtm3_single/N99E999.hgt");
    let msg = load_dem(&missing).unwrap_err().to_string();
    assert_eq!(msg, format!("{}: no such file", missing.display()));

    // A real tile copied under a name that is not a tile name.
    let renamed = tmp.path().join("innsbruck.hgt");
    std::fs::copy(dir.join("srtm3_single/N40W074.hgt"), &renamed).unwrap();
    let msg = load_dem(&renamed).unwrap_err().to_string();
    assert!(
        msg.contains("innsbruck.hgt") && !msg.contains('\n'),
        "{msg}"
    );

    // A truncated copy of a real tile.
    let bytes = std::fs::read(dir.join("srtm3_single/N40W074.hgt")).unwrap();
    let cut = tmp.path().join("N40W074.hgt");
    std::fs::write(&cut, &bytes[..bytes.len() - 2402]).unwrap();
    let msg = load_dem(&cut).unwrap_err().to_string();
    assert!(
        msg.contains("2882400 bytes") && msg.contains("2884802"),
        "{msg}"
    );
}

#[test]
fn bigtujunga_geotiff_projected_utm() {
    let Some(dir) = data_dir() else { return };
    let hf = load(&dir.join("topotoolbox/bigtujunga.tif"));
    // SOURCES.md §4: int16, 643 rows × 1197 cols, 30 m, UTM 11N, 315 .. 2295 m, mean 1226.6,
    // GDAL_NODATA 32767 set but unused.
    assert_eq!((hf.width, hf.height), (1197, 643));
    assert_eq!((hf.spacing_x, hf.spacing_y), (30.0, 30.0));
    assert_eq!(hf.min_max(), (315.0, 2295.0));
    assert_eq!(hf.voids_filled, 0);
    let m = mean(&hf);
    assert!((m - 1226.6).abs() < 0.06, "mean {m}");
    // Upper-left corner E 376313.655, N 3807917.828 (pixel is area): the south-west sample's
    // centre is half a pixel east of it and 642.5 pixels south.
    match &hf.geo {
        Some(GeoReference::Projected {
            crs,
            easting,
            northing,
        }) => {
            assert_eq!(crs, "EPSG:32611");
            assert!((easting - (376_313.655 + 15.0)).abs() < 1e-3, "{easting}");
            assert!(
                (northing - (3_807_917.828 - 642.5 * 30.0)).abs() < 1e-3,
                "{northing}"
            );
        }
        other => panic!("expected a projected reference, got {other:?}"),
    }
    assert!(
        hf.spacing_note.contains("EPSG:32611"),
        "{}",
        hf.spacing_note
    );
}
