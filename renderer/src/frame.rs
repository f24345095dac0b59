//! The renderer and its frame, in the order of DESIGN.md's data flow:
//! camera → tile selection → uploads through the staging ring → record (one multi-draw
//! indirect) → submit → read back.

use std::sync::Arc;
use std::time::Instant;

use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::camera::Camera;
use crate::gpu::{DrawIndexedIndirect, FrameUniforms, TileInstance};
use crate::terrain::mesh::tile_indices;
use crate::terrain::tiles::{select_full_resolution, SelectionStats, TileGrid};
use crate::terrain::Heightfield;
use crate::vk::descriptors::FrameDescriptorPools;
use crate::vk::frame_context::FrameContexts;
use crate::vk::image::{transition, Image2d, ImageDesc};
use crate::vk::pipeline::{TerrainPipeline, BINDING_FRAME, BINDING_HEIGHTS, BINDING_INSTANCES};
use crate::vk::staging::StagingRing;
use crate::vk::target::{OffscreenTarget, DEPTH_CLEAR};
use crate::vk::timestamps::{GpuTimer, Pass};
use crate::vk::{
    Buffer, Device, DeviceDesc, Instance, ValidationCounters, VkError, VkResultExt,
    FRAMES_IN_FLIGHT,
};

/// Vertices per tile side (m = 2^j + 1). DESIGN.md default.
pub const DEFAULT_TILE_SIZE: u32 = 17;

#[derive(Debug, Clone)]
pub struct RendererDesc {
    pub validation: bool,
    pub device: DeviceDesc,
    pub width: u32,
    pub height: u32,
    /// Hard upload budget per frame (bytes), the size of one staging-ring region.
    pub staging_budget: u64,
    pub tile_size: u32,
}

impl Default for RendererDesc {
    fn default() -> Self {
        Self {
            validation: cfg!(debug_assertions),
            device: DeviceDesc::default(),
            width: 1920,
            height: 1080,
            staging_budget: 8 << 20,
            tile_size: DEFAULT_TILE_SIZE,
        }
    }
}

/// What one frame did (DESIGN.md "Every stage reports what it did").
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct FrameStats {
    pub frame: u64,
    pub tiles_considered: u32,
    pub tiles_culled: u32,
    pub tiles_drawn: u32,
    pub triangles: u64,
    pub draw_calls: u32,
    pub bytes_uploaded: u64,
    pub cpu_select_us: f64,
    pub cpu_record_us: f64,
    pub gpu_upload_ms: f64,
    pub gpu_terrain_ms: f64,
}

/// What loading a heightfield onto the GPU did.
#[derive(Debug, Clone, Copy, Default)]
pub struct UploadStats {
    pub bytes: u64,
    /// Submissions the upload was split into (by the per-frame staging budget).
    pub submissions: u32,
}

/// Per-frame-in-flight device buffers, filled from the staging ring each frame.
struct FrameBuffers {
    uniforms: Buffer,
    instances: Buffer,
    indirect: Buffer,
}

impl FrameBuffers {
    fn destroy(&mut self, device: &Device) {
        self.indirect.destroy(device);
        self.instances.destroy(device);
        self.uniforms.destroy(device);
    }
}

/// The terrain on the GPU: the height texture and the tile grid over it.
struct GpuTerrain {
    heights: Image2d,
    grid: TileGrid,
    frame_buffers: Vec<FrameBuffers>,
}

/// Owns every Vulkan object. Fields are destroyed explicitly in reverse creation order by
/// [`TerrainRenderer::destroy`] (also called from `Drop`).
pub struct TerrainRenderer {
    instance: Instance,
    device: Device,
    frames: FrameContexts,
    staging: StagingRing,
    descriptors: FrameDescriptorPools,
    timer: GpuTimer,
    pipeline: TerrainPipeline,
    target: OffscreenTarget,
    tile_index_buffer: Buffer,
    terrain: Option<GpuTerrain>,
    /// Which frame contexts wrote timestamps not read yet.
    timed: [bool; FRAMES_IN_FLIGHT],
    frame_counter: u64,
    tile_size: u32,
    instances_scratch: Vec<TileInstance>,
    destroyed: bool,
}

