//! The terrain pipeline: descriptor set layout, pipeline layout, graphics pipeline (dynamic
//! rendering, reversed-Z GREATER depth test), the sky pipeline on the same layout
//! (`sky_pipeline.rs`) and the height sampler: one coherent group, made
//! in [`TerrainPipeline::new`] and destroyed in reverse by [`TerrainPipeline::destroy`].

use ash::vk;

use super::device::Device;
use super::error::{VkError, VkResultExt};
use super::graphics_pipeline::{create_graphics_pipeline, DepthUse, GraphicsPipelineDesc};
use super::set_layout::{create_set_and_layout, set_binding};

const TERRAIN_VERT: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/terrain.vert.spv"));
const TERRAIN_FRAG: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/terrain.frag.spv"));

/// Bindings of set 0 (see shaders/terrain.vert).
pub const BINDING_FRAME: u32 = 0;
pub const BINDING_INSTANCES: u32 = 1;
pub const BINDING_CLIPMAP: u32 = 2;
pub const BINDING_POOLS: u32 = 3;
/// The levels' normal maps (shaders/normal_map.glsl), sampled by the fragment shader.
pub const BINDING_NORMAL_MAPS: u32 = 4;
/// Draped imagery (RGBA8 sRGB, mipmapped) and land-cover classes (R8_UINT): shaders/drape.glsl.
pub const BINDING_IMAGERY: u32 = 5;
pub const BINDING_CLASSES: u32 = 6;
/// The streamed imagery windows (RGBA8 sRGB array, a layer per level, toroidal: REPEAT):
/// render/imagery_stream.rs, shaders/drape.glsl.
pub const BINDING_IMAGERY_STREAM: u32 = 7;
/// A projected grid's node polynomials, parallel to the instances (render/gpu.rs
/// `GeoPolynomial`; one zero element on other grids).
pub const BINDING_POLYNOMIALS: u32 = 8;
/// Refined-tile pools bound as an array (r = 1..=POOL_BINDINGS).
pub const POOL_BINDINGS: u32 = aerie_terrain::select::MAX_REFINEMENT;

pub struct TerrainPipeline {
    pub set_layout: vk::DescriptorSetLayout,
    pub layout: vk::PipelineLayout,
    pub raw: vk::Pipeline,
    /// The sky, drawn after the terrain where the depth is still 0.
    pub sky: vk::Pipeline,
    pub height_sampler: vk::Sampler,
    /// Bilinear and repeating, no mips: the normal maps and the streamed imagery windows are
    /// toroidal, so the texture wraps as the level's samples (the window's texels) do.
    pub normal_sampler: vk::Sampler,
}

impl TerrainPipeline {
    pub fn new(device: &Device) -> Result<Self, VkError> {
        let mut this = Self {
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            raw: vk::Pipeline::null(),
            sky: vk::Pipeline::null(),
            height_sampler: vk::Sampler::null(),
            normal_sampler: vk::Sampler::null(),
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

        let normal_info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::REPEAT)
            .address_mode_v(vk::SamplerAddressMode::REPEAT)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(0.0);
        self.normal_sampler =
            // SAFETY: the device is live; the create-info is complete and outlives the call.
            unsafe { device.raw.create_sampler(&normal_info, None) }.call("vkCreateSampler")?;

        let vs_fs = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT;
        use vk::DescriptorType as T;
        use vk::ShaderStageFlags as S;
        let bindings = [
            set_binding(BINDING_FRAME, T::UNIFORM_BUFFER, 1, vs_fs),
            set_binding(BINDING_INSTANCES, T::STORAGE_BUFFER, 1, S::VERTEX),
            set_binding(BINDING_CLIPMAP, T::COMBINED_IMAGE_SAMPLER, 1, S::VERTEX),
            set_binding(
                BINDING_POOLS,
                T::COMBINED_IMAGE_SAMPLER,
                POOL_BINDINGS,
                S::VERTEX,
            ),
            set_binding(
                BINDING_NORMAL_MAPS,
                T::COMBINED_IMAGE_SAMPLER,
                1,
                S::FRAGMENT,
            ),
            set_binding(BINDING_IMAGERY, T::COMBINED_IMAGE_SAMPLER, 1, S::FRAGMENT),
            set_binding(BINDING_CLASSES, T::COMBINED_IMAGE_SAMPLER, 1, S::FRAGMENT),
            set_binding(
                BINDING_IMAGERY_STREAM,
                T::COMBINED_IMAGE_SAMPLER,
                1,
                S::FRAGMENT,
            ),
            set_binding(BINDING_POLYNOMIALS, T::STORAGE_BUFFER, 1, S::VERTEX),
        ];
        (self.set_layout, self.layout) = create_set_and_layout(device, &bindings, None)?;

        self.raw = create_graphics_pipeline(
            device,
            &GraphicsPipelineDesc {
                vert_spv: TERRAIN_VERT,
                frag_spv: TERRAIN_FRAG,
                layout: self.layout,
                // Reversed-Z: nearer is larger.
                depth: DepthUse::NearestWrites,
                // The vertex shader reads the tile instances and heights from storage.
                bindings: &[],
                attributes: &[],
            },
        )?;
        self.sky = super::sky_pipeline::create_sky_pipeline(device, self.layout)?;
        Ok(())
    }

    /// Sky and terrain pipelines, then pipeline layout, set layout and sampler (reverse of
    /// creation).
    /// Idempotent: the handles are nulled, and destroying a null handle does nothing. Commands
    /// using the pipeline must have completed (owners destroy after `Device::wait_idle`).
    pub fn destroy(&mut self, device: &Device) {
        // No command using them is pending (contract above).
        // SAFETY: each handle is null or was created by `new` on this device and is destroyed once (all are nulled below).
        unsafe {
            device.raw.destroy_pipeline(self.sky, None);
            device.raw.destroy_pipeline(self.raw, None);
            device.raw.destroy_pipeline_layout(self.layout, None);
            device
                .raw
                .destroy_descriptor_set_layout(self.set_layout, None);
            device.raw.destroy_sampler(self.height_sampler, None);
            device.raw.destroy_sampler(self.normal_sampler, None);
        }
        *self = Self {
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            raw: vk::Pipeline::null(),
            sky: vk::Pipeline::null(),
            height_sampler: vk::Sampler::null(),
            normal_sampler: vk::Sampler::null(),
        };
    }
}
