//! Recording one frame (`frame.rs`'s `render_frame`): the staged buffer and texture copies
//! (timed as the upload pass), the GPU normal pass when the normals are computed there (timed,
//! empty otherwise), the terrain pass (timed), the entities and the overlay copy.

use ash::vk;

use crate::render::drape_textures::DrapeTextures;
use crate::render::entity_pass::EntityPass;
use crate::render::gpu::{EntityPush, FrameUniforms, TileInstance};
use crate::render::normal_pass::{NormalBatch, NormalPass, NormalTargets};
use crate::render::overlay_pass::{record_panel_copy, Panel};
use crate::render::plan::FramePlan;
use crate::render::resources::GpuTerrain;
use crate::render::terrain_pass::{record_terrain_pass, write_descriptors};
use crate::render::tess_pass::{FragmentImages, TessTerrain};
use crate::render::upload::{record_image_copies, StagedFrame};
use crate::vk::access::{memory_barrier, Access};
use crate::vk::frame_context::FrameContext;
use crate::vk::pipeline::TerrainPipeline;
use crate::vk::target::OffscreenTarget;
use crate::vk::timestamps::Pass;
use crate::vk::{Device, VkError};

/// What recording a frame reads besides its context.
pub struct RecordParts<'a> {
    pub terrain: &'a GpuTerrain,
    pub pipeline: &'a TerrainPipeline,
    pub target: &'a OffscreenTarget,
    pub tile_index_buffer: vk::Buffer,
    pub overlay: Option<&'a Panel>,
    /// Draw the sky where no terrain is (the full look).
    pub sky: bool,
    pub entities: Option<(&'a EntityPass, EntityPush)>,
    pub drape: &'a DrapeTextures,
    /// The tessellation baseline, drawn instead of the tiles.
    pub tess: Option<&'a TessTerrain>,
    /// `--normals gpu`: the pass and the normal jobs of this frame's strips.
    pub gpu_normals: Option<(&'a mut NormalPass, NormalBatch)>,
}

impl RecordParts<'_> {
    /// Records the frame up to (not including) the read-back or present blit: the staged
    /// buffer and texture copies (timed as the upload pass), the GPU normal pass (timed; its
    /// timestamps written back to back without one), the terrain pass (timed), the overlay
    /// copy. Returns the command buffer, still recording.
    pub fn record(
        &mut self,
        d: &Device,
        frame: &mut FrameContext,
        plan: &FramePlan,
        staged: &StagedFrame,
    ) -> Result<vk::CommandBuffer, VkError> {
        let t = self.terrain;
        let fb = &t.frame_buffers[frame.index()];
        let set = frame.allocate_set(d, self.pipeline.set_layout)?;
        let samplers = (self.pipeline.height_sampler, self.pipeline.normal_sampler);
        write_descriptors(d, set, fb, t, samplers.0, samplers.1, self.drape);
        // The tessellation set shares the fragment shader's textures (normal maps, drape).
        let fragment_images = FragmentImages {
            normals: (t.normals.view, self.pipeline.normal_sampler),
            imagery: (self.drape.imagery_view(), self.drape.linear),
            classes: (self.drape.classes_view(), self.drape.nearest),
            imagery_stream: (self.drape.stream.view(), self.pipeline.normal_sampler),
        };
        let tess = match self.tess {
            Some(tess) => Some((
                tess,
                tess.write_set(d, frame, fb.uniforms.raw, &fragment_images)?,
            )),
            None => None,
        };
        let src = frame.staging_buffer();
        let cmd = frame.begin_recording(d)?;
        frame.reset_timestamps(d, cmd);
        frame.time_begin(d, cmd, Pass::Upload);
        let copy = |dst: vk::Buffer, offset: u64, size: usize| {
            let region = vk::BufferCopy {
                src_offset: offset,
                dst_offset: 0,
                size: size as u64,
            };
            // `size` bytes were staged at `offset` of the live staging buffer, and `dst` is this
            // frame's live buffer, sized for them (the instance and polynomial buffers were grown to
            // the plan's counts before staging).
            // SAFETY: `cmd` is recording.
            unsafe { d.raw.cmd_copy_buffer(cmd, src, dst, &[region]) }
        };
        copy(
            fb.uniforms.raw,
            staged.uniforms,
            std::mem::size_of::<FrameUniforms>(),
        );
        if !plan.draws.is_empty() {
            copy(
                fb.indirect.raw,
                staged.draws,
                std::mem::size_of_val(plan.draws.as_slice()),
            );
        }
        if let Some(off) = staged.instances {
            let size = plan.instances.len() * std::mem::size_of::<TileInstance>();
            copy(fb.instances.raw, off, size);
        }
        if let Some(off) = staged.polynomials {
            copy(
                fb.polynomials.raw,
                off,
                std::mem::size_of_val(plan.polynomials.as_slice()),
            );
        }
        record_image_copies(d, cmd, src, t.levels.raw, &staged.strip_copies);
        record_image_copies(d, cmd, src, t.normals.raw, &staged.normal_copies);
        for (image, copies) in t.pool_images.iter().zip(&staged.pool_copies) {
            record_image_copies(d, cmd, src, image.raw, copies);
        }
        let mut readers = vec![
            Access::IndirectBuffer,
            Access::AnyShaderReadUniformBuffer,
            Access::VertexShaderReadStorageBuffer,
        ];
        if tess.is_some() {
            // The uniforms and (since the load's upload) the heights, read past the vertex stage.
            readers.push(Access::TessellationShaderRead);
        }
        memory_barrier(d, cmd, &[Access::TransferWrite], &readers);
        frame.time_end(d, cmd, Pass::Upload);

        // After the strips' heights (their copies' barrier covers the compute stage).
        frame.time_begin(d, cmd, Pass::Normals);
        if let Some((pass, batch)) = self.gpu_normals.as_mut() {
            let targets = NormalTargets {
                levels_view: t.levels.view,
                height_sampler: self.pipeline.height_sampler,
                normals: t.normals.raw,
                side: t.plan.clipmap.texture_side(),
            };
            pass.record(d, frame, cmd, &targets, batch)?;
        }
        frame.time_end(d, cmd, Pass::Normals);

        frame.time_begin(d, cmd, Pass::Terrain);
        self.target.record_begin(d, cmd);
        record_terrain_pass(
            d,
            cmd,
            self.target,
            self.pipeline,
            set,
            self.tile_index_buffer,
            fb.indirect.raw,
            plan.draw_count,
            self.sky,
            &|cmd| {
                if let Some((tess, set)) = tess {
                    tess.record_draw(d, cmd, set);
                }
            },
        );
        if let Some((p, push)) = &self.entities {
            p.record(d, cmd, frame.index(), self.target, push);
        }
        frame.time_end(d, cmd, Pass::Terrain);
        if let (Some(p), Some(off)) = (self.overlay, staged.overlay) {
            let extent = (self.target.width, self.target.height);
            record_panel_copy(d, cmd, src, off, self.target.colour.raw, extent, p);
        }
        Ok(cmd)
    }
}
