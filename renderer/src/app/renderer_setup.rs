//! The one place a [`RendererDesc`] is assembled from command-line choices (`render`, `fly`,
//! every configuration of `bench`), and the checks of the size, field of view and patch side
//! that come with it.

use std::sync::Arc;

use crate::app::args::{DrapeArgs, GpuArgs};
use crate::app::failure::{bad_input, Failure};
use crate::render::drape_textures::{DrapeInput, SharedDrapeInput};
use crate::render::frame::{NormalSource, RendererDesc};
use crate::render::tile_instances::SkirtRule;
use crate::render::uniforms::Look;
use crate::vk::DeviceDesc;
use aerie_config::parse_size;
use aerie_terrain::camera::Frustum;
use aerie_terrain::select::{LodMode, SelectParams, MAX_REFINEMENT};

/// Refined-tile pools of a `full` renderer: brute force draws every visible tile at full
/// resolution, so it needs room for all of them.
const FULL_POOL_CAPACITY: [u32; MAX_REFINEMENT as usize] = [1024, 512, 256, 128, 48, 16];

/// The output image: its size and symmetric frustum.
#[derive(Debug, Clone, Copy)]
pub struct View {
    pub width: u32,
    pub height: u32,
    pub frustum: Frustum,
}

/// Checks `--size WxH` and `--fov` (degrees) and makes the frustum.
pub fn parse_view(size: &str, fov_deg: f64) -> Result<View, Failure> {
    let (width, height) = parse_size(size).map_err(|e| bad_input(format!("--size: {e}")))?;
    if !(fov_deg.is_finite() && fov_deg > 0.0 && fov_deg < 180.0) {
        return Err(bad_input(format!(
            "--fov: {fov_deg} is outside (0, 180) degrees"
        )));
    }
    let frustum = Frustum::try_symmetric(fov_deg.to_radians(), width, height)
        .map_err(|e| bad_input(format!("--fov: {e}")))?;
    Ok(View {
        width,
        height,
        frustum,
    })
}

/// Tiles per clipmap patch side for `--patch n`: n must be P·(m−1)+1 with P even and ≥ 8.
pub fn patch_tiles(patch: u32) -> Result<u32, Failure> {
    patch_tiles_of(patch, RendererDesc::default().tile_size)
}

/// [`patch_tiles`] for tiles of `tile_size` vertices a side (m).
pub fn patch_tiles_of(patch: u32, tile_size: u32) -> Result<u32, Failure> {
    let q = tile_size.saturating_sub(1).max(1);
    if patch < 8 * q + 1 || !(patch - 1).is_multiple_of(2 * q) {
        return Err(bad_input(format!(
            "--patch: {patch} must be P·{q}+1 with P even and ≥ 8 (e.g. {} or {})",
            8 * q + 1,
            16 * q + 1
        )));
    }
    Ok((patch - 1) / q)
}

/// What a command chose for one renderer.
#[derive(Debug, Clone)]
pub struct RendererChoice {
    pub gpu: Option<String>,
    pub validate: bool,
    pub width: u32,
    pub height: u32,
    pub patch_tiles: u32,
    pub mode: LodMode,
    pub tau_px: f64,
    pub curvature: bool,
    pub debug_tiles: bool,
    pub look: Look,
    pub normal_maps: bool,
    pub normal_source: NormalSource,
    /// Bounded: drop tiles hidden behind nearer terrain.
    pub horizon_cull: bool,
    /// Bounded, one view (plane or ellipsoid): carry refined ring tiles across frames.
    pub carry: bool,
    /// Which tile edges get a skirt.
    pub skirts: SkirtRule,
}

