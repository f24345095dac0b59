//! The terrain's GPU objects: level textures (one array layer per level, toroidal), one texture
//! array per refined-tile pool, and the per-frame-in-flight buffers the frame's pushes land in —
//! with the CPU plan state that decides what they hold.

use std::sync::Arc;

use ash::vk;
use gpu_allocator::MemoryLocation;

use aerie_terrain::bake::ErrorBake;
use aerie_terrain::clipmap::ClipmapDesc;
use aerie_terrain::select::MAX_REFINEMENT;
use aerie_terrain::source::{SourceGrid, TerrainSource};

use crate::render::desc::NormalSource;
use crate::render::gpu::{DrawIndexedIndirect, FrameUniforms, GeoPolynomial, TileInstance};
use crate::render::normal_pass::NormalTargets;
use crate::render::plan::{PlanState, MAX_INSTANCES};
use crate::render::pool_atlas::PoolLimits;
use crate::render::terrain_draws::MAX_TERRAIN_DRAWS;
use crate::vk::frame_context::FrameContext;
use crate::vk::image::{Image2d, ImageDesc};
use crate::vk::{Buffer, Device, VkError, FRAMES_IN_FLIGHT};

/// The normal maps' texel format: x and y of the unit normal (z ≥ 0 is reconstructed), 2 bytes
/// a texel, half the heights' 4 (`render/normal_map.rs`).
pub const NORMAL_FORMAT: vk::Format = vk::Format::R8G8_SNORM;

/// Initial instance capacity cap: what every LOD mode but `full` needs at most in practice.
const INITIAL_MAX_INSTANCES: usize = 1 << 16;
/// Initial instance capacity per ring tile: a refined tile draws up to 4^r nodes, but few are.
const INITIAL_INSTANCES_PER_TILE: usize = 16;
/// Initial instance capacity floor, for tiny datasets.
const MIN_INITIAL_INSTANCES: usize = 4096;

/// Per-frame-in-flight device buffers, filled from the staging region each frame.
pub struct FrameBuffers {
    pub uniforms: Buffer,
    pub instances: Buffer,
    /// A projected grid's node polynomials, parallel to `instances`.
    pub polynomials: Buffer,
    pub indirect: Buffer,
    /// TileInstance slots in `instances`.
    pub instance_capacity: usize,
    /// GeoPolynomial slots in `polynomials`: one (never read) until a projected grid's frame
    /// needs more.
    pub polynomial_capacity: usize,
}

impl FrameBuffers {
    pub fn new(
        d: &Device,
        max_instances: usize,
        max_polynomials: usize,
    ) -> Result<FrameBuffers, VkError> {
        let dst = vk::BufferUsageFlags::TRANSFER_DST;
        let mut uniforms = Buffer::new(
            d,
            "frame uniforms",
            std::mem::size_of::<FrameUniforms>() as u64,
            vk::BufferUsageFlags::UNIFORM_BUFFER | dst,
            MemoryLocation::GpuOnly,
        )?;
        let mut instances = match Buffer::new(
            d,
            "tile instances",
            (max_instances.max(1) * std::mem::size_of::<TileInstance>()) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER | dst,
            MemoryLocation::GpuOnly,
        ) {
            Ok(b) => b,
            Err(e) => {
                uniforms.destroy(d);
                return Err(e);
            }
        };
        let mut polynomials = match Buffer::new(
            d,
            "tile polynomials",
            (max_polynomials.max(1) * std::mem::size_of::<GeoPolynomial>()) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER | dst,
            MemoryLocation::GpuOnly,
        ) {
            Ok(b) => b,
            Err(e) => {
                instances.destroy(d);
                uniforms.destroy(d);
                return Err(e);
            }
        };
        let indirect = match Buffer::new(
            d,
            "indirect draws",
            (std::mem::size_of::<DrawIndexedIndirect>() * MAX_TERRAIN_DRAWS) as u64,
            vk::BufferUsageFlags::INDIRECT_BUFFER | dst,
            MemoryLocation::GpuOnly,
        ) {
            Ok(b) => b,
            Err(e) => {
                polynomials.destroy(d);
                instances.destroy(d);
                uniforms.destroy(d);
                return Err(e);
            }
        };
        Ok(FrameBuffers {
            uniforms,
            instances,
            polynomials,
            indirect,
            instance_capacity: max_instances.max(1),
            polynomial_capacity: max_polynomials.max(1),
        })
    }

