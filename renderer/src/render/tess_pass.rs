//! The hardware-tessellation baseline (`--lod tess`, document 001) on the GPU: the level-0
//! heights in one storage buffer, the density of the base mesh (taken once at load), one
//! host-visible buffer of patch records per frame in flight, and the draw — one non-indexed
//! draw of three control points per patch, recorded inside the terrain pass.
//!
//! Heights come from the full-resolution grid, not the clipmap: the mode refuses datasets whose
//! grid does not fit one storage buffer on this device and sources that do not hold every
//! sample in memory (a streamed store). A geographic or UTM grid is drawn on the WGS84
//! ellipsoid as the tiles are: each drawn cell gets a relative-to-eye frame
//! (`render/geo_instances.rs`, [`GeoFields`], a second storage buffer) and the evaluation
//! shader places its vertices with `shaders/geo_node.glsl`; the cells' boxes and distances
//! come from their true world positions ([`TessPlacement`], at load).

use std::sync::Arc;
use std::time::Instant;

use ash::vk;
use gpu_allocator::MemoryLocation;

use aerie_terrain::camera::Camera;
use aerie_terrain::geodesy::GeoGrid;
use aerie_terrain::select::{
    select_patches, triangles_emitted, Spacing, TessDensity, TessParams, TessPatch, TessPlacement,
    TessStats, DEFAULT_TOL_M, TESS_LEVEL_CAP, TESS_PATCH,
};
use aerie_terrain::source::{SampleRect, SourceGrid, TerrainSource};

use crate::render::geo_instances::{GeoEye, GeoFields};
use crate::render::upload::stream_buffer;
use crate::vk::frame_context::{FrameContext, FrameRing};
use crate::vk::pipeline::{
    BINDING_CLASSES, BINDING_IMAGERY, BINDING_IMAGERY_STREAM, BINDING_NORMAL_MAPS,
};
use crate::vk::tess_pipeline::{
    TessPipeline, TESS_BINDING_CELLS, TESS_BINDING_FRAME, TESS_BINDING_HEIGHTS,
    TESS_BINDING_PATCHES,
};
use crate::vk::{Buffer, Device, VkError, FRAMES_IN_FLIGHT};

/// The textures `shaders/terrain.frag` samples (normal maps, imagery, land-cover classes), at
/// the same binding numbers in the tessellation set as in the terrain's.
pub struct FragmentImages {
    pub normals: (vk::ImageView, vk::Sampler),
    pub imagery: (vk::ImageView, vk::Sampler),
    pub classes: (vk::ImageView, vk::Sampler),
    pub imagery_stream: (vk::ImageView, vk::Sampler),
}

/// One patch record (`shaders/terrain_tess.glsl` `TessPatchGpu`, std430).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TessPatchGpu {
    pub origin_rel: [f32; 2],
    pub origin_sample: [i32; 2],
    pub extent: [i32; 2],
    pub north_west: u32,
    pub geo_cell: u32,
    pub levels: [f32; 4],
    pub geo_centre: [i32; 2],
    pub pad: [u32; 2],
}

/// The record of `patch` for an eye at `eye` (pure).
pub fn patch_record(
    density: &TessDensity,
    spacing: [f64; 2],
    eye: glam::DVec3,
    patch: &TessPatch,
) -> TessPatchGpu {
    let [cx, cy] = patch.cell;
    let sw = density.corner_sample(cx, cy);
    let ne = density.corner_sample(cx + 1, cy + 1);
    TessPatchGpu {
        origin_rel: [
            (sw[0] as f64 * spacing[0] - eye.x) as f32,
            (sw[1] as f64 * spacing[1] - eye.y) as f32,
        ],
        origin_sample: [sw[0] as i32, sw[1] as i32],
        extent: [(ne[0] - sw[0]) as i32, (ne[1] - sw[1]) as i32],
        north_west: patch.north_west as u32,
        geo_cell: 0,
        levels: [patch.outer[0], patch.outer[1], patch.outer[2], patch.inner],
        geo_centre: [0, 0],
        pad: [0, 0],
    }
}

