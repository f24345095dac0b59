//! `--normals gpu` (`NormalSource::Gpu`): the normal texels of the level strips computed on the
//! GPU from the heights just copied into the level textures, instead of on the CPU and through
//! the staging ring. After a submission's strip copies, one dispatch per [`NormalJob`] (each
//! strip piece with its one-sample border, `normal_map::gpu_normal_jobs`) runs
//! `shaders/normal_map.comp`, which writes packed RG8_SNORM texels into a device-local storage
//! buffer; the buffer is then copied into the normal texture with `vkCmdCopyBufferToImage`,
//! the same copy regions the CPU path's staged texels take.
//!
//! **Why a buffer and a copy, not a storage image.** STORAGE_IMAGE on R8G8_SNORM is optional
//! in Vulkan (it is not in the formats every device must support, and the shader's `rg8_snorm`
//! qualifier needs `shaderStorageImageExtendedFormats`): a buffer written with `packSnorm4x8`
//! and copied works on every device, keeps the texture's usage and layout as they are (sampled,
//! transfer destination) and costs one copy of 2 bytes a texel on the GPU.

use ash::vk;
use gpu_allocator::MemoryLocation;

use aerie_terrain::clipmap::CacheRegion;

use crate::render::gpu::NormalPush;
use crate::render::jobs::ImageUpload;
use crate::render::normal_map::{gpu_normal_jobs, level_spacing, NormalJob, NormalTexel};
use crate::render::upload::record_image_copies;
use crate::vk::access::{image_barrier, memory_barrier, Access};
use crate::vk::compute_pipeline::ComputePipeline;
use crate::vk::conv::map_texel_copy;
use crate::vk::frame_context::{FrameContext, FrameRing};
use crate::vk::{Buffer, Device, VkError};

const NORMAL_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/normal_map.comp.spv"));

/// Bindings of the pass's set (shaders/normal_map.comp).
const BINDING_HEIGHTS: u32 = 0;
const BINDING_TEXELS: u32 = 1;
/// Invocations per work group (the shader's local_size_x); two texels each.
const GROUP_SIZE: u64 = 64;

/// The pipeline and the output buffer of the GPU normal pass.
pub struct NormalPass {
    pipeline: ComputePipeline,
    /// The packed texels of one submission's jobs; replaced by a larger one on demand (the old
    /// one destroyed with the frame that replaced it).
    buffer: Buffer,
    /// Metres between level-0 samples (east, north): the grid's, as the CPU normals use them.
    spacing: [f64; 2],
}

/// One submission's jobs, placed in the output buffer.
pub struct NormalBatch {
    pub jobs: Vec<NormalJob>,
    /// First uint of each job's texels in the buffer.
    offsets: Vec<u32>,
    uints: u64,
}

impl NormalBatch {
    /// The jobs of the level uploads `uploads` (each inside its level's cache region in
    /// `caches`, textures of `side` texels), laid out one after another (4-byte aligned: the
    /// copy's offset must be a multiple of 4 and of the texel's 2 bytes).
    pub fn new(
        uploads: &[ImageUpload],
        caches: &[Option<CacheRegion>],
        side: u32,
    ) -> Result<NormalBatch, VkError> {
        let mut jobs = Vec::new();
        for u in uploads {
            let level = u.step.trailing_zeros();
            let Some(region) = caches.get(level as usize).cloned().flatten() else {
                return Err(VkError::Other(format!(
                    "a level-{level} strip was uploaded before its cache region was placed"
                )));
            };
            let origin = u.origin_sample.map(|o| o >> level);
            jobs.extend(gpu_normal_jobs(level, origin, u.size, region.origin, side));
        }
        let mut offsets = Vec::with_capacity(jobs.len());
        let mut uints = 0u64;
        for j in &jobs {
            offsets.push(u32::try_from(uints).map_err(|_| too_large())?);
            uints += j.texels().div_ceil(2);
        }
        Ok(NormalBatch {
            jobs,
            offsets,
            uints,
        })
    }

    pub fn is_empty(&self) -> bool {
        self.jobs.is_empty()
    }

    /// Bytes of packed texels the batch writes.
    pub fn bytes(&self) -> u64 {
        self.uints * 4
    }

