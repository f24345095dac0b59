//! Headerless raw grids (`.f32`/`.r32`/`.raw` f32, `.u16`/`.r16` u16). Nothing in the file says
//! its size, so a `<file>.json` sidecar with `width` and `height` is required.

use std::path::Path;

use super::error::{io_err, show, size_err, DemError};
use super::finish::{check_dims, finish};
use super::placement::Placement;
use super::sidecar::Sidecar;
use crate::Heightfield;

const KEYS: &[&str] = &[
    "width",
    "height",
    "format",
    "spacing_x",
    "spacing_y",
    "scale",
    "offset",
    "north_up",
    // Free-form provenance (`aerie gen-dem` records kind and seed here); not interpreted.
    "generator",
];

/// Sample encoding of a raw file, chosen by the sidecar's `format` or the extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SampleFormat {
    F32Le,
    F32Be,
    U16Le,
    U16Be,
}

impl SampleFormat {
    const ALL: [SampleFormat; 4] = [Self::F32Le, Self::F32Be, Self::U16Le, Self::U16Be];

    fn name(self) -> &'static str {
        match self {
            Self::F32Le => "f32le",
            Self::F32Be => "f32be",
            Self::U16Le => "u16le",
            Self::U16Be => "u16be",
        }
    }

    pub(crate) fn bytes(self) -> usize {
        match self {
            Self::F32Le | Self::F32Be => 4,
            Self::U16Le | Self::U16Be => 2,
        }
    }

    fn is_float(self) -> bool {
        self.bytes() == 4
    }
}

/// A raw file's sidecar, read and checked against the file's length: what it holds and how.
pub(crate) struct RawGrid {
    pub width: usize,
    pub height: usize,
    pub format: SampleFormat,
    pub scale: f64,
    pub offset: f64,
    pub north_up: bool,
    pub place: Placement,
    /// Bytes of samples (= the file's length).
    pub bytes: u64,
}

/// Reads `path`'s sidecar and checks the file's length against it (nothing of the samples is
/// read).
pub(crate) fn raw_grid(path: &Path, default: SampleFormat) -> Result<RawGrid, DemError> {
    let sc = Sidecar::require(path, KEYS, "\"width\" and \"height\"")?;
    let width = sc
        .usize("width")?
        .ok_or_else(|| sc.err("width", "required (samples per row)"))?;
    let height = sc
        .usize("height")?
        .ok_or_else(|| sc.err("height", "required (number of rows)"))?;
    let format = match sc.str("format")? {
        None => default,
        Some(s) => SampleFormat::ALL
            .into_iter()
            .find(|f| f.name() == s)
            .ok_or_else(|| {
                sc.err(
                    "format",
                    format!(
                        "unknown format \"{s}\" (accepted: {})",
                        SampleFormat::ALL.map(|f| f.name()).join(", ")
                    ),
                )
            })?,
    };
    let (scale, offset) = if format.is_float() {
        for key in ["scale", "offset"] {
            if sc.f64(key)?.is_some() {
                return Err(sc.err(
                    key,
                    format!("applies only to u16 formats (format is {})", format.name()),
                ));
            }
        }
        (1.0, 0.0)
    } else {
        sc.height_scale_offset()?
    };
    let north_up = sc.bool("north_up")?.unwrap_or(true);
    let place = Placement::metric(Some(&sc))?;
    check_dims(path, width, height)?;
    let expected = width
        .checked_mul(height)
        .and_then(|n| n.checked_mul(format.bytes()))
        .and_then(|n| u64::try_from(n).ok())
        .ok_or_else(|| sc.err("width", format!("{width}×{height} grid is too large")))?;
    // Check the length before reading so a wrong sidecar does not pull in a huge file.
    let found = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    let length_err = |found: u64| {
        let how = if found < expected {
            format!("truncated by {} bytes", expected - found)
        } else {
            format!("too long by {} bytes", found - expected)
        };
        size_err(
            path,
            format!(
                "expected {expected} bytes ({width}×{height} {} samples per {}), found {found} ({how})",
                format.name(),
                show(sc.path())
            ),
        )
    };
    if found != expected {
        return Err(length_err(found));
    }
    Ok(RawGrid {
        width,
        height,
        format,
        scale,
        offset,
        north_up,
        place,
        bytes: expected,
    })
}

pub(super) fn load_raw(path: &Path, default: SampleFormat) -> Result<Heightfield, DemError> {
    let g = raw_grid(path, default)?;
    let samples = read_samples(path, g.bytes, g.format, g.width, g.scale, g.offset)?;
    finish(path, g.width, g.height, samples, g.north_up, g.place)
}