    /// Call after the device is idle.
    pub fn destroy(&mut self, device: &Device) {
        self.indirect.destroy(device);
        self.polynomials.destroy(device);
        self.instances.destroy(device);
        self.uniforms.destroy(device);
    }
}

/// The terrain on the GPU and the plan state deciding its contents (the source is the plan's).
pub struct GpuTerrain {
    /// What the source serves (grid, spacing, valid extent).
    pub grid: SourceGrid,
    pub levels: Image2d,
    /// The levels' normal maps (same layout, RG8_SNORM, `render/normal_map.rs`); a 1×1
    /// placeholder without normal maps.
    pub normals: Image2d,
    /// One texture array per pool r = 1..=MAX_REFINEMENT (a 1×1 placeholder when r has none).
    pub pool_images: Vec<Image2d>,
    /// One per frame in flight, indexed by the frame context.
    pub frame_buffers: Vec<FrameBuffers>,
    pub plan: PlanState,
}

impl GpuTerrain {
    /// What the GPU normal pass reads and writes of the terrain (the heights fetched through
    /// `height_sampler`).
    pub fn normal_targets(&self, height_sampler: vk::Sampler) -> NormalTargets {
        NormalTargets {
            levels_view: self.levels.view,
            height_sampler,
            normals: self.normals.raw,
            side: self.plan.clipmap.texture_side(),
        }
    }

    /// Creates the textures and per-frame buffers for `source`'s terrain (checked against the
    /// device's limits); their contents are undefined until initialised and filled.
    pub fn new(
        d: &Device,
        source: Arc<dyn TerrainSource>,
        bake: Arc<ErrorBake>,
        clipmap: ClipmapDesc,
        pool_capacity: &[u32; MAX_REFINEMENT as usize],
        pool_layers: Option<u32>,
        normals: Option<NormalSource>,
    ) -> Result<Self, VkError> {
        let normal_maps = normals.is_some();
        Self::check_level_limits(d, &clipmap)?;
        let level_count = clipmap.level_count();
        let side = clipmap.texture_side();
        let max = d.properties.limits.max_image_dimension2_d;
        let max_layers = d.properties.limits.max_image_array_layers;
        let grid = source.grid().clone();
        // Geographic data is drawn on the ellipsoid (`PlanState::new` places it); the rest on
        // the flat plane.
        let mut plan = PlanState::new(bake, source, clipmap, pool_capacity);
        // Each pool's slots laid out within this device's limits: one a layer while they fit
        // its layers, else packed several to a layer (`pool_atlas.rs`).
        plan.fit_pools(PoolLimits {
            max_layers: pool_layers.map_or(max_layers, |l| l.clamp(1, max_layers)),
            max_side: max,
        })
        .map_err(VkError::Other)?;
        let image_desc = |w: u32, layers: u32| ImageDesc {
            width: w,
            height: w,
            format: vk::Format::R32_SFLOAT,
            usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
            aspect: vk::ImageAspectFlags::COLOR,
            layers,
            mips: 1,
        };
        let levels = Image2d::new(d, "level textures", image_desc(side, level_count))?;
        if normals == Some(NormalSource::Cpu) {
            // On the GPU the texels are computed from the level textures (`normal_pass.rs`).
            plan.feed
                .gatherer
                .set_normal_maps(Some([grid.spacing_x, grid.spacing_y]));
        }
        let (nside, nlayers) = if normal_maps {
            (side, level_count)
        } else {
            (1, 1)
        };
        let mut normal_desc = ImageDesc {
            format: NORMAL_FORMAT,
            ..image_desc(nside, nlayers)
        };
        // Read back by the tests of the normal maps (`TerrainRenderer::read_normal_layer`).
        normal_desc.usage |= vk::ImageUsageFlags::TRANSFER_SRC;
        let normals = match Image2d::new(d, "normal maps", normal_desc) {
            Ok(n) => n,
            Err(e) => {
                let mut levels = levels;
                levels.destroy(d);
                return Err(e);
            }
        };
        let mut this = Self {
            grid,
            levels,
            normals,
            pool_images: Vec::new(),
            frame_buffers: Vec::new(),
            plan,
        };
        for (r, pool) in (1..).zip(&this.plan.pools) {
            let (w, layers) = if pool.lru.capacity() == 0 {
                (1, 1) // a placeholder so every binding is valid
            } else {
                (pool.atlas.width(), pool.atlas.layers)
            };
            if w > max || layers > max_layers {
                this.destroy(d);
                return Err(VkError::Other(format!(
                    "pool r={r}: {layers} layers of {w}² exceed this device's limits"
                )));
            }
            match Image2d::new(d, "refined-tile pool", image_desc(w, layers)) {
                Ok(image) => this.pool_images.push(image),
                Err(e) => {
                    this.destroy(d);
                    return Err(e);
                }
            }
        }
        // Nodes per frame: every ring tile of every level plus the coarsest grid when nothing is
        // refined, a few nodes per refined tile — grown on demand up to MAX_INSTANCES.
        let clipmap = &this.plan.clipmap;
        let [cx, cy] = clipmap.dataset_tiles(level_count - 1);
        let ring_tiles =
            (level_count * clipmap.patch_tiles * clipmap.patch_tiles + cx * cy) as usize;
        let max_instances = (ring_tiles * INITIAL_INSTANCES_PER_TILE)
            .clamp(MIN_INITIAL_INSTANCES, INITIAL_MAX_INSTANCES);
        for _ in 0..FRAMES_IN_FLIGHT {
            match FrameBuffers::new(d, max_instances, 1) {
                Ok(b) => this.frame_buffers.push(b),
                Err(e) => {
                    this.destroy(d);
                    return Err(e);
                }
            }
        }
        Ok(this)
    }