/// The base mesh on the ellipsoid: what culling needs (`placement`) and each cell's frame with
/// the eye at the world origin (`fields`, `geo_origin.xyz` replaced each frame by the centre
/// relative to the eye, from `centres` in f64), all computed at load.
pub struct TessGeo {
    pub placement: TessPlacement,
    fields: Vec<GeoFields>,
    centres: Vec<glam::DVec3>,
    /// Samples from a cell's south-west sample to its frame's centre (both axes).
    half: i32,
}

impl TessGeo {
    /// `density`'s cells on `grid` (pure).
    pub fn new(density: &TessDensity, grid: &GeoGrid) -> Self {
        let at_origin = GeoEye::new(grid, glam::DVec3::ZERO);
        let [nx, ny] = density.cells;
        let (mut fields, mut centres) = (Vec::new(), Vec::new());
        for cy in 0..ny {
            for cx in 0..nx {
                let sw = density.corner_sample(cx, cy);
                let (f, c) =
                    at_origin.node_fields_rel([sw[0] as i64, sw[1] as i64], 1, density.patch);
                fields.push(f);
                centres.push(c);
            }
        }
        Self {
            placement: TessPlacement::new(density, grid),
            fields,
            centres,
            half: (density.patch / 2) as i32,
        }
    }

    /// The frames of the cells `patches` draw, in order, one per cell (a cell's two patches are
    /// consecutive), into `cells`; each record told its cell's frame (pure).
    pub fn cell_records(
        &self,
        density: &TessDensity,
        eye: glam::DVec3,
        patches: &[TessPatch],
        records: &mut [TessPatchGpu],
        cells: &mut Vec<GeoFields>,
    ) {
        cells.clear();
        let mut last = None;
        for (p, r) in patches.iter().zip(records.iter_mut()) {
            let i = (p.cell[1] * density.cells[0] + p.cell[0]) as usize;
            if last != Some(i) {
                let mut f = self.fields[i];
                let rel = self.centres[i] - eye;
                f.geo_origin[..3].copy_from_slice(&[rel.x as f32, rel.y as f32, rel.z as f32]);
                cells.push(f);
                last = Some(i);
            }
            r.geo_cell = (cells.len() - 1) as u32;
            r.geo_centre = [self.half, self.half];
        }
    }
}

/// Refuses what this baseline cannot draw, naming why (pure).
pub fn check_tess_grid(grid: &SourceGrid, max_buffer: u64) -> Result<(), String> {
    let bytes = grid.valid_width as u64 * grid.valid_height as u64 * 4;
    if bytes > max_buffer {
        return Err(format!(
            "--lod tess: the {}×{} level-0 heights ({} MiB) exceed this device's largest storage buffer ({} MiB)",
            grid.valid_width,
            grid.valid_height,
            bytes >> 20,
            max_buffer >> 20
        ));
    }
    Ok(())
}

/// The baseline's GPU objects and its per-frame CPU state.
pub struct TessTerrain {
    pub pipeline: TessPipeline,
    pub density: TessDensity,
    /// Milliseconds the density took at load.
    pub density_ms: f64,
    /// On the ellipsoid: the cells' boxes and frames.
    geo: Option<TessGeo>,
    spacing: [f64; 2],
    d_max_m: f64,
    heights: Buffer,
    /// One per frame in flight (host-visible, written before the frame's submission).
    patch_buffers: Vec<Buffer>,
    /// The drawn cells' frames, one buffer per frame in flight (one zeroed record on the flat
    /// path, which the shader reads as "flat").
    cell_buffers: Vec<Buffer>,
    scratch: Vec<TessPatch>,
    records: Vec<TessPatchGpu>,
    cells: Vec<GeoFields>,
    /// The frame's draws (first patch, patches): chunks of at most [`TRIANGLES_PER_DRAW`].
    pub draws: Vec<(u32, u32)>,
}

/// Triangles one draw may make: Mesa's software tessellation (lavapipe 22.3) indexes a draw's
/// generated vertices with 16 bits, and a draw past 65536 vertices comes out scrambled
/// (measured: wrong triangles and missing patches above ~110 000 triangles in one draw).
pub const TRIANGLES_PER_DRAW: u64 = 32768;

