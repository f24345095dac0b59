//! The entity pipeline (issue 18): pipeline layout with one push-constant range and the
//! graphics pipeline for instanced models (per-vertex positions and normals, per-instance
//! offset, scale and axes as vertex attributes; dynamic rendering; reversed-Z GREATER depth
//! test against the terrain's depth). Made in [`EntityPipeline::new`], destroyed in reverse by
//! [`EntityPipeline::destroy`].

use ash::vk;

use super::device::Device;
use super::error::{VkError, VkResultExt};
use super::graphics_pipeline::{create_graphics_pipeline, DepthUse, GraphicsPipelineDesc};

const ENTITY_VERT: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/entity.vert.spv"));
const ENTITY_FRAG: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/entity.frag.spv"));

/// Layout of the vertex streams, in bytes (the renderer's `EntityVertex` and
/// `EntityInstance`: four-float columns each).
#[derive(Clone, Copy, Debug)]
pub struct EntityStreams {
    /// Bytes per vertex (binding 0): position vec4, normal vec4.
    pub vertex_stride: u32,
    /// Bytes per instance (binding 1): four vec4.
    pub instance_stride: u32,
    /// Bytes of the push-constant block.
    pub push_bytes: u32,
}

pub struct EntityPipeline {
    pub layout: vk::PipelineLayout,
    pub raw: vk::Pipeline,
}

impl EntityPipeline {
    pub fn new(device: &Device, streams: EntityStreams) -> Result<Self, VkError> {
        let mut this = Self {
            layout: vk::PipelineLayout::null(),
            raw: vk::Pipeline::null(),
        };
        if let Err(e) = this.create(device, streams) {
            this.destroy(device);
            return Err(e);
        }
        Ok(this)
    }

    fn create(&mut self, device: &Device, streams: EntityStreams) -> Result<(), VkError> {
        let ranges = [vk::PushConstantRange {
            stage_flags: vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            offset: 0,
            size: streams.push_bytes,
        }];
        let layout_info = vk::PipelineLayoutCreateInfo::default().push_constant_ranges(&ranges);
        // SAFETY: the device is live; `ranges` outlives the call.
        self.layout = unsafe { device.raw.create_pipeline_layout(&layout_info, None) }
            .call("vkCreatePipelineLayout")?;
        self.raw = create_pipeline(device, self.layout, streams)?;
        Ok(())
    }

    /// Pipeline, then its layout. Idempotent; commands using them must have completed.
    pub fn destroy(&mut self, device: &Device) {
        // No command using them is pending (contract above).
        // SAFETY: each handle is null or was created by `new` on this device, destroyed once.
        unsafe {
            device.raw.destroy_pipeline(self.raw, None);
            device.raw.destroy_pipeline_layout(self.layout, None);
        }
        self.raw = vk::Pipeline::null();
        self.layout = vk::PipelineLayout::null();
    }
}

/// Per-vertex position and normal (binding 0) and per-instance offset, scale and axes (binding
/// 1), four floats each, depth-tested against the terrain's reversed-Z depth.
fn create_pipeline(
    device: &Device,
    layout: vk::PipelineLayout,
    streams: EntityStreams,
) -> Result<vk::Pipeline, VkError> {
    let bindings = [
        vk::VertexInputBindingDescription {
            binding: 0,
            stride: streams.vertex_stride,
            input_rate: vk::VertexInputRate::VERTEX,
        },
        vk::VertexInputBindingDescription {
            binding: 1,
            stride: streams.instance_stride,
            input_rate: vk::VertexInputRate::INSTANCE,
        },
    ];
    let attribute =
        |location: u32, binding: u32, offset: u32| vk::VertexInputAttributeDescription {
            location,
            binding,
            format: vk::Format::R32G32B32A32_SFLOAT,
            offset,
        };
    let attributes = [
        attribute(0, 0, 0),
        attribute(1, 0, 16),
        attribute(2, 1, 0),
        attribute(3, 1, 16),
        attribute(4, 1, 32),
        attribute(5, 1, 48),
    ];
    create_graphics_pipeline(
        device,
        &GraphicsPipelineDesc {
            vert_spv: ENTITY_VERT,
            frag_spv: ENTITY_FRAG,
            layout,
            // Against the terrain's depth: nearer is larger.
            depth: DepthUse::NearestWrites,
            bindings: &bindings,
            attributes: &attributes,
        },
    )
}
