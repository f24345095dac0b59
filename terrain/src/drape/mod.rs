//! Rasters draped on the terrain (issue 17): 8-bit GeoTIFF imagery (RGB, RGBA or grey) and
//! land-cover class codes, read with their geo-reference ([`read`]) and resampled onto a
//! raster aligned with the terrain's grid ([`register`]) — pure CPU, so the registration is
//! tested against the f64 geodesy without a GPU.
//!
//! The draped raster covers the grid's cells: `size` texels across the `width` samples' cells
//! `[-0.5, width - 0.5]` (sample units), so texel `t`'s centre is at grid coordinate
//! `(t + 0.5) · width / size − 0.5` and a shader reads it at `uv = (grid + 0.5) / width`,
//! whatever the size. Row 0 is the southern edge, like the grid.

pub mod encode;
pub mod error;
pub mod levels;
pub mod mips;
pub mod read;
pub mod register;

pub use encode::{encode_geotiff, EncodeRef};
pub use error::DrapeError;
pub use levels::{level_extent, store_texels_per_sample, LevelDraper, MAX_STORE_TEXELS_PER_SAMPLE};
pub use read::{read_raster, GeoRaster, RasterCrs, RasterRef};
pub use register::{
    drape_codes, drape_rgba, drape_rgba_window, grid_to_pixel, DrapeSize, DrapeStats, TerrainGrid,
    TexelWindow, CODE_NONE, MAX_TEXELS_PER_SAMPLE,
};

#[cfg(test)]
mod tests;
