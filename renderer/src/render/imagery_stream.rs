//! The streamed imagery windows on the GPU (issue 17: a store's imagery paged in like the
//! heights): one RGBA8 sRGB array texture, a layer per streamed level, `side²` texels holding
//! that level's window around the eye toroidally (absolute texel t at t mod side, so the
//! pipeline's repeating bilinear sampler of the normal maps, at set 0 binding 7, wraps as the
//! window does), drawn by `shaders/drape.glsl` over the coarse level the imagery texture holds
//! whole. `render/imagery_clipmap.rs` decides
//! which cell goes where; this room carries it out.
//!
//! Each frame, before the frame's own submission: the windows are placed around the eye, and
//! the wanted cells (coarse levels first, then nearest) are gathered from the source
//! (`TerrainSource::gather_imagery`) and copied in one submission of their own — at most
//! [`MAX_CELLS_PER_FRAME`]. A cell whose pages are not resident stops the level's fills for
//! this frame (the gather asked for its pages); after [`MAX_MISSES_PER_FRAME`] such misses the
//! frame stops looking. Cells off the raster are cleared to transparent. A level's window is
//! sampled only once every one of its cells is filled (`FrameUniforms.imagery_regions`).
//! Without windows the texture is a 1×1 placeholder the shader never samples.

use ash::vk;

use aerie_terrain::source::TerrainSource;

use crate::render::gpu::FrameUniforms;
use crate::render::imagery_clipmap::{ImageryClipmap, ImageryClipmapDesc, CELL};
use crate::render::upload::{initialise_images, record_image_copies};
use crate::vk::conv::map_texel_copy;
use crate::vk::frame_context::FrameRing;
use crate::vk::image::{Image2d, ImageDesc};
use crate::vk::{Device, VkError};

/// Cells copied per frame at most: 64 × 16 KiB = 1 MiB of staging (a window's row of cells
/// at the default side and more).
pub const MAX_CELLS_PER_FRAME: usize = 64;

/// Cells found not resident before a frame stops looking (each miss asked for its pages).
pub const MAX_MISSES_PER_FRAME: usize = 8;

/// Bytes of one cell's texels.
const CELL_BYTES: usize = (CELL * CELL * 4) as usize;

/// Running totals of the streamed imagery.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ImageryStreamTotals {
    /// Cells copied (with texels, and cleared because off the raster).
    pub cells: u64,
    pub cleared: u64,
    /// Cells wanted whose pages were not resident when tried.
    pub not_resident: u64,
    /// Submissions made for them.
    pub submissions: u64,
}

/// The array texture, its sampler and the windows' state.
pub struct ImageryStream {
    image: Image2d,
    clipmap: Option<ImageryClipmap>,
    /// Cells wanted and not filled after the last update.
    pending: u32,
    /// The frame's gathered cells, [`CELL_BYTES`] each, before they are staged.
    scratch: Vec<u8>,
    pub totals: ImageryStreamTotals,
}

impl ImageryStream {
    /// The texture for `windows` (a 1×1 placeholder without), moved into the layout it is
    /// sampled in; its texels are undefined until filled (never sampled before).
    pub fn new(
        d: &Device,
        ring: &mut FrameRing,
        windows: Option<&ImageryClipmapDesc>,
    ) -> Result<Self, VkError> {
        let clipmap = windows
            .map(|w| ImageryClipmap::new(w.clone()))
            .transpose()
            .map_err(|e| VkError::Other(format!("imagery windows: {e}")))?;
        let (side, layers) = windows.map_or((1, 1), |w| (w.side, w.levels()));
        let max = d.properties.limits;
        if side > max.max_image_dimension2_d || layers > max.max_image_array_layers {
            return Err(VkError::Other(format!(
                "imagery windows of {side}² × {layers} levels exceed this device's {}² × {}",
                max.max_image_dimension2_d, max.max_image_array_layers
            )));
        }
        let desc = ImageDesc {
            width: side,
            height: side,
            format: vk::Format::R8G8B8A8_SRGB,
            usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
            aspect: vk::ImageAspectFlags::COLOR,
            layers,
            mips: 1,
        };
        let image = Image2d::new(d, "imagery windows", desc)?;
        let mut this = Self {
            image,
            clipmap,
            pending: 0,
            scratch: Vec::new(),
            totals: ImageryStreamTotals::default(),
        };
        if let Err(e) = initialise_images(d, ring, [this.image.raw]) {
            this.destroy(d);
            return Err(e);
        }
        Ok(this)
    }

    pub fn view(&self) -> vk::ImageView {
        self.image.view
    }

    /// Device bytes of the texture.
    pub fn bytes(&self) -> u64 {
        self.image.bytes
    }

