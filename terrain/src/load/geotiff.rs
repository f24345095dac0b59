//! GeoTIFF elevation grids (`.tif`, `.tiff`) through the `tiff` crate: one sample per pixel of
//! i16, u16, i32, u32, f32 or f64 (stripped or tiled, any compression the crate decodes), placed
//! by `ModelPixelScale` + `ModelTiepoint`, the CRS read from the GeoKey directory, `GDAL_NODATA`
//! samples treated as voids (filled and counted like SRTM voids).
//!
//! Projected grids (GTModelType 1) keep their metre spacing (feet are converted) and get a
//! [`GeoReference::Projected`] with `EPSG:<ProjectedCSType>` or "projected (unknown CRS)".
//! Geographic grids (GTModelType 2) are put on the local tangent plane at their centre latitude
//! like SRTM tiles. Without `ModelPixelScale` the 30 m default applies and the note says so.

use std::path::Path;

use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::tags::Tag;
use tiff::ColorType;

use super::error::{format_err, io_err, size_err, DemError};
use super::finish::{check_dims, finish};
use super::geo::geographic_spacing_m;
use super::placement::Placement;
use super::sidecar::{implausible_spacing, short, DEFAULT_SPACING_M};
use crate::{GeoReference, Heightfield};

/// Largest grid accepted (samples): 32769², so a lying header cannot ask for terabytes.
const MAX_SAMPLES: u64 = 1 << 30;

// GeoKey ids (GeoTIFF 1.0 spec, section 6.2).
/// Largest plausible projected model coordinate, metres.
const MAX_MODEL_COORD_M: f64 = 1e8;
const GT_MODEL_TYPE: u16 = 1024;
const GT_RASTER_TYPE: u16 = 1025;
pub(crate) const GEOGRAPHIC_TYPE: u16 = 2048;
const PROJECTED_CS_TYPE: u16 = 3072;
const PROJ_LINEAR_UNITS: u16 = 3076;

fn tiff_err(path: &Path, what: &str, e: tiff::TiffError) -> DemError {
    format_err(path, format!("{what}: {e}"))
}

/// The GeoKey directory as (key id, value) for keys stored inline (location 0).
pub(crate) fn geo_keys(dir: &[u16]) -> Vec<(u16, u16)> {
    if dir.len() < 4 {
        return Vec::new();
    }
    let n = dir[3] as usize;
    dir[4..]
        .chunks_exact(4)
        .take(n)
        .filter(|e| e[1] == 0 && e[2] == 1)
        .map(|e| (e[0], e[3]))
        .collect()
}

pub(crate) fn key(keys: &[(u16, u16)], id: u16) -> Option<u16> {
    keys.iter().find(|(k, _)| *k == id).map(|&(_, v)| v)
}

