//! One descriptor set's layout and the pipeline layout over it (with at most one push-constant
//! range): what each of the renderer's pipelines owns beside the pipeline itself.

use ash::vk;

use super::device::Device;
use super::error::{VkError, VkResultExt};

/// Binding `binding` of `count` descriptors of type `ty`, seen by `stages`.
pub fn set_binding(
    binding: u32,
    ty: vk::DescriptorType,
    count: u32,
    stages: vk::ShaderStageFlags,
) -> vk::DescriptorSetLayoutBinding<'static> {
    vk::DescriptorSetLayoutBinding::default()
        .binding(binding)
        .descriptor_type(ty)
        .descriptor_count(count)
        .stage_flags(stages)
}

/// Creates the set layout of `bindings` (distinct numbers) and a pipeline layout of that one
/// set and `push` (stages, bytes from offset 0). On failure nothing is left created.
pub fn create_set_and_layout(
    device: &Device,
    bindings: &[vk::DescriptorSetLayoutBinding],
    push: Option<(vk::ShaderStageFlags, u32)>,
) -> Result<(vk::DescriptorSetLayout, vk::PipelineLayout), VkError> {
    let set_info = vk::DescriptorSetLayoutCreateInfo::default().bindings(bindings);
    // SAFETY: the device is live; `set_info` and `bindings` outlive the call.
    let set_layout = unsafe { device.raw.create_descriptor_set_layout(&set_info, None) }
        .call("vkCreateDescriptorSetLayout")?;
    let ranges: Vec<vk::PushConstantRange> = push
        .map(|(stage_flags, size)| vk::PushConstantRange {
            stage_flags,
            offset: 0,
            size,
        })
        .into_iter()
        .collect();
    let set_layouts = [set_layout];
    let layout_info = vk::PipelineLayoutCreateInfo::default()
        .set_layouts(&set_layouts)
        .push_constant_ranges(&ranges);
    // SAFETY: the device and the set layout are live; the arrays outlive the call.
    match unsafe { device.raw.create_pipeline_layout(&layout_info, None) } {
        Ok(layout) => Ok((set_layout, layout)),
        Err(result) => {
            // SAFETY: `set_layout` was just created and nothing uses it.
            unsafe { device.raw.destroy_descriptor_set_layout(set_layout, None) };
            Err(VkError::Call {
                call: "vkCreatePipelineLayout",
                result,
            })
        }
    }
}
