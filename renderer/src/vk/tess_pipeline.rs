//! The tessellation baseline's pipeline (document 001): vertex, tessellation control and
//! evaluation, and the terrain's own fragment shader; patch lists of three control points; its
//! own set layout (frame uniforms, patch records, level-0 heights). The states other than the
//! stages and the topology are those of `graphics_pipeline.rs` (two-sided fill, reversed-Z
//! GREATER with writes, dynamic viewport and scissor, dynamic rendering into the offscreen
//! target's formats). Made in [`TessPipeline::new`], destroyed in reverse by
//! [`TessPipeline::destroy`].

use ash::vk;

use super::device::Device;
use super::error::VkError;
use super::graphics_pipeline::{create_with_stages, DepthUse, Primitives};
use super::pipeline::{
    BINDING_CLASSES, BINDING_IMAGERY, BINDING_IMAGERY_STREAM, BINDING_NORMAL_MAPS,
};
use super::set_layout::{create_set_and_layout, set_binding};
use super::shader::shader_module;

const TESS_VERT: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/terrain_tess.vert.spv"));
const TESS_TESC: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/terrain_tess.tesc.spv"));
const TESS_TESE: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/terrain_tess.tese.spv"));
const TERRAIN_FRAG: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/terrain.frag.spv"));

/// Bindings of the tessellation set (see shaders/terrain_tess.tese).
pub const TESS_BINDING_FRAME: u32 = 0;
pub const TESS_BINDING_PATCHES: u32 = 1;
pub const TESS_BINDING_HEIGHTS: u32 = 2;
/// The drawn cells' frames on the ellipsoid (`GeoFields`, one zeroed record when flat).
pub const TESS_BINDING_CELLS: u32 = 3;

pub struct TessPipeline {
    pub set_layout: vk::DescriptorSetLayout,
    pub layout: vk::PipelineLayout,
    pub raw: vk::Pipeline,
}

impl TessPipeline {
    /// Fails with a named reason on a device without `tessellationShader`.
    pub fn new(device: &Device) -> Result<Self, VkError> {
        if !device.tessellation {
            return Err(VkError::Other(format!(
                "--lod tess: {} does not offer tessellationShader",
                device.name
            )));
        }
        let mut this = Self {
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            raw: vk::Pipeline::null(),
        };
        if let Err(e) = this.create(device) {
            this.destroy(device);
            return Err(e);
        }
        Ok(this)
    }

    fn create(&mut self, device: &Device) -> Result<(), VkError> {
        use vk::ShaderStageFlags as S;
        let binding = |b: u32, ty: vk::DescriptorType, stages: S| set_binding(b, ty, 1, stages);
        let bindings = [
            binding(
                TESS_BINDING_FRAME,
                vk::DescriptorType::UNIFORM_BUFFER,
                S::TESSELLATION_EVALUATION | S::FRAGMENT,
            ),
            binding(
                TESS_BINDING_PATCHES,
                vk::DescriptorType::STORAGE_BUFFER,
                S::VERTEX | S::TESSELLATION_CONTROL | S::TESSELLATION_EVALUATION,
            ),
            binding(
                TESS_BINDING_HEIGHTS,
                vk::DescriptorType::STORAGE_BUFFER,
                S::TESSELLATION_EVALUATION,
            ),
            binding(
                TESS_BINDING_CELLS,
                vk::DescriptorType::STORAGE_BUFFER,
                S::TESSELLATION_EVALUATION,
            ),
            // terrain.frag's textures, at the terrain set's numbers.
            binding(
                BINDING_NORMAL_MAPS,
                vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                S::FRAGMENT,
            ),
            binding(
                BINDING_IMAGERY,
                vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                S::FRAGMENT,
            ),
            binding(
                BINDING_CLASSES,
                vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                S::FRAGMENT,
            ),
            binding(
                BINDING_IMAGERY_STREAM,
                vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                S::FRAGMENT,
            ),
        ];
        (self.set_layout, self.layout) = create_set_and_layout(device, &bindings, None)?;
        let mut modules = Vec::new();
        let made = [TESS_VERT, TESS_TESC, TESS_TESE, TERRAIN_FRAG]
            .iter()
            .try_for_each(|spv| {
                modules.push(shader_module(device, spv)?);
                Ok::<(), VkError>(())
            });
        let result = made.and_then(|()| create(device, self.layout, &modules));
        // A pipeline does not need its modules after creation.
        for m in modules {
            // SAFETY: each module is live and ours, and no creation is using it any more.
            unsafe { device.raw.destroy_shader_module(m, None) };
        }
        self.raw = result?;
        Ok(())
    }

    /// Pipeline, pipeline layout, set layout (reverse of creation). Idempotent; commands using
    /// them must have completed.
    pub fn destroy(&mut self, device: &Device) {
        // Each handle is null or was created by `new` on this device and is destroyed once (all
        // are nulled below); no command using them is pending (the contract above).
        // SAFETY: live-or-null handles of this device, destroyed once, unused by the GPU.
        unsafe {
            device.raw.destroy_pipeline(self.raw, None);
            device.raw.destroy_pipeline_layout(self.layout, None);
            device
                .raw
                .destroy_descriptor_set_layout(self.set_layout, None);
        }
        *self = Self {
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            raw: vk::Pipeline::null(),
        };
    }
}

fn create(
    device: &Device,
    layout: vk::PipelineLayout,
    modules: &[vk::ShaderModule],
) -> Result<vk::Pipeline, VkError> {
    let stage = |s: vk::ShaderStageFlags, m: vk::ShaderModule| {
        vk::PipelineShaderStageCreateInfo::default()
            .stage(s)
            .module(m)
            .name(c"main")
    };
    let stages = [
        stage(vk::ShaderStageFlags::VERTEX, modules[0]),
        stage(vk::ShaderStageFlags::TESSELLATION_CONTROL, modules[1]),
        stage(vk::ShaderStageFlags::TESSELLATION_EVALUATION, modules[2]),
        stage(vk::ShaderStageFlags::FRAGMENT, modules[3]),
    ];
    let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
    // Triangles of three control points; `new` checked tessellationShader.
    let patches = Primitives::Patches(3);
    create_with_stages(
        device,
        layout,
        DepthUse::NearestWrites,
        &stages,
        &vertex_input,
        patches,
    )
}