    /// The windows' shape (None: nothing streamed).
    pub fn windows(&self) -> Option<&ImageryClipmapDesc> {
        self.clipmap.as_ref().map(ImageryClipmap::desc)
    }

    /// Cells wanted and not filled after the last update (0 once every window is filled).
    pub fn pending(&self) -> u32 {
        self.pending
    }

    /// Whether every level's window around the last placement is filled.
    pub fn complete(&self) -> bool {
        self.clipmap
            .as_ref()
            .is_none_or(|c| (0..c.desc().levels()).all(|l| c.region(l).is_some()))
    }

    /// Places the windows around `viewer` (level-0 grid coordinates, `PlanState::viewer`)
    /// and copies the wanted cells `source` holds; returns the cells copied.
    pub fn update(
        &mut self,
        d: &Device,
        ring: &mut FrameRing,
        source: &dyn TerrainSource,
        viewer: [f64; 2],
    ) -> Result<u32, VkError> {
        let Some(clipmap) = self.clipmap.as_mut() else {
            return Ok(0);
        };
        clipmap.place(viewer);
        let wanted = clipmap.wanted(viewer);
        self.pending = wanted.len() as u32;
        if wanted.is_empty() {
            return Ok(0);
        }
        let budget = (ring.staging_budget() as usize / CELL_BYTES).min(MAX_CELLS_PER_FRAME);
        // Gathered first, so that a frame whose cells are all missing takes no frame context.
        let mut done = Vec::new();
        let (mut misses, mut stalled) = (0usize, Vec::new());
        for fill in wanted {
            if done.len() == budget || misses == MAX_MISSES_PER_FRAME {
                break;
            }
            // A level waiting on a page fills nothing more this frame: its nearest cells first.
            if stalled.contains(&fill.level) {
                continue;
            }
            let at = done.len() * CELL_BYTES;
            self.scratch.resize(at + CELL_BYTES, 0);
            let texels = &mut self.scratch[at..];
            if fill.empty {
                texels.fill(0);
                self.totals.cleared += 1;
            } else if let Err(e) = source.gather_imagery(&fill.rect, texels) {
                if e.failed {
                    // A page the source could not read (named by it): drawn without imagery
                    // there, as the heights are drawn coarser.
                    texels.fill(0);
                    self.totals.cleared += 1;
                } else {
                    self.totals.not_resident += 1;
                    misses += 1;
                    stalled.push(fill.level);
                    continue;
                }
            }
            done.push(fill);
        }
        if done.is_empty() {
            return Ok(0);
        }
        let mut frame = ring.begin_frame(d)?;
        let mut copies = Vec::with_capacity(done.len());
        for (i, fill) in done.iter().enumerate() {
            let bytes = &self.scratch[i * CELL_BYTES..(i + 1) * CELL_BYTES];
            let offset = frame.staging().push(bytes, 4)?;
            copies.push(map_texel_copy(offset, 0, fill.level, fill.texel, [CELL; 2]));
        }
        let src = frame.staging_buffer();
        let cmd = frame.begin_recording(d)?;
        record_image_copies(d, cmd, src, self.image.raw, &copies);
        let _in_flight = frame.submit(d)?;
        for fill in &done {
            clipmap.filled(fill);
        }
        self.pending -= done.len() as u32;
        self.totals.cells += done.len() as u64;
        self.totals.submissions += 1;
        Ok(done.len() as u32)
    }

    /// [`Self::update`] until it copies nothing more: every cell the source holds now, in as
    /// many submissions as that takes (load time, a still image's warm-up).
    pub fn fill(
        &mut self,
        d: &Device,
        ring: &mut FrameRing,
        source: &dyn TerrainSource,
        viewer: [f64; 2],
    ) -> Result<u32, VkError> {
        let mut total = 0;
        loop {
            match self.update(d, ring, source, viewer)? {
                0 => return Ok(total),
                n => total += n,
            }
        }
    }

    /// Says in `u` which windows the shader may sample (`shaders/drape.glsl`).
    pub fn write_uniforms(&self, u: &mut FrameUniforms) {
        let Some(c) = self.clipmap.as_ref() else {
            return;
        };
        let desc = c.desc();
        u.imagery_stream = [
            desc.levels() as i32,
            desc.texels_per_sample as i32,
            desc.side as i32,
            0,
        ];
        for (level, r) in u.imagery_regions.iter_mut().enumerate() {
            *r = match c.region(level as u32) {
                Some((origin, _)) => [origin[0] as i32, origin[1] as i32, 1, 0],
                None => [0; 4],
            };
        }
    }

    /// Call after the device is idle. Idempotent.
    pub fn destroy(&mut self, d: &Device) {
        self.image.destroy(d);
    }
}
