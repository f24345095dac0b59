//! The renderer and its frame, in the order of DESIGN.md's data flow:
//! camera → clipmap placement (level centres, dirty strips) → tile selection (cull, projected
//! error, refinement) → refined-tile pools (LRU, budgeted misses, prefetch) → uploads through the
//! staging ring → instance + indirect build → record (one multi-draw indirect) → submit → read back.

use std::sync::Arc;
use std::time::Instant;

use ash::vk;
use glam::DVec3;
use gpu_allocator::MemoryLocation;

use crate::render::gpu::{DrawIndexedIndirect, FrameUniforms, TileInstance};
use crate::vk::descriptors::FrameDescriptorPools;
use crate::vk::frame_context::FrameContexts;
use crate::vk::image::{transition, Image2d, ImageDesc};
use crate::vk::pipeline::{
    TerrainPipeline, BINDING_CLIPMAP, BINDING_FRAME, BINDING_INSTANCES, BINDING_POOLS,
};
use crate::vk::staging::StagingRing;
use crate::vk::swapchain::PresentTarget;
use crate::vk::target::{OffscreenTarget, DEPTH_CLEAR};
use crate::vk::timestamps::{GpuTimer, Pass};
use crate::vk::{
    Buffer, Device, DeviceDesc, Instance, ValidationCounters, VkError, VkResultExt,
    FRAMES_IN_FLIGHT,
};
use aerie_terrain::bake::ErrorBake;
use aerie_terrain::camera::Camera;
use aerie_terrain::clipmap::{
    place_levels, toroidal_pieces, update_cache, CacheRegion, ClipmapDesc,
};
use aerie_terrain::dataset::Dataset;
use aerie_terrain::gather::gather;
use aerie_terrain::mesh::skirted_tile_indices;
use aerie_terrain::pool::{RefinedTilePool, Request, TileKey};
use aerie_terrain::select::{
    neighbour_eps, select_tiles, select_tiles_multi, DrawItem, SelectParams, Selection, View,
    MAX_REFINEMENT,
};

/// Vertices per tile side (m = 2^j + 1). DESIGN.md default.
pub const DEFAULT_TILE_SIZE: u32 = 17;
/// Instance groups drawn: unrefined (r = 0) and r = 1..=MAX_REFINEMENT.
const RESOLUTIONS: usize = MAX_REFINEMENT as usize + 1;
/// Largest number of m×m instances one frame may draw (48 bytes each per frame in flight). The
/// instance buffers start smaller (sized from the ring tiles) and grow on demand up to this —
/// `full` on a large dataset draws every visible finest node.
const MAX_INSTANCES: usize = 1 << 20;
/// Initial instance capacity cap: what every LOD mode but `full` needs at most in practice.
const INITIAL_MAX_INSTANCES: usize = 1 << 16;

#[derive(Debug, Clone)]
pub struct RendererDesc {
    pub validation: bool,
    /// Extra instance extensions, e.g. the surface extensions a window needs.
    pub instance_extensions: Vec<std::ffi::CString>,
    pub device: DeviceDesc,
    pub width: u32,
    pub height: u32,
    /// Hard upload budget per frame (bytes), the size of one staging-ring region.
    pub staging_budget: u64,
    /// m: vertices per tile side.
    pub tile_size: u32,
    /// P: tiles per clipmap patch side (n = P(m−1)+1: 8 → 129, 16 → 257).
    pub patch_tiles: u32,
    /// Cache margin of each level texture, whole tiles per side.
    pub margin_tiles: u32,
    /// Slots of the refined-tile pool for r = 1..=6 (0 = none: tiles needing that r are drawn
    /// at the best resolution below it and counted as late).
    pub pool_capacity: [u32; MAX_REFINEMENT as usize],
    pub select: SelectParams,
    /// Colour tiles by level and refinement (the seed's figure 3).
    pub debug_tiles: bool,
    /// Skirt depth = factor × ½(ε + the largest of ε and its edge neighbours' ε) + minimum
    /// (metres): at the default 2, ε + max(ε, neighbours' ε), which closes the cracks a
    /// neighbour drawn at another level can open (`select::neighbour_eps`). Must be ≥ 1.
    pub skirt_factor: f32,
    pub skirt_min_m: f32,
    /// Prefetch looks this many frames ahead along the eye's motion.
    pub prefetch_frames: f64,
}

impl Default for RendererDesc {
    fn default() -> Self {
        Self {
            validation: cfg!(debug_assertions),
            instance_extensions: Vec::new(),
            device: DeviceDesc::default(),
            width: 1920,
            height: 1080,
            staging_budget: 8 << 20,
            tile_size: DEFAULT_TILE_SIZE,
            patch_tiles: 8,
            margin_tiles: 2,
            pool_capacity: [256, 128, 48, 32, 16, 0],
            select: SelectParams::default(),
            debug_tiles: false,
            skirt_factor: 2.0,
            skirt_min_m: 1.0,
            prefetch_frames: 20.0,
        }
    }
}

/// What one frame did (DESIGN.md "Every stage reports what it did").
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct FrameStats {
    pub frame: u64,
    pub finest_level: u32,
    pub tiles_considered: u32,
    pub tiles_culled: u32,
    /// Ring tiles drawn (considered − culled).
    pub tiles_drawn: u32,
    /// Drawn ring tiles per refinement r chosen by the bound (index r; 0 = unrefined).
    pub tiles_by_refinement: [u32; RESOLUTIONS],
    /// m×m instances drawn: one per unrefined tile, one per quadtree node of a refined tile.
    pub instances: u32,
    /// Tiles drawn coarser than the bound asked because their upload did not fit this frame.
    pub tiles_late: u32,
    /// Tiles whose bound could not be met within the refinement cap.
    pub tiles_unbounded: u32,
    pub triangles: u64,
    pub draw_calls: u32,
    pub bytes_clipmap: u64,
    pub bytes_refined: u64,
    /// Everything through the staging ring this frame (uniforms, instances, indirect included).
    pub bytes_uploaded: u64,
    /// Clipmap uploads that exceeded the frame's budget and were streamed in extra submissions.
    pub budget_spills: u32,
    pub pool_hits: u32,
    pub pool_misses: u32,
    pub prefetched: u32,
    /// A hash of the selection (nodes and refinements): equal for channels sharing one.
    #[serde(skip)]
    pub selection_digest: u64,
    pub cpu_select_us: f64,
    pub cpu_upload_us: f64,
    pub cpu_record_us: f64,
    pub gpu_upload_ms: f64,
    pub gpu_terrain_ms: f64,
}