    /// Whether this device can hold the level textures of `clipmap`.
    pub fn check_level_limits(d: &Device, clipmap: &ClipmapDesc) -> Result<(), VkError> {
        let (level_count, side) = (clipmap.level_count(), clipmap.texture_side());
        let max = d.properties.limits.max_image_dimension2_d;
        let max_layers = d.properties.limits.max_image_array_layers;
        if side > max || level_count > max_layers {
            return Err(VkError::Other(format!(
                "level textures of {side}² × {level_count} exceed this device's limits ({max}², {max_layers} layers)"
            )));
        }
        Ok(())
    }

    /// Every terrain texture: the levels, their normal maps, then the pools.
    pub fn images(&self) -> impl Iterator<Item = vk::Image> + '_ {
        [self.levels.raw, self.normals.raw]
            .into_iter()
            .chain(self.pool_images.iter().map(|p| p.raw))
    }

    /// Makes `frame`'s buffers hold `instances` records and `polynomials` polynomials: a
    /// larger set replaces them, the old one destroyed once this frame's submission has
    /// completed.
    pub fn reserve_instances(
        &mut self,
        d: &Device,
        frame: &mut FrameContext,
        instances: usize,
        polynomials: usize,
    ) -> Result<(), VkError> {
        reserve_instances(&mut self.frame_buffers, d, frame, (instances, polynomials))
    }

    /// Call after the device is idle.
    pub fn destroy(&mut self, device: &Device) {
        for b in &mut self.frame_buffers {
            b.destroy(device);
        }
        for p in &mut self.pool_images {
            p.destroy(device);
        }
        self.normals.destroy(device);
        self.levels.destroy(device);
    }
}

/// [`GpuTerrain::reserve_instances`] on the buffers alone (while the plan's samples are
/// borrowed for staging).
pub fn reserve_instances(
    frame_buffers: &mut [FrameBuffers],
    d: &Device,
    frame: &mut FrameContext,
    (instances, polynomials): (usize, usize),
) -> Result<(), VkError> {
    {
        let i = frame.index();
        let fb = &frame_buffers[i];
        if instances <= fb.instance_capacity && polynomials <= fb.polynomial_capacity {
            return Ok(());
        }
        let size = |n: usize, held: usize| n.max(held).next_power_of_two().min(MAX_INSTANCES);
        let grown = FrameBuffers::new(
            d,
            size(instances, fb.instance_capacity),
            // A grid without polynomials keeps its one element.
            if polynomials > fb.polynomial_capacity {
                size(polynomials, fb.polynomial_capacity)
            } else {
                fb.polynomial_capacity
            },
        )?;
        let old = std::mem::replace(&mut frame_buffers[i], grown);
        frame.defer_destroy(old.indirect);
        frame.defer_destroy(old.polynomials);
        frame.defer_destroy(old.instances);
        frame.defer_destroy(old.uniforms);
        Ok(())
    }
}
