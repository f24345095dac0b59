//! The one graphics-pipeline recipe every pass shares (terrain, sky, entities): a vertex and a
//! fragment shader from embedded SPIR-V, triangle lists, two-sided fill, one sample, dynamic
//! viewport and scissor, dynamic rendering into the offscreen target's colour and depth formats.
//! What differs between passes is named here: how the pass uses the reversed-Z depth, and its
//! vertex streams.

use ash::vk;

use super::conv::{COLOUR_FORMAT, DEPTH_FORMAT};
use super::device::Device;
use super::error::VkError;
use super::shader::shader_module;

/// How a pass uses the reversed-Z depth buffer (cleared to 0 = infinitely far).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DepthUse {
    /// Drawn where nearer than what is there (GREATER), writing its depth: terrain, entities.
    NearestWrites,
    /// Drawn only where the depth is still the clear value (EQUAL 0), not writing: the sky.
    WhereNothingDrawn,
}

/// The depth state of `depth` (pure).
pub fn map_depth_use(depth: DepthUse) -> vk::PipelineDepthStencilStateCreateInfo<'static> {
    let (write, op) = match depth {
        DepthUse::NearestWrites => (true, vk::CompareOp::GREATER),
        DepthUse::WhereNothingDrawn => (false, vk::CompareOp::EQUAL),
    };
    vk::PipelineDepthStencilStateCreateInfo::default()
        .depth_test_enable(true)
        .depth_write_enable(write)
        .depth_compare_op(op)
}

/// What one pass's pipeline is made of.
pub struct GraphicsPipelineDesc<'a> {
    pub vert_spv: &'a [u8],
    pub frag_spv: &'a [u8],
    /// Live, created on the same device.
    pub layout: vk::PipelineLayout,
    pub depth: DepthUse,
    /// Vertex streams (none: the vertex shader reads storage buffers or generates vertices).
    pub bindings: &'a [vk::VertexInputBindingDescription],
    pub attributes: &'a [vk::VertexInputAttributeDescription],
}

/// Creates the pipeline `desc` describes; its shader modules are destroyed before returning,
/// whether or not the pipeline was made.
pub fn create_graphics_pipeline(
    device: &Device,
    desc: &GraphicsPipelineDesc,
) -> Result<vk::Pipeline, VkError> {
    let vert = shader_module(device, desc.vert_spv)?;
    let frag = match shader_module(device, desc.frag_spv) {
        Ok(f) => f,
        Err(e) => {
            // SAFETY: `vert` was just created and no pipeline was made from it.
            unsafe { device.raw.destroy_shader_module(vert, None) };
            return Err(e);
        }
    };
    let result = create(device, desc, vert, frag);
    // A pipeline does not need its modules after creation.
    // SAFETY: both modules are live and ours, and no creation is using them any more.
    unsafe {
        device.raw.destroy_shader_module(frag, None);
        device.raw.destroy_shader_module(vert, None);
    }
    result
}

fn create(
    device: &Device,
    desc: &GraphicsPipelineDesc,
    vert: vk::ShaderModule,
    frag: vk::ShaderModule,
) -> Result<vk::Pipeline, VkError> {
    let stages = [
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::VERTEX)
            .module(vert)
            .name(c"main"),
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::FRAGMENT)
            .module(frag)
            .name(c"main"),
    ];
    let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
        .vertex_binding_descriptions(desc.bindings)
        .vertex_attribute_descriptions(desc.attributes);
    let shape = Primitives::Triangles;
    create_with_stages(
        device,
        desc.layout,
        desc.depth,
        &stages,
        &vertex_input,
        shape,
    )
}

/// What the input assembler hands the first stage.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Primitives {
    Triangles,
    /// Patches of this many control points, for tessellation stages.
    Patches(u32),
}

/// The recipe's fixed states (two-sided fill, one sample, dynamic viewport and scissor,
/// rendering into the offscreen target's formats) around the caller's `stages` and vertex
/// input: what every pipeline of the renderer is made with, the tessellated one included.
pub fn create_with_stages(
    device: &Device,
    layout: vk::PipelineLayout,
    depth: DepthUse,
    stages: &[vk::PipelineShaderStageCreateInfo],
    vertex_input: &vk::PipelineVertexInputStateCreateInfo,
    primitives: Primitives,
) -> Result<vk::Pipeline, VkError> {
    let (topology, control_points) = match primitives {
        Primitives::Triangles => (vk::PrimitiveTopology::TRIANGLE_LIST, 0),
        Primitives::Patches(n) => (vk::PrimitiveTopology::PATCH_LIST, n),
    };
    let input_assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(topology);
    let tessellation =
        vk::PipelineTessellationStateCreateInfo::default().patch_control_points(control_points);
    let viewport = vk::PipelineViewportStateCreateInfo::default()
        .viewport_count(1)
        .scissor_count(1);
    // Two-sided: terrain seen from below its skirts, glTF models open or wound either way.
    let raster = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(vk::CullModeFlags::NONE)
        .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
        .line_width(1.0);
    let multisample = vk::PipelineMultisampleStateCreateInfo::default()
        .rasterization_samples(vk::SampleCountFlags::TYPE_1);
    let depth = map_depth_use(depth);
    let blend_attachments = [vk::PipelineColorBlendAttachmentState::default()
        .color_write_mask(vk::ColorComponentFlags::RGBA)];
    let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
    let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
    let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
    let colour_formats = [COLOUR_FORMAT];
    let mut rendering = vk::PipelineRenderingCreateInfo::default()
        .color_attachment_formats(&colour_formats)
        .depth_attachment_format(DEPTH_FORMAT);
    let mut info = vk::GraphicsPipelineCreateInfo::default()
        .stages(stages)
        .vertex_input_state(vertex_input)
        .input_assembly_state(&input_assembly)
        .viewport_state(&viewport)
        .rasterization_state(&raster)
        .multisample_state(&multisample)
        .depth_stencil_state(&depth)
        .color_blend_state(&blend)
        .dynamic_state(&dynamic)
        .layout(layout)
        .push_next(&mut rendering);
    if control_points > 0 {
        info = info.tessellation_state(&tessellation);
    }
    // The modules and the layout are live on this device; every state struct, array and the
    // chained rendering info outlive the call; the formats match the offscreen target's; a
    // tessellated pipeline's device has tessellationShader enabled (its caller checks).
    // SAFETY: the device is live.
    unsafe {
        device
            .raw
            .create_graphics_pipelines(vk::PipelineCache::null(), &[info], None)
    }
    .map(|p| p[0])
    .map_err(|(_, result)| VkError::Call {
        call: "vkCreateGraphicsPipelines",
        result,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_uses_map_to_reversed_z_states() {
        let near = map_depth_use(DepthUse::NearestWrites);
        assert_eq!(
            (near.depth_write_enable, near.depth_compare_op),
            (vk::TRUE, vk::CompareOp::GREATER)
        );
        let sky = map_depth_use(DepthUse::WhereNothingDrawn);
        assert_eq!(
            (sky.depth_write_enable, sky.depth_compare_op),
            (vk::FALSE, vk::CompareOp::EQUAL)
        );
        assert_eq!(sky.depth_test_enable, vk::TRUE);
    }
}
