//! The terrain pass: the frame's descriptor set and one multi-draw indirect into the offscreen
//! target (one command per refinement group).

use ash::vk;

use crate::render::drape_textures::DrapeTextures;
use crate::render::gpu::DrawIndexedIndirect;
use crate::render::resources::{FrameBuffers, GpuTerrain};
use crate::render::sky_pass::record_sky;
use crate::render::uniforms::SKY_LINEAR;
use crate::vk::pipeline::{
    TerrainPipeline, BINDING_CLASSES, BINDING_CLIPMAP, BINDING_FRAME, BINDING_IMAGERY,
    BINDING_IMAGERY_STREAM, BINDING_INSTANCES, BINDING_NORMAL_MAPS, BINDING_POLYNOMIALS,
    BINDING_POOLS,
};
use crate::vk::target::{OffscreenTarget, DEPTH_CLEAR};
use crate::vk::Device;

/// Descriptors one frame's set needs (its pool holds [`DESCRIPTOR_SETS`] such sets).
pub fn descriptor_pool_sizes() -> [vk::DescriptorPoolSize; 3] {
    [
        vk::DescriptorPoolSize {
            ty: vk::DescriptorType::UNIFORM_BUFFER,
            descriptor_count: DESCRIPTOR_SETS,
        },
        vk::DescriptorPoolSize {
            ty: vk::DescriptorType::STORAGE_BUFFER,
            // The tiles' instances and polynomials, or the tessellation set's patches, heights
            // and cells.
            descriptor_count: DESCRIPTOR_SETS * 3,
        },
        vk::DescriptorPoolSize {
            ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            // The clipmap, the pools, the normal maps, then the imagery, the classes and the
            // streamed imagery windows.
            descriptor_count: DESCRIPTOR_SETS * (2 + aerie_terrain::select::MAX_REFINEMENT + 3),
        },
    ]
}

/// Sets per frame's descriptor pool: one is used; the rest is headroom.
pub const DESCRIPTOR_SETS: u32 = 4;

/// Points `set` at this frame's buffers and every height texture (sampled with `sampler`).
pub fn write_descriptors(
    d: &Device,
    set: vk::DescriptorSet,
    fb: &FrameBuffers,
    t: &GpuTerrain,
    sampler: vk::Sampler,
    normal_sampler: vk::Sampler,
    drape: &DrapeTextures,
) {
    let uniform_info = [vk::DescriptorBufferInfo {
        buffer: fb.uniforms.raw,
        offset: 0,
        range: vk::WHOLE_SIZE,
    }];
    let instance_info = [vk::DescriptorBufferInfo {
        buffer: fb.instances.raw,
        offset: 0,
        range: vk::WHOLE_SIZE,
    }];
    let polynomial_info = [vk::DescriptorBufferInfo {
        buffer: fb.polynomials.raw,
        offset: 0,
        range: vk::WHOLE_SIZE,
    }];
    let image = |view| vk::DescriptorImageInfo {
        sampler,
        image_view: view,
        image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
    };
    let clipmap_info = [image(t.levels.view)];
    let pool_info: Vec<_> = t.pool_images.iter().map(|p| image(p.view)).collect();
    let normal_info = [vk::DescriptorImageInfo {
        sampler: normal_sampler,
        ..image(t.normals.view)
    }];
    let drape_image = |view, sampler| vk::DescriptorImageInfo {
        sampler,
        image_view: view,
        image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
    };
    let imagery_info = [drape_image(drape.imagery_view(), drape.linear)];
    let classes_info = [drape_image(drape.classes_view(), drape.nearest)];
    let stream_info = [drape_image(drape.stream.view(), normal_sampler)];
    let writes = [
        vk::WriteDescriptorSet::default()
            .dst_set(set)
            .dst_binding(BINDING_FRAME)
            .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
            .buffer_info(&uniform_info),
        vk::WriteDescriptorSet::default()
            .dst_set(set)
            .dst_binding(BINDING_INSTANCES)
            .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
            .buffer_info(&instance_info),
        vk::WriteDescriptorSet::default()
            .dst_set(set)
            .dst_binding(BINDING_POLYNOMIALS)
            .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
            .buffer_info(&polynomial_info),
        vk::WriteDescriptorSet::default()
            .dst_set(set)
            .dst_binding(BINDING_CLIPMAP)
            .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
            .image_info(&clipmap_info),
        vk::WriteDescriptorSet::default()
            .dst_set(set)
            .dst_binding(BINDING_POOLS)
            .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
            .image_info(&pool_info),
        vk::WriteDescriptorSet::default()
            .dst_set(set)
            .dst_binding(BINDING_NORMAL_MAPS)
            .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
            .image_info(&normal_info),
        vk::WriteDescriptorSet::default()
            .dst_set(set)
            .dst_binding(BINDING_IMAGERY)
            .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
            .image_info(&imagery_info),
        vk::WriteDescriptorSet::default()
            .dst_set(set)
            .dst_binding(BINDING_CLASSES)
            .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
            .image_info(&classes_info),
        vk::WriteDescriptorSet::default()
            .dst_set(set)
            .dst_binding(BINDING_IMAGERY_STREAM)
            .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
            .image_info(&stream_info),
    ];
    // `set` comes from this frame's pool, whose previous submission has completed (the frame
    // context); every buffer, view and the sampler written are live; the info arrays outlive
    // the call.
    // SAFETY: no pending command buffer uses `set`, and every handle written is live.
    unsafe { d.raw.update_descriptor_sets(&writes, &[]) };
}

/// The terrain pass: clear, bind, one multi-draw indirect (one command per resolution), then
/// with `sky` the sky where no terrain was drawn (`sky_pass.rs`).
#[allow(clippy::too_many_arguments)]
pub fn record_terrain_pass(
    d: &Device,
    cmd: vk::CommandBuffer,
    target: &OffscreenTarget,
    pipeline: &TerrainPipeline,
    set: vk::DescriptorSet,
    index_buffer: vk::Buffer,
    indirect: vk::Buffer,
    draw_count: u32,
    sky: bool,
    // Draws recorded after the tiles, before the sky (the tessellation baseline's patches).
    extra: &dyn Fn(vk::CommandBuffer),
) {
    let sky_colour = [SKY_LINEAR[0], SKY_LINEAR[1], SKY_LINEAR[2], 1.0];
    target.begin_rendering(d, cmd, Some((sky_colour, DEPTH_CLEAR)));
    // The pipeline, `set` (written for this frame), the index buffer and `indirect`
    // (draw_count commands of the stride given, staged this frame) are live.
    // SAFETY: `cmd` is recording inside the rendering begun on the target.
    unsafe {
        if draw_count > 0 {
            d.raw
                .cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline.raw);
            d.raw.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::GRAPHICS,
                pipeline.layout,
                0,
                &[set],
                &[],
            );
            d.raw
                .cmd_bind_index_buffer(cmd, index_buffer, 0, vk::IndexType::UINT32);
            // One multi-draw indirect for every tile: no per-tile Vulkan calls.
            d.raw.cmd_draw_indexed_indirect(
                cmd,
                indirect,
                0,
                draw_count,
                std::mem::size_of::<DrawIndexedIndirect>() as u32,
            );
        }
    }
    extra(cmd);
    if sky {
        record_sky(d, cmd, pipeline, set);
    }
    target.end_rendering(d, cmd);
}