/// The draws (first patch, patch count) of patches making `triangles[i]` triangles each, each
/// draw at most `budget` triangles unless one patch alone makes more (pure).
pub fn chunk_draws(triangles: &[u64], budget: u64) -> Vec<(u32, u32)> {
    let mut out: Vec<(u32, u32)> = Vec::new();
    let mut sum = 0;
    for (i, &t) in triangles.iter().enumerate() {
        match out.last_mut() {
            Some((_, n)) if sum + t <= budget => {
                *n += 1;
                sum += t;
            }
            _ => {
                out.push((i as u32, 1));
                sum = t;
            }
        }
    }
    out
}

impl TessTerrain {
    /// Reads every valid level-0 sample of `source`, takes the density (and on the ellipsoid,
    /// `earth`, the cells' placement), uploads the heights.
    pub fn new(
        d: &Device,
        ring: &mut FrameRing,
        source: &Arc<dyn TerrainSource>,
        earth: Option<&GeoGrid>,
    ) -> Result<Self, VkError> {
        let grid = source.grid().clone();
        let max = d.properties.limits.max_storage_buffer_range as u64;
        check_tess_grid(&grid, max).map_err(VkError::Other)?;
        let size = [grid.valid_width, grid.valid_height];
        let mut samples = vec![0.0f32; size[0] as usize * size[1] as usize];
        let rect = SampleRect {
            level: 0,
            origin: [0, 0],
            size,
        };
        source.gather(&rect, &mut samples).map_err(|e| {
            VkError::Other(format!(
                "--lod tess: needs every sample in memory; page ({}, {}) of level {} is not resident (load the dataset itself, not a streamed store)",
                e.px, e.py, e.level
            ))
        })?;
        let t0 = Instant::now();
        let density =
            TessDensity::new(&samples, size, TESS_PATCH, DEFAULT_TOL_M).map_err(VkError::Other)?;
        let geo = earth.map(|g| TessGeo::new(&density, g));
        let density_ms = t0.elapsed().as_secs_f64() * 1e3;
        let mut pipeline = TessPipeline::new(d)?;
        let bytes: &[u8] = bytemuck::cast_slice(&samples);
        let heights = Buffer::new(
            d,
            "level-0 heights",
            bytes.len() as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        );
        let mut heights = match heights {
            Ok(b) => b,
            Err(e) => {
                pipeline.destroy(d);
                return Err(e);
            }
        };
        if let Err(e) = stream_buffer(d, ring, bytes, heights.raw) {
            d.wait_idle();
            heights.destroy(d);
            pipeline.destroy(d);
            return Err(e);
        }
        let (w, h) = (
            grid.valid_width as f64 * grid.spacing_x,
            grid.valid_height as f64 * grid.spacing_y,
        );
        Ok(Self {
            pipeline,
            density,
            density_ms,
            geo,
            spacing: [grid.spacing_x, grid.spacing_y],
            d_max_m: w.hypot(h),
            heights,
            patch_buffers: Vec::new(),
            cell_buffers: Vec::new(),
            scratch: Vec::new(),
            records: Vec::new(),
            cells: Vec::new(),
            draws: Vec::new(),
        })
    }

