//! A compute pipeline: its descriptor set layout (one set), pipeline layout (that set and one
//! push-constant range) and the pipeline, one coherent group made in [`ComputePipeline::new`]
//! and destroyed in reverse by [`ComputePipeline::destroy`].

use ash::vk;

use super::device::Device;
use super::error::VkError;
use super::set_layout::{create_set_and_layout, set_binding};
use super::shader::shader_module;

pub struct ComputePipeline {
    pub set_layout: vk::DescriptorSetLayout,
    pub layout: vk::PipelineLayout,
    pub raw: vk::Pipeline,
}

impl ComputePipeline {
    /// The pipeline of the compute shader `spv` (entry `main`), its set 0 made of `bindings`
    /// (each for the compute stage) and `push_bytes` of push constants.
    pub fn new(
        device: &Device,
        spv: &[u8],
        bindings: &[(u32, vk::DescriptorType)],
        push_bytes: u32,
    ) -> Result<Self, VkError> {
        let mut this = Self {
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            raw: vk::Pipeline::null(),
        };
        if let Err(e) = this.create(device, spv, bindings, push_bytes) {
            this.destroy(device);
            return Err(e);
        }
        Ok(this)
    }

    fn create(
        &mut self,
        device: &Device,
        spv: &[u8],
        bindings: &[(u32, vk::DescriptorType)],
        push_bytes: u32,
    ) -> Result<(), VkError> {
        let stage = vk::ShaderStageFlags::COMPUTE;
        let bindings: Vec<_> = bindings
            .iter()
            .map(|&(binding, ty)| set_binding(binding, ty, 1, stage))
            .collect();
        let push = Some((stage, push_bytes));
        (self.set_layout, self.layout) = create_set_and_layout(device, &bindings, push)?;
        let module = shader_module(device, spv)?;
        let stage_info = vk::PipelineShaderStageCreateInfo::default()
            .stage(stage)
            .module(module)
            .name(c"main");
        let info = [vk::ComputePipelineCreateInfo::default()
            .stage(stage_info)
            .layout(self.layout)];
        // SAFETY: the device, module and layout are live; `info` outlives the call.
        let made = unsafe {
            device
                .raw
                .create_compute_pipelines(vk::PipelineCache::null(), &info, None)
        };
        // The module is needed only while the pipeline is created.
        // SAFETY: no pipeline creation using it is in progress any more (the call returned).
        unsafe { device.raw.destroy_shader_module(module, None) };
        self.raw = made.map_err(|(_, result)| VkError::Call {
            call: "vkCreateComputePipelines",
            result,
        })?[0];
        Ok(())
    }

    /// Pipeline, layout, then set layout. Idempotent; commands using them must have completed.
    pub fn destroy(&mut self, device: &Device) {
        // No command using them is pending (contract above).
        // SAFETY: each handle is null or was created by `new` on this device, destroyed once.
        unsafe {
            device.raw.destroy_pipeline(self.raw, None);
            device.raw.destroy_pipeline_layout(self.layout, None);
            device
                .raw
                .destroy_descriptor_set_layout(self.set_layout, None);
        }
        self.raw = vk::Pipeline::null();
        self.layout = vk::PipelineLayout::null();
        self.set_layout = vk::DescriptorSetLayout::null();
    }
}
