//! The terrain pipeline: descriptor set layout, pipeline layout, graphics pipeline (dynamic
//! rendering, reversed-Z GREATER depth test) and the height sampler: one coherent group, made
//! in [`TerrainPipeline::new`] and destroyed in reverse by [`TerrainPipeline::destroy`].

use ash::vk;

use super::conv::{COLOUR_FORMAT, DEPTH_FORMAT};
use super::device::Device;
use super::error::{VkError, VkResultExt};

const TERRAIN_VERT: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/terrain.vert.spv"));
const TERRAIN_FRAG: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/terrain.frag.spv"));

/// Bindings of set 0 (see shaders/terrain.vert).
pub const BINDING_FRAME: u32 = 0;
pub const BINDING_INSTANCES: u32 = 1;
pub const BINDING_CLIPMAP: u32 = 2;
pub const BINDING_POOLS: u32 = 3;
/// Refined-tile pools bound as an array (r = 1..=POOL_BINDINGS).
pub const POOL_BINDINGS: u32 = aerie_terrain::select::MAX_REFINEMENT;

pub struct TerrainPipeline {
    pub set_layout: vk::DescriptorSetLayout,
    pub layout: vk::PipelineLayout,
    pub raw: vk::Pipeline,
    pub height_sampler: vk::Sampler,
}

fn shader_module(device: &Device, spv: &[u8]) -> Result<vk::ShaderModule, VkError> {
    let words = ash::util::read_spv(&mut std::io::Cursor::new(spv))
        .map_err(|e| VkError::Other(format!("embedded SPIR-V is malformed: {e}")))?;
    let info = vk::ShaderModuleCreateInfo::default().code(&words);
    // `read_spv` gave aligned, whole SPIR-V words (it checks the magic number and length), and the
    // shaders were validated by shaderc at build time.
    // SAFETY: the device is live.
    unsafe { device.raw.create_shader_module(&info, None) }.call("vkCreateShaderModule")
}

impl TerrainPipeline {
    pub fn new(device: &Device) -> Result<Self, VkError> {
        let mut this = Self {
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            raw: vk::Pipeline::null(),
            height_sampler: vk::Sampler::null(),
        };
        if let Err(e) = this.create(device) {
            this.destroy(device);
            return Err(e);
        }
        Ok(this)
    }

    fn create(&mut self, device: &Device) -> Result<(), VkError> {
        let sampler_info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::NEAREST)
            .min_filter(vk::Filter::NEAREST)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(0.0);
        self.height_sampler =
            // SAFETY: the device is live; the create-info is complete and outlives the call.
            unsafe { device.raw.create_sampler(&sampler_info, None) }.call("vkCreateSampler")?;

        let vs_fs = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT;
        let bindings = [
            vk::DescriptorSetLayoutBinding::default()
                .binding(BINDING_FRAME)
                .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                .descriptor_count(1)
                .stage_flags(vs_fs),
            vk::DescriptorSetLayoutBinding::default()
                .binding(BINDING_INSTANCES)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .descriptor_count(1)
                .stage_flags(vk::ShaderStageFlags::VERTEX),
            vk::DescriptorSetLayoutBinding::default()
                .binding(BINDING_CLIPMAP)
                .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .descriptor_count(1)
                .stage_flags(vk::ShaderStageFlags::VERTEX),
            vk::DescriptorSetLayoutBinding::default()
                .binding(BINDING_POOLS)
                .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .descriptor_count(POOL_BINDINGS)
                .stage_flags(vk::ShaderStageFlags::VERTEX),
        ];
        let set_info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
        // SAFETY: the device is live; `bindings` outlives the call and has distinct numbers.
        self.set_layout = unsafe { device.raw.create_descriptor_set_layout(&set_info, None) }
            .call("vkCreateDescriptorSetLayout")?;
        let set_layouts = [self.set_layout];
        let layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        // SAFETY: the device is live; the set layout was just created on it.
        self.layout = unsafe { device.raw.create_pipeline_layout(&layout_info, None) }
            .call("vkCreatePipelineLayout")?;

        let vert = shader_module(device, TERRAIN_VERT)?;
        let frag = match shader_module(device, TERRAIN_FRAG) {
            Ok(f) => f,
            Err(e) => {
                // SAFETY: `vert` was just created and no pipeline was made from it.
                unsafe { device.raw.destroy_shader_module(vert, None) };
                return Err(e);
            }
        };
        let result = self.create_pipeline(device, vert, frag);
        // A pipeline does not need its modules after creation, so they are destroyed whether or not
        // it succeeded.
        // SAFETY: both modules are live and ours.
        unsafe {
            device.raw.destroy_shader_module(frag, None);
            device.raw.destroy_shader_module(vert, None);
        }
        self.raw = result?;
        Ok(())
    }

    fn create_pipeline(
        &self,
        device: &Device,
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
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
        let input_assembly = vk::PipelineInputAssemblyStateCreateInfo::default()
            .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default()
            .viewport_count(1)
            .scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::NONE)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(vk::SampleCountFlags::TYPE_1);
        // Reversed-Z: nearer is larger.
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(true)
            .depth_write_enable(true)
            .depth_compare_op(vk::CompareOp::GREATER);
        let blend_attachments = [vk::PipelineColorBlendAttachmentState::default()
            .color_write_mask(vk::ColorComponentFlags::RGBA)];
        let blend =
            vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let colour_formats = [COLOUR_FORMAT];
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(&colour_formats)
            .depth_attachment_format(DEPTH_FORMAT);
        let info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&input_assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(self.layout)
            .push_next(&mut rendering);
        // The modules and the layout were created on it and are live; every state struct, array and
        // the chained rendering info outlive the call, and the dynamic-rendering formats match the
        // offscreen target's attachments.
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

    /// Pipeline, then pipeline layout, set layout and sampler (reverse of creation).
    /// Idempotent: the handles are nulled, and destroying a null handle does nothing. Commands
    /// using the pipeline must have completed (owners destroy after `Device::wait_idle`).
    pub fn destroy(&mut self, device: &Device) {
        // No command using them is pending (contract above).
        // SAFETY: each handle is null or was created by `new` on this device and is destroyed once (all are nulled below).
        unsafe {
            device.raw.destroy_pipeline(self.raw, None);
            device.raw.destroy_pipeline_layout(self.layout, None);
            device
                .raw
                .destroy_descriptor_set_layout(self.set_layout, None);
            device.raw.destroy_sampler(self.height_sampler, None);
        }
        *self = Self {
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            raw: vk::Pipeline::null(),
            height_sampler: vk::Sampler::null(),
        };
    }
}
