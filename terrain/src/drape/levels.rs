//! Imagery draped onto every level of a tile store (issue 17: imagery streamed per page like
//! the heights). Level `L`'s raster has `k` texels per level-`L` sample per axis — texel `t`'s
//! centre at grid coordinate `(t + 0.5) · 2^L / k − 0.5`, so level 0 is exactly the in-memory
//! drape at `k` texels per sample and each level covers the same cells — and
//! `⌈valid width · k / 2^L⌉` texels per row. A page of level `L` holds the texels of its
//! samples: columns `[tx0·q·k, (tx0 + ntx)·q·k)` of the level's raster (fewer at the east and
//! north edges, none over the padding). Each texel is the bilinear sample of the raster's own
//! mip whose pixels are between half the texel and the texel (so a coarse level averages
//! the imagery instead of aliasing it), rasters composited in order, the later on top. Pure.

use super::error::DrapeError;
use super::mips::raster_pyramid;
use super::read::GeoRaster;
use super::register::{
    drape_rgba_window, grid_to_pixel, pixel_ground_m, DrapeSize, TerrainGrid, TexelWindow,
};

/// Texels per sample a store's imagery may have (powers of two up to this).
pub const MAX_STORE_TEXELS_PER_SAMPLE: u32 = 4;

/// One raster and its mips, with the ground size of its level-0 pixels.
struct Pyramid {
    levels: Vec<GeoRaster>,
    pixel_m: f64,
}

/// The rasters to drape, ready for any level window of `grid` at `k` texels per sample.
pub struct LevelDraper {
    grid: TerrainGrid,
    k: u32,
    rasters: Vec<Pyramid>,
}

impl LevelDraper {
    /// Checks that every raster can be placed on `grid` (its CRS; an overlap is checked per
    /// page) and builds each raster's mips down to the texel size of level `levels − 1`.
    pub fn new(
        grid: &TerrainGrid,
        rasters: &[GeoRaster],
        k: u32,
        levels: u32,
    ) -> Result<Self, DrapeError> {
        if !k.is_power_of_two() || k > MAX_STORE_TEXELS_PER_SAMPLE {
            return Err(DrapeError {
                path: rasters.first().map(|r| r.path.clone()).unwrap_or_default(),
                reason: format!(
                    "{k} texels per sample: a store's imagery has 1, 2 or {MAX_STORE_TEXELS_PER_SAMPLE}"
                ),
            });
        }
        let spacing = grid.spacing_x.min(grid.spacing_y);
        let coarsest_m =
            spacing * f64::from(1u32 << levels.saturating_sub(1).min(30)) / f64::from(k);
        let mut out = Vec::with_capacity(rasters.len());
        for r in rasters {
            let _placed = grid_to_pixel(grid, r).map_err(|reason| DrapeError {
                path: r.path.clone(),
                reason,
            })?;
            let (px, py) = pixel_ground_m(&r.georef, r.height);
            let pixel_m = px.min(py);
            out.push(Pyramid {
                levels: raster_pyramid(r, pixel_m, coarsest_m),
                pixel_m,
            });
        }
        Ok(Self {
            grid: grid.clone(),
            k,
            rasters: out,
        })
    }

    pub fn texels_per_sample(&self) -> u32 {
        self.k
    }

    /// Texels of the coarsest level (`levels − 1`) that some raster covers: zero says the
    /// rasters miss the terrain altogether. One window of at most a few thousand texels.
    pub fn coarse_coverage(&self, levels: u32) -> usize {
        let level = levels.saturating_sub(1);
        let (w, h) = self.level_extent(level);
        self.window(level, 0, 0, w, h).1
    }

    /// Texels per row and rows of level `level`'s raster.
    pub fn level_extent(&self, level: u32) -> (usize, usize) {
        level_extent(&self.grid, self.k, level)
    }

    /// The RGBA8 texels (straight alpha, sRGB, row 0 south) of the window `w × h` at texel
    /// `(x0, y0)` of level `level`'s raster, and how many of them a raster covered.
    pub fn window(&self, level: u32, x0: usize, y0: usize, w: usize, h: usize) -> (Vec<u8>, usize) {
        let s = f64::from(1u32 << level) / f64::from(self.k);
        let win = TexelWindow {
            sx: s,
            sy: s,
            x0,
            y0,
            w,
            h,
        };
        let mut out = vec![0u8; w * h * 4];
        let mut covered = 0;
        let texel_m = s * self.grid.spacing_x.min(self.grid.spacing_y);
        for p in &self.rasters {
            // The coarsest mip whose pixels are no larger than the texel (between half and one).
            let mut m = 0;
            while m + 1 < p.levels.len() && p.pixel_m * f64::from(1u32 << (m + 1)) <= texel_m {
                m += 1;
            }
            let raster = &p.levels[m];
            let map = grid_to_pixel(&self.grid, raster).expect("checked in new");
            covered += drape_rgba_window(&win, &map, raster, &mut out, w).covered;
        }
        (out, covered)
    }
}

/// The texels per sample a store's imagery gets from its rasters' ground resolution: the
/// in-memory drape's k ([`DrapeSize::choose`]: the finest raster, within 2 % of an integer)
/// rounded up to a power of two, at most [`MAX_STORE_TEXELS_PER_SAMPLE`].
pub fn store_texels_per_sample(grid: &TerrainGrid, rasters: &[GeoRaster]) -> u32 {
    let refs: Vec<&GeoRaster> = rasters.iter().collect();
    let k = DrapeSize::choose(grid, &refs, u32::MAX).texels_per_sample;
    k.max(1)
        .next_power_of_two()
        .min(MAX_STORE_TEXELS_PER_SAMPLE)
}

/// Texels per row and rows of level `level`'s imagery raster over `grid` at `k` texels per
/// sample: `⌈valid samples · k / 2^level⌉` each.
pub fn level_extent(grid: &TerrainGrid, k: u32, level: u32) -> (usize, usize) {
    let t = |n: usize| (n * k as usize).div_ceil(1usize << level);
    (t(grid.width), t(grid.height))
}