/// Runs `$body`; on error destroys what was created so far (listed) and returns the error.
macro_rules! or_unwind {
    ($body:expr, $device:expr, [$($created:expr),*]) => {
        match $body {
            Ok(v) => v,
            Err(e) => {
                $( $created.destroy($device); )*
                return Err(e);
            }
        }
    };
}

impl TerrainRenderer {
    pub fn new(desc: &RendererDesc) -> Result<Self, VkError> {
        if !(2..=256).contains(&desc.tile_size) || !(desc.tile_size - 1).is_power_of_two() {
            return Err(VkError::Other(format!(
                "tile size {} must be 2^j + 1 in 3..=257",
                desc.tile_size
            )));
        }
        let mut instance = Instance::new(desc.validation)?;
        let mut device = match Device::new(&instance, &desc.device) {
            Ok(d) => d,
            Err(e) => {
                instance.destroy();
                return Err(e);
            }
        };
        let parts = Self::create_parts(&device, desc);
        let (frames, staging, descriptors, timer, pipeline, target, tile_index_buffer) = match parts
        {
            Ok(p) => p,
            Err(e) => {
                device.destroy();
                instance.destroy();
                return Err(e);
            }
        };
        let mut this = Self {
            instance,
            device,
            frames,
            staging,
            descriptors,
            timer,
            pipeline,
            target,
            tile_index_buffer,
            terrain: None,
            timed: [false; FRAMES_IN_FLIGHT],
            frame_counter: 0,
            tile_size: desc.tile_size,
            instances_scratch: Vec::new(),
            destroyed: false,
        };
        // The shared tile index buffer is the first upload through the ring.
        let indices = tile_indices(desc.tile_size);
        if let Err(e) = this.upload_buffer(&indices, this.tile_index_buffer.raw) {
            this.destroy();
            return Err(e);
        }
        Ok(this)
    }

    #[allow(clippy::type_complexity)]
    fn create_parts(
        d: &Device,
        desc: &RendererDesc,
    ) -> Result<
        (
            FrameContexts,
            StagingRing,
            FrameDescriptorPools,
            GpuTimer,
            TerrainPipeline,
            OffscreenTarget,
            Buffer,
        ),
        VkError,
    > {
        let sizes = [
            vk::DescriptorPoolSize {
                ty: vk::DescriptorType::UNIFORM_BUFFER,
                descriptor_count: 4,
            },
            vk::DescriptorPoolSize {
                ty: vk::DescriptorType::STORAGE_BUFFER,
                descriptor_count: 4,
            },
            vk::DescriptorPoolSize {
                ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                descriptor_count: 4,
            },
        ];
        let mut frames = FrameContexts::new(d)?;
        let mut staging = or_unwind!(StagingRing::new(d, desc.staging_budget), d, [frames]);
        let mut descriptors = or_unwind!(
            FrameDescriptorPools::new(d, 4, &sizes),
            d,
            [staging, frames]
        );
        let mut timer = or_unwind!(GpuTimer::new(d), d, [descriptors, staging, frames]);
        let mut pipeline = or_unwind!(
            TerrainPipeline::new(d),
            d,
            [timer, descriptors, staging, frames]
        );
        let mut target = or_unwind!(
            OffscreenTarget::new(d, desc.width, desc.height),
            d,
            [pipeline, timer, descriptors, staging, frames]
        );
        let m = desc.tile_size as u64;
        let index_bytes = (m - 1) * (m - 1) * 6 * 2;
        let tile_index_buffer = or_unwind!(
            Buffer::new(
                d,
                "tile indices",
                index_bytes,
                vk::BufferUsageFlags::INDEX_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuOnly,
            ),
            d,
            [target, pipeline, timer, descriptors, staging, frames]
        );
        Ok((
            frames,
            staging,
            descriptors,
            timer,
            pipeline,
            target,
            tile_index_buffer,
        ))
    }

    pub fn device_name(&self) -> &str {
        &self.device.name
    }

    pub fn validation_counters(&self) -> Arc<ValidationCounters> {
        self.instance.counters()
    }

    pub fn size(&self) -> (u32, u32) {
        (self.target.width, self.target.height)
    }