    /// Chooses the frame's patches and factors (`global` = Tg) and writes their records into
    /// `frame`'s patch buffer (grown when too small; the old one destroyed once the frame that
    /// used it has completed).
    pub fn prepare(
        &mut self,
        d: &Device,
        frame: &mut FrameContext,
        camera: &Camera,
        global: f64,
        curvature: bool,
    ) -> Result<TessStats, VkError> {
        let params = TessParams {
            global,
            d_min_m: 0.0,
            d_max_m: self.d_max_m,
            max_level: (d.properties.limits.max_tessellation_generation_level).min(TESS_LEVEL_CAP),
            // On the ellipsoid the placed boxes hold the curvature already.
            curvature: curvature && self.geo.is_none(),
        };
        let placed = self.geo.as_ref().map(|g| &g.placement);
        let stats = select_patches(
            &self.density,
            self.spacing,
            placed,
            camera,
            &params,
            &mut self.scratch,
        );
        let eye = camera.position;
        self.records.clear();
        self.records.extend(
            (self.scratch.iter()).map(|p| patch_record(&self.density, self.spacing, eye, p)),
        );
        self.cells.clear();
        match &self.geo {
            Some(g) => g.cell_records(
                &self.density,
                eye,
                &self.scratch,
                &mut self.records,
                &mut self.cells,
            ),
            None => self.cells.push(GeoFields::default()),
        }
        let i = frame.index();
        let records: &[u8] = bytemuck::cast_slice(&self.records);
        write_frame_buffer(
            d,
            frame,
            &mut self.patch_buffers,
            i,
            records,
            "tessellation patches",
        )?;
        let cells: &[u8] = bytemuck::cast_slice(&self.cells);
        write_frame_buffer(
            d,
            frame,
            &mut self.cell_buffers,
            i,
            cells,
            "tessellation cells",
        )?;
        let tris: Vec<u64> = (self.scratch.iter())
            .map(|p| triangles_emitted(p.outer, p.inner, Spacing::FractionalOdd, params.max_level))
            .collect();
        self.draws = chunk_draws(&tris, TRIANGLES_PER_DRAW);
        Ok(stats)
    }

    /// Allocates and writes the frame's tessellation set: `uniforms` (this frame's), its patch
    /// buffer, the heights, and the textures `terrain.frag` samples.
    pub fn write_set(
        &self,
        d: &Device,
        frame: &FrameContext,
        uniforms: vk::Buffer,
        images: &FragmentImages,
    ) -> Result<vk::DescriptorSet, VkError> {
        let set = frame.allocate_set(d, self.pipeline.set_layout)?;
        let info = |buffer| {
            [vk::DescriptorBufferInfo {
                buffer,
                offset: 0,
                range: vk::WHOLE_SIZE,
            }]
        };
        let (u, p, h, g) = (
            info(uniforms),
            info(self.patch_buffers[frame.index()].raw),
            info(self.heights.raw),
            info(self.cell_buffers[frame.index()].raw),
        );
        fn write<'a>(
            set: vk::DescriptorSet,
            binding: u32,
            ty: vk::DescriptorType,
            info: &'a [vk::DescriptorBufferInfo; 1],
        ) -> vk::WriteDescriptorSet<'a> {
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(binding)
                .descriptor_type(ty)
                .buffer_info(info)
        }
        let (ub, sb) = (
            vk::DescriptorType::UNIFORM_BUFFER,
            vk::DescriptorType::STORAGE_BUFFER,
        );
        let image = |(view, sampler): (vk::ImageView, vk::Sampler)| {
            [vk::DescriptorImageInfo {
                sampler,
                image_view: view,
                image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            }]
        };
        let (n, i, c, s) = (
            image(images.normals),
            image(images.imagery),
            image(images.classes),
            image(images.imagery_stream),
        );
        fn sampled<'a>(
            set: vk::DescriptorSet,
            binding: u32,
            info: &'a [vk::DescriptorImageInfo; 1],
        ) -> vk::WriteDescriptorSet<'a> {
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(binding)
                .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .image_info(info)
        }
        let writes = [
            write(set, TESS_BINDING_FRAME, ub, &u),
            write(set, TESS_BINDING_PATCHES, sb, &p),
            write(set, TESS_BINDING_HEIGHTS, sb, &h),
            write(set, TESS_BINDING_CELLS, sb, &g),
            sampled(set, BINDING_NORMAL_MAPS, &n),
            sampled(set, BINDING_IMAGERY, &i),
            sampled(set, BINDING_CLASSES, &c),
            sampled(set, BINDING_IMAGERY_STREAM, &s),
        ];
        // `set` comes from this frame's pool, whose previous submission has completed; every
        // buffer written is live; the info arrays outlive the call.
        // SAFETY: no pending command buffer uses `set`, and every handle written is live.
        unsafe { d.raw.update_descriptor_sets(&writes, &[]) };
        Ok(set)
    }

    /// Records the draw of the prepared patches (inside the terrain pass's rendering, viewport
    /// and scissor set).
    pub fn record_draw(&self, d: &Device, cmd: vk::CommandBuffer, set: vk::DescriptorSet) {
        if self.draws.is_empty() {
            return;
        }
        // The pipeline, its layout and `set` (written this frame) are live; the patch buffer
        // holds every record the draws name.
        // SAFETY: `cmd` is recording inside a rendering with dynamic viewport and scissor set.
        unsafe {
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
            for &(first, n) in &self.draws {
                d.raw.cmd_draw(cmd, 3 * n, 1, 3 * first, 0);
            }
        }
    }

    /// Call after the device is idle.
    pub fn destroy(&mut self, d: &Device) {
        for b in self.patch_buffers.iter_mut().chain(&mut self.cell_buffers) {
            b.destroy(d);
        }
        self.heights.destroy(d);
        self.pipeline.destroy(d);
    }
}

