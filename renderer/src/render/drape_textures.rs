//! Rasters draped on the terrain, on the GPU (issue 17): the imagery as one RGBA8 sRGB texture
//! with its full mip chain (set 0 binding 5, trilinear) and the land-cover classes as one
//! R8_UINT texture (binding 6, read with texelFetch), both registered to the terrain's grid by
//! `aerie_terrain::drape` and uploaded once when the terrain is loaded. Without rasters each is
//! a 1×1 placeholder (transparent; "no class"), so the pipeline layout never changes.

use std::sync::Arc;

use ash::vk;
use gpu_allocator::MemoryLocation;

use aerie_terrain::drape::mips::{mip_chain, mip_count};
use aerie_terrain::drape::{
    drape_codes, drape_rgba, level_extent, DrapeSize, DrapeStats, GeoRaster, TerrainGrid, CODE_NONE,
};
use aerie_terrain::source::SourceGrid;
use aerie_terrain::store::{choose_level, read_level, ImageryLayer};

use crate::render::imagery_clipmap::{plan_imagery_stream, ImageryClipmapDesc, ImageryStreamPlan};
use crate::render::imagery_stream::ImageryStream;
use crate::vk::access::image_range_barrier;
use crate::vk::access::Access;
use crate::vk::conv::map_texel_copy;
use crate::vk::frame_context::FrameRing;
use crate::vk::image::{Image2d, ImageDesc};
use crate::vk::{Buffer, Device, VkError, VkResultExt};

/// The largest draped texture side asked of any device (the device's own limit may be lower).
pub const MAX_DRAPE_SIDE: u32 = 8192;

/// The draped textures' default device memory budget (`--drape-mb`), MiB: as much again as
/// DESIGN's budget for the clipmap and the pools.
pub const DEFAULT_DRAPE_MIB: f64 = 64.0;

/// What the user gave to drape: the imagery files (later ones on top), the land-cover raster
/// and its code → class table ([`CODE_NONE`]: keep the derived classes), and the device bytes
/// the draped textures may take together.
#[derive(Clone)]
pub struct DrapeInput {
    pub imagery: Vec<GeoRaster>,
    pub landcover: Option<GeoRaster>,
    pub table: [u8; 256],
    pub budget_bytes: u64,
}

impl DrapeInput {
    /// Texels each texture may have under the budget: the imagery (4 bytes a texel, its mip
    /// chain 4/3 of that) gets four fifths when a land-cover raster (1 byte, no mips) shares
    /// the budget, all of it alone; the classes get the rest.
    pub fn texel_budgets(&self) -> (usize, usize) {
        let b = self.budget_bytes as f64;
        let image_share = match (self.imagery.is_empty(), self.landcover.is_some()) {
            (false, true) => 0.8,
            (false, false) => 1.0,
            (true, _) => 0.0,
        };
        let image = (b * image_share / (4.0 * 4.0 / 3.0)).floor() as usize;
        let classes = (b * (1.0 - image_share)).floor() as usize;
        (image, classes)
    }
}

impl std::fmt::Debug for DrapeInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names: Vec<&str> = self.imagery.iter().map(|r| r.path.as_str()).collect();
        f.debug_struct("DrapeInput")
            .field("imagery", &names)
            .field(
                "landcover",
                &self.landcover.as_ref().map(|r| r.path.as_str()),
            )
            .finish()
    }
}

/// The draped rasters, registered to a terrain's grid (CPU side).
#[derive(Debug, Clone, Default)]
pub struct DrapedRasters {
    /// RGBA8 sRGB texels, row 0 south.
    pub imagery: Option<(DrapeSize, Vec<u8>)>,
    /// One class per texel ([`CODE_NONE`] = derived), row 0 south.
    pub classes: Option<(DrapeSize, Vec<u8>)>,
    /// The land-cover raster's texels per raw code.
    pub code_counts: Option<DrapeStats>,
    /// A texture was made smaller than its rasters' resolution asked, to fit the budget.
    pub capped: bool,
    /// The imagery is a level of a store's imagery layer (not draped from rasters here).
    pub layer_level: Option<LayerLevel>,
    /// The layer's levels finer than that one, streamed in windows around the eye
    /// (render/imagery_stream.rs); None: nothing streamed.
    pub stream_windows: Option<ImageryClipmapDesc>,
}