    /// Starts the next frame context: waits for its fence, collects its timestamps, opens its
    /// staging region and resets its descriptor pool. Returns (index, GPU ms of its last use).
    fn begin_context(&mut self) -> Result<(usize, Option<[f64; 2]>), VkError> {
        let i = self.frames.wait_next(&self.device)?;
        let gpu = if self.timed[i] {
            self.timed[i] = false;
            Some(self.timer.read_ms(&self.device, i)?)
        } else {
            None
        };
        self.staging
            .begin_frame(&self.device, i, self.frames.frames[i].fence)?;
        self.descriptors.reset(&self.device, i)?;
        Ok((i, gpu))
    }

    /// A one-off upload of a small buffer through the ring, in its own submission.
    fn upload_buffer<T: bytemuck::Pod>(
        &mut self,
        data: &[T],
        dst: vk::Buffer,
    ) -> Result<(), VkError> {
        let (i, _) = self.begin_context()?;
        let offset = self.staging.push(data, 4)?;
        let cmd = self.frames.begin_recording(&self.device, i)?;
        let region = vk::BufferCopy {
            src_offset: offset,
            dst_offset: 0,
            size: std::mem::size_of_val(data) as u64,
        };
        unsafe {
            self.device
                .raw
                .cmd_copy_buffer(cmd, self.staging.raw(), dst, &[region]);
            let barrier = vk::MemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                .dst_access_mask(vk::AccessFlags::INDEX_READ | vk::AccessFlags::SHADER_READ);
            self.device.raw.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::VERTEX_INPUT | vk::PipelineStageFlags::VERTEX_SHADER,
                vk::DependencyFlags::empty(),
                &[barrier],
                &[],
                &[],
            );
        }
        self.frames.submit(&self.device, i)
    }

    /// Uploads a heightfield as an R32F texture, streamed through the staging ring in as many
    /// submissions as the per-frame budget requires, and builds its tile grid.
    pub fn load_terrain(&mut self, hf: &Heightfield) -> Result<UploadStats, VkError> {
        let max = self.device.properties.limits.max_image_dimension2_d as usize;
        if hf.width > max || hf.height > max {
            return Err(VkError::Other(format!(
                "heightfield {}x{} exceeds this device's largest texture ({max}x{max}); full-resolution drawing needs it in one texture",
                hf.width, hf.height
            )));
        }
        let row_bytes = hf.width as u64 * 4;
        if row_bytes > self.staging.budget() {
            return Err(VkError::Staging(format!(
                "one heightfield row ({row_bytes} bytes) exceeds the per-frame staging budget ({} bytes)",
                self.staging.budget()
            )));
        }
        if let Some(mut old) = self.terrain.take() {
            self.wait_all()?;
            Self::destroy_terrain(&self.device, &mut old);
        }
        let d = &self.device;
        let mut heights = Image2d::new(
            d,
            "heights",
            ImageDesc {
                width: hf.width as u32,
                height: hf.height as u32,
                format: vk::Format::R32_SFLOAT,
                usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
                aspect: vk::ImageAspectFlags::COLOR,
            },
        )?;
        let grid = TileGrid::new(hf, self.tile_size as usize - 1);
        let mut frame_buffers = Vec::new();
        for _ in 0..FRAMES_IN_FLIGHT {
            match Self::create_frame_buffers(d, grid.tile_count()) {
                Ok(b) => frame_buffers.push(b),
                Err(e) => {
                    for mut b in frame_buffers {
                        b.destroy(d);
                    }
                    heights.destroy(d);
                    return Err(e);
                }
            }
        }
        self.terrain = Some(GpuTerrain {
            heights,
            grid,
            frame_buffers,
        });

        let mut stats = UploadStats::default();
        let rows_per_chunk = (self.staging.budget() / row_bytes) as usize;
        let mut row = 0usize;
        while row < hf.height {
            let rows = rows_per_chunk.min(hf.height - row);
            let (i, _) = self.begin_context()?;
            let data = &hf.heights[row * hf.width..(row + rows) * hf.width];
            let offset = self.staging.push(data, 4)?;
            let cmd = self.frames.begin_recording(&self.device, i)?;
            let image = self.terrain.as_ref().expect("just set").heights.raw;
            let d = &self.device;
            if row == 0 {
                transition(
                    d,
                    cmd,
                    image,
                    vk::ImageAspectFlags::COLOR,
                    (
                        vk::ImageLayout::UNDEFINED,
                        vk::PipelineStageFlags::TOP_OF_PIPE,
                        vk::AccessFlags::empty(),
                    ),
                    (
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        vk::PipelineStageFlags::TRANSFER,
                        vk::AccessFlags::TRANSFER_WRITE,
                    ),
                );
            }
            let region = vk::BufferImageCopy::default()
                .buffer_offset(offset)
                .image_subresource(vk::ImageSubresourceLayers {
                    aspect_mask: vk::ImageAspectFlags::COLOR,
                    mip_level: 0,
                    base_array_layer: 0,
                    layer_count: 1,
                })
                .image_offset(vk::Offset3D {
                    x: 0,
                    y: row as i32,
                    z: 0,
                })
                .image_extent(vk::Extent3D {
                    width: hf.width as u32,
                    height: rows as u32,
                    depth: 1,
                });
            unsafe {
                d.raw.cmd_copy_buffer_to_image(
                    cmd,
                    self.staging.raw(),
                    image,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[region],
                )
            };
            row += rows;
            if row == hf.height {
                transition(
                    d,
                    cmd,
                    image,
                    vk::ImageAspectFlags::COLOR,
                    (
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        vk::PipelineStageFlags::TRANSFER,
                        vk::AccessFlags::TRANSFER_WRITE,
                    ),
                    (
                        vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                        vk::PipelineStageFlags::VERTEX_SHADER,
                        vk::AccessFlags::SHADER_READ,
                    ),
                );
            }
            self.frames.submit(&self.device, i)?;
            stats.bytes += (rows * hf.width * 4) as u64;
            stats.submissions += 1;
        }
        Ok(stats)
    }

    fn create_frame_buffers(d: &Device, max_tiles: usize) -> Result<FrameBuffers, VkError> {
        let dst = vk::BufferUsageFlags::TRANSFER_DST;
        let mut uniforms = Buffer::new(
            d,
            "frame uniforms",
            std::mem::size_of::<FrameUniforms>() as u64,
            vk::BufferUsageFlags::UNIFORM_BUFFER | dst,
            MemoryLocation::GpuOnly,
        )?;
        let mut instances = or_unwind!(
            Buffer::new(
                d,
                "tile instances",
                (max_tiles.max(1) * std::mem::size_of::<TileInstance>()) as u64,
                vk::BufferUsageFlags::STORAGE_BUFFER | dst,
                MemoryLocation::GpuOnly,
            ),
            d,
            [uniforms]
        );
        let indirect = or_unwind!(
            Buffer::new(
                d,
                "indirect draws",
                std::mem::size_of::<DrawIndexedIndirect>() as u64 * 4,
                vk::BufferUsageFlags::INDIRECT_BUFFER | dst,
                MemoryLocation::GpuOnly,
            ),
            d,
            [instances, uniforms]
        );
        Ok(FrameBuffers {
            uniforms,
            instances,
            indirect,
        })
    }

    /// Renders one frame from `camera` into the offscreen target and waits for it, so that
    /// [`Self::colour_rgba`] / [`Self::depth`] and the GPU timings are ready on return.
    pub fn render(&mut self, camera: &Camera) -> Result<FrameStats, VkError> {
        let Some(terrain) = self.terrain.as_ref() else {
            return Err(VkError::Other("render called before load_terrain".into()));
        };
        let mut stats = FrameStats {
            frame: self.frame_counter,
            ..Default::default()
        };

        // Tile selection (pure CPU).
        let t0 = Instant::now();
        self.instances_scratch.clear();
        let sel: SelectionStats =
            select_full_resolution(&terrain.grid, camera, &mut self.instances_scratch);
        stats.tiles_considered = sel.considered;
        stats.tiles_culled = sel.culled;
        stats.tiles_drawn = sel.drawn;
        let m = self.tile_size as u64;
        stats.triangles = sel.drawn as u64 * (m - 1) * (m - 1) * 2;
        stats.cpu_select_us = t0.elapsed().as_secs_f64() * 1e6;

        let t1 = Instant::now();
        let (i, _) = self.begin_context()?;
        let terrain = self.terrain.as_ref().expect("checked above");
        let uniforms = frame_uniforms(camera, &terrain.grid, self.tile_size);
        let draw = DrawIndexedIndirect {
            index_count: ((m - 1) * (m - 1) * 6) as u32,
            instance_count: self.instances_scratch.len() as u32,
            first_index: 0,
            vertex_offset: 0,
            first_instance: 0,
        };
        let off_uniforms = self.staging.push(&[uniforms], 16)?;
        let off_draw = self.staging.push(&[draw], 4)?;
        let off_instances = if self.instances_scratch.is_empty() {
            None
        } else {
            Some(self.staging.push(&self.instances_scratch, 16)?)
        };
        stats.bytes_uploaded = self.staging.used();

        let d = &self.device;
        let fb = &terrain.frame_buffers[i];
        let set = self.descriptors.allocate(d, i, self.pipeline.set_layout)?;
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
        let image_info = [vk::DescriptorImageInfo {
            sampler: self.pipeline.height_sampler,
            image_view: terrain.heights.view,
            image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
        }];
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
                .dst_binding(BINDING_HEIGHTS)
                .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .image_info(&image_info),
        ];
        unsafe { d.raw.update_descriptor_sets(&writes, &[]) };

        let cmd = self.frames.begin_recording(d, i)?;
        self.timer.reset(d, cmd, i);

        // Uploads: staging ring → this frame's device buffers.
        self.timer.begin(d, cmd, i, Pass::Upload);
        let src = self.staging.raw();
        let copy = |dst: vk::Buffer, offset: u64, size: u64| unsafe {
            d.raw.cmd_copy_buffer(
                cmd,
                src,
                dst,
                &[vk::BufferCopy {
                    src_offset: offset,
                    dst_offset: 0,
                    size,
                }],
            )
        };
        copy(
            fb.uniforms.raw,
            off_uniforms,
            std::mem::size_of::<FrameUniforms>() as u64,
        );
        copy(
            fb.indirect.raw,
            off_draw,
            std::mem::size_of::<DrawIndexedIndirect>() as u64,
        );
        if let Some(off) = off_instances {
            let size = std::mem::size_of_val(self.instances_scratch.as_slice()) as u64;
            copy(fb.instances.raw, off, size);
        }
        unsafe {
            let barrier = vk::MemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                .dst_access_mask(
                    vk::AccessFlags::UNIFORM_READ
                        | vk::AccessFlags::SHADER_READ
                        | vk::AccessFlags::INDIRECT_COMMAND_READ,
                );
            d.raw.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::DRAW_INDIRECT
                    | vk::PipelineStageFlags::VERTEX_SHADER
                    | vk::PipelineStageFlags::FRAGMENT_SHADER,
                vk::DependencyFlags::empty(),
                &[barrier],
                &[],
                &[],
            );
        }
        self.timer.end(d, cmd, i, Pass::Upload);

        // Terrain pass.
        self.timer.begin(d, cmd, i, Pass::Terrain);
        self.target.record_begin(d, cmd);
        let (w, h) = (self.target.width, self.target.height);
        let colour_attachment = [vk::RenderingAttachmentInfo::default()
            .image_view(self.target.colour.view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue {
                color: vk::ClearColorValue {
                    float32: [SKY_LINEAR[0], SKY_LINEAR[1], SKY_LINEAR[2], 1.0],
                },
            })];
        let depth_attachment = vk::RenderingAttachmentInfo::default()
            .image_view(self.target.depth.view)
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: DEPTH_CLEAR,
                    stencil: 0,
                },
            });
        let area = vk::Rect2D {
            offset: vk::Offset2D { x: 0, y: 0 },
            extent: vk::Extent2D {
                width: w,
                height: h,
            },
        };
        let rendering = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(&colour_attachment)
            .depth_attachment(&depth_attachment);
        unsafe {
            d.raw.cmd_begin_rendering(cmd, &rendering);
            d.raw.cmd_set_viewport(
                cmd,
                0,
                &[vk::Viewport {
                    x: 0.0,
                    y: 0.0,
                    width: w as f32,
                    height: h as f32,
                    min_depth: 0.0,
                    max_depth: 1.0,
                }],
            );
            d.raw.cmd_set_scissor(cmd, 0, &[area]);
            if !self.instances_scratch.is_empty() {
                d.raw
                    .cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.pipeline.raw);
                d.raw.cmd_bind_descriptor_sets(
                    cmd,
                    vk::PipelineBindPoint::GRAPHICS,
                    self.pipeline.layout,
                    0,
                    &[set],
                    &[],
                );
                d.raw.cmd_bind_index_buffer(
                    cmd,
                    self.tile_index_buffer.raw,
                    0,
                    vk::IndexType::UINT16,
                );
                // One multi-draw indirect for all tiles: no per-tile Vulkan calls.
                d.raw.cmd_draw_indexed_indirect(
                    cmd,
                    fb.indirect.raw,
                    0,
                    1,
                    std::mem::size_of::<DrawIndexedIndirect>() as u32,
                );
                stats.draw_calls = 1;
            }
            d.raw.cmd_end_rendering(cmd);
        }
        self.timer.end(d, cmd, i, Pass::Terrain);
        self.target.record_readback(d, cmd);
        self.frames.submit(d, i)?;
        self.timed[i] = true;
        stats.cpu_record_us = t1.elapsed().as_secs_f64() * 1e6;

        // Headless: wait for this frame so its image and timings can be read.
        self.frames.wait(&self.device, i)?;
        self.timed[i] = false;
        let gpu = self.timer.read_ms(&self.device, i)?;
        stats.gpu_upload_ms = gpu[Pass::Upload as usize];
        stats.gpu_terrain_ms = gpu[Pass::Terrain as usize];
        self.frame_counter += 1;
        Ok(stats)
    }

    /// RGBA8 (sRGB) of the last rendered frame, rows top to bottom.
    pub fn colour_rgba(&self) -> Vec<u8> {
        self.target.colour_rgba()
    }

    /// Reversed-Z depth of the last rendered frame (0 = sky).
    pub fn depth(&self) -> Vec<f32> {
        self.target.depth()
    }

    fn wait_all(&self) -> Result<(), VkError> {
        unsafe { self.device.raw.device_wait_idle() }.call("vkDeviceWaitIdle")
    }

    fn destroy_terrain(device: &Device, t: &mut GpuTerrain) {
        for b in &mut t.frame_buffers {
            b.destroy(device);
        }
        t.heights.destroy(device);
    }

    /// Destroys everything in reverse creation order. Idempotent.
    pub fn destroy(&mut self) {
        if self.destroyed {
            return;
        }
        self.destroyed = true;
        self.device.wait_idle();
        let d = &self.device;
        if let Some(mut t) = self.terrain.take() {
            Self::destroy_terrain(d, &mut t);
        }
        self.tile_index_buffer.destroy(d);
        self.target.destroy(d);
        self.pipeline.destroy(d);
        self.timer.destroy(d);
        self.descriptors.destroy(d);
        self.staging.destroy(d);
        self.frames.destroy(d);
        self.device.destroy();
        self.instance.destroy();
    }
}

