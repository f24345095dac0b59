//! What a renderer is made with: size, budgets, tile and clipmap shape, pools, LOD parameters.

use aerie_terrain::clipmap::ClipmapDesc;
use aerie_terrain::select::{SelectParams, MAX_REFINEMENT};
use aerie_terrain::source::SampleRect;

use crate::render::tile_instances::SkirtRule;
use crate::render::uniforms::Look;
use crate::vk::DeviceDesc;

/// Vertices per tile side (m = 2^j + 1). DESIGN.md default.
pub const DEFAULT_TILE_SIZE: u32 = 17;

/// Where the normal maps' texels are computed (issue 17; README "Normal maps").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NormalSource {
    /// On the CPU with each strip, from the full-resolution samples (the mean level-0 gradient
    /// over each texel's footprint, `render/normal_map.rs`), staged after its heights.
    #[default]
    Cpu,
    /// On the GPU after the strips' copies, from each level's own heights (central differences
    /// of the level's samples, `render/normal_pass.rs`): nothing computed or staged on the CPU.
    Gpu,
}

/// How to build a [`crate::render::frame::TerrainRenderer`].
#[derive(Debug, Clone)]
pub struct RendererDesc {
    pub validation: bool,
    /// Extra instance extensions, e.g. the surface extensions a window needs.
    pub instance_extensions: Vec<std::ffi::CString>,
    pub device: DeviceDesc,
    pub width: u32,
    pub height: u32,
    /// Hard upload budget per frame (bytes), the size of one staging-ring region. The frame's
    /// instance records are staged there too: when a selection's records would take more than
    /// half the region, it grows to hold them beside this budget (`jobs::staging_to_hold`;
    /// once per growth the device is waited idle).
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
    /// At most this many array layers in a pool's image (None: the device's
    /// `maxImageArrayLayers`). A pool with more slots packs several to a layer
    /// (`render/pool_atlas.rs`); fewer layers pack sooner — the tests draw that way on lavapipe.
    pub pool_layers: Option<u32>,
    pub select: SelectParams,
    /// Colour tiles by level and refinement (the seed's figure 3).
    pub debug_tiles: bool,
    /// Shading: plain, full (land cover, sky, aerial perspective) or the class view.
    pub look: Look,
    /// Keep normal maps of the full-resolution heights for the level textures and light level
    /// tiles with them (`render/normal_map.rs`); off: per-vertex normals of the drawn level.
    pub normal_maps: bool,
    /// Where the normal maps' texels are computed (with `normal_maps` on).
    pub normal_source: NormalSource,
    /// Skirt depth = factor × ½(ε + the largest of ε and its edge neighbours' ε) + minimum
    /// (metres): at the default 2, ε + max(ε, neighbours' ε), which closes the cracks a
    /// neighbour drawn at another level can open (`select::node_skirts`). Must be ≥ 1.
    pub skirt_factor: f32,
    pub skirt_min_m: f32,
    /// Which edges get skirts: by default those not shared with a node drawn at the same
    /// resolution — the same vertices on both sides — (`select::node_skirts`); `Everywhere`
    /// as DESIGN.md's "Cracks" first drew them; `None` shows the cracks (tests). CDLOD draws
    /// none whatever this says.
    pub skirts: SkirtRule,
    /// Prefetch looks this many frames ahead along the eye's motion.
    pub prefetch_frames: f64,
    /// The first frame after each load also selects the views around the eye and prefetches
    /// their refined tiles (`warm_start.rs`): for flights and the image generator, whose next
    /// frames may look anywhere; a still image, drawn once, has no next frames to spare.
    pub warm_start: bool,
    /// Imagery and a land-cover raster draped on the terrain (registered when it is loaded).
    pub drape: Option<crate::render::drape_textures::SharedDrapeInput>,
    /// Device bytes the draped textures may take (`--drape-mb`): also what a store's imagery
    /// layer may fill when no `--imagery` is given.
    pub drape_budget_bytes: u64,
    /// Drape a store's imagery layer when the source has one (and no `--imagery` is given);
    /// off only to measure what draping costs.
    pub drape_store_imagery: bool,
    /// Stream the layer's levels finer than the one that fits the budget whole in windows
    /// around the eye (render/imagery_stream.rs); off: that level alone, everywhere.
    pub drape_stream_imagery: bool,
}

