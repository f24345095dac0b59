//! Registration: a raster resampled onto the terrain's grid. Each texel centre of the draped
//! raster → the grid's geographic or projected coordinates → the raster's CRS (geographic or
//! UTM; other projected CRSs only onto a terrain in the same CRS) → raster pixel → bilinear
//! (imagery, premultiplied by alpha) or nearest (class codes). Pure.
//!
//! The exact mapping is evaluated on a lattice every [`LATTICE`] texels and interpolated
//! between (the map from one smooth coordinate system to another is affine to far below a
//! pixel over a few texels); cells with a corner outside a projection's domain are mapped
//! texel by texel.

use super::error::DrapeError;
use super::read::{GeoRaster, RasterCrs, RasterRef};
use crate::geodesy::{projected_crs, UtmZone};
use crate::load::geographic_spacing_m;
use crate::GeoReference;

/// The class texture's "no class here" value (the derived classes apply).
pub const CODE_NONE: u8 = 255;
/// At most this many draped texels per grid sample (imagery finer than that is averaged).
pub const MAX_TEXELS_PER_SAMPLE: u32 = 16;
/// Texels between exactly mapped lattice points.
const LATTICE: usize = 16;

/// The terrain's level-0 grid with its geo-reference.
#[derive(Debug, Clone, PartialEq)]
pub struct TerrainGrid {
    /// Samples per row and rows (the real extent, no padding).
    pub width: usize,
    pub height: usize,
    /// Metres between columns and rows.
    pub spacing_x: f64,
    pub spacing_y: f64,
    pub geo: GeoReference,
}

impl TerrainGrid {
    /// The grid, or why nothing can be draped on it (no geo-reference).
    pub fn new(
        width: usize,
        height: usize,
        spacing_x: f64,
        spacing_y: f64,
        geo: Option<&GeoReference>,
    ) -> Result<Self, String> {
        let geo = geo.cloned().ok_or_else(|| {
            "the terrain has no geo-reference, so a geo-referenced raster cannot be placed on it"
                .to_string()
        })?;
        Ok(Self {
            width,
            height,
            spacing_x,
            spacing_y,
            geo,
        })
    }
}

/// The draped raster's size: `width × height` texels over the grid's cells (see the module
/// documentation of `drape`); `texels_per_sample` is k (0 when the grid is wider than the
/// texture limit and the raster is coarser than the grid).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DrapeSize {
    pub width: usize,
    pub height: usize,
    pub texels_per_sample: u32,
}

impl DrapeSize {
    /// An integer k ≥ 1 of texels per grid sample, from the finest raster's ground resolution,
    /// capped by [`MAX_TEXELS_PER_SAMPLE`] and by `max_texture` texels per side; a grid wider
    /// than `max_texture` gets `max_texture` texels (k = 0 says so).
    pub fn choose(grid: &TerrainGrid, rasters: &[&GeoRaster], max_texture: u32) -> Self {
        let max = max_texture.max(1) as usize;
        let side = grid.width.max(grid.height).max(1);
        if side > max {
            return Self {
                width: grid.width.min(max),
                height: grid.height.min(max),
                texels_per_sample: 0,
            };
        }
        let mut k = 1u32;
        for r in rasters {
            let (px, py) = pixel_ground_m(&r.georef, r.height);
            let ratio = (grid.spacing_x / px).max(grid.spacing_y / py);
            // Within 2 % of an integer is that integer: the ground sizes of the grid and the
            // raster are taken at different latitudes (1.5" imagery on a 3" grid is 2).
            let want = (ratio / 1.02).ceil();
            if want.is_finite() && want > 1.0 {
                k = k.max((want as u32).min(MAX_TEXELS_PER_SAMPLE));
            }
        }
        let k = k.min((max / side) as u32).max(1);
        Self {
            width: grid.width * k as usize,
            height: grid.height * k as usize,
            texels_per_sample: k,
        }
    }

    /// This size, or the largest that holds at most `max_texels` texels: fewer texels per
    /// sample first (k keeps its meaning), then — when even one per sample is too many — a
    /// texture coarser than the grid (k = 0), the aspect kept.
    pub fn within(self, grid: &TerrainGrid, max_texels: usize) -> Self {
        if self.texels() <= max_texels {
            return self;
        }
        let cells = (grid.width * grid.height).max(1) as f64;
        let f = (max_texels.max(1) as f64 / cells).sqrt();
        let k = f.floor() as u32;
        if k >= 1 {
            return Self {
                width: grid.width * k as usize,
                height: grid.height * k as usize,
                texels_per_sample: k,
            };
        }
        Self {
            width: ((grid.width as f64 * f).floor() as usize).max(1),
            height: ((grid.height as f64 * f).floor() as usize).max(1),
            texels_per_sample: 0,
        }
    }