/// Writes `bytes` into frame `i`'s buffer of `buffers` (one host-visible storage buffer per
/// frame in flight, made on first use; grown to the next power of two when too small, the old
/// one destroyed once the frame that used it has completed).
fn write_frame_buffer(
    d: &Device,
    frame: &mut FrameContext,
    buffers: &mut Vec<Buffer>,
    i: usize,
    bytes: &[u8],
    name: &'static str,
) -> Result<(), VkError> {
    while buffers.len() < FRAMES_IN_FLIGHT {
        buffers.push(host_buffer(d, name, 64 << 10)?);
    }
    if (buffers[i].size as usize) < bytes.len() {
        let grown = host_buffer(d, name, bytes.len().next_power_of_two())?;
        frame.defer_destroy(std::mem::replace(&mut buffers[i], grown));
    }
    let Some(mapped) = buffers[i].mapped_mut() else {
        return Err(VkError::Other(format!("{name} buffer is not mapped")));
    };
    mapped[..bytes.len()].copy_from_slice(bytes);
    Ok(())
}

fn host_buffer(d: &Device, name: &'static str, bytes: usize) -> Result<Buffer, VkError> {
    Buffer::new(
        d,
        name,
        bytes.max(64) as u64,
        vk::BufferUsageFlags::STORAGE_BUFFER,
        MemoryLocation::CpuToGpu,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_record_matches_the_glsl_layout() {
        // std430: vec2, ivec2, ivec2 (8 each), two uints, a vec4 at 32, ivec2 and uvec2.
        assert_eq!(std::mem::size_of::<TessPatchGpu>(), 64);
        assert_eq!(std::mem::offset_of!(TessPatchGpu, levels), 32);
        assert_eq!(std::mem::offset_of!(TessPatchGpu, north_west), 24);
        assert_eq!(std::mem::offset_of!(TessPatchGpu, geo_centre), 48);
        let glsl = include_str!("../../../shaders/terrain_tess.glsl");
        let fields: Vec<&str> = glsl
            .lines()
            .filter_map(|l| {
                l.split(';')
                    .next()
                    .map(str::trim)
                    .filter(|_| l.contains(';'))
            })
            .filter(|l| {
                ["vec", "ivec", "uvec", "uint"]
                    .iter()
                    .any(|t| l.starts_with(t))
            })
            .collect();
        assert_eq!(
            fields,
            [
                "vec2 origin_rel",
                "ivec2 origin_sample",
                "ivec2 extent",
                "uint north_west",
                "uint geo_cell",
                "vec4 levels",
                "ivec2 geo_centre",
                "uvec2 pad"
            ]
        );
    }

    #[test]
    fn draws_are_chunked_by_triangles() {
        assert_eq!(chunk_draws(&[], 10), vec![]);
        assert_eq!(
            chunk_draws(&[4, 4, 4, 20, 1, 9], 10),
            vec![(0, 2), (2, 1), (3, 1), (4, 2)]
        );
    }

    #[test]
    fn records_hold_the_cell_relative_to_the_eye() {
        let hs: Vec<f32> = (0..(70 * 40)).map(|i| (i % 7) as f32).collect();
        let d = TessDensity::new(&hs, [70, 40], 32, 0.5).unwrap();
        let p = TessPatch {
            cell: [2, 1],
            north_west: true,
            outer: [3.0, 5.0, 7.0],
            inner: 9.0,
        };
        let r = patch_record(&d, [30.0, 20.0], glam::DVec3::new(100.0, 50.0, 9.0), &p);
        assert_eq!(r.origin_sample, [64, 32]);
        // The last cell ends at the last sample.
        assert_eq!(r.extent, [5, 7]);
        assert_eq!(r.origin_rel, [64.0 * 30.0 - 100.0, 32.0 * 20.0 - 50.0]);
        assert_eq!((r.north_west, r.levels), (1, [3.0, 5.0, 7.0, 9.0]));
    }

    #[test]
    fn each_drawn_cell_gets_its_frame_relative_to_the_eye() {
        let d = 1.0 / 1200.0;
        let geo = aerie_terrain::GeoReference::Geographic {
            south_lat_deg: 47.0,
            west_lon_deg: 11.0,
            dlat_deg: d,
            dlon_deg: d,
        };
        let (sx, sy) = aerie_terrain::load::geographic_spacing_m(47.05, d, d);
        let grid = GeoGrid::of(Some(&geo), sx, sy).unwrap();
        let hs: Vec<f32> = (0..(97 * 65)).map(|i| (i % 11) as f32).collect();
        let density = TessDensity::new(&hs, [97, 65], 32, 0.5).unwrap();
        let tg = TessGeo::new(&density, &grid);
        let eye = glam::DVec3::new(1500.0, -700.0, 2200.0);
        let patch = |cx, cy, nw| TessPatch {
            cell: [cx, cy],
            north_west: nw,
            outer: [1.0; 3],
            inner: 1.0,
        };
        let patches = [patch(0, 0, false), patch(0, 0, true), patch(2, 1, true)];
        let mut records: Vec<TessPatchGpu> = (patches.iter())
            .map(|p| patch_record(&density, [sx, sy], eye, p))
            .collect();
        let mut cells = Vec::new();
        tg.cell_records(&density, eye, &patches, &mut records, &mut cells);
        // One frame per cell, both halves of cell (0, 0) on the first.
        assert_eq!(cells.len(), 2);
        assert_eq!(
            records.iter().map(|r| r.geo_cell).collect::<Vec<_>>(),
            [0, 0, 1]
        );
        assert!(records.iter().all(|r| r.geo_centre == [16, 16]));
        // Each frame is the tiles' own for a node of 32 samples at step 1 at that cell, seen
        // from the eye (the same fields, the centre within f32 rounding of a fresh one).
        let from_eye = GeoEye::new(&grid, eye);
        for (k, (cx, cy)) in [(0u32, 0u32), (2, 1)].into_iter().enumerate() {
            let want = from_eye.node_fields([cx as i64 * 32, cy as i64 * 32], 1, 32);
            let got = cells[k];
            assert_eq!(got.geo_axis_r, want.geo_axis_r);
            assert_eq!(got.geo_radius, want.geo_radius);
            for a in 0..3 {
                let (g, w) = (got.geo_origin[a], want.geo_origin[a]);
                assert!(
                    (g - w).abs() <= 1e-3 + 1e-6 * w.abs(),
                    "{k} {a}: {g} vs {w}"
                );
            }
            assert_eq!(got.geo_origin[3], want.geo_origin[3]);
        }
    }

    #[test]
    fn oversized_grids_are_refused() {
        let grid = SourceGrid {
            width: 4097,
            height: 4097,
            valid_width: 4097,
            valid_height: 4097,
            spacing_x: 30.0,
            spacing_y: 30.0,
            geo: None,
            checksum: 0,
            description: String::new(),
        };
        assert!(check_tess_grid(&grid, 1 << 30).is_ok());
        let e = check_tess_grid(&grid, 1 << 26).unwrap_err();
        assert!(e.contains("4097×4097") && e.contains("64 MiB"), "{e}");
    }
}