impl RendererDesc {
    /// Its drape fields, as `drape_textures::drape_rasters` takes them.
    pub fn drape_ask(&self) -> crate::render::drape_textures::DrapeAsk<'_> {
        crate::render::drape_textures::DrapeAsk {
            input: self.drape.as_deref(),
            budget_bytes: self.drape_budget_bytes,
            store_imagery: self.drape_store_imagery,
            stream: self.drape_stream_imagery,
        }
    }
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
            // r = 5: a 1,000 km flight 300 m above ridged terrain (1920×1080, τ = 1) draws up
            // to 32 such ring tiles in one frame; 16 slots left ~7 of them late every frame
            // (5.8 % of tile-frames there). 40 slots (1 MiB each) keep 8 for prefetch.
            // r = 3: a 1,000 km flight 600 m above ridged terrain at 30 m (32769² store,
            // 1280×720) drew up to 65 such tiles a frame; 48 slots left 1.36 % of its
            // tile-frames late for want of a slot. 96 slots (65 KiB each) cost 3 MiB more.
            pool_capacity: [256, 128, 96, 32, 40, 0],
            pool_layers: None,
            select: SelectParams::default(),
            debug_tiles: false,
            look: Look::default(),
            normal_maps: true,
            normal_source: NormalSource::Cpu,
            skirt_factor: 2.0,
            skirt_min_m: 1.0,
            skirts: SkirtRule::default(),
            prefetch_frames: 20.0,
            warm_start: false,
            drape: None,
            drape_budget_bytes: (crate::render::drape_textures::DEFAULT_DRAPE_MIB * 1048576.0)
                as u64,
            drape_store_imagery: true,
            drape_stream_imagery: true,
        }
    }
}