    /// Grid coordinates (sample units) of texel (tx, ty)'s centre.
    pub fn texel_centre(&self, grid: &TerrainGrid, tx: usize, ty: usize) -> (f64, f64) {
        (
            (tx as f64 + 0.5) * grid.width as f64 / self.width as f64 - 0.5,
            (ty as f64 + 0.5) * grid.height as f64 / self.height as f64 - 0.5,
        )
    }

    pub fn texels(&self) -> usize {
        self.width * self.height
    }
}

/// A raster pixel's ground size in metres (east, north).
pub(super) fn pixel_ground_m(r: &RasterRef, height: usize) -> (f64, f64) {
    match r.crs {
        RasterCrs::Geographic => {
            let centre = r.y0 - r.dy * (height as f64 - 1.0) / 2.0;
            geographic_spacing_m(centre.clamp(-89.0, 89.0), r.dy, r.dx)
        }
        RasterCrs::Projected { .. } => (r.dx, r.dy),
    }
}

/// Grid coordinates → the raster's model coordinates, or `None` outside a projection.
pub type Mapping<'a> = Box<dyn Fn(f64, f64) -> Option<(f64, f64)> + 'a>;

/// The map from grid coordinates (sample units) to raster pixel coordinates, or why the
/// raster cannot be placed on this terrain (naming the unsupported CRS's code).
pub fn grid_to_pixel<'a>(
    grid: &'a TerrainGrid,
    raster: &'a GeoRaster,
) -> Result<Mapping<'a>, String> {
    let r = &raster.georef;
    // Longitudes are taken the short way round from the raster's centre meridian.
    let centre_lon = r.x0 + r.dx * (raster.width as f64 - 1.0) / 2.0;
    let to_raster_crs: Mapping<'a> = match &r.crs {
        RasterCrs::Geographic => Box::new(move |lat, lon| {
            Some((
                centre_lon + (lon - centre_lon + 180.0).rem_euclid(360.0) - 180.0,
                lat,
            ))
        }),
        RasterCrs::Projected { utm: Ok(z), .. } => {
            let z: UtmZone = *z;
            Box::new(move |lat, lon| Some(z.easting_northing(lat, lon)))
        }
        RasterCrs::Projected { crs, utm: Err(why) } => {
            // Only a terrain in the very same CRS can take it (no conversion needed).
            if let GeoReference::Projected { crs: tc, .. } = &grid.geo {
                if tc != crs {
                    return Err(format!("CRS unsupported: {why}"));
                }
            } else {
                return Err(format!("CRS unsupported: {why}"));
            }
            Box::new(|_, _| None)
        }
    };
    let pixel = move |x: f64, y: f64| r.pixel_of_model(x, y);
    match &grid.geo {
        GeoReference::Geographic {
            south_lat_deg,
            west_lon_deg,
            dlat_deg,
            dlon_deg,
        } => {
            let (s, w, dlat, dlon) = (*south_lat_deg, *west_lon_deg, *dlat_deg, *dlon_deg);
            Ok(Box::new(move |gx, gy| {
                let (x, y) = to_raster_crs(s + gy * dlat, w + gx * dlon)?;
                Some(pixel(x, y))
            }))
        }
        GeoReference::Projected {
            crs,
            easting,
            northing,
        } => {
            let (e0, n0, sx, sy) = (*easting, *northing, grid.spacing_x, grid.spacing_y);
            if let RasterCrs::Projected { crs: rc, .. } = &r.crs {
                if rc == crs {
                    return Ok(Box::new(move |gx, gy| {
                        Some(pixel(e0 + gx * sx, n0 + gy * sy))
                    }));
                }
            }
            let zone = projected_crs(crs)
                .map_err(|why| format!("the terrain's CRS is unsupported for draping: {why}"))?;
            Ok(Box::new(move |gx, gy| {
                let (lat, lon) = zone.lat_lon(e0 + gx * sx, n0 + gy * sy).ok()?;
                let (x, y) = to_raster_crs(lat, lon)?;
                Some(pixel(x, y))
            }))
        }
    }
}

/// Texels `w × h` from texel `(x0, y0)` of a draped raster with `sx × sy` level-0 samples
/// per texel: texel `t`'s centre is at grid coordinate `(t + 0.5) · s − 0.5` (see the module
/// documentation of `drape`). A whole [`DrapeSize`] texture is one window; a store's imagery
/// page is a window of its level's raster (`sx = 2^L / k`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TexelWindow {
    pub sx: f64,
    pub sy: f64,
    pub x0: usize,
    pub y0: usize,
    pub w: usize,
    pub h: usize,
}

