//! 16-bit grayscale PNG heightmaps: metres = value × scale + offset, with an optional
//! `<file>.json` sidecar for scale, offset, spacing and orientation.

use std::io::Cursor;
use std::path::Path;

use image::codecs::png::PngDecoder;
use image::{ColorType, ExtendedColorType, ImageDecoder, Limits};

use super::error::{format_err, read_file, size_err, DemError};
use super::finish::{check_dims, finish};
use super::placement::Placement;
use super::sidecar::Sidecar;
use crate::Heightfield;

const KEYS: &[&str] = &["scale", "offset", "spacing_x", "spacing_y", "north_up"];

/// "8-bit RGB (Rgb8)" style description for the rejection message.
fn describe(ct: ExtendedColorType) -> String {
    let ch = ct.channel_count();
    let kind = match ch {
        1 => "grayscale",
        2 => "grayscale+alpha",
        3 => "RGB",
        4 => "RGBA",
        _ => "unknown colour type",
    };
    if ch == 0 {
        return format!("{kind} ({ct:?})");
    }
    format!(
        "{}-bit {kind} ({ct:?})",
        ct.bits_per_pixel() / u16::from(ch)
    )
}

pub(super) fn load_png(path: &Path) -> Result<Heightfield, DemError> {
    let bytes = read_file(path)?;
    let sidecar = Sidecar::load(path, KEYS)?;
    let decoder = PngDecoder::with_limits(Cursor::new(&bytes[..]), Limits::default())
        .map_err(|e| format_err(path, format!("not a readable PNG: {e}")))?;
    if decoder.color_type() != ColorType::L16 {
        return Err(format_err(
            path,
            format!(
                "expected a 16-bit grayscale PNG, found {}",
                describe(decoder.original_color_type())
            ),
        ));
    }
    let (w, h) = decoder.dimensions();
    let (width, height) = (w as usize, h as usize);
    check_dims(path, width, height)?;
    let total = decoder.total_bytes();
    if Some(total) != (width as u64).checked_mul(height as u64 * 2) {
        return Err(size_err(
            path,
            format!("decoder reports {total} bytes for {width}×{height} 16-bit samples"),
        ));
    }
    // A header may claim any size; deflate packs at most ~1032 bytes into one, so a claim
    // beyond that ratio is refused before allocating (a 91-byte file could ask for petabytes).
    let most = (bytes.len() as u64).saturating_mul(1100);
    if total > most {
        return Err(size_err(
            path,
            format!(
                "header claims {width}×{height} 16-bit samples ({total} bytes), more than a {}-byte PNG can hold",
                bytes.len()
            ),
        ));
    }
    let mut buf = vec![0u8; total as usize];
    decoder
        .read_image(&mut buf)
        .map_err(|e| format_err(path, format!("corrupt PNG data: {e}")))?;

    let sc = sidecar.as_ref();
    let (scale, offset) = match sc {
        Some(s) => s.height_scale_offset()?,
        None => (1.0, 0.0),
    };
    let north_up = sc
        .map(|s| s.bool("north_up"))
        .transpose()?
        .flatten()
        .unwrap_or(true);
    let place = Placement::metric(sc)?;
    // `read_image` yields native-endian u16 for L16.
    let samples = buf
        .chunks_exact(2)
        .map(|b| (f64::from(u16::from_ne_bytes([b[0], b[1]])) * scale + offset) as f32)
        .collect();
    finish(path, width, height, samples, north_up, place)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load::load_dem;
    use crate::load::sidecar::sidecar_path;
    use image::{ImageBuffer, Luma, Rgb};

    const W: u32 = 5;
    const H: u32 = 4;

    fn value(x: u32, y: u32) -> u16 {
        (x * 1000 + y * 7 + 60_000 * (x == 4 && y == 0) as u32) as u16
    }

    fn write_png16(dir: &Path) -> std::path::PathBuf {
        let p = dir.join("hm.png");
        ImageBuffer::<Luma<u16>, Vec<u16>>::from_fn(W, H, |x, y| Luma([value(x, y)]))
            .save(&p)
            .unwrap();
        p
    }

    #[test]
    fn png16_round_trip_with_scale_offset_sidecar() {
        let dir = tempfile::tempdir().unwrap();
        let p = write_png16(dir.path());
        std::fs::write(
            sidecar_path(&p),
            r#"{"scale": 0.1, "offset": -100, "spacing_x": 10, "spacing_y": 12.5}"#,
        )
        .unwrap();
        let hf = load_dem(&p).unwrap();
        assert_eq!((hf.width, hf.height), (W as usize, H as usize));
        assert_eq!((hf.spacing_x, hf.spacing_y), (10.0, 12.5));
        assert!(
            hf.spacing_note.contains("hm.png.json"),
            "{}",
            hf.spacing_note
        );
        for y in 0..H {
            for x in 0..W {
                // PNG row 0 is north, so it becomes the last heightfield row.
                let got = hf.at(x as usize, (H - 1 - y) as usize);
                let want = f64::from(value(x, y)) * 0.1 - 100.0;
                assert!(
                    (f64::from(got) - want).abs() < 1e-3,
                    "({x},{y}) {got} vs {want}"
                );
            }
        }
        assert_eq!(hf.voids_filled, 0);
        assert!(hf.geo.is_none());
    }

    #[test]
    fn png16_defaults_and_south_up() {
        let dir = tempfile::tempdir().unwrap();
        let p = write_png16(dir.path());
        let hf = load_dem(&p).unwrap();
        assert_eq!((hf.spacing_x, hf.spacing_y), (30.0, 30.0));
        assert_eq!(hf.at(4, (H - 1) as usize), f32::from(value(4, 0)));
        std::fs::write(sidecar_path(&p), r#"{"north_up": false}"#).unwrap();
        let hf = load_dem(&p).unwrap();
        assert_eq!(hf.at(4, 0), f32::from(value(4, 0)));
        assert_eq!(hf.at(2, 3), f32::from(value(2, 3)));
    }

    #[test]
    fn eight_bit_and_rgb_pngs_are_rejected() {
        let dir = tempfile::tempdir().unwrap();
        let p8 = dir.path().join("gray8.png");
        ImageBuffer::<Luma<u8>, Vec<u8>>::from_fn(4, 4, |x, _| Luma([x as u8]))
            .save(&p8)
            .unwrap();
        let msg = load_dem(&p8).unwrap_err().to_string();
        assert!(msg.starts_with(&format!("{}: ", p8.display())), "{msg}");
        assert!(msg.contains("8-bit grayscale"), "{msg}");

        let prgb = dir.path().join("rgb16.png");
        ImageBuffer::<Rgb<u16>, Vec<u16>>::from_fn(4, 4, |x, _| Rgb([x as u16; 3]))
            .save(&prgb)
            .unwrap();
        let msg = load_dem(&prgb).unwrap_err().to_string();
        assert!(msg.contains("16-bit RGB"), "{msg}");
    }

    #[test]
    fn bad_sidecar_keys_and_types_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let p = write_png16(dir.path());
        let sc = sidecar_path(&p);
        std::fs::write(&sc, r#"{"scale": 1, "spacingx": 5}"#).unwrap();
        let e = load_dem(&p).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, DemError::Sidecar { .. }), "{e:?}");
        assert!(msg.starts_with(&format!("{}: ", sc.display())), "{msg}");
        assert!(msg.contains("`spacingx`"), "{msg}");

        std::fs::write(&sc, r#"{"scale": "2"}"#).unwrap();
        let msg = load_dem(&p).unwrap_err().to_string();
        assert!(msg.contains("`scale`") && msg.contains("string"), "{msg}");

        std::fs::write(&sc, r#"{"spacing_x": -3}"#).unwrap();
        let msg = load_dem(&p).unwrap_err().to_string();
        assert!(msg.contains("`spacing_x`") && msg.contains("> 0"), "{msg}");

        std::fs::write(&sc, "{\"scale\": 1,\n").unwrap();
        let msg = load_dem(&p).unwrap_err().to_string();
        assert!(msg.contains("invalid JSON") && !msg.contains('\n'), "{msg}");

        std::fs::write(&sc, "[1, 2]").unwrap();
        assert!(load_dem(&p)
            .unwrap_err()
            .to_string()
            .contains("JSON object"));
    }

    #[test]
    fn garbage_png_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.png");
        std::fs::write(&p, b"\x89PNG\r\n\x1a\nnot really").unwrap();
        let msg = load_dem(&p).unwrap_err().to_string();
        assert!(
            msg.starts_with(&format!("{}: ", p.display())) && !msg.contains('\n'),
            "{msg}"
        );
    }
}
