//! The render layer, one concern per file, importing only downwards (vk/, the terrain crate)
//! and never a sibling that imports it back:
//! - `plan` (pure: the frame's decisions) over `jobs` (pure: upload jobs, byte budget),
//!   `content` (pure: which level-texture cells hold their samples), `feed` (the level strips
//!   and prefetches the plan gathers or asks its source for), `gathered` (the frame's samples
//!   from the `TerrainSource`, taken when an upload is admitted) and `stats` (what a frame did);
//! - `upload` (staging and streaming the jobs), `terrain_pass` (descriptors, the draw),
//!   `overlay_pass` (the statistics panel copy), `uniforms`, `resources` (the dataset's GPU
//!   objects), `gpu` (GPU struct layouts), `geo_instances` (pure: nodes' relative-to-eye
//!   frames on the ellipsoid), `normal_map` (pure: the levels' normal-map texels from the
//!   full-resolution heights, and the CPU twin of the GPU pass), `normal_pass` (`--normals
//!   gpu`: the compute pass that makes them from the level textures), `frame_record` (recording
//!   one frame's passes);
//! - `atmosphere` (pure: the Preetham sky, sun colour, height fog) and `landcover` (pure: the
//!   derived class rules), the CPU twins of `shaders/atmosphere.glsl` and `landcover.glsl`;
//! - `entity_lod` (pure: discrete LOD by projected size), `models` (pure: meshes, LOD chains,
//!   the default model), `gltf_model` (glTF 2.0 files → meshes), `entity_instances` (pure: the
//!   frame's instances and indirect draws), `entity_pass` (the entities' GPU objects and draw);
//! - `tess_pass` (the hardware-tessellation baseline: its heights, patch records and draw);
//! - `frame` (the renderer: plan → stage → record → submit) on top of them all.

pub mod ahead_select;
pub mod atmosphere;
pub mod banded;
pub mod content;
pub mod cpu_clock;
pub mod desc;
pub mod drape_textures;
pub mod entity_instances;
pub mod entity_lod;
pub mod entity_pass;
pub mod feed;
pub mod frame;
pub mod frame_plan;
pub mod frame_record;
pub mod gathered;
pub mod geo_instances;
pub mod gltf_model;
pub mod gpu;
pub mod imagery_clipmap;
pub mod imagery_stream;
pub mod jobs;
pub mod landcover;
pub mod models;
pub mod normal_map;
pub mod normal_pass;
pub mod overlay_pass;
pub mod plan;
pub mod pool_atlas;
pub mod resources;
pub mod sky_pass;
pub mod stats;
pub mod terrain_draws;
pub mod terrain_pass;
pub mod tess_pass;
pub mod tile_instances;
pub mod uniforms;
pub mod upload;
pub mod warm_start;