pub(super) fn load_geotiff(path: &Path) -> Result<Heightfield, DemError> {
    let file = std::fs::File::open(path).map_err(|e| io_err(path, &e))?;
    let mut dec = Decoder::new(std::io::BufReader::new(file))
        .map_err(|e| tiff_err(path, "not a readable TIFF", e))?;
    let (w, h) = dec
        .dimensions()
        .map_err(|e| tiff_err(path, "cannot read the image size", e))?;
    let (width, height) = (w as usize, h as usize);
    check_dims(path, width, height)?;
    if u64::from(w) * u64::from(h) > MAX_SAMPLES {
        return Err(size_err(
            path,
            format!("{w}×{h} grid is larger than the {MAX_SAMPLES} samples accepted"),
        ));
    }
    match dec.colortype() {
        Ok(ColorType::Gray(_)) => {}
        Ok(other) => {
            return Err(format_err(
                path,
                format!("pixel type {other:?}; an elevation GeoTIFF has one sample per pixel"),
            ))
        }
        Err(e) => return Err(tiff_err(path, "unsupported pixel layout", e)),
    }
    let find_f64s =
        |dec: &mut Decoder<_>, tag: Tag, name: &str| -> Result<Option<Vec<f64>>, DemError> {
            match dec.find_tag(tag) {
                Ok(None) => Ok(None),
                Ok(Some(v)) => v
                    .into_f64_vec()
                    .map(Some)
                    .map_err(|e| tiff_err(path, &format!("tag {name}"), e)),
                Err(e) => Err(tiff_err(path, &format!("tag {name}"), e)),
            }
        };
    let scale = find_f64s(&mut dec, Tag::ModelPixelScaleTag, "ModelPixelScale")?;
    let tie = find_f64s(&mut dec, Tag::ModelTiepointTag, "ModelTiepoint")?;
    let keys = match dec.find_tag(Tag::GeoKeyDirectoryTag) {
        Ok(Some(v)) => geo_keys(&v.into_u16_vec().unwrap_or_default()),
        _ => Vec::new(),
    };
    let nodata = match dec.find_tag(Tag::GdalNodata) {
        Ok(Some(v)) => {
            let s = v.into_string().unwrap_or_default();
            let s = s.trim_matches(|c: char| c == '\0' || c.is_whitespace());
            if s.is_empty() {
                None
            } else {
                Some(s.parse::<f64>().map_err(|_| {
                    format_err(path, format!("tag GDAL_NODATA: `{s}` is not a number"))
                })?)
            }
        }
        _ => None,
    };

    let limit = (u64::from(w) * u64::from(h) * 8) as usize;
    let mut limits = Limits::unlimited();
    limits.decoding_buffer_size = limit.max(1 << 20);
    let mut dec = dec.with_limits(limits);
    let data = dec
        .read_image()
        .map_err(|e| tiff_err(path, "cannot decode the samples", e))?;
    let is_void = |v: f64| v.is_nan() || nodata.is_some_and(|n| v == n);
    let conv = |v: f64| if is_void(v) { f32::NAN } else { v as f32 };
    let (samples, kind): (Vec<f32>, &str) = match data {
        DecodingResult::I16(v) => (v.into_iter().map(|x| conv(f64::from(x))).collect(), "i16"),
        DecodingResult::U16(v) => (v.into_iter().map(|x| conv(f64::from(x))).collect(), "u16"),
        DecodingResult::I32(v) => (v.into_iter().map(|x| conv(f64::from(x))).collect(), "i32"),
        DecodingResult::U32(v) => (v.into_iter().map(|x| conv(f64::from(x))).collect(), "u32"),
        DecodingResult::F32(mut v) => {
            for x in v.iter_mut() {
                *x = conv(f64::from(*x));
            }
            (v, "f32")
        }
        DecodingResult::F64(v) => (v.into_iter().map(conv).collect(), "f64"),
        _ => {
            return Err(format_err(
                path,
                "sample type is not one of i16, u16, i32, u32, f32, f64",
            ))
        }
    };
    if samples.len() != width * height {
        return Err(size_err(
            path,
            format!("decoded {} samples for a {w}×{h} image", samples.len()),
        ));
    }
    if let Some(i) = samples.iter().position(|v| v.is_infinite()) {
        return Err(format_err(
            path,
            format!(
                "infinite sample at (col {}, row {}) in file order",
                i % width,
                i / width
            ),
        ));
    }

    let place = placement(
        path,
        width,
        height,
        scale.as_deref(),
        tie.as_deref(),
        &keys,
        kind,
    )?;
    finish(path, width, height, samples, true, place)
}

