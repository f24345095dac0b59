//! What a renderer is made with: size, budgets, tile and clipmap shape, pools, LOD parameters.

use aerie_terrain::select::{SelectParams, MAX_REFINEMENT};

use crate::vk::DeviceDesc;

/// Vertices per tile side (m = 2^j + 1). DESIGN.md default.
pub const DEFAULT_TILE_SIZE: u32 = 17;

/// How to build a [`crate::render::frame::TerrainRenderer`].
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

impl RendererDesc {
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