/// The level of a store's imagery layer the imagery texture holds: its texel `t` is centred
/// at grid coordinate `(t + 0.5) · 2^L / k − 0.5` (`aerie_terrain::drape::levels`), so the
/// texture spans `size · 2^L / k` samples, a little more than the grid at coarse levels.
#[derive(Debug, Clone, PartialEq)]
pub struct LayerLevel {
    pub layer: std::path::PathBuf,
    pub level: u32,
    pub texels_per_sample: u32,
}

/// Plans `layer` into the imagery's share of `budget_bytes` (four fifths beside a land-cover
/// texture, as [`DrapeInput::texel_budgets`]) and `max_side` (`plan_imagery_stream`): level 0
/// whole when it fits; else a coarse level whole and the finer ones streamed in windows
/// around the eye (with `stream`). Reads the whole level into `out`'s imagery, says on stderr
/// what it read and streams, and names the damaged pages it leaves transparent.
pub fn drape_layer_level(
    out: &mut DrapedRasters,
    layer: &ImageryLayer,
    budget_bytes: u64,
    max_side: usize,
    stream: bool,
) -> Result<(), String> {
    let share = if out.classes.is_some() { 0.8 } else { 1.0 };
    let bytes = (budget_bytes as f64 * share) as u64;
    let k = layer.texels_per_sample();
    let extents: Vec<(usize, usize)> = (0..layer.layout().levels.len() as u32)
        .map(|l| level_extent(layer.grid(), k, l))
        .collect();
    let plan = match stream {
        true => plan_imagery_stream(&extents, k, bytes, max_side),
        false => choose_level(layer, bytes, max_side).map(|base| ImageryStreamPlan {
            base,
            windows: None,
        }),
    };
    let Some(ImageryStreamPlan {
        base: level,
        windows,
    }) = plan
    else {
        eprintln!(
            "warning: {}: not even its coarsest level fits --drape-mb {:.2}: drawn without imagery",
            layer.path().display(),
            budget_bytes as f64 / f64::from(1 << 20)
        );
        return Ok(());
    };
    let t = std::time::Instant::now();
    let (l, failed) = read_level(layer, level, &|_, _| {});
    for e in failed.iter().take(3) {
        eprintln!("warning: {e}; drawn without imagery there");
    }
    if failed.len() > 3 {
        eprintln!(
            "warning: {} more damaged imagery pages of level {level}",
            failed.len() - 3
        );
    }
    let density = match (&windows, level) {
        (_, 0) => format!("{k} texels per sample"),
        (Some(w), _) => format!(
            "{} samples per texel; levels 0–{} streamed in windows of {}² texels",
            l.samples_per_texel(),
            level - 1,
            w.side
        ),
        (None, _) => format!(
            "{} samples per texel; finer levels exceed --drape-mb",
            l.samples_per_texel()
        ),
    };
    eprintln!(
        "imagery: level {level} of {} ({}×{} texels, {density}), read in {:.2} s",
        layer.path().display(),
        l.width,
        l.height,
        t.elapsed().as_secs_f64()
    );
    out.capped |= level > 0 && windows.is_none();
    out.stream_windows = windows;
    let size = DrapeSize {
        width: l.width,
        height: l.height,
        // k per sample at level 0; 0 ("coarser than the grid") when 2^L > k.
        texels_per_sample: k >> level.min(31),
    };
    out.imagery = Some((size, l.rgba));
    out.layer_level = Some(LayerLevel {
        layer: l.layer,
        level,
        texels_per_sample: k,
    });
    Ok(())
}

