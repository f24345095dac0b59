//! The sky: one fullscreen triangle recorded inside the terrain's rendering, after the terrain
//! draw, on the terrain's descriptor set (its uniforms hold the sky's coefficients). The depth
//! test (EQUAL 0, `vk/sky_pipeline.rs`) leaves every terrain pixel alone, so each channel's
//! sky is drawn from that channel's own camera, wherever its terrain ends.

use ash::vk;

use crate::vk::pipeline::TerrainPipeline;
use crate::vk::sky_pipeline::SKY_VERTICES;
use crate::vk::Device;

/// Records the sky draw; `cmd` is inside a rendering of the offscreen target whose viewport
/// and scissor are set, and `set` was written for this frame.
pub fn record_sky(
    d: &Device,
    cmd: vk::CommandBuffer,
    pipeline: &TerrainPipeline,
    set: vk::DescriptorSet,
) {
    // The pipeline and its layout are live, `set` holds this frame's live uniform buffer; the
    // sky pipeline shares the terrain's layout, so the set is bound again only to be explicit
    // when no terrain was drawn.
    // SAFETY: `cmd` is recording inside a rendering with dynamic viewport and scissor set.
    unsafe {
        d.raw
            .cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline.sky);
        d.raw.cmd_bind_descriptor_sets(
            cmd,
            vk::PipelineBindPoint::GRAPHICS,
            pipeline.layout,
            0,
            &[set],
            &[],
        );
        d.raw.cmd_draw(cmd, SKY_VERTICES, 1, 0, 0);
    }
}
