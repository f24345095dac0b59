//! 8-bit GeoTIFF rasters (imagery or land-cover class codes) with their geo-reference, read by
//! the `tiff` crate and placed by the DEM loader's own GeoTIFF key reading
//! (`load::geotiff::placement`), so imagery and DEMs agree on PixelIsArea/PixelIsPoint, feet
//! and the plausibility checks.

use std::path::Path;

use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::tags::Tag;
use tiff::ColorType;

use super::error::DrapeError;
use crate::geodesy::{projected_crs, UtmZone};
use crate::load::geotiff::{geo_keys, key, placement, GEOGRAPHIC_TYPE};
use crate::GeoReference;

/// Largest raster accepted, bytes of decoded samples (a lying header cannot ask for more).
pub const MAX_RASTER_BYTES: u64 = 1 << 31;

/// Geographic CRSs taken as WGS84: WGS84 itself and datums within about a metre of it.
const WGS84_LIKE: [u16; 4] = [4326, 4979, 4258, 4269];

/// The coordinate system of a raster's model coordinates.
#[derive(Debug, Clone, PartialEq)]
pub enum RasterCrs {
    /// Longitude, latitude in degrees (WGS84).
    Geographic,
    /// Easting, northing in metres; `utm` when the CRS is UTM on WGS84, else why not (the
    /// refusal naming the EPSG code; such a raster drapes only a terrain in the same CRS).
    Projected {
        crs: String,
        utm: Result<UtmZone, String>,
    },
}

/// Where a raster's pixels are: the model coordinates of the centre of the first pixel in
/// file order (the north-west one) and the step per pixel east (`dx`) and south (`dy`).
#[derive(Debug, Clone, PartialEq)]
pub struct RasterRef {
    pub crs: RasterCrs,
    pub x0: f64,
    pub y0: f64,
    pub dx: f64,
    pub dy: f64,
}

impl RasterRef {
    /// Model coordinates (x east, y north) → continuous pixel coordinates (column, file row),
    /// pixel centres at integers.
    pub fn pixel_of_model(&self, x: f64, y: f64) -> (f64, f64) {
        ((x - self.x0) / self.dx, (self.y0 - y) / self.dy)
    }
}

/// A decoded 8-bit raster.
#[derive(Debug, Clone)]
pub struct GeoRaster {
    /// The file, as named in messages.
    pub path: String,
    pub width: usize,
    pub height: usize,
    /// Samples per pixel: 1 (grey or class codes), 3 (RGB) or 4 (RGBA).
    pub bands: usize,
    /// Samples in file order (row 0 = north), bands interleaved.
    pub data: Vec<u8>,
    pub georef: RasterRef,
}

impl GeoRaster {
    /// The samples of pixel (col, file row).
    pub fn pixel(&self, col: usize, row: usize) -> &[u8] {
        let i = (row * self.width + col) * self.bands;
        &self.data[i..i + self.bands]
    }
}

fn tiff_err(path: &Path, what: &str, e: tiff::TiffError) -> DrapeError {
    DrapeError::new(path, format!("{what}: {e}"))
}