impl DrapedRasters {
    /// The level-0 samples the imagery texture spans per axis when that is not the grid: level
    /// L of a store's layer at k texels per sample spans its texels · 2^L / k (a whole number:
    /// the level's texels are ⌈samples · k / 2^L⌉).
    pub fn imagery_span(&self) -> Option<[u64; 2]> {
        let l = self.layer_level.as_ref()?;
        let (size, _) = self.imagery.as_ref()?;
        let span =
            |texels: usize| (texels as u64 * (1u64 << l.level)) / u64::from(l.texels_per_sample);
        Some([span(size.width), span(size.height)])
    }

    /// Land-cover texels whose code the table does not know (drawn with the derived classes).
    pub fn unknown_code_texels(&self, table: &[u8; 256]) -> u64 {
        self.code_counts.as_ref().map_or(0, |s| {
            s.codes
                .iter()
                .enumerate()
                .filter(|(c, _)| table[*c] == CODE_NONE)
                .map(|(_, n)| n)
                .sum()
        })
    }
}

/// What the renderer was asked to drape (`RendererDesc`'s drape fields).
#[derive(Clone, Copy)]
pub struct DrapeAsk<'a> {
    /// `--imagery` and `--landcover`.
    pub input: Option<&'a DrapeInput>,
    /// `--drape-mb`, for a store's imagery layer.
    pub budget_bytes: u64,
    /// Draw a store's imagery layer at all; stream its finer levels.
    pub store_imagery: bool,
    pub stream: bool,
}

/// What a terrain of `grid` gets draped: `ask`'s `--imagery` and `--landcover` registered,
/// else the store's imagery `layer` planned into the budget ([`drape_layer_level`]); None
/// without either.
pub fn drape_rasters(
    ask: DrapeAsk,
    grid: &SourceGrid,
    layer: Option<&ImageryLayer>,
    max_side: u32,
) -> Result<Option<DrapedRasters>, String> {
    let mut rasters = match ask.input {
        Some(input) => Some(register(input, grid, max_side)?),
        None => None,
    };
    if let Some(layer) = layer.filter(|_| ask.store_imagery) {
        match rasters.as_mut().filter(|r| r.imagery.is_some()) {
            Some(_) => eprintln!(
                "note: --imagery is draped instead of the store's imagery layer {}",
                layer.path().display()
            ),
            None => {
                let r = rasters.get_or_insert_with(DrapedRasters::default);
                let (budget, stream) = (ask.budget_bytes, ask.stream);
                drape_layer_level(r, layer, budget, max_side as usize, stream)?;
            }
        }
    }
    Ok(rasters)
}

/// Registers `input` onto `grid`'s real extent under a texture side of `max_side`; errors name
/// the file and the reason (CRS unsupported, no overlap, terrain without geo-reference).
pub fn register(
    input: &DrapeInput,
    grid: &SourceGrid,
    max_side: u32,
) -> Result<DrapedRasters, String> {
    let first = input
        .imagery
        .first()
        .or(input.landcover.as_ref())
        .map(|r| r.path.clone())
        .unwrap_or_default();
    let terrain = TerrainGrid::new(
        grid.valid_width as usize,
        grid.valid_height as usize,
        grid.spacing_x,
        grid.spacing_y,
        grid.geo.as_ref(),
    )
    .map_err(|why| format!("{first}: {why}"))?;
    let mut out = DrapedRasters::default();
    let (image_texels, class_texels) = input.texel_budgets();
    if !input.imagery.is_empty() {
        let refs: Vec<&GeoRaster> = input.imagery.iter().collect();
        let wanted = DrapeSize::choose(&terrain, &refs, max_side);
        let size = wanted.within(&terrain, image_texels);
        out.capped |= size != wanted;
        let mut texels = vec![0u8; size.texels() * 4];
        for r in &input.imagery {
            drape_rgba(&terrain, &size, r, &mut texels).map_err(|e| e.to_string())?;
        }
        out.imagery = Some((size, texels));
    }
    if let Some(r) = &input.landcover {
        let wanted = DrapeSize::choose(&terrain, &[r], max_side);
        let size = wanted.within(&terrain, class_texels);
        out.capped |= size != wanted;
        let mut texels = vec![CODE_NONE; size.texels()];
        let stats = drape_codes(&terrain, &size, r, &input.table, &mut texels)
            .map_err(|e| e.to_string())?;
        out.classes = Some((size, texels));
        out.code_counts = Some(stats);
    }
    Ok(out)
}

