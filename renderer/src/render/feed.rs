//! What the level textures take from the source and ask of it: the cache regions and their
//! content, the level strips gathered as the levels move (what is not resident stays pending in
//! [`LevelContent`] and is retried every frame), and the wishes for the cells the selection
//! lacked or the levels will expose ahead of the eye.
//!
//! Priorities (larger first, `SampleWant`): what this frame would have drawn finer is
//! [`DRAWN_PRIORITY`] + the projected error in pixels it would remove (nearer first among
//! equals); the rest of a level's pending cells rank by nearness below that; prefetches rank
//! below everything drawn ([`PREFETCH_PRIORITY`]).

use glam::DVec3;

use aerie_terrain::clipmap::{
    toroidal_pieces, update_cache, CacheRegion, ClipmapDesc, LevelPlacement, VertexRect,
};
use aerie_terrain::source::SampleRect;

use crate::render::content::LevelContent;
use crate::render::gathered::Gatherer;
use crate::render::jobs::{within_data_cap, ImageUpload, DEFAULT_DATA_CAP_SAMPLES};
use crate::render::normal_map::NormalFootprint;

/// Base priority of what the current frame would draw finer if it were resident.
pub const DRAWN_PRIORITY: f32 = 1.0;
/// Pending level cells not needed by this frame's draw: (0, NEAR_PRIORITY], nearest highest.
const NEAR_PRIORITY: f32 = 0.5;
/// Prefetches: (0, PREFETCH_PRIORITY], nearest (or first selected) highest.
pub const PREFETCH_PRIORITY: f32 = 0.25;

/// The level textures' side of the plan state: where each level's cache is, which of its cells
/// hold their samples, and the source those samples come from.
pub struct Feed {
    pub clipmap: ClipmapDesc,
    /// Metres between samples (x east, y north).
    pub spacing: [f64; 2],
    /// Each level's cached region (None: never placed).
    pub caches: Vec<Option<CacheRegion>>,
    pub content: LevelContent,
    pub gatherer: Gatherer,
    /// Samples gathered per frame at most ([`within_data_cap`]): strips beyond it stay
    /// pending, resident, for the next frame.
    pub data_cap_samples: usize,
    /// Strip pieces left pending this frame by the cap (resident, not gathered).
    pub deferred: u32,
}

/// How an attempt to fill a pending rectangle ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Fill {
    Done,
    /// A piece's samples are not resident (asked for by the caller).
    Missing,
    /// A piece would pass the frame's data cap: it waits for the next frame.
    Capped,
}

/// Level-L samples of the vertex rectangle `rect`.
pub fn sample_rect(level: u32, rect: &VertexRect) -> SampleRect {
    SampleRect {
        level,
        origin: rect.origin.map(|o| o << level),
        size: rect.size,
    }
}

impl Feed {
    pub fn new(clipmap: ClipmapDesc, spacing: [f64; 2], gatherer: Gatherer) -> Self {
        let levels = clipmap.level_count();
        let content = LevelContent::new(levels, clipmap.texture_side(), clipmap.tile_quads);
        Feed {
            caches: vec![None; levels as usize],
            clipmap,
            spacing,
            content,
            gatherer,
            data_cap_samples: DEFAULT_DATA_CAP_SAMPLES,
            deferred: 0,
        }
    }

    /// Whether `samples` more may be gathered this frame under the data cap.
    pub fn within_cap(&self, samples: usize) -> bool {
        within_data_cap(
            self.gatherer.samples().len(),
            samples,
            self.data_cap_samples,
        )
    }

    /// A priority in (0, top] falling with the distance from `eye` to the rectangle's centre,
    /// in units of the rectangle's own size.
    fn near(&self, level: u32, rect: &VertexRect, eye: DVec3, top: f32) -> f32 {
        let scale = (1u64 << level) as f64;
        let c = [0, 1].map(|a| (rect.origin[a] as f64 + rect.size[a] as f64 / 2.0) * scale);
        let (dx, dy) = (
            c[0] * self.spacing[0] - eye.x,
            c[1] * self.spacing[1] - eye.y,
        );
        let size = rect.size[0].max(rect.size[1]) as f64 * scale * self.spacing[0];
        let d = (dx * dx + dy * dy).sqrt() / size.max(1e-9);
        top / (1.0 + d as f32)
    }

