use super::finish::{fill_voids, flip_rows};
use super::*;

#[test]
fn geographic_spacing_matches_wgs84_formula() {
    // Independent restatement: radii of curvature from a, b (not from e² directly).
    let a = 6_378_137.0_f64;
    let b = a * (1.0 - 1.0 / 298.257_223_563);
    for lat in [0.0_f64, 45.0, 60.0, -33.0] {
        let p = lat.to_radians();
        let denom = (a * a * p.cos().powi(2) + b * b * p.sin().powi(2)).sqrt();
        let m = (a * b).powi(2) / denom.powi(3);
        let n = a * a / denom;
        let d = 1.0_f64 / 1200.0;
        let (ew, ns) = geographic_spacing_m(lat, d, d);
        let want_ns = d.to_radians() * m;
        let want_ew = d.to_radians() * n * p.cos();
        assert!((ns - want_ns).abs() < 1e-6, "lat {lat}: {ns} vs {want_ns}");
        assert!((ew - want_ew).abs() < 1e-6, "lat {lat}: {ew} vs {want_ew}");
        let ratio = ew / ns;
        assert!(
            (ratio / p.cos() - 1.0).abs() < 0.01,
            "lat {lat}: E-W/N-S {ratio} vs cos {}",
            p.cos()
        );
    }
    // Known magnitudes: 3" N-S ≈ 92.2 m at the equator, ≈ 92.8 m at 60°.
    let (ew0, ns0) = geographic_spacing_m(0.0, 1.0 / 1200.0, 1.0 / 1200.0);
    assert!(
        (ns0 - 92.16).abs() < 0.1 && (ew0 - 92.77).abs() < 0.1,
        "{ew0} {ns0}"
    );
}

#[test]
fn flip_rows_reverses_row_order() {
    let mut v: Vec<f32> = (0..12).map(|i| i as f32).collect();
    flip_rows(&mut v, 4);
    assert_eq!(v, [8., 9., 10., 11., 4., 5., 6., 7., 0., 1., 2., 3.]);
    let mut v: Vec<f32> = (0..8).map(|i| i as f32).collect();
    flip_rows(&mut v, 4);
    assert_eq!(v, [4., 5., 6., 7., 0., 1., 2., 3.]);
}

#[test]
fn fill_is_linear_along_a_line_and_bounded() {
    // 5×3 grid, middle row 10 _ _ _ 50 with voids above and below only at the ends.
    let n = f32::NAN;
    let mut v = vec![
        0., 0., 0., 0., 0., //
        10., n, n, n, 50., //
        0., 0., 0., 0., 0.,
    ];
    fill_voids(&mut v, 5, 3, 1.0, 1000.0);
    // Vertical neighbours are 1000 m away (weight ~1e-3) so the row interpolation dominates.
    assert!((v[6] - 20.0).abs() < 0.2, "{}", v[6]);
    assert!((v[7] - 30.0).abs() < 0.2, "{}", v[7]);
    assert!((v[8] - 40.0).abs() < 0.2, "{}", v[8]);
    // Fully void row and column: filled in a later pass, still within the valid range.
    let mut v = vec![
        1., n, 3., //
        n, n, n, //
        7., n, 9.,
    ];
    fill_voids(&mut v, 3, 3, 1.0, 1.0);
    assert!(v.iter().all(|x| (1.0..=9.0).contains(x)), "{v:?}");
    assert!((v[4] - 5.0).abs() < 1e-4, "centre {}", v[4]);
}

#[test]
fn unknown_extension_lists_accepted_ones() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("terrain.dem");
    std::fs::write(&p, b"II*\0").unwrap();
    let e = load_dem(&p).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, DemError::UnknownExtension { .. }), "{e:?}");
    assert!(msg.starts_with(&p.display().to_string()), "{msg}");
    assert!(msg.contains(".dem") && msg.contains(".hgt.zip") && msg.contains(".tif"));
    assert!(!msg.contains('\n'));
}

#[test]
fn missing_file_says_no_such_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("N47E011.hgt");
    let e = load_dem(&p).unwrap_err();
    assert!(matches!(e, DemError::NotFound { .. }), "{e:?}");
    assert_eq!(e.to_string(), format!("{}: no such file", p.display()));
    assert_eq!(e.path(), p.display().to_string());
}

#[test]
fn directory_is_unreadable_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("x.npy");
    std::fs::create_dir(&p).unwrap();
    let msg = load_dem(&p).unwrap_err().to_string();
    assert!(msg.contains("is a directory"), "{msg}");
}

mod fuzz {
    use super::super::*;
    use crate::load::sidecar::sidecar_path;
    use proptest::prelude::*;

    fn load_as(name: &str, bytes: &[u8], sidecar: Option<&str>) {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        if let Some(s) = sidecar {
            std::fs::write(sidecar_path(&p), s).unwrap();
        }
        // Must not panic; when it fails, the message is one line starting with the path.
        if let Err(e) = load_dem(&p) {
            let msg = e.to_string();
            assert!(!msg.contains('\n'), "{msg}");
            assert!(msg.starts_with(&dir.path().display().to_string()), "{msg}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

        #[test]
        fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
            load_as("N47E011.hgt", &bytes, None);
            load_as("x.npy", &bytes, None);
            load_as("x.png", &bytes, None);
            load_as("x.tif", &bytes, None);
            load_as("x.raw", &bytes, Some(r#"{"width": 4, "height": 4}"#));
            load_as("x.hgt.zip", &bytes, None);
            load_as("x.npz", &bytes, None);
            load_as("x.png", &bytes, Some(&String::from_utf8_lossy(&bytes)));
        }

        #[test]
        fn random_bytes_behind_valid_magic_never_panic(
            bytes in proptest::collection::vec(any::<u8>(), 0..400),
            version in 0u8..4,
        ) {
            let mut npy = b"\x93NUMPY".to_vec();
            npy.push(version);
            npy.push(0);
            npy.extend_from_slice(&bytes);
            load_as("x.npy", &npy, None);
            let mut png = b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR".to_vec();
            png.extend_from_slice(&bytes);
            load_as("x.png", &png, None);
            let mut tif = b"II*\0\x08\0\0\0".to_vec();
            tif.extend_from_slice(&bytes);
            load_as("x.tif", &tif, None);
            let mut zip = b"PK\x03\x04".to_vec();
            zip.extend_from_slice(&bytes);
            load_as("x.zip", &zip, None);
        }

        #[test]
        fn random_npy_headers_never_panic(
            header in "[{}()\\[\\],:' a-z0-9<>TrueFals]{0,80}",
            data in proptest::collection::vec(any::<u8>(), 0..64),
        ) {
            let mut npy = b"\x93NUMPY\x01\x00".to_vec();
            npy.extend_from_slice(&(header.len() as u16).to_le_bytes());
            npy.extend_from_slice(header.as_bytes());
            npy.extend_from_slice(&data);
            load_as("x.npy", &npy, None);
        }

        #[test]
        fn random_raw_sidecars_never_panic(
            w in 0usize..6, h in 0usize..6, len in 0usize..200,
            fmt in prop::sample::select(vec!["f32le", "f32be", "u16le", "u16be", "bogus"]),
            fill in any::<u8>(),
        ) {
            let sc = format!(r#"{{"width": {w}, "height": {h}, "format": "{fmt}"}}"#);
            load_as("x.raw", &vec![fill; len], Some(&sc));
        }
    }
}
