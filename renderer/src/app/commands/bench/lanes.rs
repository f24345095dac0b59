//! The bench's lanes: one renderer per configuration, made alike for the first pass and for
//! every replay (`--replays`), and the start-up fill they render before the measured frames.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Instant;

use super::args::{BenchArgs, Plan};
use super::config::BenchConfig;
use super::replays;
use super::rows::FrameRow;
use super::settle;
use crate::app::failure::{renderer_failure, runtime, Failure};
use crate::app::flight_plan::FlightPlan;
use crate::app::renderer_setup::{patch_tiles_of, renderer_desc, RendererChoice};
use crate::render::frame::{RendererDesc, TerrainRenderer};
use crate::tools::image_error::ImageError;
use aerie_terrain::bake::ErrorBake;
use aerie_terrain::camera::Camera;
use aerie_terrain::select::{LodMode, Selection};
use aerie_terrain::source::TerrainSource;
use glam::DVec3;

/// The renderer of one configuration: `full` gets pools large enough to draw every visible
/// tile at full resolution (as `aerie render --lod full`).
/// A swept baseline's knob sets its patch side, split-distance scale or LOD range.
/// A configuration with another tile size (`--tile-sizes`) has tiles of that size, its patch
/// side divided into them, and pools of as many bytes as the default's: (q₀/q)² times the
/// slots (a slot holds a tile's samples), so a quarter-size tile is not held back by a pool
/// sized for fewer, larger ones.
pub(super) fn lane_desc(a: &BenchArgs, p: &Plan, config: BenchConfig) -> RendererDesc {
    let m = config.tile_size_or_default();
    let n = match (config.mode, config.knob) {
        (LodMode::Clipmap, Some(n)) => n as u32,
        _ => a.patch,
    };
    // Checked in `plan` for every tile size.
    let patch = patch_tiles_of(n, m).unwrap_or(p.patch_tiles);
    let mut desc = renderer_desc(&RendererChoice {
        gpu: a.gpu.clone(),
        validate: a.validate,
        width: p.view.width,
        height: p.view.height,
        patch_tiles: patch,
        mode: config.mode,
        tau_px: config.tau_px.unwrap_or(1.0),
        curvature: !a.no_curvature,
        debug_tiles: false,
        look: a.look.look(),
        normal_maps: a.normal_maps.on(),
        normal_source: a.normals.source(),
        horizon_cull: a.horizon_cull.on(),
        carry: a.carry_selection.on(),
        skirts: a.skirts.rule(),
    });
    desc.pool_capacity = pools_for_tile_size(desc.pool_capacity, desc.tile_size, m);
    desc.tile_size = m;
    // Each configuration starts as the image generator does (`run`).
    desc.warm_start = true;
    match (config.mode, config.knob) {
        (LodMode::Distance, Some(k)) => desc.select.distance_factor *= k,
        (LodMode::Cdlod, Some(k)) => desc.select.cdlod_range = k,
        (LodMode::Tessellation, Some(k)) => desc.select.tess_density *= k,
        _ => {}
    }
    desc
}

/// Pool slots for tiles of `to` vertices a side holding the bytes `slots` hold for tiles of
/// `from` (`slots[i]` the pool of r = i + 1): a slot of refinement r holds ((q << r) + 1)²
/// samples, so the count scales by about (q_from / q_to)² (rounded up; an empty pool stays
/// empty). A pool with more slots than the device's array layers packs several to a layer
/// (`render/pool_atlas.rs`), so the count is not capped: every size gets the same bytes.
pub(super) fn pools_for_tile_size<const N: usize>(slots: [u32; N], from: u32, to: u32) -> [u32; N] {
    let (qf, qt) = (u64::from(from.max(2) - 1), u64::from(to.max(2) - 1));
    let mut out = slots;
    for (i, s) in out.iter_mut().enumerate() {
        let side = |q: u64| ((q << (i + 1)) + 1).pow(2);
        let scaled = (u64::from(*s) * side(qf)).div_ceil(side(qt));
        *s = u32::try_from(scaled).unwrap_or(u32::MAX);
    }
    out
}