/// The offscreen renderer for `c`: validation always on in debug builds; `full` gets pools
/// large enough for every visible tile and the deepest refinement.
pub fn renderer_desc(c: &RendererChoice) -> RendererDesc {
    let defaults = RendererDesc::default();
    let full = c.mode == LodMode::Full;
    RendererDesc {
        validation: c.validate || cfg!(debug_assertions),
        device: DeviceDesc {
            name_filter: c.gpu.clone(),
            swapchain: false,
        },
        width: c.width,
        height: c.height,
        patch_tiles: c.patch_tiles,
        pool_capacity: if full {
            FULL_POOL_CAPACITY
        } else {
            defaults.pool_capacity
        },
        debug_tiles: c.debug_tiles,
        skirts: c.skirts,
        look: c.look,
        normal_maps: c.normal_maps,
        normal_source: c.normal_source,
        select: SelectParams {
            mode: c.mode,
            tau_px: c.tau_px,
            curvature: c.curvature,
            max_refinement: if full {
                MAX_REFINEMENT
            } else {
                SelectParams::default().max_refinement
            },
            horizon_cull: c.horizon_cull,
            carry: c.carry,
            ..SelectParams::default()
        },
        ..defaults
    }
}

/// A checked [`GpuArgs`]: the view and the renderer it asks for.
#[derive(Debug, Clone)]
pub struct Setup {
    pub view: View,
    pub desc: RendererDesc,
}

/// Checks every option of `g` (size, field of view, τ, patch) and assembles the renderer.
pub fn setup(g: &GpuArgs) -> Result<Setup, Failure> {
    let view = parse_view(&g.size, g.fov)?;
    if !(g.tau.is_finite() && g.tau > 0.0) {
        return Err(bad_input(format!(
            "--tau: {} must be a positive number of pixels",
            g.tau
        )));
    }
    let patch_tiles = patch_tiles(g.patch)?;
    if !(g.tess_density.is_finite() && g.tess_density > 0.0) {
        return Err(bad_input(format!(
            "--tess-density: {} must be a positive number",
            g.tess_density
        )));
    }
    let mut desc = renderer_desc(&RendererChoice {
        gpu: g.gpu.clone(),
        validate: g.validate,
        width: view.width,
        height: view.height,
        patch_tiles,
        mode: g.lod.mode(),
        tau_px: g.tau,
        curvature: !g.no_curvature,
        debug_tiles: g.debug_tiles,
        look: g.look.look(),
        normal_maps: g.normal_maps.on(),
        normal_source: g.normals.source(),
        horizon_cull: g.horizon_cull.on(),
        carry: g.carry_selection.on(),
        skirts: g.skirts.rule(),
    });
    desc.drape = drape_input(&g.drape)?;
    desc.drape_budget_bytes = drape_budget(&g.drape)?;
    desc.select.tess_density *= g.tess_density;
    Ok(Setup { view, desc })
}

/// Reads the rasters `--imagery` and `--landcover` name and the land-cover code table; a bad
/// file is bad input naming it (its registration onto the terrain comes when it is loaded).
pub fn drape_input(a: &DrapeArgs) -> Result<Option<SharedDrapeInput>, Failure> {
    drape_input_with(a, None)
}

/// As [`drape_input`], with a run config's `[landcover]` table (and the config's folder, which
/// its raster path is relative to) filling what the flags leave unset: `--landcover` wins over
/// its `raster`, `--landcover-map` over its codes.
pub fn drape_input_with(
    a: &DrapeArgs,
    config: Option<(&aerie_config::LandcoverSettings, &std::path::Path)>,
) -> Result<Option<SharedDrapeInput>, Failure> {
    use aerie_config::landcover::{parse_landcover, LandcoverMap, Preset};
    use aerie_terrain::drape::read_raster;
    let raster = a
        .landcover
        .clone()
        .or_else(|| config.and_then(|(lc, dir)| lc.raster.as_ref().map(|r| dir.join(r))));
    if let (Some((lc, _)), None) = (config, &raster) {
        if lc.raster.is_none() && a.landcover.is_none() {
            eprintln!(
                "warning: [landcover] maps codes but no raster is given (landcover.raster or --landcover): the classes are derived from the terrain"
            );
        }
    }
    let budget_bytes = drape_budget(a)?;
    if a.imagery.is_empty() && raster.is_none() {
        return Ok(None);
    }
    let read = |p: &std::path::Path| read_raster(p).map_err(|e| bad_input(e.to_string()));
    let imagery = a
        .imagery
        .iter()
        .map(|p| read(p))
        .collect::<Result<Vec<_>, _>>()?;
    let landcover = raster.as_deref().map(read).transpose()?;
    let map = match (&a.landcover_map, config) {
        (None, Some((lc, _))) => lc.map.clone(),
        (None, None) => LandcoverMap::preset(Preset::WorldCover),
        (Some(m), _) => match Preset::parse(m) {
            Some(p) => LandcoverMap::preset(p),
            None => {
                let text = std::fs::read_to_string(m).map_err(|e| {
                    bad_input(format!(
                        "--landcover-map: {m}: {e} (worldcover, corine or a TOML file)"
                    ))
                })?;
                parse_landcover(&text, m).map_err(bad_input)?
            }
        },
    };
    Ok(Some(Arc::new(DrapeInput {
        imagery,
        landcover,
        table: map.table(),
        budget_bytes,
    })))
}

