//! Fixtures of the draped-raster tests: a flat UTM terrain (zone 32N, 47°N, 30 m samples)
//! and a geographic checkerboard GeoTIFF covering it, with where the renderer draws a sample.

use std::path::Path;

use aerie::terrain::drape::{encode_geotiff, EncodeRef};
use aerie::terrain::geodesy::UtmZone;
use aerie::terrain::{GeoReference, Heightfield};
use glam::DVec3;

use crate::synthetic;

pub const SPACING: f64 = 30.0;
pub const N: usize = 129;
pub const E0: f64 = 650_000.0;
pub const N0: f64 = 5_210_000.0;

/// Where the renderer draws UTM sample (col, row) at height h: the grid on the ellipsoid, in
/// its world frame (ENU at sample (0, 0)).
pub fn sample_world(col: usize, row: usize, h: f64) -> DVec3 {
    let geo = utm_terrain(&[]).geo;
    let grid = aerie::terrain::geodesy::GeoGrid::of(geo.as_ref(), SPACING, SPACING).unwrap();
    grid.world_of_grid(
        glam::DVec2::new(col as f64 * SPACING, row as f64 * SPACING),
        h,
    )
}

pub fn zone() -> UtmZone {
    UtmZone::of_epsg(32632).unwrap()
}

/// A flat UTM terrain at 500 m (zone 32N, 47°N): the derived class there is crops.
pub fn utm_terrain(blocks: &[(usize, usize, usize, usize, f32)]) -> Heightfield {
    let mut hf = synthetic(N, N, SPACING, 500.0, blocks);
    hf.geo = Some(GeoReference::Projected {
        crs: "EPSG:32632".into(),
        easting: E0,
        northing: N0,
    });
    hf
}

pub fn write_tif(
    dir: &Path,
    name: &str,
    w: u32,
    h: u32,
    bands: usize,
    data: &[u8],
    g: EncodeRef,
) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, encode_geotiff(w, h, bands, data, Some(g)).unwrap()).unwrap();
    p
}

pub const CELL: u32 = 16;
pub const COLOURS: [[u8; 3]; 2] = [[230, 200, 40], [30, 60, 190]];

/// The geographic checkerboard covering the terrain: 1" pixels, cells of 16 pixels, its
/// north-west corner west and north of the terrain by a few pixels.
pub fn checkerboard(dir: &Path) -> (std::path::PathBuf, EncodeRef) {
    let z = zone();
    let span = (N - 1) as f64 * SPACING;
    let corners = [
        (E0, N0),
        (E0 + span, N0),
        (E0, N0 + span),
        (E0 + span, N0 + span),
    ];
    let ll: Vec<(f64, f64)> = corners
        .iter()
        .map(|&(e, n)| z.lat_lon(e, n).unwrap())
        .collect();
    let d = 1.0 / 3600.0;
    let west = ll.iter().map(|p| p.1).fold(f64::INFINITY, f64::min) - 5.3 * d;
    let east = ll.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max) + 5.0 * d;
    let north = ll.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max) + 4.6 * d;
    let south = ll.iter().map(|p| p.0).fold(f64::INFINITY, f64::min) - 5.0 * d;
    let (w, h) = (
        ((east - west) / d).ceil() as u32,
        ((north - south) / d).ceil() as u32,
    );
    let mut data = Vec::new();
    for r in 0..h {
        for c in 0..w {
            data.extend_from_slice(&COLOURS[((c / CELL + r / CELL) % 2) as usize]);
        }
    }
    let g = EncodeRef {
        epsg: 4326,
        west,
        north,
        dx: d,
        dy: d,
    };
    (write_tif(dir, "board.tif", w, h, 3, &data, g), g)
}
