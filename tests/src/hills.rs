//! Rough synthetic hills of the GPU oracle tests (`cdlod_morph.rs`, `skirt_edges.rs`,
//! `seen_quadrants.rs`): three scales of waves between about 0 and 500 m, so that a frame's
//! nodes are drawn at many resolutions side by side.

use aerie::terrain::heightfield::GeoReference;
use aerie::terrain::Heightfield;
use glam::DVec3;

/// `n` × `n` samples `spacing_x` × `spacing_y` metres apart; the finest waves `fine_m` high.
pub fn hills(
    n: usize,
    spacing_x: f64,
    spacing_y: f64,
    fine_m: f64,
    geo: Option<GeoReference>,
) -> Heightfield {
    let heights = (0..n)
        .flat_map(|r| (0..n).map(move |c| (c as f64, r as f64)))
        .map(|(c, r)| {
            (250.0
                + 180.0 * (c * 0.031).sin() * (r * 0.023).cos()
                + 45.0 * (c * 0.17 + r * 0.11).sin()
                + fine_m * (c * 0.53 - r * 0.41).cos()) as f32
        })
        .collect();
    Heightfield {
        width: n,
        height: n,
        spacing_x,
        spacing_y,
        heights,
        geo,
        voids_filled: 0,
        spacing_note: "synthetic".into(),
    }
}

/// The eye `agl` metres above `hf`'s sample nearest (x, y) metres east and north.
pub fn eye_above(hf: &Heightfield, x: f64, y: f64, agl: f64) -> DVec3 {
    let (c, r) = (
        (x / hf.spacing_x).round() as usize,
        (y / hf.spacing_y).round() as usize,
    );
    DVec3::new(x, y, hf.heights[r * hf.width + c] as f64 + agl)
}

/// [`hills`] on a geographic grid: `n` × `n` samples of 1/3600° from 46.5° N, 11° E (513:
/// about 11 km by 16 km), drawn on the WGS84 ellipsoid.
pub fn geographic_hills(n: usize, fine_m: f64) -> Heightfield {
    let d = 1.0 / 3600.0;
    let geo = GeoReference::Geographic {
        south_lat_deg: 46.5,
        west_lon_deg: 11.0,
        dlat_deg: d,
        dlon_deg: d,
    };
    let (sx, sy) = aerie::terrain::load::geographic_spacing_m(46.6, d, d);
    hills(n, sx, sy, fine_m, Some(geo))
}
