//! 8-bit GeoTIFFs in memory (PixelIsArea, one tie point at the north-west corner): what the
//! registration tests and the look tests generate their checkerboards and ramps with, and a
//! way to hand a draped raster to other tools.

use std::io::Cursor;

use tiff::encoder::{colortype, TiffEncoder};
use tiff::tags::Tag;

/// Where a generated raster lies: the CRS's EPSG code (4326 geographic, 326zz/327zz UTM, or
/// any other projected code), the model coordinates of the north-west *corner* of the first
/// pixel, and the pixel size (degrees or metres, east and south).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EncodeRef {
    pub epsg: u16,
    pub west: f64,
    pub north: f64,
    pub dx: f64,
    pub dy: f64,
}

/// Encodes `data` (file order, row 0 = north, `bands` of 1, 3 or 4 interleaved) as a GeoTIFF;
/// `None` writes a TIFF without a geo-reference. Fails only on an inconsistent size.
pub fn encode_geotiff(
    width: u32,
    height: u32,
    bands: usize,
    data: &[u8],
    geo: Option<EncodeRef>,
) -> Result<Vec<u8>, String> {
    if data.len() != width as usize * height as usize * bands {
        return Err(format!("{} bytes for {width}×{height}×{bands}", data.len()));
    }
    let mut out = Cursor::new(Vec::new());
    let mut enc = TiffEncoder::new(&mut out).map_err(|e| e.to_string())?;
    macro_rules! write {
        ($ct:ty) => {{
            let mut img = enc
                .new_image::<$ct>(width, height)
                .map_err(|e| e.to_string())?;
            if let Some(g) = geo {
                let e = img.encoder();
                e.write_tag(Tag::ModelPixelScaleTag, &[g.dx, g.dy, 0.0][..])
                    .map_err(|e| e.to_string())?;
                e.write_tag(
                    Tag::ModelTiepointTag,
                    &[0.0, 0.0, 0.0, g.west, g.north, 0.0][..],
                )
                .map_err(|e| e.to_string())?;
                let geographic = g.epsg == 4326 || (4000..5000).contains(&g.epsg);
                let (model, crs_key) = if geographic { (2, 2048) } else { (1, 3072) };
                // Version 1.1.0, 3 keys: model type, PixelIsArea, the CRS.
                let keys: [u16; 16] = [
                    1, 1, 0, 3, 1024, 0, 1, model, 1025, 0, 1, 1, crs_key, 0, 1, g.epsg,
                ];
                e.write_tag(Tag::GeoKeyDirectoryTag, &keys[..])
                    .map_err(|e| e.to_string())?;
            }
            img.write_data(data).map_err(|e| e.to_string())?;
        }};
    }
    match bands {
        1 => write!(colortype::Gray8),
        3 => write!(colortype::RGB8),
        4 => write!(colortype::RGBA8),
        b => return Err(format!("{b} bands: 1, 3 or 4 are written")),
    }
    Ok(out.into_inner())
}
