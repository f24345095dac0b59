//! aerie: a Vulkan-native, error-bounded terrain renderer for flight simulators.
//!
//! Layers, each importing only downwards (see ARCHITECTURE.md): the pure terrain decisions live
//! in the crate `aerie-terrain` (re-exported here as [`terrain`] and [`camera`]); [`vk`] is the
//! thin Vulkan plumbing; [`render`] draws one frame in the order of DESIGN.md's data flow;
//! [`sim`] is the simulator glue (pose input, host views, channels, flights); [`tools`] are
//! image error, panorama, overlay text and output files; [`app`] is the command line on top.

pub mod app;
pub mod render;
pub mod sim;
pub mod tools;
pub mod vk;

pub use aerie_terrain as terrain;
pub use aerie_terrain::camera;
