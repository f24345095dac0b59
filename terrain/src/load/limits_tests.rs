//! Absurd but finite placements are refused naming the key: spacings outside 1 mm to 100 km,
//! height scales/offsets no DEM has, GeoTIFF pixel scales and tie points off the Earth.

use std::path::{Path, PathBuf};

use image::{ImageBuffer, Luma};
use tiff::encoder::{colortype, TiffEncoder};
use tiff::tags::Tag;

use super::dem::load_dem;
use super::npy::tests::npy_bytes;
use super::sidecar::sidecar_path;

fn with_sidecar(dir: &Path, name: &str, data: &[u8], sidecar: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, data).unwrap();
    std::fs::write(sidecar_path(&p), sidecar).unwrap();
    p
}

/// Loads `p`, expecting an error whose message names every one of `names`.
fn refused(p: &Path, names: &[&str]) -> String {
    let msg = match load_dem(p) {
        Ok(hf) => panic!(
            "{} loaded: spacing {} × {}",
            p.display(),
            hf.spacing_x,
            hf.spacing_y
        ),
        Err(e) => e.to_string(),
    };
    for n in names {
        assert!(msg.contains(n), "{n:?} not in: {msg}");
    }
    assert!(!msg.contains('\n'), "{msg}");
    msg
}

fn f32_grid() -> Vec<u8> {
    [1.0f32, 2.0, 3.0, 4.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect()
}

#[test]
fn raw_sidecar_spacings_outside_1mm_to_100km_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for (key, value) in [
        ("spacing_x", "1e300"),
        ("spacing_y", "1e300"),
        ("spacing_x", "1e-9"),
        ("spacing_y", "100001"),
    ] {
        let sc = format!(r#"{{"width": 2, "height": 2, "{key}": {value}}}"#);
        let p = with_sidecar(dir.path(), "g.f32", &f32_grid(), &sc);
        let msg = refused(&p, &[key, "g.f32.json", "1 mm", "100 km"]);
        assert!(msg.contains(&format!("key `{key}`")), "{msg}");
    }
    // The ends of the range load.
    for value in ["0.001", "100000"] {
        let sc = format!(r#"{{"width": 2, "height": 2, "spacing_x": {value}}}"#);
        let p = with_sidecar(dir.path(), "g.f32", &f32_grid(), &sc);
        load_dem(&p).unwrap();
    }
}

#[test]
fn absurd_height_scale_and_offset_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let u16s: Vec<u8> = [1u16, 2, 3, 4]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    for (key, value) in [("scale", "1e300"), ("scale", "0"), ("offset", "-1e300")] {
        let sc = format!(r#"{{"width": 2, "height": 2, "format": "u16le", "{key}": {value}}}"#);
        let p = with_sidecar(dir.path(), "g.u16", &u16s, &sc);
        refused(&p, &[&format!("key `{key}`"), "plausible"]);
    }
    // PNG16 takes the same keys.
    let p = dir.path().join("h.png");
    ImageBuffer::<Luma<u16>, Vec<u16>>::from_fn(2, 2, |x, y| Luma([(x + y) as u16]))
        .save(&p)
        .unwrap();
    std::fs::write(sidecar_path(&p), r#"{"scale": 1e300}"#).unwrap();
    refused(&p, &["key `scale`", "h.png.json"]);
    std::fs::write(sidecar_path(&p), r#"{"spacing_y": 1e300}"#).unwrap();
    refused(&p, &["key `spacing_y`"]);
    // Heights no terrain has (a float grid needs no scale to get there).
    let huge: Vec<u8> = [1.0f32, 2.0, 3.0e30, 4.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let p = with_sidecar(
        dir.path(),
        "huge.f32",
        &huge,
        r#"{"width": 2, "height": 2}"#,
    );
    refused(&p, &["height out of range", "col 0, row 1"]);
}

#[test]
fn npy_sidecar_spacing_is_checked() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = npy_bytes("<f4", false, &[2, 2], &f32_grid());
    let p = with_sidecar(dir.path(), "g.npy", &bytes, r#"{"spacing_x": 1e300}"#);
    refused(&p, &["key `spacing_x`", "g.npy.json"]);
}

/// A 2×2 GeoTIFF with `scale` as ModelPixelScale, `tie` as ModelTiepoint and model type
/// `model` (1 projected, 2 geographic).
fn geotiff(path: &Path, scale: [f64; 3], tie: [f64; 6], model: u16) {
    let f = std::fs::File::create(path).unwrap();
    let mut enc = TiffEncoder::new(f).unwrap();
    let mut img = enc.new_image::<colortype::GrayI16>(2, 2).unwrap();
    img.encoder()
        .write_tag(Tag::ModelPixelScaleTag, &scale[..])
        .unwrap();
    img.encoder()
        .write_tag(Tag::ModelTiepointTag, &tie[..])
        .unwrap();
    let keys: [u16; 12] = [1, 1, 0, 2, 1024, 0, 1, model, 1025, 0, 1, 1];
    img.encoder()
        .write_tag(Tag::GeoKeyDirectoryTag, &keys[..])
        .unwrap();
    img.write_data(&[1i16, 2, 3, 4][..]).unwrap();
}

#[test]
fn geotiff_pixel_scale_and_tie_point_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("t.tif");
    let tie = [0.0, 0.0, 0.0, 1000.0, 5000.0, 0.0];
    geotiff(&p, [30.0, 30.0, 0.0], tie, 1);
    load_dem(&p).unwrap();
    for scale in [[1e300, 30.0, 0.0], [30.0, 1e300, 0.0], [1e-7, 30.0, 0.0]] {
        geotiff(&p, scale, tie, 1);
        refused(&p, &["t.tif", "ModelPixelScale", "1 mm"]);
    }
    geotiff(
        &p,
        [30.0, 30.0, 0.0],
        [0.0, 0.0, 0.0, 1e300, 5000.0, 0.0],
        1,
    );
    refused(&p, &["ModelTiepoint", "easting"]);
    // Geographic: degrees per pixel.
    let geo_tie = [0.0, 0.0, 0.0, 11.0, 47.0, 0.0];
    geotiff(&p, [1.0 / 1200.0, 1.0 / 1200.0, 0.0], geo_tie, 2);
    load_dem(&p).unwrap();
    geotiff(&p, [1e300, 1e300, 0.0], geo_tie, 2);
    refused(&p, &["ModelPixelScale", "100 km"]);
    geotiff(
        &p,
        [1.0 / 1200.0, 1.0 / 1200.0, 0.0],
        [0.0, 0.0, 0.0, 11.0, 1e300, 0.0],
        2,
    );
    refused(&p, &["ModelTiepoint", "not a place on Earth"]);
}
