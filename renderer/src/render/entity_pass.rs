//! The entity pass (issue 18): the models' GPU buffers, one instance and one indirect buffer
//! per frame in flight, and the recording — after the terrain pass, into the same colour and
//! depth attachments (loaded, not cleared), so entities are depth-tested against the terrain
//! with the same reversed-Z depth. One `vkCmdDrawIndexedIndirect` carries every (model, level)
//! group of the frame.
//!
//! Every buffer here is host-visible and written through its mapping before the submission
//! that reads it (a queue submission makes earlier host writes visible to the device), so no
//! staging copy or barrier is needed; the per-frame buffers are only rewritten once their
//! frame's fence signalled (the frame context handed out by `FrameRing::begin_frame`).

use ash::vk;
use gpu_allocator::MemoryLocation;

use aerie_terrain::camera::Camera;

use crate::render::entity_instances::{build_frame, EntityDraw, EntityFrameStats};
use crate::render::entity_lod::{LodParams, LodState, LodView};
use crate::render::gpu::{DrawIndexedIndirect, EntityInstance, EntityPush, EntityVertex};
use crate::render::models::{Model, ModelLibrary};
use crate::vk::access::{memory_barrier, Access};
use crate::vk::entity_pipeline::{EntityPipeline, EntityStreams};
use crate::vk::frame_context::FrameContext;
use crate::vk::target::OffscreenTarget;
use crate::vk::{Buffer, Device, VkError, FRAMES_IN_FLIGHT};

/// One frame slot's buffers.
struct SlotBuffers {
    instances: Buffer,
    indirect: Buffer,
    draw_count: u32,
}

/// The entities' GPU objects and per-frame state.
pub struct EntityPass {
    pipeline: EntityPipeline,
    vertices: Buffer,
    indices: Buffer,
    slots: Vec<SlotBuffers>,
    models: Vec<Model>,
    scale: f64,
    params: LodParams,
    lod: LodState,
    entities: Vec<EntityDraw>,
    last: EntityFrameStats,
}

fn host_buffer(
    d: &Device,
    name: &str,
    bytes: u64,
    usage: vk::BufferUsageFlags,
) -> Result<Buffer, VkError> {
    Buffer::new(d, name, bytes.max(256), usage, MemoryLocation::CpuToGpu)
}

fn write(buffer: &mut Buffer, bytes: &[u8]) -> Result<(), VkError> {
    let map = buffer
        .mapped_mut()
        .ok_or_else(|| VkError::Other("entity buffer is not host-visible".into()))?;
    if map.len() < bytes.len() {
        return Err(VkError::Other(format!(
            "entity buffer holds {} bytes, {} written",
            map.len(),
            bytes.len()
        )));
    }
    map[..bytes.len()].copy_from_slice(bytes);
    Ok(())
}

impl EntityPass {
    /// Creates the pipeline and the model buffers for `library`, whose models are drawn at
    /// `scale` with the LOD `params`.
    pub fn new(
        d: &Device,
        library: &ModelLibrary,
        scale: f64,
        params: LodParams,
    ) -> Result<Self, VkError> {
        if library.models.is_empty() {
            return Err(VkError::Other("entity model library is empty".into()));
        }
        let streams = EntityStreams {
            vertex_stride: std::mem::size_of::<EntityVertex>() as u32,
            instance_stride: std::mem::size_of::<EntityInstance>() as u32,
            push_bytes: std::mem::size_of::<EntityPush>() as u32,
        };
        let mut pipeline = EntityPipeline::new(d, streams)?;
        let mut created: Vec<Buffer> = Vec::new();
        let result = (|| {
            let vbytes: &[u8] = bytemuck::cast_slice(&library.vertices);
            let ibytes: &[u8] = bytemuck::cast_slice(&library.indices);
            let mut v = host_buffer(
                d,
                "entity vertices",
                vbytes.len() as u64,
                vk::BufferUsageFlags::VERTEX_BUFFER,
            )?;
            write(&mut v, vbytes)?;
            created.push(v);
            let mut i = host_buffer(
                d,
                "entity indices",
                ibytes.len() as u64,
                vk::BufferUsageFlags::INDEX_BUFFER,
            )?;
            write(&mut i, ibytes)?;
            created.push(i);
            for _ in 0..FRAMES_IN_FLIGHT {
                created.push(Self::instance_buffer(d, 64)?);
                created.push(Self::indirect_buffer(d, 16)?);
            }
            Ok(())
        })();
        if let Err(e) = result {
            for mut b in created {
                b.destroy(d);
            }
            pipeline.destroy(d);
            return Err(e);
        }
        let mut it = created.into_iter();
        let vertices = it.next().expect("created above");
        let indices = it.next().expect("created above");
        let mut slots = Vec::new();
        while let (Some(instances), Some(indirect)) = (it.next(), it.next()) {
            slots.push(SlotBuffers {
                instances,
                indirect,
                draw_count: 0,
            });
        }
        Ok(Self {
            pipeline,
            vertices,
            indices,
            slots,
            models: library.models.clone(),
            scale,
            params,
            lod: LodState::default(),
            entities: Vec::new(),
            last: EntityFrameStats::default(),
        })
    }