/// `--drape-mb` in bytes: what the draped textures may take (also a store's imagery layer).
pub fn drape_budget(a: &DrapeArgs) -> Result<u64, Failure> {
    if !(a.drape_mb.is_finite() && a.drape_mb > 0.0 && a.drape_mb <= 65536.0) {
        return Err(bad_input(format!(
            "--drape-mb: {} must be a number of MiB in (0, 65536]",
            a.drape_mb
        )));
    }
    Ok((a.drape_mb * 1024.0 * 1024.0) as u64)
}

/// What was draped, for a command's JSON summary (null without rasters): the files, the
/// textures' sizes and texels per terrain sample, the land-cover texels the raster covered and
/// those whose code the table does not know (drawn with the derived classes, by code), and the
/// textures' device bytes.
pub fn drape_json(r: &crate::render::frame::TerrainRenderer) -> serde_json::Value {
    let (Some(rasters), bytes) = r.draped() else {
        return serde_json::Value::Null;
    };
    // Without --imagery/--landcover only a store's imagery layer was draped: no files, no
    // code table (every code unknown, none counted: there is no land-cover raster).
    let input = r.desc().drape.as_deref();
    let table = input.map_or([aerie_terrain::drape::CODE_NONE; 256], |i| i.table);
    let size = |s: &aerie_terrain::drape::DrapeSize| serde_json::json!({"texels": [s.width, s.height], "texels_per_sample": s.texels_per_sample});
    let unknown: serde_json::Map<String, serde_json::Value> = rasters
        .code_counts
        .as_ref()
        .map(|s| {
            s.codes
                .iter()
                .enumerate()
                .filter(|&(c, &n)| n > 0 && table[c] == aerie_terrain::drape::CODE_NONE)
                .map(|(c, &n)| (c.to_string(), n.into()))
                .collect()
        })
        .unwrap_or_default();
    serde_json::json!({
        "imagery": input.map_or(Vec::new(), |i| i.imagery.iter().map(|r| r.path.clone()).collect()),
        "imagery_texture": rasters.imagery.as_ref().map(|(s, _)| size(s)),
        "landcover": input.and_then(|i| i.landcover.as_ref()).map(|r| r.path.clone()),
        "landcover_texture": rasters.classes.as_ref().map(|(s, _)| size(s)),
        "landcover_covered_texels": rasters.code_counts.as_ref().map(|s| s.covered),
        "unknown_code_texels": rasters.unknown_code_texels(&table),
        "unknown_codes": unknown,
        "gpu_bytes": bytes,
        "budget_bytes": input.map_or(r.desc().drape_budget_bytes, |i| i.budget_bytes),
        "capped": rasters.capped,
        "imagery_layer": rasters.layer_level.as_ref().map(|l| serde_json::json!({
            "layer": l.layer.display().to_string(),
            "level": l.level,
            "texels_per_sample": l.texels_per_sample,
        })),
        "imagery_stream": r.imagery_stream().and_then(|s| Some((s, s.windows()?))).map(|(s, w)| serde_json::json!({
            "levels": w.levels(),
            "window_texels": w.side,
            "gpu_bytes": s.bytes(),
            "cells_copied": s.totals.cells,
            "cells_cleared": s.totals.cleared,
            "cells_pending": s.pending(),
            "cells_not_resident": s.totals.not_resident,
        })),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn choice(mode: LodMode) -> RendererChoice {
        RendererChoice {
            gpu: Some("llvmpipe".into()),
            validate: true,
            width: 320,
            height: 200,
            patch_tiles: 16,
            mode,
            tau_px: 0.5,
            curvature: false,
            debug_tiles: true,
            look: Look::Classes,
            normal_maps: false,
            normal_source: NormalSource::Cpu,
            horizon_cull: true,
            carry: false,
            skirts: SkirtRule::Everywhere,
        }
    }

    #[test]
    fn the_choice_reaches_the_descriptor() {
        let d = renderer_desc(&choice(LodMode::Bounded));
        let defaults = RendererDesc::default();
        assert!(d.validation);
        assert_eq!(d.device.name_filter.as_deref(), Some("llvmpipe"));
        assert!(!d.device.swapchain);
        assert_eq!((d.width, d.height, d.patch_tiles), (320, 200, 16));
        assert!(d.debug_tiles);
        assert_eq!(d.look, Look::Classes);
        assert!(!d.normal_maps && RendererDesc::default().normal_maps);
        assert_eq!(d.select.mode, LodMode::Bounded);
        assert_eq!(d.select.tau_px, 0.5);
        assert!(!d.select.curvature);
        assert!(d.select.horizon_cull);
        assert!(!d.select.carry && SelectParams::default().carry);
        assert_eq!(d.skirts, SkirtRule::Everywhere);
        assert_eq!(defaults.skirts, SkirtRule::WhereResolutionsDiffer);
        assert_eq!(d.pool_capacity, defaults.pool_capacity);
        assert_eq!(
            d.select.max_refinement,
            SelectParams::default().max_refinement
        );
        assert_eq!(d.tile_size, defaults.tile_size);
        assert_eq!(d.staging_budget, defaults.staging_budget);
    }

    #[test]
    fn full_gets_room_for_every_tile() {
        let d = renderer_desc(&choice(LodMode::Full));
        assert_eq!(d.pool_capacity, FULL_POOL_CAPACITY);
        assert_eq!(d.select.max_refinement, MAX_REFINEMENT);
    }

    #[test]
    fn bad_views_and_patches_name_their_flag() {
        let v = parse_view("64x36", 90.0).unwrap();
        assert_eq!((v.width, v.height), (64, 36));
        for (size, fov, flag) in [
            ("64x0", 90.0, "--size"),
            ("wide", 90.0, "--size"),
            ("64x36", 0.0, "--fov"),
            ("64x36", 180.0, "--fov"),
            ("64x36", f64::NAN, "--fov"),
        ] {
            let e = parse_view(size, fov).unwrap_err();
            assert_eq!(e.code, 2);
            assert!(e.message.starts_with(flag), "{}", e.message);
        }
        assert_eq!(patch_tiles_of(129, 9).unwrap(), 16);
        assert_eq!(patch_tiles_of(513, 33).unwrap(), 16);
        // 129 = 4·32 + 1: too few tiles of 33 (P ≥ 8).
        assert!(patch_tiles_of(129, 33).is_err());
        assert_eq!(patch_tiles(129).unwrap(), 8);
        assert_eq!(patch_tiles(257).unwrap(), 16);
        for bad in [0, 1, 65, 130, 145] {
            assert!(patch_tiles(bad).unwrap_err().message.starts_with("--patch"));
        }
    }

    #[test]
    fn a_drape_budget_outside_its_range_is_bad_input_naming_the_flag() {
        for mb in [0.0, -1.0, f64::NAN, 1e9] {
            let a = DrapeArgs {
                imagery: vec!["missing.tif".into()],
                drape_mb: mb,
                ..DrapeArgs::default()
            };
            let e = drape_input(&a).unwrap_err();
            assert_eq!(e.code, 2, "{mb}: {}", e.message);
            assert!(e.message.contains("--drape-mb"), "{}", e.message);
        }
        // In range, the next check is the file itself.
        let a = DrapeArgs {
            imagery: vec!["missing.tif".into()],
            drape_mb: 64.0,
            ..DrapeArgs::default()
        };
        let e = drape_input(&a).unwrap_err();
        assert_eq!(e.code, 2);
        assert!(e.message.contains("missing.tif"), "{}", e.message);
    }
}