impl TexelWindow {
    /// The whole texture of `size` over `grid`.
    pub fn whole(grid: &TerrainGrid, size: &DrapeSize) -> Self {
        Self {
            sx: grid.width as f64 / size.width as f64,
            sy: grid.height as f64 / size.height as f64,
            x0: 0,
            y0: 0,
            w: size.width,
            h: size.height,
        }
    }

    /// Grid coordinates (sample units) of window texel (tx, ty)'s centre.
    pub fn centre(&self, tx: usize, ty: usize) -> (f64, f64) {
        (
            ((self.x0 + tx) as f64 + 0.5) * self.sx - 0.5,
            ((self.y0 + ty) as f64 + 0.5) * self.sy - 0.5,
        )
    }

    pub fn texels(&self) -> usize {
        self.w * self.h
    }
}

/// Calls `f(tx, ty, px, py)` for every texel of `win` (window coordinates) with the raster
/// pixel its centre maps to.
///
/// The lattice is anchored at the level raster's absolute texel multiples of [`LATTICE`], not
/// at the window's origin: a texel maps to the same pixel whichever window (a whole texture, a
/// store page, a streamed strip) it is drawn in, so pages and gathers agree exactly. Lattice
/// points past a window's edge (or the raster's) are evaluated like any other: the mapping is
/// defined there, and when it is not the cell falls back to exact texels.
fn for_each_texel(win: &TexelWindow, map: &Mapping<'_>, mut f: impl FnMut(usize, usize, f64, f64)) {
    if win.w == 0 || win.h == 0 {
        return;
    }
    let exact = |x: usize, y: usize| {
        // Absolute texel (x, y) of the level raster.
        let gx = (x as f64 + 0.5) * win.sx - 0.5;
        let gy = (y as f64 + 0.5) * win.sy - 0.5;
        map(gx, gy)
    };
    let (ax0, ay0) = (win.x0, win.y0);
    let (ax1, ay1) = (win.x0 + win.w, win.y0 + win.h); // exclusive
    let cells = |a0: usize, a1: usize| -> Vec<usize> {
        ((a0 / LATTICE) * LATTICE..a1).step_by(LATTICE).collect()
    };
    let (cx, cy) = (cells(ax0, ax1), cells(ay0, ay1));
    let corner_row = |y: usize| -> Vec<Option<(f64, f64)>> {
        cx.iter()
            .chain(std::iter::once(&(cx[cx.len() - 1] + LATTICE)))
            .map(|&x| exact(x, y))
            .collect()
    };
    let mut row_lo = corner_row(cy[0]);
    for &y0 in &cy {
        let y1 = y0 + LATTICE;
        let row_hi = corner_row(y1);
        let ys = y0.max(ay0)..y1.min(ay1);
        for (i, &x0) in cx.iter().enumerate() {
            let xs = x0.max(ax0)..(x0 + LATTICE).min(ax1);
            let corners = (row_lo[i], row_lo[i + 1], row_hi[i], row_hi[i + 1]);
            if let (Some(a), Some(b), Some(c), Some(d)) = corners {
                for ty in ys.clone() {
                    let v = (ty - y0) as f64 / LATTICE as f64;
                    for tx in xs.clone() {
                        let u = (tx - x0) as f64 / LATTICE as f64;
                        let lerp = |p: f64, q: f64, r: f64, s: f64| {
                            (p * (1.0 - u) + q * u) * (1.0 - v) + (r * (1.0 - u) + s * u) * v
                        };
                        f(
                            tx - ax0,
                            ty - ay0,
                            lerp(a.0, b.0, c.0, d.0),
                            lerp(a.1, b.1, c.1, d.1),
                        );
                    }
                }
            } else {
                for ty in ys.clone() {
                    for tx in xs.clone() {
                        if let Some((px, py)) = exact(tx, ty) {
                            f(tx - ax0, ty - ay0, px, py);
                        }
                    }
                }
            }
        }
        row_lo = row_hi;
    }
}

fn inside(raster: &GeoRaster, px: f64, py: f64) -> bool {
    px >= -0.5 && py >= -0.5 && px < raster.width as f64 - 0.5 && py < raster.height as f64 - 0.5
}

/// What draping one raster did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct DrapeStats {
    /// Texels the raster covered.
    pub covered: usize,
    /// Texels per raw raster value (class codes; all zero for imagery).
    pub codes: Vec<u64>,
}

fn check_overlap(raster: &GeoRaster, stats: &DrapeStats) -> Result<(), DrapeError> {
    if stats.covered == 0 {
        return Err(DrapeError {
            path: raster.path.clone(),
            reason: "no overlap with the terrain".into(),
        });
    }
    Ok(())
}

