//! The renderer and its frame, in the order of DESIGN.md's data flow: plan (clipmap placement,
//! tile selection, refined-tile pools, instances and indirect commands: `plan.rs`, pure) →
//! stage (`upload.rs`) → record (`terrain_pass.rs`, `overlay_pass.rs`) → submit → read back.

use std::sync::Arc;
use std::time::Instant;

use ash::vk;
use glam::DVec3;
use gpu_allocator::MemoryLocation;

use aerie_terrain::bake::ErrorBake;
use aerie_terrain::camera::Camera;
use aerie_terrain::clipmap::CacheRegion;
use aerie_terrain::dataset::Dataset;
use aerie_terrain::geodesy::GeoGrid;
use aerie_terrain::select::{LodMode, SelectParams, Selection};
use aerie_terrain::source::{InMemoryTerrain, StreamStats, TerrainSource};

use crate::render::cpu_clock::thread_cpu_us;
use crate::render::drape_textures::{drape_rasters, DrapeTextures, DrapedRasters, MAX_DRAPE_SIDE};
use crate::render::entity_instances::{EntityDraw, EntityFrameStats};
use crate::render::entity_lod::{LodParams, LodView};
use crate::render::entity_pass::EntityPass;
use crate::render::frame_record::RecordParts;
use crate::render::gathered::SampleCursor;
use crate::render::gpu::EntityPush;
use crate::render::imagery_stream::ImageryStream;
use crate::render::jobs::{split_level_uploads, ImageUpload, StagingBudget};
use crate::render::models::{Model, ModelLibrary};
use crate::render::normal_map::NormalTexel;
use crate::render::normal_pass::{read_normal_texels, NormalBatch, NormalPass};
use crate::render::overlay_pass::Panel;
use crate::render::plan::{fixed_reserve, plan_frame, select_frame, FrameInputs, TileMeshes};
use crate::render::resources::{reserve_instances, GpuTerrain};
use crate::render::terrain_pass::{descriptor_pool_sizes, DESCRIPTOR_SETS};
use crate::render::tess_pass::TessTerrain;
use crate::render::uniforms::{frame_uniforms, FrameLight, FLAG_NORMAL_MAP};
use crate::render::upload::{
    fit_staging, initialise_images, stage_frame, stream_buffer, stream_image_uploads, GpuNormals,
};
use crate::vk::frame_context::{FrameContext, FrameRing};
use crate::vk::pipeline::TerrainPipeline;
use crate::vk::swapchain::{PresentTarget, ACQUIRE_WAIT_STAGE};
use crate::vk::target::OffscreenTarget;
use crate::vk::timestamps::Pass;
use crate::vk::{Buffer, Device, Instance, ValidationCounters, VkError, VkResultExt};

pub use crate::render::desc::{NormalSource, RendererDesc, DEFAULT_TILE_SIZE};
pub use crate::render::stats::{FrameStats, UploadStats};
pub use crate::render::uniforms::{Lighting, Look, SKY_LINEAR};

