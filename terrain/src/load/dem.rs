//! Choosing the loader from the file name.

use std::path::Path;

use crate::Heightfield;

use super::error::{io_err, one_line, show, DemError};
use super::{geotiff, hgt, npy, png16, raw};

/// The formats `load_dem` dispatches to, decided from the file name alone.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Hgt,
    Zip,
    Tiff,
    Png,
    RawF32,
    RawU16,
    Npy,
    Npz,
}

fn kind_of(path: &Path) -> Result<Kind, DemError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let kind = if name.ends_with(".hgt") {
        Kind::Hgt
    } else if name.ends_with(".zip") {
        Kind::Zip
    } else if name.ends_with(".tif") || name.ends_with(".tiff") {
        Kind::Tiff
    } else if name.ends_with(".png") {
        Kind::Png
    } else if name.ends_with(".f32") || name.ends_with(".r32") || name.ends_with(".raw") {
        Kind::RawF32
    } else if name.ends_with(".u16") || name.ends_with(".r16") {
        Kind::RawU16
    } else if name.ends_with(".npy") {
        Kind::Npy
    } else if name.ends_with(".npz") {
        Kind::Npz
    } else {
        let ext = match name.rfind('.') {
            Some(i) if i > 0 => one_line(&name[i..]),
            _ => "(none)".to_string(),
        };
        return Err(DemError::UnknownExtension {
            path: show(path),
            ext,
        });
    };
    Ok(kind)
}

/// Loads a DEM file into a [`Heightfield`] (metres, row 0 = south, voids filled).
///
/// The format is chosen from the file name: `.hgt`, `.hgt.zip`/`.zip` (one `.hgt` inside),
/// `.tif`/`.tiff` (GeoTIFF, one sample per pixel), `.png` (16-bit grayscale, optional `<file>.json` sidecar), `.f32`/`.r32`/`.raw`/`.u16`/`.r16`
/// (raw samples, required `<file>.json` sidecar), `.npy`/`.npz` (optional sidecar).
pub fn load_dem(path: &Path) -> Result<Heightfield, DemError> {
    // Existence first: "no such file" is the most useful message for a mistyped path.
    let meta = std::fs::metadata(path).map_err(|e| io_err(path, &e))?;
    if meta.is_dir() {
        return Err(DemError::Unreadable {
            path: show(path),
            reason: "is a directory".into(),
        });
    }
    match kind_of(path)? {
        Kind::Hgt => hgt::load_hgt(path),
        Kind::Zip => hgt::load_hgt_zip(path),
        Kind::Tiff => geotiff::load_geotiff(path),
        Kind::Png => png16::load_png(path),
        Kind::RawF32 => raw::load_raw(path, raw::SampleFormat::F32Le),
        Kind::RawU16 => raw::load_raw(path, raw::SampleFormat::U16Le),
        Kind::Npy => npy::load_npy(path),
        Kind::Npz => npy::load_npz(path),
    }
}
