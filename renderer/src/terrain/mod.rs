//! Terrain data: the heightfield model and its loaders, the tile mesh, tiles and selection.

pub mod bake;
pub mod dataset;
pub mod gen;
pub mod heightfield;
pub mod load;
pub mod mesh;
pub mod gather;
pub mod select;
pub mod tiles;
pub mod clipmap;
pub mod pool;

pub use heightfield::{GeoReference, Heightfield};
pub use load::{load_dem, DemError};
