//! The ellipsoid's brute-force oracle: a geographic or UTM scene with the exact position of
//! every sample (f64 ECEF into the world frame), and the screen error of a node drawn at a
//! coarser level against those exact samples — what the bound and the carried selection are
//! checked against on geographic data.

use aerie::camera::Camera;
use aerie::terrain::geodesy::wgs84::{WGS84_A, WGS84_E2};
use aerie::terrain::geodesy::{GeoGrid, Geodetic};
use aerie::terrain::load::geographic_spacing_m;
use aerie::terrain::GeoReference;
use aerie::terrain::Heightfield;
use glam::{DVec2, DVec3};

use crate::flat_oracle::{alpine, drawn_at, scene, Scene};

/// A scene on the ellipsoid with the per-row and per-column trigonometry of its samples, so
/// that the oracle's exact positions cost a few products each.
pub struct GeoScene {
    pub s: Scene,
    pub grid: GeoGrid,
    /// Per row: (N + 0)·cos φ, N·(1 − e²)·sin φ, cos φ, sin φ.
    rows: Vec<[f64; 4]>,
    /// Per column: cos λ, sin λ.
    cols: Vec<[f64; 2]>,
    /// A projected grid's samples instead: ECEF at height 0 and the unit normal, row-major.
    samples: Vec<[DVec3; 2]>,
}

/// `hf` placed with its south-west sample at (`lat`, `lon`)°, `d`° between samples, tiles of
/// `m` samples.
pub fn geo_scene(
    name: &'static str,
    mut hf: Heightfield,
    lat: f64,
    lon: f64,
    d: f64,
    m: u32,
) -> GeoScene {
    let (sx, sy) = geographic_spacing_m(lat + d * (hf.height - 1) as f64 / 2.0, d, d);
    hf.spacing_x = sx;
    hf.spacing_y = sy;
    hf.geo = Some(GeoReference::Geographic {
        south_lat_deg: lat,
        west_lon_deg: lon,
        dlat_deg: d,
        dlon_deg: d,
    });
    let grid = GeoGrid::of(hf.geo.as_ref(), sx, sy).unwrap();
    let rows = (0..hf.height)
        .map(|r| {
            let (sp, cp) = (lat + r as f64 * d).to_radians().sin_cos();
            let n = WGS84_A / (1.0 - WGS84_E2 * sp * sp).sqrt();
            [n * cp, n * (1.0 - WGS84_E2) * sp, cp, sp]
        })
        .collect();
    let cols = (0..hf.width)
        .map(|c| {
            let (sl, cl) = (lon + c as f64 * d).to_radians().sin_cos();
            [cl, sl]
        })
        .collect();
    GeoScene {
        s: scene(name, hf, m),
        grid,
        rows,
        cols,
        samples: Vec::new(),
    }
}

/// A UTM scene: `hf` placed with its south-west sample at (easting, northing) in `crs`, tiles
/// of `m` samples.
pub fn utm_geo_scene(
    name: &'static str,
    mut hf: Heightfield,
    crs: &str,
    easting: f64,
    northing: f64,
    m: u32,
) -> GeoScene {
    hf.geo = Some(GeoReference::Projected {
        crs: crs.into(),
        easting,
        northing,
    });
    let extent = DVec2::from(hf.extent_m());
    let grid = GeoGrid::of_projected(hf.geo.as_ref(), hf.spacing_x, hf.spacing_y, extent)
        .unwrap()
        .unwrap();
    let mut samples = Vec::with_capacity(hf.width * hf.height);
    for row in 0..hf.height {
        for c in 0..hf.width {
            let g = DVec2::new(c as f64 * hf.spacing_x, row as f64 * hf.spacing_y);
            let (lat, lon) = grid.lat_lon_of_grid(g);
            let p0 = aerie::terrain::geodesy::geodetic_to_ecef(Geodetic::new(lat, lon, 0.0));
            let p1 = aerie::terrain::geodesy::geodetic_to_ecef(Geodetic::new(lat, lon, 1.0));
            samples.push([p0, p1 - p0]);
        }
    }
    GeoScene {
        s: scene(name, hf, m),
        grid,
        rows: Vec::new(),
        cols: Vec::new(),
        samples,
    }
}

impl GeoScene {
    /// World position of sample (col, row) at height h, exact (f64 ECEF into the world frame).
    pub fn world(&self, col: usize, row: usize, h: f64) -> DVec3 {
        if !self.samples.is_empty() {
            let [p0, n] = self.samples[row * self.s.ds.hf.width + col];
            return self.grid.world.ecef_to_enu(p0 + n * h);
        }
        let [ncp, nsp, cp, sp] = self.rows[row];
        let [cl, sl] = self.cols[col];
        let r = ncp + h * cp;
        let ecef = DVec3::new(r * cl, r * sl, nsp + h * sp);
        self.grid.world.ecef_to_enu(ecef)
    }
}

/// [`crate::flat_oracle::tile_error_px`] on the ellipsoid: the level-`drawn` grid over
/// level-`level` tile (tx, ty) of tiles of `m` samples, seen at `viewport`. Each true sample at
/// its exact position; the drawn point at that sample is the GPU's interpolation (SW–NE
/// diagonal) of the level's vertices, each at its exact position.
#[allow(clippy::too_many_arguments)]
pub fn geo_tile_error_px(
    g: &GeoScene,
    cam: &Camera,
    viewport: (u32, u32),
    m: u32,
    level: u32,
    tx: u32,
    ty: u32,
    drawn: u32,
) -> f64 {
    let (w, h) = viewport;
    let hf = &g.s.ds.hf;
    let q = (m - 1) as usize;
    let side = q << level;
    let step = 1usize << drawn;
    let (c0, r0) = (tx as usize * side, ty as usize * side);
    let vertex = |c: usize, row: usize| g.world(c, row, hf.at(c, row) as f64);
    let on_screen = |p: DVec2| p.x >= 0.0 && p.x <= w as f64 && p.y >= 0.0 && p.y <= h as f64;
    let mut worst: f64 = 0.0;
    for row in r0..=(r0 + side).min(hf.height - 1) {
        for c in c0..=(c0 + side).min(hf.width - 1) {
            let truth = vertex(c, row);
            let drawn = drawn_at(c, row, (c0, r0), side, step, vertex);
            let a = cam.project_px(truth, w, h);
            let b = cam.project_px(drawn, w, h);
            if let (Some((pa, _)), Some((pb, _))) = (a, b) {
                if on_screen(pa) || on_screen(pb) {
                    worst = worst.max((pa - pb).length());
                }
            }
        }
    }
    worst
}

/// The Inn valley crop where SRTM has it (its south-west sample 88 rows and columns in), on
/// the ellipsoid at 47° N, tiles of `m` samples.
pub fn alpine_47n(m: u32) -> GeoScene {
    let (lat, lon) = (47.0 + 88.0 / 1200.0, 11.0 + 88.0 / 1200.0);
    geo_scene("alpine 47°N", alpine(), lat, lon, 1.0 / 1200.0, m)
}

/// `cliffs` (seed 7, 1025²) at 70° N, where a longitude step is a third of a latitude step.
pub fn cliffs_70n(m: u32) -> GeoScene {
    let hf = aerie::terrain::gen::generate(&aerie::terrain::gen::GenParams {
        size: 1025,
        spacing: 30.0,
        kind: aerie::terrain::gen::DemKind::Cliffs,
        seed: 7,
    });
    geo_scene("cliffs 70°N", hf, 70.0, -20.0, 1.0 / 1200.0, m)
}