    /// The push constants of job `k`.
    fn push(&self, k: usize, spacing: [f64; 2], side: u32) -> Result<NormalPush, VkError> {
        let j = &self.jobs[k];
        let i32_of = |v: i64| i32::try_from(v).map_err(|_| too_large());
        let pair =
            |v: [i64; 2]| -> Result<[i32; 2], VkError> { Ok([i32_of(v[0])?, i32_of(v[1])?]) };
        Ok(NormalPush {
            origin: pair(j.sample)?,
            size: j.size,
            region_lo: pair(j.region.lo)?,
            region_hi: pair(j.region.hi)?,
            texel_lo: j.region.lo.map(|v| v.rem_euclid(side as i64) as u32),
            spacing: level_spacing(spacing, j.level),
            layer: j.level,
            side,
            offset: self.offsets[k],
            pad: 0,
        })
    }

    /// The copies of every job's texels from the buffer into the normal texture.
    fn copies(&self) -> Vec<vk::BufferImageCopy> {
        (self.jobs.iter().zip(&self.offsets))
            .map(|(j, &offset)| map_texel_copy(offset as u64 * 4, 0, j.level, j.texel, j.size))
            .collect()
    }
}

fn too_large() -> VkError {
    VkError::Other("GPU normal pass: sample coordinates or texel counts beyond 32 bits".into())
}

/// What one recording of the pass reads and writes.
#[derive(Debug, Clone, Copy)]
pub struct NormalTargets {
    /// The level textures (SHADER_READ_ONLY between uploads, read as `upload::SAMPLED`).
    pub levels_view: vk::ImageView,
    pub height_sampler: vk::Sampler,
    /// The normal texture (SHADER_READ_ONLY between uploads).
    pub normals: vk::Image,
    /// Texels per level-texture side.
    pub side: u32,
}

impl NormalPass {
    pub fn new(device: &Device, spacing: [f64; 2]) -> Result<Self, VkError> {
        let bindings = [
            (BINDING_HEIGHTS, vk::DescriptorType::COMBINED_IMAGE_SAMPLER),
            (BINDING_TEXELS, vk::DescriptorType::STORAGE_BUFFER),
        ];
        let push = std::mem::size_of::<NormalPush>() as u32;
        let mut pipeline = ComputePipeline::new(device, NORMAL_COMP, &bindings, push)?;
        let buffer = match Self::output(device, 1 << 16) {
            Ok(b) => b,
            Err(e) => {
                pipeline.destroy(device);
                return Err(e);
            }
        };
        Ok(NormalPass {
            pipeline,
            buffer,
            spacing,
        })
    }

    fn output(device: &Device, bytes: u64) -> Result<Buffer, VkError> {
        Buffer::new(
            device,
            "GPU normal texels",
            bytes,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
        )
    }

    /// Records `batch` into `frame`'s command buffer `cmd`, after the strips' heights were copied
    /// into the level textures (their barrier made them visible to the compute stage): the
    /// dispatches, then the copy into the normal texture, left SHADER_READ_ONLY. Grows the
    /// output buffer first when the batch needs more.
    pub fn record(
        &mut self,
        d: &Device,
        frame: &mut FrameContext,
        cmd: vk::CommandBuffer,
        targets: &NormalTargets,
        batch: &NormalBatch,
    ) -> Result<(), VkError> {
        if batch.is_empty() {
            return Ok(());
        }
        if batch.bytes() > self.buffer.size {
            let grown = Self::output(d, batch.bytes().next_power_of_two())?;
            frame.defer_destroy(std::mem::replace(&mut self.buffer, grown));
        }
        let set = frame.allocate_set(d, self.pipeline.set_layout)?;
        self.write_set(d, set, targets);
        // The previous submission's copy out of the buffer is done before it is written again.
        memory_barrier(
            d,
            cmd,
            &[Access::TransferRead],
            &[Access::ComputeShaderWriteStorageBuffer],
        );
        let bind = vk::PipelineBindPoint::COMPUTE;
        // The pipeline and its layout are live (owned by `self`) and `set` was written above
        // with live views and buffers.
        // SAFETY: `cmd` is recording on `d`.
        unsafe {
            d.raw.cmd_bind_pipeline(cmd, bind, self.pipeline.raw);
            d.raw
                .cmd_bind_descriptor_sets(cmd, bind, self.pipeline.layout, 0, &[set], &[]);
        }
        for (k, job) in batch.jobs.iter().enumerate() {
            let push = batch.push(k, self.spacing, targets.side)?;
            let groups = job.texels().div_ceil(2).div_ceil(GROUP_SIZE);
            let groups = u32::try_from(groups).map_err(|_| too_large())?;
            // The push range is the layout's (the struct's size, compute stage); every
            // invocation writes inside the job's uints, which the buffer holds (grown above).
            // SAFETY: `cmd` is recording with the pipeline and set bound.
            unsafe {
                d.raw.cmd_push_constants(
                    cmd,
                    self.pipeline.layout,
                    vk::ShaderStageFlags::COMPUTE,
                    0,
                    bytemuck::bytes_of(&push),
                );
                d.raw.cmd_dispatch(cmd, groups, 1, 1);
            }
        }
        memory_barrier(
            d,
            cmd,
            &[Access::ComputeShaderWriteStorageBuffer],
            &[Access::TransferRead],
        );
        record_image_copies(d, cmd, self.buffer.raw, targets.normals, &batch.copies());
        Ok(())
    }