/// Spacing, geo-reference and the note, from the pixel scale, the first tie point and the keys.
pub(crate) fn placement(
    path: &Path,
    width: usize,
    height: usize,
    scale: Option<&[f64]>,
    tie: Option<&[f64]>,
    keys: &[(u16, u16)],
    kind: &str,
) -> Result<Placement, DemError> {
    let Some(scale) = scale else {
        return Ok(Placement {
            spacing_x: DEFAULT_SPACING_M,
            spacing_y: DEFAULT_SPACING_M,
            geo: None,
            spacing_note: format!(
                "GeoTIFF {kind} without ModelPixelScale: default {DEFAULT_SPACING_M} m grid, {DEFAULT_SPACING_M} m E-W, {DEFAULT_SPACING_M} m N-S"
            ),
        });
    };
    if scale.len() < 2 || !scale[..2].iter().all(|s| s.is_finite() && *s > 0.0) {
        return Err(format_err(
            path,
            format!("tag ModelPixelScale: {scale:?} does not give two positive pixel sizes"),
        ));
    }
    let (sx, sy) = (scale[0], scale[1]);
    // Tie point (i, j, k) → (x, y, z): raster position (i, j) sits at model (x, y).
    let (ti, tj, x, y) = match tie {
        Some(t) if t.len() >= 6 && t.iter().take(6).all(|v| v.is_finite()) => {
            (t[0], t[1], t[3], t[4])
        }
        Some(t) => {
            return Err(format_err(
                path,
                format!(
                    "tag ModelTiepoint: {} values, expected 6 finite ones",
                    t.len()
                ),
            ))
        }
        None => (0.0, 0.0, 0.0, 0.0),
    };
    // PixelIsArea (the default): raster (0,0) is the corner of the first pixel, whose sample
    // is at (0.5, 0.5). PixelIsPoint: raster (0,0) is the sample itself.
    let centre = if key(keys, GT_RASTER_TYPE) == Some(2) {
        0.0
    } else {
        0.5
    };
    // Model coordinates of the south-west sample (last file row, first column).
    let west = x + (centre - ti) * sx;
    let south = y - ((height - 1) as f64 + centre - tj) * sy;
    let model = key(keys, GT_MODEL_TYPE);
    let scale_err =
        |what: String| format_err(path, format!("tag ModelPixelScale: {scale:?}: {what}"));
    let tie_err = |what: String| format_err(path, format!("tag ModelTiepoint: {what}"));
    if model == Some(2) {
        // Degrees: the steps must give a plausible ground spacing, the corner a place on Earth.
        let (ew, ns) = geographic_spacing_m(south.clamp(-90.0, 90.0), sy, sx);
        // E-W at the equator: near the poles a fine step is still a real grid.
        if let Some(why) =
            implausible_spacing(sx.to_radians() * 6_378_137.0).or(implausible_spacing(ns))
        {
            return Err(scale_err(format!(
                "{why} (degrees per pixel, {} m E-W, {} m N-S)",
                short(ew),
                short(ns)
            )));
        }
        let north = south + (height - 1) as f64 * sy;
        if !(south >= -90.0 && north <= 90.0 && (-360.0..=360.0).contains(&west)) {
            return Err(tie_err(format!(
                "the grid spans latitudes {}° to {}° from longitude {}°, not a place on Earth",
                short(south),
                short(north),
                short(west)
            )));
        }
        let mut place = Placement::geographic(south, west, sy, sx, height);
        let epsg = key(keys, GEOGRAPHIC_TYPE)
            .filter(|&c| c != 0 && c != 32767)
            .map(|c| format!(" EPSG:{c}"))
            .unwrap_or_default();
        place.spacing_note = format!("GeoTIFF {kind}{epsg}, {}", place.spacing_note);
        return Ok(place);
    }
    // Projected (or unspecified): the model unit is the metre unless the keys say feet.
    let (unit, unit_name) = match key(keys, PROJ_LINEAR_UNITS) {
        Some(9002) => (0.3048, "feet"),
        Some(9003) => (1200.0 / 3937.0, "US survey feet"),
        _ => (1.0, "metres"),
    };
    let crs = match key(keys, PROJECTED_CS_TYPE) {
        Some(c) if c != 0 && c != 32767 => format!("EPSG:{c}"),
        _ => "projected (unknown CRS)".to_string(),
    };
    let (spacing_x, spacing_y) = (sx * unit, sy * unit);
    if let Some(why) = implausible_spacing(spacing_x).or(implausible_spacing(spacing_y)) {
        return Err(scale_err(format!("{why} ({unit_name})")));
    }
    // Model coordinates beyond 1e8 m (a thousand times the Earth's radius) are no map.
    for (name, v) in [("easting", west * unit), ("northing", south * unit)] {
        if v.abs() > MAX_MODEL_COORD_M {
            return Err(tie_err(format!(
                "{name} {} m of the south-west sample is beyond ±{MAX_MODEL_COORD_M:e} m",
                short(v)
            )));
        }
    }
    let note = format!(
        "GeoTIFF {kind} {crs} grid (ModelPixelScale in {unit_name}): {spacing_x} m E-W, {spacing_y} m N-S"
    );
    let geo = (model == Some(1) || tie.is_some()).then_some(GeoReference::Projected {
        crs,
        easting: west * unit,
        northing: south * unit,
    });
    let _ = width;
    Ok(Placement {
        spacing_x,
        spacing_y,
        geo,
        spacing_note: note,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load::load_dem;
    use tiff::encoder::{colortype, TiffEncoder};

    /// Writes a small GeoTIFF with the given tags, samples in file order (north row first).
    fn write_i16(path: &Path, w: u32, h: u32, data: &[i16], geo: bool, nodata: Option<&str>) {
        let f = std::fs::File::create(path).unwrap();
        let mut enc = TiffEncoder::new(f).unwrap();
        let mut img = enc.new_image::<colortype::GrayI16>(w, h).unwrap();
        if geo {
            img.encoder()
                .write_tag(Tag::ModelPixelScaleTag, &[30.0f64, 30.0, 0.0][..])
                .unwrap();
            img.encoder()
                .write_tag(
                    Tag::ModelTiepointTag,
                    &[0.0f64, 0.0, 0.0, 1000.0, 5000.0, 0.0][..],
                )
                .unwrap();
            // Version 1.1.0, 3 keys: projected, PixelIsArea, EPSG:32611.
            let keys: [u16; 16] = [1, 1, 0, 3, 1024, 0, 1, 1, 1025, 0, 1, 1, 3072, 0, 1, 32611];
            img.encoder()
                .write_tag(Tag::GeoKeyDirectoryTag, &keys[..])
                .unwrap();
        }
        if let Some(n) = nodata {
            img.encoder().write_tag(Tag::GdalNodata, n).unwrap();
        }
        img.write_data(data).unwrap();
    }

    #[test]
    fn projected_i16_with_nodata() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.tif");
        // 4×3, file row 0 = north; one nodata sample.
        let data: Vec<i16> = vec![
            10, 11, 12, 13, //
            20, -9999, 22, 23, //
            30, 31, 32, 33,
        ];
        write_i16(&p, 4, 3, &data, true, Some("-9999"));
        let hf = load_dem(&p).unwrap();
        assert_eq!((hf.width, hf.height), (4, 3));
        assert_eq!((hf.spacing_x, hf.spacing_y), (30.0, 30.0));
        assert_eq!(hf.voids_filled, 1);
        // Row 0 = south = last file row.
        assert_eq!(hf.at(0, 0), 30.0);
        assert_eq!(hf.at(3, 2), 13.0);
        let v = hf.at(1, 1);
        assert!((11.0..=31.0).contains(&v), "filled void {v}");
        assert_eq!(
            hf.geo,
            Some(GeoReference::Projected {
                crs: "EPSG:32611".into(),
                easting: 1015.0,
                northing: 5000.0 - 2.5 * 30.0,
            })
        );
        assert!(
            hf.spacing_note.contains("EPSG:32611"),
            "{}",
            hf.spacing_note
        );
    }

    #[test]
    fn plain_tiff_gets_default_spacing_and_no_geo() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("plain.tiff");
        write_i16(&p, 2, 2, &[1, 2, 3, 4], false, None);
        let hf = load_dem(&p).unwrap();
        assert_eq!(hf.geo, None);
        assert_eq!(hf.heights, [3.0, 4.0, 1.0, 2.0]);
        assert!(hf.spacing_note.contains("default"), "{}", hf.spacing_note);
    }

    #[test]
    fn f32_and_rgb_and_garbage() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f.tif");
        {
            let f = std::fs::File::create(&p).unwrap();
            let mut enc = TiffEncoder::new(f).unwrap();
            enc.write_image::<colortype::Gray32Float>(2, 2, &[1.5, f32::NAN, -2.0, 4.0])
                .unwrap();
        }
        let hf = load_dem(&p).unwrap();
        assert_eq!(hf.voids_filled, 1);
        assert_eq!(hf.at(0, 1), 1.5);
        let p = dir.path().join("rgb.tif");
        {
            let f = std::fs::File::create(&p).unwrap();
            let mut enc = TiffEncoder::new(f).unwrap();
            enc.write_image::<colortype::RGB8>(2, 2, &[0u8; 12])
                .unwrap();
        }
        let msg = load_dem(&p).unwrap_err().to_string();
        assert!(msg.contains("one sample per pixel"), "{msg}");
        let p = dir.path().join("bad.tif");
        std::fs::write(&p, b"II*\0garbage").unwrap();
        let msg = load_dem(&p).unwrap_err().to_string();
        assert!(
            msg.starts_with(&p.display().to_string()) && !msg.contains('\n'),
            "{msg}"
        );
    }
}
