//! The render layer, one concern per file, importing only downwards (vk/, the terrain crate)
//! and never a sibling that imports it back:
//! - `plan` (pure: the frame's decisions) over `jobs` (pure: upload jobs, byte budget) and
//!   `stats` (what a frame did);
//! - `upload` (staging and streaming the jobs), `terrain_pass` (descriptors, the draw),
//!   `overlay_pass` (the statistics panel copy), `uniforms`, `resources` (the dataset's GPU
//!   objects), `gpu` (GPU struct layouts);
//! - `frame` (the renderer: plan → stage → record → submit) on top of them all.

pub mod desc;
pub mod frame;
pub mod gpu;
pub mod jobs;
pub mod overlay_pass;
pub mod plan;
pub mod resources;
pub mod stats;
pub mod terrain_pass;
pub mod uniforms;
pub mod upload;