/// One sampled 2-D texture of `format` with `mips` levels, the copy's destination.
fn texture(
    d: &Device,
    name: &str,
    (width, height): (u32, u32),
    format: vk::Format,
    mips: u32,
) -> Result<Image2d, VkError> {
    let desc = ImageDesc {
        width,
        height,
        format,
        usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
        aspect: vk::ImageAspectFlags::COLOR,
        layers: 0,
        mips,
    };
    Image2d::new(d, name, desc)
}

/// Records a barrier over every mip of `image` from the `prev` uses to the `next`.
fn barrier(
    d: &Device,
    cmd: vk::CommandBuffer,
    image: &Image2d,
    prev: &[Access],
    next: &[Access],
    discard: bool,
) {
    image_range_barrier(d, cmd, image.raw, image.range(), prev, next, discard);
}

/// The draped textures and their samplers.
pub struct DrapeTextures {
    imagery: Image2d,
    classes: Image2d,
    /// Trilinear, clamped: the imagery.
    pub linear: vk::Sampler,
    /// Nearest: the classes (an integer format is never filtered).
    pub nearest: vk::Sampler,
    /// The draped sizes (None: placeholder).
    pub imagery_size: Option<DrapeSize>,
    pub classes_size: Option<DrapeSize>,
    /// The streamed imagery windows (a placeholder when nothing is streamed).
    pub stream: ImageryStream,
}

impl DrapeTextures {
    /// Creates the textures for `rasters` (placeholders without) and uploads them in one
    /// submission through a temporary staging buffer, waiting for it (load time only).
    pub fn new(
        d: &Device,
        ring: &mut FrameRing,
        rasters: Option<&DrapedRasters>,
    ) -> Result<Self, VkError> {
        let windows = rasters.and_then(|r| r.stream_windows.as_ref());
        let mut stream = ImageryStream::new(d, ring, windows)?;
        let placeholders = texture(d, "imagery", (1, 1), vk::Format::R8G8B8A8_SRGB, 1).and_then(
            |i| match texture(d, "classes", (1, 1), vk::Format::R8_UINT, 1) {
                Ok(c) => Ok((i, c)),
                Err(e) => {
                    let mut i = i;
                    i.destroy(d);
                    Err(e)
                }
            },
        );
        let (imagery, classes) = match placeholders {
            Ok(p) => p,
            Err(e) => {
                stream.destroy(d);
                return Err(e);
            }
        };
        let mut this = Self {
            imagery,
            classes,
            linear: vk::Sampler::null(),
            nearest: vk::Sampler::null(),
            imagery_size: None,
            classes_size: None,
            stream,
        };
        if let Err(e) = this.create(d, ring, rasters) {
            this.destroy(d);
            return Err(e);
        }
        Ok(this)
    }