impl FrameStats {
    pub const CSV_HEADER: &'static str = "frame,finest_level,tiles_considered,tiles_culled,tiles_drawn,refined_r0,refined_r1,refined_r2,refined_r3,refined_r4,refined_r5,refined_r6,instances,tiles_late,tiles_unbounded,triangles,draw_calls,bytes_clipmap,bytes_refined,bytes_uploaded,budget_spills,pool_hits,pool_misses,prefetched,cpu_select_us,cpu_upload_us,cpu_record_us,gpu_upload_ms,gpu_terrain_ms";

    pub fn csv_row(&self) -> String {
        let r = &self.tiles_by_refinement;
        format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.1},{:.1},{:.1},{:.3},{:.3}",
            self.frame,
            self.finest_level,
            self.tiles_considered,
            self.tiles_culled,
            self.tiles_drawn,
            r[0],
            r[1],
            r[2],
            r[3],
            r[4],
            r[5],
            r[6],
            self.instances,
            self.tiles_late,
            self.tiles_unbounded,
            self.triangles,
            self.draw_calls,
            self.bytes_clipmap,
            self.bytes_refined,
            self.bytes_uploaded,
            self.budget_spills,
            self.pool_hits,
            self.pool_misses,
            self.prefetched,
            self.cpu_select_us,
            self.cpu_upload_us,
            self.cpu_record_us,
            self.gpu_upload_ms,
            self.gpu_terrain_ms
        )
    }
}

/// What loading a dataset onto the GPU did.
#[derive(Debug, Clone, Copy, Default)]
pub struct UploadStats {
    pub bytes: u64,
    /// Submissions the upload was split into (by the per-frame staging budget).
    pub submissions: u32,
    pub levels: u32,
}

/// Per-frame-in-flight device buffers, filled from the staging ring each frame.
struct FrameBuffers {
    uniforms: Buffer,
    instances: Buffer,
    indirect: Buffer,
    /// TileInstance slots in `instances`.
    instance_capacity: usize,
}

impl FrameBuffers {
    fn destroy(&mut self, device: &Device) {
        self.indirect.destroy(device);
        self.instances.destroy(device);
        self.uniforms.destroy(device);
    }
}

/// A refined-tile pool: the LRU bookkeeping and its texture array (one layer per slot).
struct PoolTexture {
    image: Image2d,
    /// Samples per slot side: 2^r(m−1)+1.
    side: u32,
    lru: RefinedTilePool,
}