impl Drop for TerrainRenderer {
    fn drop(&mut self) {
        self.destroy();
    }
}

/// Linear-light sky colour (clear colour and haze).
pub const SKY_LINEAR: [f32; 3] = [0.38, 0.55, 0.80];

/// Sun from the north-west (the cartographic convention for shaded relief), 40° up.
fn sun_direction() -> [f32; 3] {
    let (az, el) = (315f64.to_radians(), 40f64.to_radians());
    [
        (el.cos() * az.sin()) as f32,
        (el.cos() * az.cos()) as f32,
        el.sin() as f32,
    ]
}

fn frame_uniforms(camera: &Camera, grid: &TileGrid, tile_size: u32) -> FrameUniforms {
    let m = camera.relative_world_to_clip_f32();
    let s = sun_direction();
    FrameUniforms {
        relative_world_to_clip: m.to_cols_array_2d(),
        sun_dir: [s[0], s[1], s[2], 0.22],
        sky_colour: [SKY_LINEAR[0], SKY_LINEAR[1], SKY_LINEAR[2], 90_000.0],
        grid_spacing: [
            grid.spacing_x as f32,
            grid.spacing_y as f32,
            camera.position.z as f32,
            0.0,
        ],
        grid_size: [
            grid.width as i32,
            grid.height as i32,
            tile_size as i32 - 1,
            0,
        ],
    }
}