/// A configuration's renderer with its CPU mirror of the selection (for the oracle) and its
/// worst frame so far.
pub(super) struct Lane {
    pub(super) config: BenchConfig,
    pub(super) renderer: TerrainRenderer,
    /// Reported in the summaries (false for a `full` renderer made only as the reference, and
    /// for the feature-cost variants).
    pub(super) reported: bool,
    /// `--feature-costs`: which feature this renderer has off (an index of the costs' list).
    pub(super) variant: Option<usize>,
    pub(super) selection: Selection,
    pub(super) depth: Vec<f32>,
    pub(super) heat: Vec<f32>,
    pub(super) worst_heat: Vec<f32>,
    pub(super) worst: Option<(u32, f64)>,
    pub(super) image_total: ImageError,
}

/// The start-up fill (`--settle`, [`settle`]): each lane renders the flight's first pose until
/// a frame leaves nothing late or pending, at most `max` frames; summary.md's line on it (of
/// the first flight; a `replay` fills the measured lanes again, silently).
pub(super) fn settle_lanes(
    lanes: &mut [Lane],
    flight: &FlightPlan,
    p: &Plan,
    max: u32,
    replay: bool,
) -> Result<Option<String>, Failure> {
    if max == 0 {
        return Ok(None);
    }
    let (pos, att) = flight.pose_at(0.0);
    let camera = Camera::new(pos, att, p.view.frustum);
    let started = Instant::now();
    let mut fills = Vec::new();
    // A replay fills only the measured lanes (the reference and the variants are not flown again).
    for lane in lanes.iter_mut().filter(|l| l.reported || !replay) {
        let mut settler = settle::Settler::new(max);
        while settler.wants_frame() {
            let stats = lane
                .renderer
                .render(&camera)
                .map_err(|e| runtime(format!("{} start-up frame: {e}", lane.config.label())))?;
            settler.rendered(&stats);
        }
        if lane.reported {
            fills.push((lane.config.label(), settler.fill()));
        }
    }
    let line = settle::describe(max, &fills);
    if let (Some(l), false) = (&line, replay) {
        eprintln!("{l} ({:.1} s)", started.elapsed().as_secs_f64());
    }
    Ok(line)
}

/// What every renderer of a flight is made with besides its own configuration.
pub(super) struct LaneInputs<'a> {
    pub a: &'a BenchArgs,
    pub p: &'a Plan,
    pub drape: Option<crate::render::drape_textures::SharedDrapeInput>,
    pub drape_budget: u64,
    /// The error bakes, one per tile size drawn (`bake_for` picks a renderer's).
    pub bakes: &'a [Arc<ErrorBake>],
    pub eye0: DVec3,
}

/// The bake of tiles of `tile_size` among `bakes` (one is made for every size a run draws).
pub(super) fn bake_for(
    bakes: &[Arc<ErrorBake>],
    tile_size: u32,
) -> Result<&Arc<ErrorBake>, Failure> {
    bakes
        .iter()
        .find(|b| b.params.tile_size == tile_size)
        .ok_or_else(|| runtime(format!("no error bake with tiles of {tile_size} was made")))
}

impl LaneInputs<'_> {
    /// A renderer of `config` (`edit` changes its description first: a feature-cost variant),
    /// loaded from `source` at the flight's first eye; a failure names the configuration.
    pub fn open(
        &self,
        config: BenchConfig,
        source: Arc<dyn TerrainSource>,
        edit: impl FnOnce(&mut RendererDesc),
    ) -> Result<TerrainRenderer, Failure> {
        let mut desc = lane_desc(self.a, self.p, config);
        desc.drape = self.drape.clone();
        desc.drape_budget_bytes = self.drape_budget;
        edit(&mut desc);
        let bake = bake_for(self.bakes, desc.tile_size)?.clone();
        let mut renderer = TerrainRenderer::new(&desc).map_err(runtime)?;
        renderer.load_source(source, bake, self.eye0).map_err(|e| {
            let mut f = renderer_failure(e);
            f.message = format!("{}: {}", config.label(), f.message);
            f
        })?;
        Ok(renderer)
    }
}

impl Lane {
    /// A lane around a renderer just opened, nothing measured yet.
    pub fn new(
        config: BenchConfig,
        renderer: TerrainRenderer,
        reported: bool,
        variant: Option<usize>,
    ) -> Self {
        Lane {
            config,
            renderer,
            reported,
            variant,
            selection: Selection::default(),
            depth: Vec::new(),
            heat: Vec::new(),
            worst_heat: Vec::new(),
            worst: None,
            image_total: ImageError {
                tau_px: config.tau_for_error(),
                ..Default::default()
            },
        }
    }
}