/// FNV-1a over every selected node: channels drawn from one shared selection report the same.
fn selection_digest(sel: &Selection) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for i in &sel.items {
        for v in [
            i.level,
            i.tx,
            i.ty,
            i.refinement,
            i.node_level,
            i.node_tx,
            i.node_ty,
        ] {
            h = (h ^ v as u64).wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

/// One region of a texture to fill from the dataset: texel rectangle in `layer`, and the
/// dataset samples `origin + (i, j)·step`.
#[derive(Debug, Clone, Copy)]
struct ImageUpload {
    layer: u32,
    texel: [u32; 2],
    size: [u32; 2],
    origin_sample: [i64; 2],
    step: u32,
}

impl ImageUpload {
    fn bytes(&self) -> u64 {
        self.size[0] as u64 * self.size[1] as u64 * 4
    }
}

/// Where in the shared index buffer the tile's indices live.
#[derive(Debug, Clone, Copy, Default)]
struct IndexRange {
    first: u32,
    count: u32,
}

/// The dataset on the GPU: level textures (one array layer per level, toroidal), pools, and
/// the per-frame buffers sized for the worst selection.
struct GpuTerrain {
    dataset: Arc<Dataset>,
    bake: Arc<ErrorBake>,
    clipmap: ClipmapDesc,
    levels: Image2d,
    caches: Vec<Option<CacheRegion>>,
    pools: Vec<PoolTexture>,
    frame_buffers: Vec<FrameBuffers>,
    prev_eye: Option<DVec3>,
}

/// Owns every Vulkan object. Destroyed explicitly in reverse creation order by
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
    index_range: IndexRange,
    terrain: Option<GpuTerrain>,
    desc: RendererDesc,
    timed: [bool; FRAMES_IN_FLIGHT],
    frame_counter: u64,
    selection: Selection,
    prefetch_selection: Selection,
    instances: [Vec<TileInstance>; RESOLUTIONS],
    /// What is drawn this frame: selected nodes (late tiles coarsened) with their pool slot.
    draw_list: Vec<(DrawItem, u32)>,
    /// Channels sharing one selection (issue 7): when set, every frame selects tiles for all of
    /// them (per tile the largest ρ/τ among the channels that see it), whichever one is drawn.
    channels: Vec<(Camera, (u32, u32), f64)>,
    /// Statistics panel copied into the top-left corner of every frame while set (overlay.rs).
    overlay: Option<crate::tools::overlay::Panel>,
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
        if !(3..=257).contains(&desc.tile_size) || !(desc.tile_size - 1).is_power_of_two() {
            return Err(VkError::Other(format!(
                "tile size {} must be 2^j + 1 in 3..=257",
                desc.tile_size
            )));
        }
        if !(desc.skirt_factor >= 1.0 && desc.skirt_min_m >= 0.0) {
            return Err(VkError::Other(format!(
                "skirt factor {} must be ≥ 1 and minimum {} m ≥ 0",
                desc.skirt_factor, desc.skirt_min_m
            )));
        }
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
        // Every instance is one m×m node with its skirt: one shared index list.
        let indices = skirted_tile_indices(desc.tile_size);
        let index_range = IndexRange {
            first: 0,
            count: indices.len() as u32,
        };
        let parts = Self::create_parts(&device, desc, indices.len() as u64 * 4);
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
            index_range,
            terrain: None,
            desc: desc.clone(),
            timed: [false; FRAMES_IN_FLIGHT],
            frame_counter: 0,
            selection: Selection::default(),
            prefetch_selection: Selection::default(),
            instances: Default::default(),
            draw_list: Vec::new(),
            channels: Vec::new(),
            overlay: None,
            destroyed: false,
        };
        let dst = this.tile_index_buffer.raw;
        if let Err(e) = this.stream_buffer(bytemuck::cast_slice(&indices), dst) {
            this.destroy();
            return Err(e);
        }
        Ok(this)
    }

    #[allow(clippy::type_complexity)]
    fn create_parts(
        d: &Device,
        desc: &RendererDesc,
        index_bytes: u64,
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
                descriptor_count: 4 * (1 + MAX_REFINEMENT),
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

    pub fn desc(&self) -> &RendererDesc {
        &self.desc
    }

    /// Makes the following frames select tiles once for all these channels (camera, viewport,
    /// τ), so adjacent channels draw every shared tile at the same resolution and seams match.
    /// Empty = select for the camera being drawn only.
    pub fn set_channels(&mut self, channels: Vec<(Camera, (u32, u32), f64)>) {
        self.channels = channels;
    }

    /// Draws `panel` over the top-left corner of the following frames (None: no overlay).
    pub fn set_overlay(&mut self, panel: Option<crate::tools::overlay::Panel>) {
        self.overlay = panel;
    }

    /// Changes the LOD decision (mode, τ, curvature...) for the following frames.
    pub fn set_select_params(&mut self, params: SelectParams) {
        self.desc.select = params;
    }

    /// Pool counters (hits, misses, evictions, late) per refinement r = 1..=6.
    pub fn pool_counters(&self) -> Vec<aerie_terrain::pool::PoolCounters> {
        self.terrain
            .as_ref()
            .map(|t| t.pools.iter().map(|p| p.lru.counters()).collect())
            .unwrap_or_default()
    }

    /// Starts the next frame context: waits for its fence, opens its staging region and resets
    /// its descriptor pool.
    fn begin_context(&mut self) -> Result<usize, VkError> {
        self.begin_context_timed().map(|(i, _)| i)
    }

    /// As [`Self::begin_context`], also returning the GPU pass times of the frame that last used
    /// the context when it was submitted without waiting (windowed presentation).
    fn begin_context_timed(&mut self) -> Result<(usize, Option<[f64; 2]>), VkError> {
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

    /// Uploads bytes into a device buffer through the ring, in as many submissions as the
    /// per-frame budget requires.
    fn stream_buffer(&mut self, bytes: &[u8], dst: vk::Buffer) -> Result<(), VkError> {
        let chunk = (self.staging.budget() / 2).max(4) / 4 * 4;
        let mut done = 0usize;
        while done < bytes.len() {
            let n = (bytes.len() - done).min(chunk as usize);
            let i = self.begin_context()?;
            let offset = self.staging.push(&bytes[done..done + n], 4)?;
            let cmd = self.frames.begin_recording(&self.device, i)?;
            let region = vk::BufferCopy {
                src_offset: offset,
                dst_offset: done as u64,
                size: n as u64,
            };
            unsafe {
                let d = &self.device.raw;
                d.cmd_copy_buffer(cmd, self.staging.raw(), dst, &[region]);
                let barrier = vk::MemoryBarrier::default()
                    .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                    .dst_access_mask(vk::AccessFlags::INDEX_READ | vk::AccessFlags::SHADER_READ);
                d.cmd_pipeline_barrier(
                    cmd,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::PipelineStageFlags::VERTEX_INPUT | vk::PipelineStageFlags::VERTEX_SHADER,
                    vk::DependencyFlags::empty(),
                    &[barrier],
                    &[],
                    &[],
                );
            }
            self.frames.submit(&self.device, i)?;
            done += n;
        }
        Ok(())
    }

    /// Loads a dataset and its bake: creates the level textures and pools and fills every level
    /// around `eye` (streamed through the ring over as many submissions as the budget needs).
    pub fn load_terrain(
        &mut self,
        dataset: Arc<Dataset>,
        bake: Arc<ErrorBake>,
        eye: DVec3,
    ) -> Result<UploadStats, VkError> {
        let hf = &dataset.hf;
        if bake.width as usize != hf.width || bake.height as usize != hf.height {
            return Err(VkError::Other(format!(
                "bake is for {}x{} samples, dataset has {}x{}",
                bake.width, bake.height, hf.width, hf.height
            )));
        }
        if bake.params.tile_size != self.desc.tile_size {
            return Err(VkError::Other(format!(
                "bake uses tiles of {} vertices, renderer {}: re-bake with --tile-size {}",
                bake.params.tile_size, self.desc.tile_size, self.desc.tile_size
            )));
        }
        let clipmap = ClipmapDesc {
            tile_quads: self.desc.tile_size - 1,
            patch_tiles: self.desc.patch_tiles,
            margin_tiles: self.desc.margin_tiles,
            width: hf.width as u32,
            height: hf.height as u32,
        };
        clipmap
            .validate()
            .map_err(|e| VkError::Other(format!("clipmap: {e}")))?;
        let level_count = clipmap.level_count();
        if bake.levels.len() < level_count as usize {
            return Err(VkError::Other(format!(
                "bake has {} levels, the clipmap needs {level_count}: re-bake with --levels 0",
                bake.levels.len()
            )));
        }
        let side = clipmap.texture_side();
        let max = self.device.properties.limits.max_image_dimension2_d;
        let max_layers = self.device.properties.limits.max_image_array_layers;
        if side > max || level_count > max_layers {
            return Err(VkError::Other(format!(
                "level textures of {side}² × {level_count} exceed this device's limits ({max}², {max_layers} layers)"
            )));
        }
        if let Some(mut old) = self.terrain.take() {
            self.wait_all()?;
            Self::destroy_terrain(&self.device, &mut old);
        }
        let d = &self.device;
        let image_desc = |w: u32, layers: u32| ImageDesc {
            width: w,
            height: w,
            format: vk::Format::R32_SFLOAT,
            usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
            aspect: vk::ImageAspectFlags::COLOR,
            layers,
        };
        let mut levels = Image2d::new(d, "level textures", image_desc(side, level_count))?;
        let mut pools: Vec<PoolTexture> = Vec::new();
        for r in 1..=MAX_REFINEMENT {
            let capacity = self.desc.pool_capacity[r as usize - 1];
            let slot_side = (clipmap.tile_quads << r) + 1;
            let (w, layers) = if capacity == 0 {
                (1, 1) // a placeholder so every binding is valid
            } else {
                (slot_side, capacity)
            };
            if w > max || layers > max_layers {
                for mut p in pools {
                    p.image.destroy(d);
                }
                levels.destroy(d);
                return Err(VkError::Other(format!(
                    "pool r={r}: {layers} slots of {w}² exceed this device's limits"
                )));
            }
            match Image2d::new(d, "refined-tile pool", image_desc(w, layers)) {
                Ok(image) => pools.push(PoolTexture {
                    image,
                    side: slot_side,
                    lru: RefinedTilePool::new(capacity),
                }),
                Err(e) => {
                    for mut p in pools {
                        p.image.destroy(d);
                    }
                    levels.destroy(d);
                    return Err(e);
                }
            }
        }
        // Nodes per frame: every ring tile of every level plus the coarsest grid when nothing is
        // refined, up to 4^r nodes per refined tile — capped at MAX_INSTANCES (an error names
        // the count if a selection ever exceeds it).
        let [cx, cy] = clipmap.dataset_tiles(level_count - 1);
        let ring_tiles =
            (level_count * clipmap.patch_tiles * clipmap.patch_tiles + cx * cy) as usize;
        let max_instances = (ring_tiles * 16).clamp(4096, INITIAL_MAX_INSTANCES);
        let mut frame_buffers = Vec::new();
        for _ in 0..FRAMES_IN_FLIGHT {
            match Self::create_frame_buffers(d, max_instances) {
                Ok(b) => frame_buffers.push(b),
                Err(e) => {
                    for mut b in frame_buffers {
                        b.destroy(d);
                    }
                    for mut p in pools {
                        p.image.destroy(d);
                    }
                    levels.destroy(d);
                    return Err(e);
                }
            }
        }
        self.terrain = Some(GpuTerrain {
            dataset,
            bake,
            caches: vec![None; level_count as usize],
            clipmap,
            levels,
            pools,
            frame_buffers,
            prev_eye: None,
        });
        self.initialise_images()?;
        // First fill of every level around the eye, streamed.
        let jobs = self.plan_clipmap_updates(eye);
        let bytes = jobs.iter().map(ImageUpload::bytes).sum();
        let submissions = self.stream_image_uploads(&jobs)?;
        Ok(UploadStats {
            bytes,
            submissions,
            levels: level_count,
        })
    }

    /// Moves every texture into SHADER_READ_ONLY, the layout it rests in between uploads.
    fn initialise_images(&mut self) -> Result<(), VkError> {
        let i = self.begin_context()?;
        let cmd = self.frames.begin_recording(&self.device, i)?;
        let t = self.terrain.as_ref().expect("terrain set");
        let images = std::iter::once(t.levels.raw).chain(t.pools.iter().map(|p| p.image.raw));
        for image in images {
            transition(
                &self.device,
                cmd,
                image,
                vk::ImageAspectFlags::COLOR,
                (
                    vk::ImageLayout::UNDEFINED,
                    vk::PipelineStageFlags::TOP_OF_PIPE,
                    vk::AccessFlags::empty(),
                ),
                (
                    vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                    vk::PipelineStageFlags::VERTEX_SHADER,
                    vk::AccessFlags::SHADER_READ,
                ),
            );
        }
        self.frames.submit(&self.device, i)
    }

    /// Decides which level-texture regions must be (re)loaded for an eye position and records
    /// the new cache regions. Levels that did not move yield nothing.
    fn plan_clipmap_updates(&mut self, eye: DVec3) -> Vec<ImageUpload> {
        let t = self.terrain.as_mut().expect("terrain set");
        let hf = &t.dataset.hf;
        let viewer = [eye.x / hf.spacing_x, eye.y / hf.spacing_y];
        let placements = place_levels(&t.clipmap, viewer);
        let side = t.clipmap.texture_side();
        let mut jobs = Vec::new();
        for p in &placements {
            let (region, rects) = update_cache(&t.clipmap, t.caches[p.level as usize].as_ref(), p);
            for rect in &rects {
                for piece in toroidal_pieces(rect, side) {
                    let step = 1u32 << p.level;
                    jobs.push(ImageUpload {
                        layer: p.level,
                        texel: piece.texel,
                        size: piece.size,
                        origin_sample: [
                            (rect.origin[0] + piece.src_offset[0] as i64) * step as i64,
                            (rect.origin[1] + piece.src_offset[1] as i64) * step as i64,
                        ],
                        step,
                    });
                }
            }
            t.caches[p.level as usize] = Some(region);
        }
        jobs
    }

    /// Uploads level-texture regions in as many submissions as the budget requires (rows of a
    /// region are split across submissions when needed). Returns the submission count.
    fn stream_image_uploads(&mut self, jobs: &[ImageUpload]) -> Result<u32, VkError> {
        let mut pending: std::collections::VecDeque<ImageUpload> = jobs.iter().copied().collect();
        let mut submissions = 0;
        while !pending.is_empty() {
            let i = self.begin_context()?;
            let mut copies = Vec::new();
            while let Some(job) = pending.pop_front() {
                let row_bytes = job.size[0] as u64 * 4;
                let fit_rows = (self.staging.remaining().saturating_sub(64) / row_bytes) as u32;
                if fit_rows == 0 {
                    if copies.is_empty() {
                        return Err(VkError::Staging(format!(
                            "one level-texture row ({row_bytes} bytes) exceeds the per-frame staging budget ({} bytes)",
                            self.staging.budget()
                        )));
                    }
                    pending.push_front(job);
                    break;
                }
                let rows = fit_rows.min(job.size[1]);
                let (head, tail) = split_rows(&job, rows);
                copies.push(self.stage_upload(&head)?);
                if let Some(tail) = tail {
                    pending.push_front(tail);
                    break;
                }
            }
            let cmd = self.frames.begin_recording(&self.device, i)?;
            let t = self.terrain.as_ref().expect("terrain set");
            record_image_copies(&self.device, cmd, self.staging.raw(), t.levels.raw, &copies);
            self.frames.submit(&self.device, i)?;
            submissions += 1;
        }
        Ok(submissions)
    }

    /// Gathers one upload's samples into the open staging region; returns its copy region.
    fn stage_upload(&mut self, job: &ImageUpload) -> Result<vk::BufferImageCopy, VkError> {
        let t = self.terrain.as_ref().expect("terrain set");
        stage_gather(&mut self.staging, &t.dataset.hf, job)
    }

    fn create_frame_buffers(d: &Device, max_instances: usize) -> Result<FrameBuffers, VkError> {
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
                (max_instances.max(1) * std::mem::size_of::<TileInstance>()) as u64,
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
                (std::mem::size_of::<DrawIndexedIndirect>() * RESOLUTIONS) as u64,
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
            instance_capacity: max_instances.max(1),
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
        if self.terrain.is_none() {
            return Err(VkError::Other("render called before load_terrain".into()));
        }
        let mut stats = FrameStats {
            frame: self.frame_counter,
            ..Default::default()
        };
        let viewport = (self.target.width, self.target.height);

        // Clipmap placement and tile selection (pure CPU).
        let t0 = Instant::now();
        let mut clip_jobs = self.plan_clipmap_updates(camera.position);
        {
            let t = self.terrain.as_ref().expect("checked");
            let hf = &t.dataset.hf;
            let viewer = [
                camera.position.x / hf.spacing_x,
                camera.position.y / hf.spacing_y,
            ];
            let placements = place_levels(&t.clipmap, viewer);
            if self.channels.is_empty() {
                select_tiles(
                    &t.bake,
                    &t.clipmap,
                    &placements,
                    camera,
                    viewport,
                    &self.desc.select,
                    &mut self.selection,
                );
            } else {
                let views: Vec<View> = self
                    .channels
                    .iter()
                    .map(|(c, vp, tau)| View {
                        camera: c,
                        viewport: *vp,
                        tau_px: *tau,
                    })
                    .collect();
                select_tiles_multi(
                    &t.bake,
                    &t.clipmap,
                    &placements,
                    &views,
                    &self.desc.select,
                    &mut self.selection,
                );
            }
        }
        stats.selection_digest = selection_digest(&self.selection);
        stats.cpu_select_us = t0.elapsed().as_secs_f64() * 1e6;
        stats.finest_level = self.selection.finest_level;
        stats.tiles_unbounded = self.selection.unbounded;
        for l in &self.selection.levels {
            stats.tiles_considered += l.considered;
            stats.tiles_culled += l.culled;
            stats.tiles_drawn += l.drawn;
            for (sum, n) in stats.tiles_by_refinement.iter_mut().zip(l.refined) {
                *sum += n;
            }
        }

        // Uploads: clipmap strips first (mandatory), then pool misses within what is left.
        let t1 = Instant::now();
        let fixed_reserve = 1024
            + (std::mem::size_of::<DrawIndexedIndirect>() * RESOLUTIONS) as u64
            + (self.selection.items.len() * std::mem::size_of::<TileInstance>()) as u64
            + self.overlay.as_ref().map_or(0, |p| p.bytes() + 16);
        let clip_bytes: u64 = clip_jobs.iter().map(ImageUpload::bytes).sum();
        if clip_bytes + fixed_reserve + 64 * clip_jobs.len() as u64 > self.staging.budget() {
            // A jump (or a tiny budget): stream the level updates before this frame.
            stats.budget_spills = self.stream_image_uploads(&clip_jobs)?;
            stats.bytes_clipmap += clip_bytes;
            clip_jobs.clear();
        }
        let (i, previous_gpu) = self.begin_context_timed()?;
        let mut clip_copies = Vec::with_capacity(clip_jobs.len());
        for job in &clip_jobs {
            clip_copies.push(self.stage_upload(job)?);
            stats.bytes_clipmap += job.bytes();
        }
        let mut pool_copies: [Vec<vk::BufferImageCopy>; MAX_REFINEMENT as usize] =
            Default::default();
        self.resolve_refined_tiles(&mut stats, &mut pool_copies, fixed_reserve)?;
        self.prefetch(
            camera,
            viewport,
            &mut stats,
            &mut pool_copies,
            fixed_reserve,
        )?;
        self.build_instances(camera, &mut stats);
        let t = self.terrain.as_ref().expect("checked");
        let mut draws = [DrawIndexedIndirect::default(); RESOLUTIONS];
        let mut first_instance = 0u32;
        for (r, draw) in draws.iter_mut().enumerate() {
            let n = self.instances[r].len() as u32;
            let range = self.index_range;
            *draw = DrawIndexedIndirect {
                index_count: range.count,
                instance_count: if range.count == 0 { 0 } else { n },
                first_index: range.first,
                vertex_offset: 0,
                first_instance,
            };
            first_instance += n;
            stats.triangles += n as u64 * (range.count as u64 / 3);
        }
        let total_instances = first_instance as usize;
        if total_instances > MAX_INSTANCES {
            return Err(VkError::Other(format!(
                "selection of {total_instances} tiles exceeds the largest instance buffer ({MAX_INSTANCES})"
            )));
        }
        if total_instances > t.frame_buffers[i].instance_capacity {
            // Grow this frame's buffers: their fence has signalled (begin_context waited), so
            // nothing in flight reads them.
            let grown = Self::create_frame_buffers(
                &self.device,
                total_instances.next_power_of_two().min(MAX_INSTANCES),
            )?;
            let t = self.terrain.as_mut().expect("checked");
            let mut old = std::mem::replace(&mut t.frame_buffers[i], grown);
            old.destroy(&self.device);
        }
        let t = self.terrain.as_ref().expect("checked");
        let uniforms = frame_uniforms(camera, t, &self.desc);
        let off_uniforms = self.staging.push(&[uniforms], 16)?;
        let off_draws = self.staging.push(&draws, 4)?;
        let mut off_instances = None;
        if total_instances > 0 {
            let (offset, bytes) = self.staging.alloc(
                (total_instances * std::mem::size_of::<TileInstance>()) as u64,
                16,
            )?;
            let out: &mut [TileInstance] = bytemuck::cast_slice_mut(bytes);
            let mut k = 0;
            for group in &self.instances {
                out[k..k + group.len()].copy_from_slice(group);
                k += group.len();
            }
            off_instances = Some(offset);
        }
        let off_overlay = match &self.overlay {
            Some(p) if p.bytes() > 0 => Some(self.staging.push(&p.rgba, 16)?),
            _ => None,
        };
        stats.bytes_uploaded = self.staging.used();
        stats.cpu_upload_us = t1.elapsed().as_secs_f64() * 1e6;

        // Record.
        let t2 = Instant::now();
        let d = &self.device;
        let fb = &t.frame_buffers[i];
        let set = self.descriptors.allocate(d, i, self.pipeline.set_layout)?;
        write_descriptors(d, set, fb, t, self.pipeline.height_sampler);
        let cmd = self.frames.begin_recording(d, i)?;
        self.timer.reset(d, cmd, i);
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
            off_draws,
            std::mem::size_of_val(&draws) as u64,
        );
        if let Some(off) = off_instances {
            let size = (total_instances * std::mem::size_of::<TileInstance>()) as u64;
            copy(fb.instances.raw, off, size);
        }
        record_image_copies(d, cmd, src, t.levels.raw, &clip_copies);
        for (p, copies) in t.pools.iter().zip(&pool_copies) {
            record_image_copies(d, cmd, src, p.image.raw, copies);
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

        self.timer.begin(d, cmd, i, Pass::Terrain);
        self.target.record_begin(d, cmd);
        let draw_count = if total_instances > 0 {
            RESOLUTIONS as u32
        } else {
            0
        };
        record_terrain_pass(
            d,
            cmd,
            &self.target,
            &self.pipeline,
            set,
            self.tile_index_buffer.raw,
            fb.indirect.raw,
            draw_count,
        );
        stats.draw_calls = (draw_count > 0) as u32;
        self.timer.end(d, cmd, i, Pass::Terrain);
        if let (Some(p), Some(off)) = (&self.overlay, off_overlay) {
            let extent = (self.target.width, self.target.height);
            crate::tools::overlay::record_panel_copy(
                d,
                cmd,
                src,
                off,
                self.target.colour.raw,
                extent,
                p,
            );
        }
        match present {
            None => {
                self.target.record_readback(d, cmd);
                self.frames.submit(d, i)?;
            }
            Some(p) => {
                self.target.record_blit_to(d, cmd, p.image, p.extent);
                self.frames.submit_with(
                    d,
                    i,
                    &[p.acquired],
                    &[vk::PipelineStageFlags::TRANSFER],
                    &[p.rendered],
                )?;
            }
        }
        self.timed[i] = true;
        stats.cpu_record_us = t2.elapsed().as_secs_f64() * 1e6;

        if present.is_none() {
            // Headless: wait for this frame so its image and timings can be read.
            self.frames.wait(&self.device, i)?;
            self.timed[i] = false;
            let gpu = self.timer.read_ms(&self.device, i)?;
            stats.gpu_upload_ms = gpu[Pass::Upload as usize];
            stats.gpu_terrain_ms = gpu[Pass::Terrain as usize];
        } else if let Some(gpu) = previous_gpu {
            stats.gpu_upload_ms = gpu[Pass::Upload as usize];
            stats.gpu_terrain_ms = gpu[Pass::Terrain as usize];
        }
        if let Some(t) = self.terrain.as_mut() {
            t.prev_eye = Some(camera.position);
        }
        self.frame_counter += 1;
        Ok(stats)
    }

    /// Finds or uploads the pool slot of every refined ring tile (its nodes follow one another in
    /// the selection). A miss that does not fit the budget leaves the tile at its best resident
    /// resolution — its nodes coarsened to that level — and is counted late.
    fn resolve_refined_tiles(
        &mut self,
        stats: &mut FrameStats,
        copies: &mut [Vec<vk::BufferImageCopy>; MAX_REFINEMENT as usize],
        reserve: u64,
    ) -> Result<(), VkError> {
        let frame = self.frame_counter;
        let t = self.terrain.as_mut().expect("checked");
        for p in &mut t.pools {
            p.lru.begin_frame(frame);
        }
        let q = t.clipmap.tile_quads;
        self.draw_list.clear();
        let items = &self.selection.items;
        let mut k = 0;
        while k < items.len() {
            let first = items[k];
            let end = k + items[k..]
                .iter()
                .take_while(|i| (i.level, i.tx, i.ty) == (first.level, first.tx, first.ty))
                .count();
            let group = &items[k..end];
            k = end;
            let r = first.refinement;
            if r == 0 {
                self.draw_list.extend(group.iter().map(|&i| (i, 0)));
                continue;
            }
            let key = TileKey {
                level: first.level,
                tx: first.tx,
                ty: first.ty,
                refinement: r,
            };
            let pool = &mut t.pools[r as usize - 1];
            let slot_bytes = pool.side as u64 * pool.side as u64 * 4;
            let staging = &self.staging;
            let mut can = || staging.remaining() >= slot_bytes + reserve + 256;
            let (resident_r, slot) = match pool.lru.request(key, &mut can) {
                Request::Hit { slot } => {
                    stats.pool_hits += 1;
                    (r, slot)
                }
                Request::Miss { slot, .. } => {
                    stats.pool_misses += 1;
                    let job = refined_upload(q, &key, slot, pool.side);
                    copies[r as usize - 1].push(stage_gather(
                        &mut self.staging,
                        &t.dataset.hf,
                        &job,
                    )?);
                    stats.bytes_refined += job.bytes();
                    (r, slot)
                }
                Request::Unavailable => {
                    stats.tiles_late += 1;
                    // Best resident resolution below r (r = 0, the clipmap, is always there).
                    let mut best = (0, 0);
                    for lower in (1..r).rev() {
                        let k2 = TileKey {
                            refinement: lower,
                            ..key
                        };
                        let p2 = &mut t.pools[lower as usize - 1];
                        if p2.lru.is_resident(&k2) {
                            if let Request::Hit { slot } = p2.lru.request(k2, &mut || false) {
                                best = (lower, slot);
                                break;
                            }
                        }
                    }
                    best
                }
            };
            if resident_r == r {
                self.draw_list.extend(group.iter().map(|&i| (i, slot)));
                continue;
            }
            // Coarsen: nodes finer than level L − r' become their ancestor at that level.
            let floor = first.level - resident_r;
            let start = self.draw_list.len();
            for &i in group {
                let up = floor.saturating_sub(i.node_level);
                let node_level = i.node_level.max(floor);
                let (node_tx, node_ty) = (i.node_tx >> up, i.node_ty >> up);
                let coarse = DrawItem {
                    refinement: resident_r,
                    node_level,
                    node_tx,
                    node_ty,
                    eps_m: t.bake.eps(node_level, node_tx, node_ty),
                    ..i
                };
                let seen = self.draw_list[start..].iter().any(|(d, _)| {
                    (d.node_level, d.node_tx, d.node_ty) == (node_level, node_tx, node_ty)
                });
                if !seen {
                    self.draw_list.push((coarse, slot));
                }
            }
        }
        Ok(())
    }

    /// Uploads, with whatever budget is left, the refined tiles the eye will need
    /// `prefetch_frames` frames from now along its motion (DESIGN.md "Pools": we budget and
    /// prefetch them). Never evicts a slot used in the last two frames.
    fn prefetch(
        &mut self,
        camera: &Camera,
        viewport: (u32, u32),
        stats: &mut FrameStats,
        copies: &mut [Vec<vk::BufferImageCopy>; MAX_REFINEMENT as usize],
        reserve: u64,
    ) -> Result<(), VkError> {
        let t = self.terrain.as_mut().expect("checked");
        let Some(prev) = t.prev_eye else {
            return Ok(());
        };
        let motion = camera.position - prev;
        if motion.length_squared() < 1e-6 || self.desc.prefetch_frames <= 0.0 {
            return Ok(());
        }
        let ahead = Camera {
            position: camera.position + motion * self.desc.prefetch_frames,
            ..*camera
        };
        let hf = &t.dataset.hf;
        let viewer = [
            ahead.position.x / hf.spacing_x,
            ahead.position.y / hf.spacing_y,
        ];
        let placements = place_levels(&t.clipmap, viewer);
        select_tiles(
            &t.bake,
            &t.clipmap,
            &placements,
            &ahead,
            viewport,
            &self.desc.select,
            &mut self.prefetch_selection,
        );
        let q = t.clipmap.tile_quads;
        let mut last = None;
        for item in &self.prefetch_selection.items {
            if item.refinement == 0 || last == Some((item.level, item.tx, item.ty)) {
                continue;
            }
            last = Some((item.level, item.tx, item.ty));
            let key = TileKey {
                level: item.level,
                tx: item.tx,
                ty: item.ty,
                refinement: item.refinement,
            };
            let pool = &mut t.pools[item.refinement as usize - 1];
            if pool.lru.is_resident(&key) || pool.lru.capacity() == 0 {
                continue;
            }
            let slot_bytes = pool.side as u64 * pool.side as u64 * 4;
            let staging = &self.staging;
            let mut can = || staging.remaining() >= slot_bytes + reserve + 256;
            if let Request::Miss { slot, .. } = pool.lru.prefetch(key, &mut can, 2) {
                let job = refined_upload(q, &key, slot, pool.side);
                copies[item.refinement as usize - 1].push(stage_gather(
                    &mut self.staging,
                    &t.dataset.hf,
                    &job,
                )?);
                stats.bytes_refined += job.bytes();
                stats.prefetched += 1;
            } else if self.staging.remaining() < slot_bytes + reserve + 256 {
                break;
            }
        }
        Ok(())
    }

    /// Per-instance data grouped by refinement (unrefined first, then r = 1..): node origin
    /// relative to the eye (f64 → f32), sample origin, vertex step, level, pool slot and the
    /// node's place in it, skirt depth.
    fn build_instances(&mut self, camera: &Camera, stats: &mut FrameStats) {
        let t = self.terrain.as_ref().expect("checked");
        let q = t.clipmap.tile_quads as i64;
        let hf = &t.dataset.hf;
        for g in &mut self.instances {
            g.clear();
        }
        let nodes: Vec<(u32, u32, u32, f32)> = self
            .draw_list
            .iter()
            .map(|(i, _)| (i.node_level, i.node_tx, i.node_ty, i.eps_m))
            .collect();
        let reach = neighbour_eps(&nodes);
        for (&(item, slot), &reach_m) in self.draw_list.iter().zip(&reach) {
            let node = q << item.node_level;
            let origin = [item.node_tx as i64 * node, item.node_ty as i64 * node];
            let r = item.refinement;
            let (mut slot_x, mut slot_y, mut slot_stride) = (0, 0, 1);
            if r > 0 {
                // The slot holds the ring tile at level L − r.
                let tile = q << item.level;
                let slot_step = 1i64 << (item.level - r);
                slot_x = ((origin[0] - item.tx as i64 * tile) / slot_step) as u32;
                slot_y = ((origin[1] - item.ty as i64 * tile) / slot_step) as u32;
                slot_stride = 1u32 << (item.node_level - (item.level - r));
            }
            self.instances[r as usize].push(TileInstance {
                origin_rel: [
                    (origin[0] as f64 * hf.spacing_x - camera.position.x) as f32,
                    (origin[1] as f64 * hf.spacing_y - camera.position.y) as f32,
                ],
                origin_sample: [origin[0] as i32, origin[1] as i32],
                step: 1 << item.node_level,
                level: item.level,
                refinement: r,
                slot,
                // ε + max(ε, neighbours' ε) at the default factor 2 (see neighbour_eps).
                skirt_m: 0.5 * self.desc.skirt_factor * (item.eps_m + reach_m)
                    + self.desc.skirt_min_m,
                slot_x,
                slot_y,
                slot_stride,
            });
            stats.instances += 1;
        }
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
        for p in &mut t.pools {
            p.image.destroy(device);
        }
        t.levels.destroy(device);
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

/// Gathers one upload's samples straight into the open staging region; returns its copy region.
fn stage_gather(
    staging: &mut StagingRing,
    hf: &aerie_terrain::Heightfield,
    job: &ImageUpload,
) -> Result<vk::BufferImageCopy, VkError> {
    let (offset, bytes) = staging.alloc(job.bytes(), 4)?;
    gather(
        hf,
        job.origin_sample,
        job.step,
        job.size,
        bytemuck::cast_slice_mut(bytes),
    );
    Ok(buffer_image_copy(offset, job))
}

/// The upload of refined tile `key` into `slot`: (2^r q + 1)² samples at stride 2^(L−r).
fn refined_upload(q: u32, key: &TileKey, slot: u32, side: u32) -> ImageUpload {
    let tile = (q as i64) << key.level;
    ImageUpload {
        layer: slot,
        texel: [0, 0],
        size: [side, side],
        origin_sample: [key.tx as i64 * tile, key.ty as i64 * tile],
        step: 1 << (key.level - key.refinement),
    }
}

/// Splits an upload after `rows` rows.
fn split_rows(job: &ImageUpload, rows: u32) -> (ImageUpload, Option<ImageUpload>) {
    if rows >= job.size[1] {
        return (*job, None);
    }
    let head = ImageUpload {
        size: [job.size[0], rows],
        ..*job
    };
    let tail = ImageUpload {
        texel: [job.texel[0], job.texel[1] + rows],
        size: [job.size[0], job.size[1] - rows],
        origin_sample: [
            job.origin_sample[0],
            job.origin_sample[1] + rows as i64 * job.step as i64,
        ],
        ..*job
    };
    (head, Some(tail))
}

fn buffer_image_copy(offset: u64, job: &ImageUpload) -> vk::BufferImageCopy {
    vk::BufferImageCopy::default()
        .buffer_offset(offset)
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: job.layer,
            layer_count: 1,
        })
        .image_offset(vk::Offset3D {
            x: job.texel[0] as i32,
            y: job.texel[1] as i32,
            z: 0,
        })
        .image_extent(vk::Extent3D {
            width: job.size[0],
            height: job.size[1],
            depth: 1,
        })
}

/// Copies staged regions into a sampled texture: SHADER_READ_ONLY → TRANSFER_DST (contents kept,
/// after earlier frames' vertex-shader reads), the copies, then back to SHADER_READ_ONLY.
fn record_image_copies(
    device: &Device,
    cmd: vk::CommandBuffer,
    staging: vk::Buffer,
    image: vk::Image,
    copies: &[vk::BufferImageCopy],
) {
    if copies.is_empty() {
        return;
    }
    let sampled = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
    let dst = vk::ImageLayout::TRANSFER_DST_OPTIMAL;
    transition(
        device,
        cmd,
        image,
        vk::ImageAspectFlags::COLOR,
        (
            sampled,
            vk::PipelineStageFlags::VERTEX_SHADER,
            vk::AccessFlags::SHADER_READ,
        ),
        (
            dst,
            vk::PipelineStageFlags::TRANSFER,
            vk::AccessFlags::TRANSFER_WRITE,
        ),
    );
    unsafe {
        device
            .raw
            .cmd_copy_buffer_to_image(cmd, staging, image, dst, copies)
    };
    transition(
        device,
        cmd,
        image,
        vk::ImageAspectFlags::COLOR,
        (
            dst,
            vk::PipelineStageFlags::TRANSFER,
            vk::AccessFlags::TRANSFER_WRITE,
        ),
        (
            sampled,
            vk::PipelineStageFlags::VERTEX_SHADER,
            vk::AccessFlags::SHADER_READ,
        ),
    );
}

fn write_descriptors(
    d: &Device,
    set: vk::DescriptorSet,
    fb: &FrameBuffers,
    t: &GpuTerrain,
    sampler: vk::Sampler,
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
    let image = |view| vk::DescriptorImageInfo {
        sampler,
        image_view: view,
        image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
    };
    let clipmap_info = [image(t.levels.view)];
    let pool_info: Vec<_> = t.pools.iter().map(|p| image(p.image.view)).collect();
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
            .dst_binding(BINDING_CLIPMAP)
            .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
            .image_info(&clipmap_info),
        vk::WriteDescriptorSet::default()
            .dst_set(set)
            .dst_binding(BINDING_POOLS)
            .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
            .image_info(&pool_info),
    ];
    unsafe { d.raw.update_descriptor_sets(&writes, &[]) };
}

