//! Terrain data: the heightfield model and its loaders, the tile mesh, tiles and selection.

pub mod bake;
pub mod clipmap;
pub mod dataset;
pub mod gather;
pub mod gen;
pub mod heightfield;
pub mod load;
pub mod mesh;
pub mod pool;
pub mod select;
pub mod tiles;

pub use heightfield::{GeoReference, Heightfield};
pub use load::{load_dem, DemError};