impl RendererDesc {
    /// The frame plan's inputs for one camera drawn alone — no other channel, no overlay, this
    /// description's selection, prefetch, skirts and staging budget (offsets aligned to
    /// `alignment`): what the CPU-only flight (`fly --no-draw`) and the benchmarks plan.
    pub fn solo_frame_inputs<'a>(
        &'a self,
        frame: u64,
        camera: &'a aerie_terrain::camera::Camera,
        viewport: (u32, u32),
        tile_meshes: crate::render::plan::TileMeshes,
        alignment: u64,
    ) -> crate::render::plan::FrameInputs<'a> {
        crate::render::plan::FrameInputs {
            frame,
            camera,
            viewport,
            channels: &[],
            channels_generation: 0,
            select: &self.select,
            prefetch_frames: self.prefetch_frames,
            skirt_factor: self.skirt_factor,
            skirt_min_m: self.skirt_min_m,
            skirts: self.skirts,
            overlay_bytes: None,
            tile_meshes,
            staging: crate::render::jobs::StagingBudget::new(self.staging_budget, alignment),
        }
    }

    /// The clipmap this renderer lays over `grid`.
    pub fn clipmap(&self, grid: &aerie_terrain::source::SourceGrid) -> ClipmapDesc {
        ClipmapDesc {
            tile_quads: self.tile_size - 1,
            patch_tiles: self.patch_tiles,
            margin_tiles: self.margin_tiles,
            width: grid.width,
            height: grid.height,
        }
    }

    /// The clipmap over `grid` for a terrain baked as `bake`, or why that bake cannot be drawn
    /// by this renderer (sizes, tile size, levels), naming the re-bake that fixes it (pure).
    pub fn clipmap_for_bake(
        &self,
        grid: &aerie_terrain::source::SourceGrid,
        bake: &aerie_terrain::bake::ErrorBake,
    ) -> Result<ClipmapDesc, String> {
        if bake.width != grid.width || bake.height != grid.height {
            return Err(format!(
                "bake is for {}x{} samples, dataset has {}x{}",
                bake.width, bake.height, grid.width, grid.height
            ));
        }
        if bake.params.tile_size != self.tile_size {
            return Err(format!(
                "bake uses tiles of {} vertices, renderer {}: re-bake with --tile-size {}",
                bake.params.tile_size, self.tile_size, self.tile_size
            ));
        }
        let clipmap = self.clipmap(grid);
        clipmap.validate().map_err(|e| format!("clipmap: {e}"))?;
        let level_count = clipmap.level_count();
        if bake.levels.len() < level_count as usize {
            return Err(format!(
                "bake has {} levels, the clipmap needs {level_count}: re-bake with --levels 0",
                bake.levels.len()
            ));
        }
        Ok(clipmap)
    }

    /// The sample rectangles the first frame draws from wherever the eye is: the coarsest
    /// level's whole texture (it never moves). A caller streaming its terrain waits for these
    /// once before loading it — the only wait — so that the first frame has the whole terrain
    /// to draw, coarse, and never anything stale; with normal maps, with the level its normal
    /// texels are computed from on the CPU. Empty for a clipmap that cannot be laid.
    pub fn start_up_rects(&self, grid: &aerie_terrain::source::SourceGrid) -> Vec<SampleRect> {
        let clipmap = self.clipmap(grid);
        if clipmap.validate().is_err() {
            return Vec::new();
        }
        let coarsest = SampleRect {
            level: clipmap.level_count() - 1,
            origin: [0, 0],
            size: [clipmap.texture_side(); 2],
        };
        let mut rects = vec![coarsest];
        if self.normal_maps && self.normal_source == NormalSource::Cpu {
            // Its normal texels' footprints (render/normal_map.rs), read with it.
            let fp = crate::render::normal_map::NormalFootprint::of_level(coarsest.level);
            rects.push(fp.rect(coarsest.origin, coarsest.size));
        }
        rects
    }

    /// GPU bytes of the level textures (one R32F layer per level) and the refined-tile pools
    /// this renderer makes over `grid`: DESIGN.md's budget is 64 MiB at the defaults.
    pub fn terrain_texture_bytes(&self, grid: &aerie_terrain::source::SourceGrid) -> u64 {
        let clipmap = self.clipmap(grid);
        let side = clipmap.texture_side() as u64;
        let levels = clipmap.level_count() as u64 * side * side;
        let q = (self.tile_size - 1) as u64;
        let pools: u64 = (1..=MAX_REFINEMENT as u64)
            .zip(self.pool_capacity)
            .map(|(r, n)| n as u64 * ((q << r) + 1).pow(2))
            .sum();
        (levels + pools) * 4
    }

    /// Refuses a tile size that is not 2^j + 1 in 3..=257 and skirts that cannot close cracks.
    pub fn validate(&self) -> Result<(), String> {
        if !(3..=257).contains(&self.tile_size) || !(self.tile_size - 1).is_power_of_two() {
            return Err(format!(
                "tile size {} must be 2^j + 1 in 3..=257",
                self.tile_size
            ));
        }
        if !(self.skirt_factor >= 1.0 && self.skirt_min_m >= 0.0) {
            return Err(format!(
                "skirt factor {} must be ≥ 1 and minimum {} m ≥ 0",
                self.skirt_factor, self.skirt_min_m
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(side: u32) -> aerie_terrain::source::SourceGrid {
        aerie_terrain::source::SourceGrid {
            width: side,
            height: side,
            valid_width: side,
            valid_height: side,
            spacing_x: 30.0,
            spacing_y: 30.0,
            geo: None,
            checksum: 0,
            description: String::new(),
        }
    }

    #[test]
    fn the_default_textures_fit_the_gpu_budget_and_the_flights_peak_pool_use() {
        let d = RendererDesc::default();
        // The largest store shown (32769², 12 levels) and a small grid.
        for side in [32769, 4097] {
            let bytes = d.terrain_texture_bytes(&grid(side));
            assert!(bytes <= 64 << 20, "{side}²: {bytes} bytes over 64 MiB");
        }
        // 40 r = 5 slots of 513² f32, 32 of 257², ...: the arithmetic, checked once.
        let pools =
            4 * (256 * 33 * 33 + 128 * 65 * 65 + 96 * 129 * 129 + 32 * 257 * 257 + 40 * 513 * 513);
        // 9 clipmap levels of 192² texels (the coarsest holds the whole 32769² grid).
        let levels = 4 * 9 * 192 * 192;
        assert_eq!(d.terrain_texture_bytes(&grid(32769)), pools + levels);
        // The peak of r = 5 ring tiles one frame drew on the 1,000 km flight, and room to
        // prefetch beside it.
        assert!(d.pool_capacity[4] >= 32 + 8, "{:?}", d.pool_capacity);
        // And of r = 3 tiles on the 32769² flight.
        assert!(d.pool_capacity[2] >= 65 + 8, "{:?}", d.pool_capacity);
    }

    #[test]
    fn default_is_valid_and_bad_shapes_are_refused() {
        assert_eq!(RendererDesc::default().validate(), Ok(()));
        for tile_size in [2, 16, 18, 513] {
            let d = RendererDesc {
                tile_size,
                ..Default::default()
            };
            assert!(
                d.validate().unwrap_err().contains("tile size"),
                "{tile_size}"
            );
        }
        let d = RendererDesc {
            skirt_factor: 0.5,
            ..Default::default()
        };
        assert!(d.validate().unwrap_err().contains("skirt factor"));
        let d = RendererDesc {
            skirt_min_m: f32::NAN,
            ..Default::default()
        };
        assert!(d.validate().is_err());
    }
}
