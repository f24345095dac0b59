//! DEM loaders: turn elevation files (SRTM `.hgt`/`.hgt.zip`, GeoTIFF, 16-bit PNG, raw f32/u16,
//! NumPy `.npy`/`.npz`) into a [`Heightfield`](crate::Heightfield) in metres, row 0 = south;
//! [`stitch`] puts adjacent SRTM tiles (a folder or a list) together into one grid.
//!
//! Every loader ends in `finish::finish` so the flip, the void fill and the sanity checks are
//! the same for all formats. Bad input is reported as a one-line [`DemError`] that names the
//! file (DESIGN.md "Conventions": bad data files stop start-up with a message naming the file,
//! the key or offset, and the reason) — never a panic.

mod archive;
mod dem;
mod error;
mod finish;
mod geo;
pub(crate) mod geotiff;
mod hgt;
mod npy;
pub(crate) mod placement;
mod png16;
mod raw;
mod raw_rows;
mod sidecar;
pub mod stitch;

pub use dem::load_dem;
pub use error::DemError;
pub use geo::geographic_spacing_m;
pub use raw_rows::RawRows;

#[cfg(test)]
mod limits_tests;
#[cfg(test)]
mod tests;