/// Owns every Vulkan object. Destroyed explicitly in reverse creation order by
/// [`TerrainRenderer::destroy`] (also called from `Drop`).
pub struct TerrainRenderer {
    instance: Instance,
    device: Device,
    /// Every per-frame-in-flight resource; the only owner of the frame index.
    ring: FrameRing,
    pipeline: TerrainPipeline,
    target: OffscreenTarget,
    tile_index_buffer: Buffer,
    /// Indices of one skirted tile in `tile_index_buffer`: (first, count).
    tile_meshes: TileMeshes,
    terrain: Option<GpuTerrain>,
    /// `--normals gpu`: the compute pass making the normal texels (made at load).
    gpu_normals: Option<NormalPass>,
    /// `--lod tess`: the tessellation baseline's heights, density and pipeline (made at load).
    tess: Option<TessTerrain>,
    desc: RendererDesc,
    frame_counter: u64,
    selection: Selection,
    /// Channels sharing one selection (issue 7): when set, every frame selects tiles for all of
    /// them (per tile the largest ρ/τ among the channels that see it), whichever one is drawn.
    channels: Vec<(Camera, (u32, u32), f64)>,
    /// Counts `set_channels` calls: the plan reuses the shared selection while it is unchanged.
    channels_generation: u64,
    /// Statistics panel copied into the top-left corner of every frame while set.
    overlay: Option<Panel>,
    /// Sun and haze of the next frames.
    light: FrameLight,
    /// Other traffic (CIGI entities), drawn after the terrain when set.
    entities: Option<EntityPass>,
    /// Draped imagery and land cover (placeholders until a terrain with rasters is loaded).
    drape: Option<DrapeTextures>,
    /// What the last load draped (for summaries and the land-cover tests).
    draped: Option<Arc<DrapedRasters>>,
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
        desc.validate().map_err(VkError::Other)?;
        let extra: Vec<&std::ffi::CStr> = desc
            .instance_extensions
            .iter()
            .map(|e| e.as_c_str())
            .collect();
        let mut instance = Instance::with_extensions(desc.validation, &extra)?;
        let mut device = match Device::new(&instance, &desc.device) {
            Ok(d) => d,
            Err(e) => {
                instance.destroy();
                return Err(e);
            }
        };
        // Every instance is one m×m node with its skirt: one shared vertex layout, indexed
        // whole or (quadrants drawn at their parent's resolution) coarse.
        let (indices, tile_meshes) = TileMeshes::indices(desc.tile_size);
        let (ring, pipeline, target, tile_index_buffer) =
            match Self::create_parts(&device, desc, indices.len() as u64 * 4) {
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
            ring,
            pipeline,
            target,
            tile_index_buffer,
            tile_meshes,
            terrain: None,
            gpu_normals: None,
            tess: None,
            desc: desc.clone(),
            frame_counter: 0,
            selection: Selection::default(),
            channels: Vec::new(),
            channels_generation: 0,
            overlay: None,
            light: FrameLight::default(),
            entities: None,
            drape: None,
            draped: None,
            destroyed: false,
        };
        let dst = this.tile_index_buffer.raw;
        let bytes = bytemuck::cast_slice(&indices);
        if let Err(e) = stream_buffer(&this.device, &mut this.ring, bytes, dst) {
            this.destroy();
            return Err(e);
        }
        match DrapeTextures::new(&this.device, &mut this.ring, None) {
            Ok(t) => this.drape = Some(t),
            Err(e) => {
                this.destroy();
                return Err(e);
            }
        }
        Ok(this)
    }

    fn create_parts(
        d: &Device,
        desc: &RendererDesc,
        index_bytes: u64,
    ) -> Result<(FrameRing, TerrainPipeline, OffscreenTarget, Buffer), VkError> {
        let sizes = descriptor_pool_sizes();
        let mut ring = FrameRing::new(d, desc.staging_budget, DESCRIPTOR_SETS, &sizes)?;
        let mut pipeline = or_unwind!(TerrainPipeline::new(d), d, [ring]);
        let mut target = or_unwind!(
            OffscreenTarget::new(d, desc.width, desc.height),
            d,
            [pipeline, ring]
        );
        let tile_index_buffer = or_unwind!(
            Buffer::new(
                d,
                "tile indices",
                index_bytes,
                vk::BufferUsageFlags::INDEX_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuOnly,
            ),
            d,
            [target, pipeline, ring]
        );
        Ok((ring, pipeline, target, tile_index_buffer))
    }

    /// What the last load draped on the terrain (None without rasters), and the textures'
    /// device bytes.
    pub fn draped(&self) -> (Option<Arc<DrapedRasters>>, u64) {
        let bytes = self.drape.as_ref().map_or(0, DrapeTextures::bytes);
        (self.draped.clone(), bytes)
    }

    /// `--lod tess`: milliseconds the base mesh's density took at load.
    pub fn tess_density_ms(&self) -> Option<f64> {
        self.tess.as_ref().map(|t| t.density_ms)
    }

    pub fn device_name(&self) -> &str {
        &self.device.name
    }

    /// Bytes one frame may stage now and how often the region grew (`jobs::staging_to_hold`).
    pub fn staging_region(&self) -> (u64, u32) {
        (self.ring.staging_budget(), self.ring.staging_growths())
    }

    /// The last frame's tile selection (before the budget's decisions): for tests and tools.
    pub fn selection(&self) -> &Selection {
        &self.selection
    }

    pub fn validation_counters(&self) -> Arc<ValidationCounters> {
        self.instance.counters()
    }

    pub fn size(&self) -> (u32, u32) {
        (self.target.width, self.target.height)
    }

    pub fn desc(&self) -> &RendererDesc {
        &self.desc
    }

    /// Makes the following frames select tiles once for all these channels (camera, viewport,
    /// τ), so adjacent channels draw every shared tile at the same resolution and seams match.
    /// Empty = select for the camera being drawn only.
    pub fn set_channels(&mut self, channels: Vec<(Camera, (u32, u32), f64)>) {
        self.channels = channels;
        self.channels_generation += 1;
    }

    /// Draws `panel` over the top-left corner of the following frames (None: no overlay).
    pub fn set_overlay(&mut self, panel: Option<Panel>) {
        self.overlay = panel;
    }

    /// Sun and haze for the next frames (a host's Celestial Sphere / Atmosphere Control).
    pub fn set_lighting(&mut self, lighting: Lighting) {
        self.light.set(lighting);
    }

    /// Draws entities with the models of `library` from now on (their instances come from
    /// [`Self::set_entities`]).
    pub fn set_entity_models(
        &mut self,
        library: &ModelLibrary,
        scale: f64,
        params: LodParams,
    ) -> Result<(), VkError> {
        let pass = EntityPass::new(&self.device, library, scale, params)?;
        if let Some(mut old) = self.entities.replace(pass) {
            self.wait_all()?;
            old.destroy(&self.device);
        }
        Ok(())
    }

    /// The entities of the following frames (ignored until models are set).
    pub fn set_entities(&mut self, entities: Vec<EntityDraw>) {
        if let Some(p) = self.entities.as_mut() {
            p.set_entities(entities);
        }
    }

    /// What the last frame drew of the entities, when models are set.
    pub fn entity_stats(&self) -> Option<EntityFrameStats> {
        self.entities.as_ref().map(EntityPass::last_stats)
    }

    /// The entity models, when set.
    pub fn entity_models(&self) -> &[Model] {
        self.entities.as_ref().map_or(&[], EntityPass::models)
    }

    /// Changes the LOD decision (mode, τ, curvature...) for the following frames.
    pub fn set_select_params(&mut self, params: SelectParams) {
        self.desc.select = params;
    }

    /// The source's running totals (zero for a dataset in memory; none before a load).
    pub fn stream_stats(&self) -> StreamStats {
        self.terrain
            .as_ref()
            .map(|t| t.plan.feed.gatherer.stream_stats())
            .unwrap_or_default()
    }

    /// Asks the source, with the next frame's request, for samples the renderer itself does
    /// not draw yet (the host's queries over tiles not resident).
    pub fn want_samples(&mut self, wants: &[aerie_terrain::source::SampleWant]) {
        if let Some(t) = self.terrain.as_mut() {
            t.plan.feed.gatherer.want_extra(wants);
        }
    }

    /// Level-texture cells still waiting for their samples (0 once every level is filled).
    pub fn pending_cells(&self) -> u32 {
        self.terrain
            .as_ref()
            .map_or(0, |t| t.plan.feed.pending_cells())
    }

    /// The streamed imagery windows (None before a load).
    pub fn imagery_stream(&self) -> Option<&ImageryStream> {
        self.drape.as_ref().map(|t| &t.stream)
    }

    /// Copies every streamed imagery cell around `eye` (world metres) that the source holds
    /// now, in as many submissions as that takes, without drawing (a still image's warm-up);
    /// returns the cells copied.
    pub fn fill_imagery(&mut self, eye: DVec3) -> Result<u32, VkError> {
        let (Some(t), Some(drape)) = (self.terrain.as_ref(), self.drape.as_mut()) else {
            return Ok(0);
        };
        let source = t.plan.feed.gatherer.source().as_ref();
        let viewer = t.plan.viewer(eye);
        (drape.stream).fill(&self.device, &mut self.ring, source, viewer)
    }

    /// Pool counters (hits, misses, evictions, late) per refinement r = 1..=6.
    pub fn pool_counters(&self) -> Vec<aerie_terrain::pool::PoolCounters> {
        self.terrain
            .as_ref()
            .map(|t| t.plan.pools.iter().map(|p| p.lru.counters()).collect())
            .unwrap_or_default()
    }

    /// The Vulkan instance and device, for creating window surfaces and swapchains on them.
    pub fn vulkan(&self) -> (&Instance, &Device) {
        (&self.instance, &self.device)
    }

    /// Recreates the offscreen target at a new size (e.g. after a window resize).
    pub fn resize(&mut self, width: u32, height: u32) -> Result<(), VkError> {
        if (width, height) == (self.target.width, self.target.height) {
            return Ok(());
        }
        self.wait_all()?;
        let new = OffscreenTarget::new(&self.device, width, height)?;
        let mut old = std::mem::replace(&mut self.target, new);
        old.destroy(&self.device);
        self.desc.width = width;
        self.desc.height = height;
        Ok(())
    }

    /// Loads a dataset held in memory and its bake ([`Self::load_source`] over an
    /// [`InMemoryTerrain`]: one path for every source).
    pub fn load_terrain(
        &mut self,
        dataset: Arc<Dataset>,
        bake: Arc<ErrorBake>,
        eye: DVec3,
    ) -> Result<UploadStats, VkError> {
        // The bake was checked against these samples when it was read or made.
        let source = InMemoryTerrain::with_checksum(dataset, bake.source_checksum);
        self.load_source(Arc::new(source), bake, eye)
    }

    /// Loads a terrain source and its bake: creates the level textures and pools and fills
    /// every level around `eye` with what the source holds (streamed through the ring over as
    /// many submissions as the budget needs); what it does not hold yet is asked for and
    /// filled by the following frames, which draw coarser meanwhile. Never waits for the source:
    /// a caller that wants the coarsest level there for the first frame waits for
    /// [`RendererDesc::start_up_rects`] on its source first.
    pub fn load_source(
        &mut self,
        source: Arc<dyn TerrainSource>,
        bake: Arc<ErrorBake>,
        eye: DVec3,
    ) -> Result<UploadStats, VkError> {
        let grid = source.grid().clone();
        crate::render::geo_instances::check_curvature_choice(
            self.desc.select.curvature,
            grid.geo.as_ref(),
        )
        .map_err(VkError::Input)?;
        let clipmap = (self.desc)
            .clipmap_for_bake(&grid, &bake)
            .map_err(VkError::Input)?;
        let level_count = clipmap.level_count();
        GpuTerrain::check_level_limits(&self.device, &clipmap)?;
        if let Some(mut old) = self.terrain.take() {
            self.wait_all()?;
            old.destroy(&self.device);
        }
        let max_side = self
            .device
            .properties
            .limits
            .max_image_dimension2_d
            .min(MAX_DRAPE_SIDE);
        let rasters = drape_rasters(
            self.desc.drape_ask(),
            &grid,
            source.imagery_layer(),
            max_side,
        )
        .map_err(VkError::Input)?;
        // A terrain without rasters after one with them gets the placeholders back.
        if rasters.is_some() || self.draped.is_some() {
            self.wait_all()?;
            if let Some(mut old) = self.drape.take() {
                old.destroy(&self.device);
            }
            self.drape = Some(DrapeTextures::new(
                &self.device,
                &mut self.ring,
                rasters.as_ref(),
            )?);
            self.draped = rasters.map(Arc::new);
        }
        if let Some(mut old) = self.tess.take() {
            self.wait_all()?;
            old.destroy(&self.device);
        }
        let d = &self.device;
        if self.desc.select.mode == LodMode::Tessellation {
            let earth = GeoGrid::of(grid.geo.as_ref(), grid.spacing_x, grid.spacing_y);
            self.tess = Some(TessTerrain::new(
                d,
                &mut self.ring,
                &source,
                earth.as_ref(),
            )?);
        }
        if let Some(mut old) = self.gpu_normals.take() {
            old.destroy(d);
        }
        let normals = self.desc.normal_maps.then_some(self.desc.normal_source);
        if normals == Some(NormalSource::Gpu) {
            self.gpu_normals = Some(NormalPass::new(d, [grid.spacing_x, grid.spacing_y])?);
        }
        let mut t = GpuTerrain::new(
            d,
            source,
            bake,
            clipmap,
            &self.desc.pool_capacity,
            self.desc.pool_layers,
            normals,
        )?;
        t.plan.warm_start = self.desc.warm_start;
        let staged_normals = normals == Some(NormalSource::Cpu);
        // First fill of every level around the eye, streamed.
        let strips = t.plan.strips_around(eye);
        let height_sampler = self.pipeline.height_sampler;
        let gpu_normals = self.gpu_normals.as_mut();
        let loaded = initialise_images(d, &mut self.ring, t.images()).and_then(|()| {
            let (budget, align) = (self.ring.staging_budget(), self.ring.staging_alignment());
            let submissions = split_level_uploads(&strips, budget, align, staged_normals)?;
            let image = t.levels.raw;
            let gatherer = &t.plan.feed.gatherer;
            let mut samples = SampleCursor::new(gatherer.samples());
            let mut normals = SampleCursor::new(gatherer.normals());
            let normals = staged_normals.then_some((t.normals.raw, &mut normals));
            let targets = t.normal_targets(height_sampler);
            let caches = &t.plan.feed.caches;
            let mut hook = gpu_normals.map(|p| {
                move |f: &mut FrameContext, cmd, jobs: &[ImageUpload]| {
                    p.record(
                        d,
                        f,
                        cmd,
                        &targets,
                        &NormalBatch::new(jobs, caches, targets.side)?,
                    )
                }
            });
            stream_image_uploads(
                d,
                &mut self.ring,
                &mut samples,
                image,
                normals,
                hook.as_mut().map(|h| h as &mut GpuNormals),
                &submissions,
            )
        });
        self.terrain = Some(t);
        // The streamed imagery the source holds already, so that the first frame draws it.
        if loaded.is_ok() {
            self.fill_imagery(eye)?;
        }
        Ok(UploadStats {
            bytes: strips.iter().map(ImageUpload::bytes).sum(),
            submissions: loaded?,
            levels: level_count,
        })
    }

    /// Renders one frame from `camera` into the offscreen target and waits for it, so that
    /// [`Self::colour_rgba`] / [`Self::depth`] and the GPU timings are ready on return.
    pub fn render(&mut self, camera: &Camera) -> Result<FrameStats, VkError> {
        self.render_frame(camera, None)
    }

    /// Renders one frame and, with `present`, copies it into a swapchain image instead of
    /// reading it back: the submission waits for `present.acquired` before the copy, signals
    /// `present.rendered` after it, and does not wait for the GPU (frames stay in flight; the
    /// GPU timings returned are those of the frame that last used this frame context).
    pub fn render_frame(
        &mut self,
        camera: &Camera,
        present: Option<&PresentTarget>,
    ) -> Result<FrameStats, VkError> {
        let Some(t) = self.terrain.as_mut() else {
            return Err(VkError::Other("render called before load_terrain".into()));
        };
        let d = &self.device;
        let mut inputs = FrameInputs {
            frame: self.frame_counter,
            camera,
            viewport: (self.target.width, self.target.height),
            channels: &self.channels,
            channels_generation: self.channels_generation,
            select: &self.desc.select,
            prefetch_frames: self.desc.prefetch_frames,
            skirt_factor: self.desc.skirt_factor,
            skirt_min_m: self.desc.skirt_min_m,
            skirts: self.desc.skirts,
            overlay_bytes: self.overlay.as_ref().map(Panel::bytes),
            tile_meshes: self.tile_meshes,
            staging: StagingBudget::new(self.ring.staging_budget(), self.ring.staging_alignment()),
        };

        // Plan: clipmap placement and tile selection, then the budget's decisions (pure CPU).
        let t0 = Instant::now();
        let cpu0 = thread_cpu_us();
        // The tessellation baseline draws from its own patches, not the clipmap's tiles.
        let tess_mode = self.desc.select.mode == LodMode::Tessellation;
        if tess_mode && self.tess.is_none() {
            return Err(VkError::Other(
                "--lod tess: the terrain was loaded for another mode; load it again".into(),
            ));
        }
        let strips = if tess_mode {
            // Nothing of the clipmap is drawn: no strips, no tiles (the last load's samples,
            // already staged, are forgotten as a selection would).
            t.plan.feed.gatherer.begin_frame();
            self.selection = Selection::default();
            Vec::new()
        } else {
            select_frame(&mut t.plan, &inputs, &mut self.selection)
        };
        let mut cpu_select_us = t0.elapsed().as_secs_f64() * 1e6;
        // Instance records share the staging region: one they would crowd grows first.
        let nodes = self.selection.items.len();
        let reserve = fixed_reserve(nodes, t.plan.projected(), inputs.overlay_bytes);
        if let Some(b) = fit_staging(&mut self.ring, d, self.desc.staging_budget, reserve)? {
            inputs.staging = b;
        }
        let t1 = Instant::now();
        let plan = plan_frame(&mut t.plan, &inputs, &self.selection, strips)?;
        let cpu_thread_plan_us = thread_cpu_us() - cpu0;

        // Stage: spilled strips in their own submissions, then this frame's region, from the
        // samples the plan gathered in that order.
        let levels = t.levels.raw;
        let mut samples = SampleCursor::new(t.plan.feed.gatherer.samples());
        let mut normals = SampleCursor::new(t.plan.feed.gatherer.normals());
        let spilled_normals = plan.normal_maps.then_some((t.normals.raw, &mut normals));
        let targets = t.normal_targets(self.pipeline.height_sampler);
        let (caches, side) = (&t.plan.feed.caches, targets.side);
        let mut hook = self.gpu_normals.as_mut().map(|p| {
            move |f: &mut FrameContext, cmd, jobs: &[ImageUpload]| {
                p.record(
                    d,
                    f,
                    cmd,
                    &targets,
                    &NormalBatch::new(jobs, caches, targets.side)?,
                )
            }
        });
        stream_image_uploads(
            d,
            &mut self.ring,
            &mut samples,
            levels,
            spilled_normals,
            hook.as_mut().map(|h| h as &mut GpuNormals),
            &plan.spilled_strips,
        )?;
        // The streamed imagery's cells, in their own submission before the frame's.
        let imagery_cells = match self.drape.as_mut() {
            Some(drape) => {
                let source = t.plan.feed.gatherer.source().as_ref();
                let viewer = t.plan.viewer(camera.position);
                drape.stream.update(d, &mut self.ring, source, viewer)?
            }
            None => 0,
        };
        let mut frame = self.ring.begin_frame(d)?;
        let records = (plan.instances.len(), plan.polynomials.len());
        reserve_instances(&mut t.frame_buffers, d, &mut frame, records)?;
        let tess_stats = match self.tess.as_mut() {
            Some(tess) if tess_mode => {
                let t3 = Instant::now();
                let (g, curvature) = (self.desc.select.tess_density, self.desc.select.curvature);
                let s = tess.prepare(d, &mut frame, camera, g, curvature)?;
                cpu_select_us += t3.elapsed().as_secs_f64() * 1e6;
                Some(s)
            }
            _ => None,
        };
        let (curvature, debug_tiles) = (self.desc.select.curvature, self.desc.debug_tiles);
        let mut uniforms = frame_uniforms(
            camera,
            &t.grid,
            t.plan.earth.as_ref(),
            &t.plan.clipmap,
            curvature,
            debug_tiles,
            self.desc.look,
            &self.light,
        );
        if self.desc.normal_maps && !tess_mode {
            uniforms.grid_size[3] |= FLAG_NORMAL_MAP;
        }
        if let Some(span) = self.draped.as_ref().and_then(|d| d.imagery_span()) {
            // shaders/drape.glsl: the level-0 samples the imagery texture spans.
            uniforms.clipmap[2..4].copy_from_slice(&span.map(|n| n as i32));
        }
        if let Some(drape) = self.drape.as_ref() {
            drape.stream.write_uniforms(&mut uniforms);
        }
        let overlay = self.overlay.as_ref();
        let staging = frame.staging();
        let staged = stage_frame(
            staging,
            &mut samples,
            &mut normals,
            &plan,
            &uniforms,
            overlay,
        )?;
        let mut stats = FrameStats {
            cpu_select_us,
            cpu_thread_plan_us,
            imagery_cells,
            imagery_cells_pending: self.drape.as_ref().map_or(0, |t| t.stream.pending()),
            cpu_upload_us: t1.elapsed().as_secs_f64() * 1e6,
            ..plan.stats
        };
        if let Some(s) = tess_stats {
            stats.tiles_considered = s.cells;
            stats.tiles_culled = s.culled;
            stats.tiles_drawn = s.cells - s.culled;
            stats.instances = s.patches;
            stats.triangles = s.triangles;
            stats.draw_calls = self.tess.as_ref().map_or(0, |t| t.draws.len() as u32);
        }
        let views: Vec<LodView> = (self.channels.iter())
            .map(|&(camera, viewport, _)| LodView { camera, viewport })
            .collect();
        let viewport = (self.target.width, self.target.height);
        if let Some(p) = self.entities.as_mut() {
            let s = p.prepare(d, &mut frame, camera, viewport, &views)?;
            stats.triangles += s.triangles();
        }
        let push = EntityPush {
            relative_world_to_clip: uniforms.relative_world_to_clip,
            sun_dir: uniforms.sun_dir,
            sky_colour: uniforms.sky_colour,
        };

        // Record.
        let t2 = Instant::now();
        let mut parts = RecordParts {
            terrain: t,
            pipeline: &self.pipeline,
            target: &self.target,
            tile_index_buffer: self.tile_index_buffer.raw,
            overlay,
            sky: self.desc.look.draws_sky(),
            entities: self.entities.as_ref().map(|p| (p, push)),
            drape: self
                .drape
                .as_ref()
                .ok_or_else(|| VkError::Other("draped textures missing".into()))?,
            tess: self.tess.as_ref().filter(|_| tess_mode),
            gpu_normals: match self.gpu_normals.as_mut() {
                Some(p) => Some((p, NormalBatch::new(&plan.strips, caches, side)?)),
                None => None,
            },
        };
        let cmd = parts.record(d, &mut frame, &plan, &staged)?;
        let previous_gpu = frame.previous_gpu_ms();

        // Submit.
        let gpu = match present {
            None => {
                self.target.record_readback(d, cmd);
                let submitted = frame.submit(d)?;
                stats.cpu_record_us = t2.elapsed().as_secs_f64() * 1e6;
                stats.cpu_thread_us = thread_cpu_us() - cpu0;
                // Headless: wait for this frame so its image and timings can be read.
                self.ring.wait(d, submitted)?
            }
            Some(p) => {
                self.target.record_blit_to(d, cmd, p.image, p.extent);
                let stage = [ACQUIRE_WAIT_STAGE];
                let _in_flight = frame.submit_with(d, &[p.acquired], &stage, &[p.rendered])?;
                stats.cpu_record_us = t2.elapsed().as_secs_f64() * 1e6;
                stats.cpu_thread_us = thread_cpu_us() - cpu0;
                previous_gpu
            }
        };
        if let Some(gpu) = gpu {
            stats.gpu_upload_ms = gpu[Pass::Upload as usize];
            stats.gpu_terrain_ms = gpu[Pass::Terrain as usize];
            stats.gpu_normals_ms = gpu[Pass::Normals as usize];
        }
        self.frame_counter += 1;
        Ok(stats)
    }

    /// Layer `level` of the normal texture (side² texels, row-major, texel = sample mod side),
    /// read back after the frames rendered so far: for the tests of the normal maps.
    pub fn read_normal_layer(&mut self, level: u32) -> Result<Vec<NormalTexel>, VkError> {
        let t = self
            .terrain
            .as_ref()
            .ok_or(VkError::Other("no terrain loaded".into()))?;
        read_normal_texels(&self.device, &mut self.ring, &t.normals, level)
    }

    /// Each level's cache region (level-L vertices; None before it is placed) and the level
    /// textures' side.
    pub fn level_regions(&self) -> (Vec<Option<CacheRegion>>, u32) {
        self.terrain.as_ref().map_or((Vec::new(), 0), |t| {
            (t.plan.feed.caches.clone(), t.plan.clipmap.texture_side())
        })
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
        // SAFETY: the device is live (destroyed only in `destroy`); waiting has no other effect.
        unsafe { self.device.raw.device_wait_idle() }.call("vkDeviceWaitIdle")
    }

    /// Destroys everything in reverse creation order. Idempotent.
    pub fn destroy(&mut self) {
        if self.destroyed {
            return;
        }
        self.destroyed = true;
        self.device.wait_idle();
        let d = &self.device;
        if let Some(mut p) = self.entities.take() {
            p.destroy(d);
        }
        if let Some(mut p) = self.gpu_normals.take() {
            p.destroy(d);
        }
        if let Some(mut t) = self.terrain.take() {
            t.destroy(d);
        }
        if let Some(mut t) = self.tess.take() {
            t.destroy(d);
        }
        if let Some(mut t) = self.drape.take() {
            t.destroy(d);
        }
        self.tile_index_buffer.destroy(d);
        self.target.destroy(d);
        self.pipeline.destroy(d);
        self.ring.destroy(d);
        self.device.destroy();
        self.instance.destroy();
    }
}

impl Drop for TerrainRenderer {
    fn drop(&mut self) {
        self.destroy();
    }
}
