//! The render layer: the renderer's state, the frame plan, uploads, the terrain pass, stats.

pub mod frame;
pub mod gpu;