/// Reads and decodes the file in 4 MiB pieces, so a 1 GB grid costs 1 GB of memory, not 2.
fn read_samples(
    path: &Path,
    expected: u64,
    format: SampleFormat,
    width: usize,
    scale: f64,
    offset: f64,
) -> Result<Vec<f32>, DemError> {
    use std::io::Read as _;
    let mut file = std::fs::File::open(path).map_err(|e| io_err(path, &e))?;
    let count = (expected / format.bytes() as u64) as usize;
    let mut out = Vec::with_capacity(count);
    let mut buf = vec![0u8; (4 << 20) / format.bytes() * format.bytes()];
    let mut done = 0u64;
    while done < expected {
        let n = (expected - done).min(buf.len() as u64) as usize;
        file.read_exact(&mut buf[..n]).map_err(|e| {
            size_err(
                path,
                format!("expected {expected} bytes, reading failed at byte offset {done}: {e}"),
            )
        })?;
        decode(
            path,
            &buf[..n],
            format,
            width,
            scale,
            offset,
            out.len(),
            &mut out,
        )?;
        done += n as u64;
    }
    Ok(out)
}

/// Decodes whole samples of `bytes` onto `out`; `first` is the index of the first one in the file.
#[allow(clippy::too_many_arguments)]
pub(crate) fn decode(
    path: &Path,
    bytes: &[u8],
    format: SampleFormat,
    width: usize,
    scale: f64,
    offset: f64,
    first: usize,
    out: &mut Vec<f32>,
) -> Result<(), DemError> {
    for (k, b) in bytes.chunks_exact(format.bytes()).enumerate() {
        let i = first + k;
        let v = match format {
            SampleFormat::F32Le => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            SampleFormat::F32Be => f32::from_be_bytes([b[0], b[1], b[2], b[3]]),
            SampleFormat::U16Le => {
                (f64::from(u16::from_le_bytes([b[0], b[1]])) * scale + offset) as f32
            }
            SampleFormat::U16Be => {
                (f64::from(u16::from_be_bytes([b[0], b[1]])) * scale + offset) as f32
            }
        };
        if format.is_float() && !v.is_finite() {
            return Err(non_finite(path, v, i, width, 4));
        }
        out.push(v);
    }
    Ok(())
}

/// Error for a NaN/inf sample `i` (file order) of a grid `width` wide with `item`-byte samples;
/// `header` bytes precede the data.
pub(crate) fn non_finite_at(
    path: &Path,
    v: f64,
    i: usize,
    width: usize,
    item: usize,
    header: usize,
) -> DemError {
    DemError::NonFinite {
        path: show(path),
        col: i % width.max(1),
        row: i / width.max(1),
        offset: (header + i * item) as u64,
        value: if v.is_nan() {
            "NaN".into()
        } else {
            format!("{v}")
        },
    }
}

