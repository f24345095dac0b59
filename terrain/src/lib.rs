//! aerie's terrain decisions, pure CPU (no Vulkan, no windowing: Cargo enforces it): the
//! heightfield model and its loaders, the exact error bake, clipmap placement, tile selection,
//! the refined-tile pools, the tile mesh and the camera math they are all computed from.

pub mod bake;
pub mod camera;
pub mod clipmap;
pub mod dataset;
pub mod drape;
pub mod fast_hash;
pub mod gather;
pub mod gen;
pub mod geodesy;
pub mod heightfield;
pub mod load;
pub mod mesh;
pub mod pool;
pub mod query;
pub mod select;
pub mod source;
pub mod store;
pub mod stream;
#[cfg(test)]
mod test_rng;
pub mod tiles;

pub use heightfield::{GeoReference, Heightfield};
pub use load::{load_dem, DemError};