    fn write_set(&self, d: &Device, set: vk::DescriptorSet, targets: &NormalTargets) {
        let image = [vk::DescriptorImageInfo {
            sampler: targets.height_sampler,
            image_view: targets.levels_view,
            image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
        }];
        let buffer = [vk::DescriptorBufferInfo {
            buffer: self.buffer.raw,
            offset: 0,
            range: vk::WHOLE_SIZE,
        }];
        let writes = [
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(BINDING_HEIGHTS)
                .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .image_info(&image),
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(BINDING_TEXELS)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&buffer),
        ];
        // `set` was just allocated from this frame's pool and no command using it was recorded
        // yet; the view, sampler and buffer are live.
        // SAFETY: the device is live and `writes` (with its infos) outlives the call.
        unsafe { d.raw.update_descriptor_sets(&writes, &[]) };
    }

    /// Call after the device is idle.
    pub fn destroy(&mut self, device: &Device) {
        self.buffer.destroy(device);
        self.pipeline.destroy(device);
    }
}

/// Layer `level` of the normal texture `normals` (side² texels, row-major, texel = sample mod
/// side), read back in one submission waited for.
pub fn read_normal_texels(
    d: &Device,
    ring: &mut FrameRing,
    normals: &crate::vk::image::Image2d,
    level: u32,
) -> Result<Vec<NormalTexel>, VkError> {
    let side = normals.desc.width;
    let readers = &crate::render::upload::SAMPLED;
    let bytes = read_texture_layer(d, ring, normals.raw, level, side, 2, readers)?;
    Ok(bytes
        .chunks_exact(2)
        .map(|c| [c[0] as i8, c[1] as i8])
        .collect())
}

/// Reads back layer `layer` of a `side`² texture of `texel_bytes` bytes a texel that rests in
/// SHADER_READ_ONLY (read by `readers`), in one submission waited for: the normal texture or
/// the level textures, for the tests that check the GPU pass against its CPU twin.
pub fn read_texture_layer(
    d: &Device,
    ring: &mut FrameRing,
    image: vk::Image,
    layer: u32,
    side: u32,
    texel_bytes: u64,
    readers: &[Access],
) -> Result<Vec<u8>, VkError> {
    let bytes = side as u64 * side as u64 * texel_bytes;
    let usage = vk::BufferUsageFlags::TRANSFER_DST;
    let mut out = Buffer::new(
        d,
        "texture read-back",
        bytes,
        usage,
        MemoryLocation::GpuToCpu,
    )?;
    let result = (|| {
        let mut frame = ring.begin_frame(d)?;
        let cmd = frame.begin_recording(d)?;
        let colour = vk::ImageAspectFlags::COLOR;
        image_barrier(
            d,
            cmd,
            image,
            colour,
            readers,
            &[Access::TransferRead],
            false,
        );
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: colour,
                mip_level: 0,
                base_array_layer: layer,
                layer_count: 1,
            })
            .image_extent(vk::Extent3D {
                width: side,
                height: side,
                depth: 1,
            });
        // `image` is in TRANSFER_SRC_OPTIMAL (the barrier above), `layer` is one of its layers
        // (the caller's), and `out` holds side² texels.
        // SAFETY: `cmd` is recording on `d`; both objects are live.
        unsafe {
            d.raw.cmd_copy_image_to_buffer(
                cmd,
                image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                out.raw,
                &[region],
            )
        };
        image_barrier(
            d,
            cmd,
            image,
            colour,
            &[Access::TransferRead],
            readers,
            false,
        );
        memory_barrier(d, cmd, &[Access::TransferWrite], &[Access::HostRead]);
        let submitted = frame.submit(d)?;
        ring.wait(d, submitted)?;
        out.mapped()
            .map(|m| m[..bytes as usize].to_vec())
            .ok_or_else(|| VkError::Other("read-back buffer is not mapped".into()))
    })();
    out.destroy(d);
    result
}