/// Reads an 8-bit GeoTIFF (grey, RGB or RGBA; stripped or tiled, any compression the `tiff`
/// crate decodes) with its geo-reference. Errors name the file and the reason: not a TIFF,
/// not 8-bit, no geo-reference, a geographic CRS that is not WGS84.
pub fn read_raster(path: &Path) -> Result<GeoRaster, DrapeError> {
    let file = std::fs::File::open(path).map_err(|e| DrapeError::new(path, e.to_string()))?;
    let mut dec = Decoder::new(std::io::BufReader::new(file))
        .map_err(|e| tiff_err(path, "not a readable TIFF", e))?;
    let (w, h) = dec
        .dimensions()
        .map_err(|e| tiff_err(path, "cannot read the image size", e))?;
    let bands = match dec.colortype() {
        Ok(ColorType::Gray(8)) => 1,
        Ok(ColorType::RGB(8)) => 3,
        Ok(ColorType::RGBA(8)) => 4,
        Ok(other) => {
            return Err(DrapeError::new(
                path,
                format!(
                    "not 8-bit: pixel type {other:?} (a draped raster is 8-bit grey, RGB or RGBA)"
                ),
            ))
        }
        Err(e) => return Err(tiff_err(path, "unsupported pixel layout", e)),
    };
    let bytes = u64::from(w) * u64::from(h) * bands as u64;
    if w == 0 || h == 0 || bytes > MAX_RASTER_BYTES {
        return Err(DrapeError::new(
            path,
            format!("{w}×{h}×{bands} raster is empty or larger than the {MAX_RASTER_BYTES} bytes accepted"),
        ));
    }
    let f64s = |dec: &mut Decoder<_>, tag: Tag, name: &str| match dec.find_tag(tag) {
        Ok(None) => Ok(None),
        Ok(Some(v)) => v
            .into_f64_vec()
            .map(Some)
            .map_err(|e| tiff_err(path, &format!("tag {name}"), e)),
        Err(e) => Err(tiff_err(path, &format!("tag {name}"), e)),
    };
    let scale = f64s(&mut dec, Tag::ModelPixelScaleTag, "ModelPixelScale")?;
    let tie = f64s(&mut dec, Tag::ModelTiepointTag, "ModelTiepoint")?;
    let keys = match dec.find_tag(Tag::GeoKeyDirectoryTag) {
        Ok(Some(v)) => geo_keys(&v.into_u16_vec().unwrap_or_default()),
        _ => Vec::new(),
    };
    let (width, height) = (w as usize, h as usize);
    if scale.is_none() || tie.is_none() {
        return Err(DrapeError::new(
            path,
            "missing geo-reference: a draped raster needs ModelPixelScale and ModelTiepoint (ModelTransformation is not supported)",
        ));
    }
    let place = placement(
        path,
        width,
        height,
        scale.as_deref(),
        tie.as_deref(),
        &keys,
        "u8",
    )?;
    let north_row = (height - 1) as f64;
    let georef = match place.geo {
        Some(GeoReference::Geographic {
            south_lat_deg,
            west_lon_deg,
            dlat_deg,
            dlon_deg,
        }) => {
            if let Some(code) = key(&keys, GEOGRAPHIC_TYPE)
                .filter(|&c| c != 0 && c != 32767 && !WGS84_LIKE.contains(&c))
            {
                return Err(DrapeError::new(
                    path,
                    format!("CRS unsupported: geographic EPSG:{code} is not WGS84 (EPSG:4326) or a datum within a metre of it (4979, 4258, 4269)"),
                ));
            }
            RasterRef {
                crs: RasterCrs::Geographic,
                x0: west_lon_deg,
                y0: south_lat_deg + north_row * dlat_deg,
                dx: dlon_deg,
                dy: dlat_deg,
            }
        }
        Some(GeoReference::Projected {
            crs,
            easting,
            northing,
        }) => RasterRef {
            x0: easting,
            y0: northing + north_row * place.spacing_y,
            dx: place.spacing_x,
            dy: place.spacing_y,
            crs: RasterCrs::Projected {
                utm: projected_crs(&crs),
                crs,
            },
        },
        None => {
            return Err(DrapeError::new(
                path,
                "missing geo-reference: no model type or tie point",
            ))
        }
    };
    let mut limits = Limits::unlimited();
    limits.decoding_buffer_size = (bytes as usize).max(1 << 20);
    let mut dec = dec.with_limits(limits);
    let data = match dec
        .read_image()
        .map_err(|e| tiff_err(path, "cannot decode the samples", e))?
    {
        DecodingResult::U8(v) => v,
        _ => {
            return Err(DrapeError::new(
                path,
                "not 8-bit: samples decode wider than a byte",
            ))
        }
    };
    if data.len() != width * height * bands {
        return Err(DrapeError::new(
            path,
            format!("decoded {} bytes for a {w}×{h}×{bands} raster", data.len()),
        ));
    }
    Ok(GeoRaster {
        path: path.display().to_string(),
        width,
        height,
        bands,
        data,
        georef,
    })
}