/// Flies the measured frames again, `a.replays − 1` times (`--replays`, [`replays`]): each
/// reported lane's renderer is replaced by a fresh one (the old one's validation verdict kept
/// in `validation`), filled at the first pose as before and rendering every frame, each
/// replay in its own order of the configurations ([`replays::lane_order`]; the reference and
/// the feature-cost variants are not flown again); a frame's row takes a faster replay of the
/// same work.
pub(super) fn replay(
    lanes: &mut [Lane],
    inputs: &LaneInputs,
    source: &Arc<dyn TerrainSource>,
    flight: &FlightPlan,
    rows: &mut [FrameRow],
    validation: &mut Vec<String>,
) -> Result<(), Failure> {
    let (a, p) = (inputs.a, inputs.p);
    let total_frames = a.warmup + a.frames;
    let at: HashMap<(u32, usize), usize> = rows
        .iter()
        .enumerate()
        .map(|(r, row)| ((row.frame, row.config), r))
        .collect();
    let measured: Vec<usize> = (0..lanes.len()).filter(|&i| lanes[i].reported).collect();
    let m = measured.len();
    let started = Instant::now();
    for replay in 1..a.replays() {
        for &i in &measured {
            let lane = &mut lanes[i];
            let fresh = inputs.open(lane.config, source.clone(), |_| {})?;
            let mut old = std::mem::replace(&mut lane.renderer, fresh);
            let counters = old.validation_counters();
            old.destroy();
            if let Err(e) = counters.verdict() {
                validation.push(format!("{}: {e}", lane.config.label()));
            }
        }
        settle_lanes(lanes, flight, p, a.settle, true)?;
        for k in 0..total_frames {
            let (pos, att) = flight.pose_at(k as f64 / a.fps);
            let camera = Camera::new(pos, att, p.view.frustum);
            for j in replays::lane_order(m, replay, k) {
                let i = measured[j];
                let lane = &mut lanes[i];
                let t0 = Instant::now();
                let stats = lane.renderer.render(&camera).map_err(|e| {
                    runtime(format!(
                        "{} replay {replay} frame {k}: {e}",
                        lane.config.label()
                    ))
                })?;
                let wall_ms = t0.elapsed().as_secs_f64() * 1e3;
                let Some(&r) = at.get(&(k, i)) else {
                    continue;
                };
                let row = &mut rows[r];
                replays::take(
                    &mut row.wall_ms,
                    &mut row.stats,
                    &mut row.replays,
                    replay,
                    wall_ms,
                    &stats,
                );
            }
        }
        eprintln!(
            "bench: replay {}/{} of {total_frames} frames × {m} configurations, {:.0} s elapsed",
            replay + 1,
            a.replays(),
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::pools_for_tile_size;

    #[test]
    fn pools_keep_their_bytes_across_tile_sizes() {
        let slots = [256u32, 128, 96, 32, 40, 0];
        assert_eq!(pools_for_tile_size(slots, 17, 17), slots);
        let small = pools_for_tile_size(slots, 17, 9);
        for (i, (&a, &b)) in slots.iter().zip(&small).enumerate() {
            let r = i + 1;
            let bytes = |n: u32, q: u64| u64::from(n) * ((q << r) + 1).pow(2);
            // At least the bytes of before, less than one more slot above them.
            assert!(bytes(b, 8) >= bytes(a, 16), "r = {r}: {b} slots");
            assert!(
                b == 0 || bytes(b - 1, 8) < bytes(a, 16),
                "r = {r}: {b} slots"
            );
        }
        assert_eq!(small[5], 0, "an empty pool stays empty");
        // About four smaller slots to one of the default's at r = 1 (33² / 17² samples).
        assert_eq!(small[0], (256 * 33 * 33u32).div_ceil(17 * 17));
        // Tiles of 5: r = 1 wants 256 · 33² / 9² slots, more than 2048 array layers hold:
        // not capped (the pool packs them several to a layer), the same bytes.
        let tiny = pools_for_tile_size(slots, 17, 5);
        assert_eq!(tiny[0], (256 * 33 * 33u32).div_ceil(9 * 9));
        assert!(tiny[0] > 2048, "{tiny:?}");
        // Larger tiles: fewer slots, never more than given.
        let large = pools_for_tile_size(slots, 17, 33);
        assert!(large.iter().zip(&slots).all(|(a, b)| a <= b), "{large:?}");
    }
}
