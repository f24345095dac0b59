//! The sky's graphics pipeline: a fullscreen triangle at depth 0 drawn after the terrain with
//! an EQUAL depth test and no depth writes (reversed-Z clears to 0, so it fills exactly the
//! pixels no terrain covered). It shares the terrain's pipeline layout (set 0, binding 0: the
//! frame's uniforms); [`super::pipeline::TerrainPipeline`] owns and destroys it.

use ash::vk;

use super::device::Device;
use super::error::VkError;
use super::graphics_pipeline::{create_graphics_pipeline, DepthUse, GraphicsPipelineDesc};

const SKY_VERT: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/sky.vert.spv"));
const SKY_FRAG: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/sky.frag.spv"));

/// Vertices of the fullscreen triangle (generated in `shaders/sky.vert`).
pub const SKY_VERTICES: u32 = 3;

/// Creates the sky pipeline on `layout` (the terrain's, live).
pub fn create_sky_pipeline(
    device: &Device,
    layout: vk::PipelineLayout,
) -> Result<vk::Pipeline, VkError> {
    create_graphics_pipeline(
        device,
        &GraphicsPipelineDesc {
            vert_spv: SKY_VERT,
            frag_spv: SKY_FRAG,
            layout,
            // Only where the depth is still the clear value 0 (reversed-Z: infinitely far).
            depth: DepthUse::WhereNothingDrawn,
            // The fullscreen triangle is generated in the vertex shader.
            bindings: &[],
            attributes: &[],
        },
    )
}