    fn create(
        &mut self,
        d: &Device,
        ring: &mut FrameRing,
        rasters: Option<&DrapedRasters>,
    ) -> Result<(), VkError> {
        let sampler = |filter: vk::Filter, mip: vk::SamplerMipmapMode, max_lod: f32| {
            vk::SamplerCreateInfo::default()
                .mag_filter(filter)
                .min_filter(filter)
                .mipmap_mode(mip)
                .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
                .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
                .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
                .max_lod(max_lod)
        };
        let info = sampler(
            vk::Filter::LINEAR,
            vk::SamplerMipmapMode::LINEAR,
            vk::LOD_CLAMP_NONE,
        );
        // SAFETY: the device is live; the create-info is complete.
        self.linear = unsafe { d.raw.create_sampler(&info, None) }.call("vkCreateSampler")?;
        let info = sampler(vk::Filter::NEAREST, vk::SamplerMipmapMode::NEAREST, 0.0);
        // SAFETY: as above.
        self.nearest = unsafe { d.raw.create_sampler(&info, None) }.call("vkCreateSampler")?;

        let max = d.properties.limits.max_image_dimension2_d;
        let check = |s: &DrapeSize, what: &str| {
            if s.width as u32 > max || s.height as u32 > max {
                return Err(VkError::Other(format!(
                    "{what} texture {}×{} exceeds this device's {max}² limit",
                    s.width, s.height
                )));
            }
            Ok(())
        };
        // (image, level sizes and bytes) to upload.
        let mut imagery_levels: Vec<(usize, usize, Vec<u8>)> = vec![(1, 1, vec![0, 0, 0, 0])];
        let mut class_level: (usize, usize, Vec<u8>) = (1, 1, vec![CODE_NONE]);
        if let Some((s, texels)) = rasters.and_then(|r| r.imagery.as_ref()) {
            check(s, "imagery")?;
            self.imagery.destroy(d);
            let mips = mip_count(s.width, s.height);
            self.imagery = texture(
                d,
                "imagery",
                (s.width as u32, s.height as u32),
                vk::Format::R8G8B8A8_SRGB,
                mips,
            )?;
            imagery_levels = vec![(s.width, s.height, texels.clone())];
            imagery_levels.extend(mip_chain(s.width, s.height, texels));
            self.imagery_size = Some(*s);
        }
        if let Some((s, texels)) = rasters.and_then(|r| r.classes.as_ref()) {
            check(s, "land-cover")?;
            class_level = (s.width, s.height, texels.clone());
            self.classes_size = Some(*s);
        }
        self.classes.destroy(d);
        self.classes = texture(
            d,
            "land-cover classes",
            (class_level.0 as u32, class_level.1 as u32),
            vk::Format::R8_UINT,
            1,
        )?;
        let padded = |n: usize| n.div_ceil(4) * 4;
        let total: usize = imagery_levels
            .iter()
            .map(|l| padded(l.2.len()))
            .sum::<usize>()
            + padded(class_level.2.len());
        let mut staging = Buffer::new(
            d,
            "drape staging",
            total as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        let result = self.upload(d, ring, &mut staging, &imagery_levels, &class_level);
        d.wait_idle();
        staging.destroy(d);
        result
    }

    fn upload(
        &self,
        d: &Device,
        ring: &mut FrameRing,
        staging: &mut Buffer,
        imagery: &[(usize, usize, Vec<u8>)],
        classes: &(usize, usize, Vec<u8>),
    ) -> Result<(), VkError> {
        let Some(map) = staging.mapped_mut() else {
            return Err(VkError::Other(
                "drape staging buffer is not host-visible".into(),
            ));
        };
        let mut offset = 0usize;
        let mut copies: Vec<(vk::Image, vk::BufferImageCopy)> = Vec::new();
        let levels = imagery
            .iter()
            .enumerate()
            .map(|(m, l)| (self.imagery.raw, m as u32, l));
        for (image, mip, (w, h, bytes)) in levels.chain([(self.classes.raw, 0, classes)]) {
            map[offset..offset + bytes.len()].copy_from_slice(bytes);
            let size = [*w as u32, *h as u32];
            copies.push((image, map_texel_copy(offset as u64, mip, 0, [0, 0], size)));
            // Copies start at multiples of 4 bytes (the texel size of RGBA8; R8 needs 1).
            offset += bytes.len().div_ceil(4) * 4;
        }
        let mut frame = ring.begin_frame(d)?;
        let cmd = frame.begin_recording(d)?;
        for image in [&self.imagery, &self.classes] {
            barrier(
                d,
                cmd,
                image,
                &[Access::Nothing],
                &[Access::TransferWrite],
                true,
            );
        }
        for (image, copy) in &copies {
            // SAFETY: `cmd` is recording; the staging buffer holds these bytes at the offsets, and each region lies inside its live image (TRANSFER_DST layout after the barrier).
            unsafe {
                d.raw.cmd_copy_buffer_to_image(
                    cmd,
                    staging.raw,
                    *image,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    std::slice::from_ref(copy),
                )
            };
        }
        for image in [&self.imagery, &self.classes] {
            barrier(
                d,
                cmd,
                image,
                &[Access::TransferWrite],
                &[Access::FragmentShaderReadSampledImage],
                false,
            );
        }
        let _in_flight = frame.submit(d)?;
        Ok(())
    }

    pub fn imagery_view(&self) -> vk::ImageView {
        self.imagery.view
    }

    pub fn classes_view(&self) -> vk::ImageView {
        self.classes.view
    }

    /// Device bytes of the textures (the imagery's whole mip chain, the streamed windows).
    pub fn bytes(&self) -> u64 {
        self.imagery.bytes + self.classes.bytes + self.stream.bytes()
    }

    /// Imagery extent and mip count.
    pub fn imagery_extent(&self) -> ((u32, u32), u32) {
        let desc = &self.imagery.desc;
        ((desc.width, desc.height), desc.mips.max(1))
    }

    /// Call after the device is idle. Idempotent.
    pub fn destroy(&mut self, d: &Device) {
        self.stream.destroy(d);
        self.classes.destroy(d);
        self.imagery.destroy(d);
        // SAFETY: null or created by `create` on this device; no pending command uses them; nulled below.
        unsafe {
            d.raw.destroy_sampler(self.nearest, None);
            d.raw.destroy_sampler(self.linear, None);
        }
        self.nearest = vk::Sampler::null();
        self.linear = vk::Sampler::null();
    }
}

/// The input shared by every renderer a command makes.
pub type SharedDrapeInput = Arc<DrapeInput>;

#[cfg(test)]
mod tests {
    use super::*;