fn non_finite(path: &Path, v: f32, i: usize, width: usize, item: usize) -> DemError {
    non_finite_at(path, f64::from(v), i, width, item, 0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load::load_dem;
    use crate::load::sidecar::sidecar_path;

    fn write(dir: &Path, name: &str, data: &[u8], sidecar: Option<&str>) -> std::path::PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, data).unwrap();
        if let Some(s) = sidecar {
            std::fs::write(sidecar_path(&p), s).unwrap();
        }
        p
    }

    const VALS: [f32; 6] = [1.5, -2.25, 3.0, 100.0, 200.5, -1e4];

    #[test]
    fn raw_f32_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let le: Vec<u8> = VALS.iter().flat_map(|v| v.to_le_bytes()).collect();
        let p = write(
            dir.path(),
            "a.f32",
            &le,
            Some(r#"{"width": 3, "height": 2, "spacing_x": 5, "spacing_y": 7}"#),
        );
        let hf = load_dem(&p).unwrap();
        assert_eq!(
            (hf.width, hf.height, hf.spacing_x, hf.spacing_y),
            (3, 2, 5.0, 7.0)
        );
        // north_up default: file row 0 becomes heightfield row 1.
        assert_eq!(hf.heights, [100.0, 200.5, -1e4, 1.5, -2.25, 3.0]);

        let be: Vec<u8> = VALS.iter().flat_map(|v| v.to_be_bytes()).collect();
        let p = write(
            dir.path(),
            "b.raw",
            &be,
            Some(r#"{"width": 3, "height": 2, "format": "f32be", "north_up": false}"#),
        );
        let hf = load_dem(&p).unwrap();
        assert_eq!(hf.heights, VALS);
        assert_eq!((hf.spacing_x, hf.spacing_y), (30.0, 30.0));
    }

    #[test]
    fn raw_u16_with_scale_offset() {
        let dir = tempfile::tempdir().unwrap();
        let vals: [u16; 4] = [0, 1, 1000, 65535];
        let le: Vec<u8> = vals.iter().flat_map(|v| v.to_le_bytes()).collect();
        let p = write(
            dir.path(),
            "h.r16",
            &le,
            Some(r#"{"width": 2, "height": 2, "scale": 0.5, "offset": -10, "north_up": false}"#),
        );
        let hf = load_dem(&p).unwrap();
        assert_eq!(hf.heights, [-10.0, -9.5, 490.0, 32757.5]);
        let be: Vec<u8> = vals.iter().flat_map(|v| v.to_be_bytes()).collect();
        let p = write(
            dir.path(),
            "h.u16",
            &be,
            Some(r#"{"width": 2, "height": 2, "format": "u16be", "north_up": false}"#),
        );
        assert_eq!(load_dem(&p).unwrap().heights, [0.0, 1.0, 1000.0, 65535.0]);
    }

    #[test]
    fn truncated_and_too_long_raw_say_expected_and_found() {
        let dir = tempfile::tempdir().unwrap();
        let sc = r#"{"width": 3, "height": 2}"#;
        let p = write(dir.path(), "t.f32", &[0u8; 20], Some(sc));
        let e = load_dem(&p).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, DemError::Size { .. }), "{e:?}");
        assert!(msg.starts_with(&format!("{}: ", p.display())), "{msg}");
        assert!(
            msg.contains("expected 24 bytes")
                && msg.contains("found 20")
                && msg.contains("truncated"),
            "{msg}"
        );
        let p = write(dir.path(), "l.f32", &[0u8; 30], Some(sc));
        let msg = load_dem(&p).unwrap_err().to_string();
        assert!(
            msg.contains("found 30") && msg.contains("too long by 6"),
            "{msg}"
        );
    }

    #[test]
    fn nan_and_inf_are_rejected_with_position() {
        let dir = tempfile::tempdir().unwrap();
        let mut vals = VALS;
        vals[4] = f32::NAN; // (col 1, row 1)
        let le: Vec<u8> = vals.iter().flat_map(|v| v.to_le_bytes()).collect();
        let p = write(
            dir.path(),
            "n.f32",
            &le,
            Some(r#"{"width": 3, "height": 2}"#),
        );
        let e = load_dem(&p).unwrap_err();
        assert!(
            matches!(
                e,
                DemError::NonFinite {
                    col: 1,
                    row: 1,
                    offset: 16,
                    ..
                }
            ),
            "{e:?}"
        );
        let msg = e.to_string();
        assert!(
            msg.contains("NaN") && msg.contains("byte offset 16"),
            "{msg}"
        );
        vals[4] = 0.0;
        vals[2] = f32::NEG_INFINITY;
        let le: Vec<u8> = vals.iter().flat_map(|v| v.to_le_bytes()).collect();
        let p = write(
            dir.path(),
            "i.f32",
            &le,
            Some(r#"{"width": 3, "height": 2}"#),
        );
        let msg = load_dem(&p).unwrap_err().to_string();
        assert!(
            msg.contains("-inf") && msg.contains("byte offset 8"),
            "{msg}"
        );
    }

    #[test]
    fn sidecar_problems() {
        let dir = tempfile::tempdir().unwrap();
        let p = write(dir.path(), "m.f32", &[0u8; 16], None);
        let msg = load_dem(&p).unwrap_err().to_string();
        assert!(msg.starts_with(&format!("{}: ", p.display())), "{msg}");
        assert!(
            msg.contains(&sidecar_path(&p).display().to_string()),
            "{msg}"
        );

        let p = write(dir.path(), "w.f32", &[0u8; 16], Some(r#"{"height": 2}"#));
        let msg = load_dem(&p).unwrap_err().to_string();
        assert!(msg.contains("`width`") && msg.contains("required"), "{msg}");

        let p = write(
            dir.path(),
            "s.f32",
            &[0u8; 16],
            Some(r#"{"width": 2, "height": 2, "scale": 2}"#),
        );
        let msg = load_dem(&p).unwrap_err().to_string();
        assert!(msg.contains("`scale`") && msg.contains("u16"), "{msg}");

        let p = write(
            dir.path(),
            "f.f32",
            &[0u8; 16],
            Some(r#"{"width": 2, "height": 2, "format": "f64le"}"#),
        );
        let msg = load_dem(&p).unwrap_err().to_string();
        assert!(msg.contains("f64le") && msg.contains("u16be"), "{msg}");

        let p = write(
            dir.path(),
            "x.f32",
            &[0u8; 16],
            Some(r#"{"width": 2.5, "height": 2}"#),
        );
        let msg = load_dem(&p).unwrap_err().to_string();
        assert!(msg.contains("`width`") && msg.contains("integer"), "{msg}");
    }

    #[test]
    fn degenerate_sizes_are_rejected() {
        let dir = tempfile::tempdir().unwrap();
        let p = write(
            dir.path(),
            "z.f32",
            &[],
            Some(r#"{"width": 0, "height": 5}"#),
        );
        assert!(load_dem(&p).unwrap_err().to_string().contains("zero-size"));
        let p = write(
            dir.path(),
            "o.f32",
            &[0u8; 20],
            Some(r#"{"width": 1, "height": 5}"#),
        );
        assert!(load_dem(&p).unwrap_err().to_string().contains("2×2"));
        let p = write(
            dir.path(),
            "big.f32",
            &[0u8; 4],
            Some(r#"{"width": 18446744073709551615, "height": 18446744073709551615}"#),
        );
        assert!(load_dem(&p).is_err());
    }
}
