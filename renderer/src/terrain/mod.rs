//! Terrain data: the heightfield model and its loaders.

pub mod heightfield;
pub mod load;

pub use heightfield::{GeoReference, Heightfield};
pub use load::{load_dem, DemError};