    /// Level L of a layer at k per sample over `w × h` samples, as `drape_layer_level` puts it.
    fn layer(w: usize, h: usize, k: u32, level: u32) -> DrapedRasters {
        let (tw, th) = (
            (w * k as usize).div_ceil(1 << level),
            (h * k as usize).div_ceil(1 << level),
        );
        DrapedRasters {
            imagery: Some((
                DrapeSize {
                    width: tw,
                    height: th,
                    texels_per_sample: k >> level,
                },
                Vec::new(),
            )),
            layer_level: Some(LayerLevel {
                layer: "x.aerie-imagery".into(),
                level,
                texels_per_sample: k,
            }),
            ..DrapedRasters::default()
        }
    }

    #[test]
    fn a_layer_level_spans_its_texels_in_samples_and_a_drape_spans_the_grid() {
        // 129 × 100 samples: level 3 at k = 2 has 33 × 25 texels of 4 samples.
        assert_eq!(layer(129, 100, 2, 3).imagery_span(), Some([132, 100]));
        // Finer than a sample (k = 4, level 1): exactly the grid.
        assert_eq!(layer(129, 100, 4, 1).imagery_span(), Some([129, 100]));
        assert_eq!(layer(129, 100, 1, 0).imagery_span(), Some([129, 100]));
        assert_eq!(layer(1201, 1201, 2, 7).imagery_span(), Some([1216, 1216]));
        let drape = DrapedRasters {
            layer_level: None,
            ..layer(129, 100, 2, 0)
        };
        assert_eq!(
            drape.imagery_span(),
            None,
            "an in-memory drape spans the grid"
        );
    }
}
