//! aerie: a Vulkan-native, error-bounded terrain renderer for flight simulators.
//!
//! Pure-CPU parts (terrain data, camera math, GPU struct layouts) need no Vulkan device;
//! `vk` is the thin Vulkan plumbing; `render` draws one frame in the order of DESIGN.md's data flow.

pub mod camera;
pub mod channel;
pub mod cli;
pub mod commands;
pub mod flight;
pub mod frame;
pub mod gpu;
pub mod headless;
pub mod host_view;
pub mod image_error;
pub mod output;
pub mod overlay;
pub mod panorama;
pub mod pose_input;
pub mod stats_csv;
pub mod terrain;
pub mod vk;
pub mod window;
