//! Shared set-up of aerie's criterion micro-benchmarks (`benches/`): generated datasets, their
//! bakes, clipmap descriptions and a flight of cameras. Run with `make bench` (or
//! `cargo bench -p aerie-bench`); `AERIE_BENCH_SIZE` sets the side of the selection dataset
//! (default 16385, the DESIGN.md target size: 1.07 GB generated and baked once, in memory).

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::terrain::bake::{bake, BakeParams, ErrorBake};
use aerie::terrain::clipmap::ClipmapDesc;
use aerie::terrain::dataset::Dataset;
use aerie::terrain::gen::{generate, DemKind, GenParams};
use glam::DVec3;

/// Vertices per tile side (the renderer's default m).
pub const TILE_SIZE: u32 = 17;

/// Side of the dataset the selection benchmark uses: `AERIE_BENCH_SIZE` or 16385.
pub fn selection_size() -> usize {
    std::env::var("AERIE_BENCH_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .filter(|&n: &usize| n >= 257)
        .unwrap_or(16385)
}

/// A generated `size`² terrain (deterministic) at 10 m spacing.
pub fn generated(size: usize, kind: DemKind) -> Dataset {
    let hf = generate(&GenParams {
        size,
        spacing: 10.0,
        kind,
        seed: 2026,
    });
    Dataset::from_heightfield(hf, format!("generated {} {size}²", kind.name()))
}

/// Every level's error bake (m = 17).
pub fn baked(ds: &Dataset) -> ErrorBake {
    bake(
        ds,
        BakeParams {
            tile_size: TILE_SIZE,
            levels: 0,
        },
        &|_, _| {},
    )
}

/// The renderer's default clipmap (n = 129, margin 2 tiles) over `width × height` samples.
pub fn clipmap_desc(width: usize, height: usize) -> ClipmapDesc {
    ClipmapDesc {
        tile_quads: TILE_SIZE - 1,
        patch_tiles: 8,
        margin_tiles: 2,
        width: width as u32,
        height: height as u32,
    }
}

/// `n` cameras of a 340 m/s pass at 30 fps across the middle of a `side_m`-wide square,
/// 600 m up, pitched 12° down, 90° FOV on `w × h`.
pub fn flight(side_m: f64, n: usize, w: u32, h: u32) -> Vec<Camera> {
    let frustum = Frustum::symmetric(90f64.to_radians(), w, h);
    let heading = 70f64.to_radians();
    let dir = DVec3::new(heading.sin(), heading.cos(), 0.0);
    let start = DVec3::new(side_m / 2.0, side_m / 2.0, 3_600.0) - dir * (n as f64 * 340.0 / 60.0);
    (0..n)
        .map(|k| {
            Camera::new(
                start + dir * (k as f64 * 340.0 / 30.0),
                Attitude::from_degrees(70.0, -12.0, 0.0),
                frustum,
            )
        })
        .collect()
}

/// The issue-15 selection set-up: a `size`² ridged terrain at 10 m spacing, or the same samples
/// on a 1″ geographic grid from 46°N 7°E (4.6° square at 16385²), drawn on the ellipsoid.
pub struct TargetScene {
    pub name: &'static str,
    pub ds: Dataset,
    pub bake: ErrorBake,
    pub clip: ClipmapDesc,
    /// The ellipsoid grid (geographic scene), `None` on the flat plane.
    pub earth: Option<aerie::terrain::geodesy::GeoGrid>,
}

impl TargetScene {
    /// The flat scene (`geographic` false) or the geographic one.
    pub fn new(size: usize, geographic: bool) -> Self {
        let mut ds = generated(size, DemKind::Ridged);
        let mut earth = None;
        if geographic {
            let (lat, lon, d) = (46.0, 7.0, 1.0 / 3600.0);
            let mid = lat + d * (size - 1) as f64 / 2.0;
            let (sx, sy) = aerie::terrain::load::geographic_spacing_m(mid, d, d);
            let geo = aerie::terrain::GeoReference::Geographic {
                south_lat_deg: lat,
                west_lon_deg: lon,
                dlat_deg: d,
                dlon_deg: d,
            };
            earth = aerie::terrain::geodesy::GeoGrid::of(Some(&geo), sx, sy);
            let mut hf = ds.hf;
            (hf.spacing_x, hf.spacing_y, hf.geo) = (sx, sy, Some(geo));
            ds = Dataset::from_heightfield(hf, format!("generated ridged {size}² geographic"));
        }
        let bake = baked(&ds);
        let clip = clipmap_desc(ds.hf.width, ds.hf.height);
        Self {
            name: if geographic { "geographic" } else { "flat" },
            ds,
            bake,
            clip,
            earth,
        }
    }

    /// The clipmap viewer (level-0 samples) of a camera.
    pub fn viewer(&self, cam: &Camera) -> [f64; 2] {
        let g = match &self.earth {
            Some(e) => e.grid_of_world(cam.position),
            None => cam.position,
        };
        [g.x / self.ds.hf.spacing_x, g.y / self.ds.hf.spacing_y]
    }

    /// `n` cameras of a 100 m/s low pass at 60 fps across the middle, `agl` metres above the
    /// ground under each, pitched 10° down, 90° FOV on `w × h` (local level on the ellipsoid).
    pub fn flight_agl(&self, n: usize, w: u32, h: u32, agl: f64) -> Vec<Camera> {
        let hf = &self.ds.hf;
        let (ex, ey) = hf.extent_m();
        let frustum = Frustum::symmetric(90f64.to_radians(), w, h);
        let heading = 70f64;
        let dir = glam::DVec2::new(heading.to_radians().sin(), heading.to_radians().cos());
        let start = glam::DVec2::new(ex / 2.0, ey / 2.0) - dir * (n as f64 * 100.0 / 120.0);
        (0..n)
            .map(|k| {
                let g = start + dir * (k as f64 * 100.0 / 60.0);
                let alt = hf.height_at_m(g.x, g.y) + agl;
                let att = Attitude::from_degrees(heading, -10.0, 0.0);
                match &self.earth {
                    Some(e) => {
                        let (lat, lon) = e.lat_lon_of_grid(g);
                        let pos = e.world_of_geodetic(aerie::terrain::geodesy::Geodetic::new(
                            lat, lon, alt,
                        ));
                        Camera::new(pos, att.in_frame(e.local_enu_axes(lat, lon)), frustum)
                    }
                    None => Camera::new(DVec3::new(g.x, g.y, alt), att, frustum),
                }
            })
            .collect()
    }
}

/// This thread's CPU time, microseconds: per-frame figures on a loaded machine, where the wall
/// clock's p99 is the scheduler's time slice (the renderer's own clock, which `fly` reports).
pub use aerie::render::cpu_clock::thread_cpu_us;