    fn instance_buffer(d: &Device, count: usize) -> Result<Buffer, VkError> {
        host_buffer(
            d,
            "entity instances",
            (count * std::mem::size_of::<EntityInstance>()) as u64,
            vk::BufferUsageFlags::VERTEX_BUFFER,
        )
    }

    fn indirect_buffer(d: &Device, count: usize) -> Result<Buffer, VkError> {
        host_buffer(
            d,
            "entity draws",
            (count * std::mem::size_of::<DrawIndexedIndirect>()) as u64,
            vk::BufferUsageFlags::INDIRECT_BUFFER,
        )
    }

    /// The entities of the following frames.
    pub fn set_entities(&mut self, entities: Vec<EntityDraw>) {
        self.entities = entities;
    }

    /// The models (their levels' triangle counts and errors, for reports).
    pub fn models(&self) -> &[Model] {
        &self.models
    }

    /// What the last prepared frame drew.
    pub fn last_stats(&self) -> EntityFrameStats {
        self.last
    }

    /// Decides, culls and writes this frame's instances and draws into `frame`'s slot (its
    /// previous use has completed: `frame` was handed out after its fence). `views` are every
    /// channel of the frame (empty: `camera`'s alone).
    pub fn prepare(
        &mut self,
        d: &Device,
        frame: &mut FrameContext,
        camera: &Camera,
        viewport: (u32, u32),
        views: &[LodView],
    ) -> Result<EntityFrameStats, VkError> {
        let t0 = std::time::Instant::now();
        let own = [LodView {
            camera: *camera,
            viewport,
        }];
        let views = if views.is_empty() { &own[..] } else { views };
        let built = build_frame(
            &self.models,
            self.scale,
            &self.params,
            &mut self.lod,
            &self.entities,
            views,
            camera,
        );
        let slot = &mut self.slots[frame.index()];
        let ibytes: &[u8] = bytemuck::cast_slice(&built.instances);
        if ibytes.len() as u64 > slot.instances.size {
            let grown = Self::instance_buffer(d, built.instances.len().next_power_of_two())?;
            frame.defer_destroy(std::mem::replace(&mut slot.instances, grown));
        }
        let dbytes: &[u8] = bytemuck::cast_slice(&built.draws);
        if dbytes.len() as u64 > slot.indirect.size {
            let grown = Self::indirect_buffer(d, built.draws.len().next_power_of_two())?;
            frame.defer_destroy(std::mem::replace(&mut slot.indirect, grown));
        }
        write(&mut slot.instances, ibytes)?;
        write(&mut slot.indirect, dbytes)?;
        slot.draw_count = built.draws.len() as u32;
        let mut stats = built.stats;
        stats.cpu_us = t0.elapsed().as_secs_f64() * 1e6;
        self.last = stats;
        Ok(stats)
    }

    /// Records the pass into `cmd` after the terrain pass: the attachments' writes made
    /// visible, rendering resumed with their contents loaded, one multi-draw indirect.
    pub fn record(
        &self,
        d: &Device,
        cmd: vk::CommandBuffer,
        slot_index: usize,
        target: &OffscreenTarget,
        push: &EntityPush,
    ) {
        let slot = &self.slots[slot_index];
        if slot.draw_count == 0 {
            return;
        }
        // The terrain pass's colour and depth writes before this pass reads and writes them.
        // (Global barriers, one per use: a memory barrier has no layout to share.)
        for u in [
            Access::ColourAttachmentWrite,
            Access::DepthAttachmentReadWrite,
        ] {
            memory_barrier(d, cmd, &[u], &[u]);
        }
        target.begin_rendering(d, cmd, None);
        // The pipeline, the vertex, index, instance and indirect buffers are live, and the
        // indirect buffer holds `draw_count` commands written before submission; the terrain
        // pass left the target's views in the attachment layouts.
        // SAFETY: `cmd` is recording inside the rendering begun on the target.
        unsafe {
            d.raw
                .cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.pipeline.raw);
            d.raw.cmd_push_constants(
                cmd,
                self.pipeline.layout,
                vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
                0,
                bytemuck::bytes_of(push),
            );
            d.raw.cmd_bind_vertex_buffers(
                cmd,
                0,
                &[self.vertices.raw, slot.instances.raw],
                &[0, 0],
            );
            d.raw
                .cmd_bind_index_buffer(cmd, self.indices.raw, 0, vk::IndexType::UINT32);
            d.raw.cmd_draw_indexed_indirect(
                cmd,
                slot.indirect.raw,
                0,
                slot.draw_count,
                std::mem::size_of::<DrawIndexedIndirect>() as u32,
            );
        }
        target.end_rendering(d, cmd);
    }

    /// Destroys every buffer and the pipeline (after the device is idle). Idempotent.
    pub fn destroy(&mut self, d: &Device) {
        for s in &mut self.slots {
            s.indirect.destroy(d);
            s.instances.destroy(d);
        }
        self.indices.destroy(d);
        self.vertices.destroy(d);
        self.pipeline.destroy(d);
    }
}