/// The terrain pass: clear, bind, one multi-draw indirect (one command per resolution).
#[allow(clippy::too_many_arguments)]
fn record_terrain_pass(
    d: &Device,
    cmd: vk::CommandBuffer,
    target: &OffscreenTarget,
    pipeline: &TerrainPipeline,
    set: vk::DescriptorSet,
    index_buffer: vk::Buffer,
    indirect: vk::Buffer,
    draw_count: u32,
) {
    let (w, h) = (target.width, target.height);
    let colour_attachment = [vk::RenderingAttachmentInfo::default()
        .image_view(target.colour.view)
        .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::STORE)
        .clear_value(vk::ClearValue {
            color: vk::ClearColorValue {
                float32: [SKY_LINEAR[0], SKY_LINEAR[1], SKY_LINEAR[2], 1.0],
            },
        })];
    let depth_attachment = vk::RenderingAttachmentInfo::default()
        .image_view(target.depth.view)
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
        d.raw.cmd_end_rendering(cmd);
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

fn frame_uniforms(camera: &Camera, t: &GpuTerrain, desc: &RendererDesc) -> FrameUniforms {
    let m = camera.relative_world_to_clip_f32();
    let s = sun_direction();
    let hf = &t.dataset.hf;
    let curvature = if desc.select.curvature {
        (1.0 / (2.0 * aerie_terrain::select::EARTH_RADIUS_M)) as f32
    } else {
        0.0
    };
    FrameUniforms {
        relative_world_to_clip: m.to_cols_array_2d(),
        sun_dir: [s[0], s[1], s[2], 0.22],
        sky_colour: [SKY_LINEAR[0], SKY_LINEAR[1], SKY_LINEAR[2], 90_000.0],
        grid_spacing: [
            hf.spacing_x as f32,
            hf.spacing_y as f32,
            camera.position.z as f32,
            curvature,
        ],
        grid_size: [
            t.dataset.valid_width as i32,
            t.dataset.valid_height as i32,
            t.clipmap.tile_quads as i32,
            desc.debug_tiles as i32,
        ],
        clipmap: [t.clipmap.texture_side() as i32, t.caches.len() as i32, 0, 0],
    }
}