/// Drapes an 8-bit raster (grey, RGB or RGBA) over `out` (RGBA8, `size` texels, row 0 south):
/// bilinear, composited over what is there by its alpha; outside the raster nothing changes
/// (a fresh `out` of zeros is transparent there).
pub fn drape_rgba(
    grid: &TerrainGrid,
    size: &DrapeSize,
    raster: &GeoRaster,
    out: &mut [u8],
) -> Result<DrapeStats, DrapeError> {
    let map = grid_to_pixel(grid, raster).map_err(|reason| DrapeError {
        path: raster.path.clone(),
        reason,
    })?;
    assert_eq!(
        out.len(),
        size.texels() * 4,
        "RGBA target of the drape size"
    );
    let win = TexelWindow::whole(grid, size);
    let stats = drape_rgba_window(&win, &map, raster, out, size.width);
    check_overlap(raster, &stats)?;
    Ok(stats)
}

/// [`drape_rgba`] over one window of texels (`out`: `win.w × win.h` RGBA8, row 0 south, of
/// which each row is `stride` texels), composited over what is there; the stats count the
/// texels covered (no overlap is not an error here: a page may lie outside the imagery).
pub fn drape_rgba_window(
    win: &TexelWindow,
    map: &Mapping<'_>,
    raster: &GeoRaster,
    out: &mut [u8],
    stride: usize,
) -> DrapeStats {
    let mut stats = DrapeStats::default();
    let (w, h) = (raster.width as i64, raster.height as i64);
    for_each_texel(win, map, |tx, ty, px, py| {
        if !inside(raster, px, py) {
            return;
        }
        let (fx, fy) = (px.floor(), py.floor());
        let (u, v) = (px - fx, py - fy);
        let mut acc = [0.0f64; 4];
        for (dx, dy, wgt) in [
            (0, 0, (1.0 - u) * (1.0 - v)),
            (1, 0, u * (1.0 - v)),
            (0, 1, (1.0 - u) * v),
            (1, 1, u * v),
        ] {
            if wgt == 0.0 {
                continue;
            }
            let c = (fx as i64 + dx).clamp(0, w - 1) as usize;
            let r = (fy as i64 + dy).clamp(0, h - 1) as usize;
            let p = raster.pixel(c, r);
            let (rgb, a) = match raster.bands {
                1 => ([p[0]; 3], 255),
                3 => ([p[0], p[1], p[2]], 255),
                _ => ([p[0], p[1], p[2]], p[3]),
            };
            let a = f64::from(a) / 255.0 * wgt;
            for i in 0..3 {
                acc[i] += f64::from(rgb[i]) * a;
            }
            acc[3] += a;
        }
        if acc[3] <= 0.0 {
            return;
        }
        stats.covered += 1;
        let i = (ty * stride + tx) * 4;
        let dst = &mut out[i..i + 4];
        let (a_s, a_d) = (acc[3], f64::from(dst[3]) / 255.0);
        let a_o = a_s + a_d * (1.0 - a_s);
        for c in 0..3 {
            let v = (acc[c] + f64::from(dst[c]) * a_d * (1.0 - a_s)) / a_o;
            dst[c] = v.round().clamp(0.0, 255.0) as u8;
        }
        dst[3] = (a_o * 255.0).round().clamp(0.0, 255.0) as u8;
    });
    stats
}

/// Drapes a one-band raster of class codes onto `out` (one byte per texel, row 0 south):
/// nearest pixel, the code mapped through `table` (code → class; [`CODE_NONE`] leaves the
/// texel as it is). Texels per raw code are counted in the stats.
pub fn drape_codes(
    grid: &TerrainGrid,
    size: &DrapeSize,
    raster: &GeoRaster,
    table: &[u8; 256],
    out: &mut [u8],
) -> Result<DrapeStats, DrapeError> {
    if raster.bands != 1 {
        return Err(DrapeError {
            path: raster.path.clone(),
            reason: format!(
                "a land-cover raster has one band of class codes, this one has {}",
                raster.bands
            ),
        });
    }
    let map = grid_to_pixel(grid, raster).map_err(|reason| DrapeError {
        path: raster.path.clone(),
        reason,
    })?;
    assert_eq!(out.len(), size.texels(), "class target of the drape size");
    let mut stats = DrapeStats {
        covered: 0,
        codes: vec![0; 256],
    };
    for_each_texel(&TexelWindow::whole(grid, size), &map, |tx, ty, px, py| {
        if !inside(raster, px, py) {
            return;
        }
        let c = (px.round().max(0.0) as usize).min(raster.width - 1);
        let r = (py.round().max(0.0) as usize).min(raster.height - 1);
        let code = raster.pixel(c, r)[0];
        stats.covered += 1;
        stats.codes[code as usize] += 1;
        let class = table[code as usize];
        if class != CODE_NONE {
            out[ty * size.width + tx] = class;
        }
    });
    check_overlap(raster, &stats)?;
    Ok(stats)
}