    /// Moves every level's cache region to `placements` (invalidating the cells it exposes) and
    /// returns the uploads of every pending cell whose samples the source holds now, gathered;
    /// the cells it does not hold are asked for, nearest first, and stay pending.
    pub fn update_levels(&mut self, placements: &[LevelPlacement], eye: DVec3) -> Vec<ImageUpload> {
        for p in placements {
            let l = p.level as usize;
            let (region, exposed) = update_cache(&self.clipmap, self.caches[l].as_ref(), p);
            self.content.moved(p.level, &region, &exposed);
            self.caches[l] = Some(region);
        }
        let mut jobs = Vec::new();
        self.deferred = 0;
        let q = self.clipmap.tile_quads;
        for level in 0..self.clipmap.level_count() {
            for rect in self.content.pending(level) {
                if self.gatherer.is_resident(&sample_rect(level, &rect))
                    && self.fill(level, &rect, &mut jobs) == Fill::Done
                {
                    continue;
                }
                // Cell by cell: what is there now comes now, the rest is asked for.
                for cy in 0..rect.size[1] / q {
                    for cx in 0..rect.size[0] / q {
                        let cell = VertexRect {
                            origin: [
                                rect.origin[0] + (cx * q) as i64,
                                rect.origin[1] + (cy * q) as i64,
                            ],
                            size: [q, q],
                        };
                        if !self.content.cell_pending(level, cell.origin) {
                            continue; // filled by the attempt on the whole rectangle
                        }
                        match self.fill(level, &cell, &mut jobs) {
                            Fill::Done => {}
                            // Resident: gathered in a later frame.
                            Fill::Capped => self.deferred += 1,
                            Fill::Missing => {
                                let priority = self.near(level, &cell, eye, NEAR_PRIORITY);
                                self.gatherer.want(sample_rect(level, &cell), priority);
                                for r in self.gatherer.take_normal_misses() {
                                    self.gatherer.want(r, priority);
                                }
                            }
                        }
                    }
                }
            }
        }
        jobs
    }

    /// Gathers the toroidal pieces of pending `rect` (whole cells) into uploads, marking each
    /// piece's cells filled; stops at a piece that is not resident or over the frame's data
    /// cap (the pieces before it stay).
    fn fill(&mut self, level: u32, rect: &VertexRect, jobs: &mut Vec<ImageUpload>) -> Fill {
        let side = self.clipmap.texture_side();
        let step = 1u32 << level;
        for piece in toroidal_pieces(rect, side) {
            let origin = [0, 1].map(|a| rect.origin[a] + piece.src_offset[a] as i64);
            let job = ImageUpload {
                layer: level,
                texel: piece.texel,
                size: piece.size,
                origin_sample: origin.map(|o| o * step as i64),
                step,
            };
            if !self.within_cap(piece.size[0] as usize * piece.size[1] as usize) {
                return Fill::Capped;
            }
            if self.gatherer.gather(&job).is_err() {
                return Fill::Missing;
            }
            // The normal texels come with the heights or the piece waits for both.
            if self.gatherer.gather_normals(&job).is_err() {
                self.gatherer.ungather(&job);
                return Fill::Missing;
            }
            let done = VertexRect {
                origin,
                size: piece.size,
            };
            self.content.filled(level, &done);
            jobs.push(job);
        }
        Fill::Done
    }

    /// Asks for the cells of the level tiles the selection wanted but could not draw (level,
    /// tx, ty, projected error it would remove): each tile's own cells and its neighbours'
    /// (read for normals) that are still pending.
    pub fn want_tiles(&mut self, wants: &[(u32, u32, u32, f32)], eye: DVec3) {
        let q = self.clipmap.tile_quads as i64;
        for &(level, tx, ty, rho) in wants {
            if level >= self.clipmap.level_count() {
                continue;
            }
            let rho = if rho.is_finite() { rho } else { f32::MAX / 4.0 };
            for cy in ty as i64 - 1..=ty as i64 + 1 {
                for cx in tx as i64 - 1..=tx as i64 + 1 {
                    let origin = [cx * q, cy * q];
                    if !self.content.cell_pending(level, origin) {
                        continue;
                    }
                    let cell = VertexRect {
                        origin,
                        size: [q as u32; 2],
                    };
                    let priority = DRAWN_PRIORITY + rho + self.near(level, &cell, eye, 0.5);
                    let wanted = sample_rect(level, &cell);
                    self.gatherer.want(wanted, priority);
                    if self.gatherer.normal_maps() {
                        let fp = NormalFootprint::of_level(level);
                        self.gatherer
                            .want(fp.rect(wanted.origin, wanted.size), priority);
                    }
                }
            }
        }
    }

    /// Asks, below anything drawn, for the level strips the levels would expose if they were
    /// placed at `ahead` (where the eye will be), those not resident.
    pub fn want_ahead(&mut self, ahead: &[LevelPlacement], eye_ahead: DVec3) {
        for p in ahead {
            let old = self.caches[p.level as usize].as_ref();
            let (_, exposed) = update_cache(&self.clipmap, old, p);
            if old.is_none() {
                continue; // not placed yet: its first fill is pending anyway
            }
            for rect in exposed.iter().filter(|r| r.size[0] > 0 && r.size[1] > 0) {
                let wanted = sample_rect(p.level, rect);
                if !self.gatherer.is_resident(&wanted) {
                    let priority = self.near(p.level, rect, eye_ahead, PREFETCH_PRIORITY);
                    self.gatherer.want(wanted, priority);
                }
            }
        }
    }

    /// Level-texture cells still waiting for their samples, over every level.
    pub fn pending_cells(&self) -> u32 {
        let q = self.clipmap.tile_quads;
        (0..self.clipmap.level_count())
            .flat_map(|l| self.content.pending(l))
            .map(|r| (r.size[0] / q) * (r.size[1] / q))
            .sum()
    }
}
