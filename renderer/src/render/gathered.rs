//! The frame's samples, gathered from the [`TerrainSource`] at the moment the plan admits each
//! upload: an upload is planned only once its samples are in hand, so a page evicted between
//! the decision and the staging can never leave a texture stale. Staging then copies them in
//! the plan's order (strips, then pool uploads). The source never blocks: what it does not hold
//! is answered `NotResident` at once, and the plan asks for it ([`Gatherer::want`]).

use std::sync::Arc;
use std::time::{Duration, Instant};

use aerie_terrain::source::{NotResident, SampleRect, SampleWant, StreamStats, TerrainSource};

use crate::render::jobs::ImageUpload;
use crate::render::normal_map::{normal_texels, NormalFootprint, NormalTexel};

/// The renderer's view of its source for one frame: the samples gathered, the time spent
/// gathering them and the wishes to pass on.
pub struct Gatherer {
    source: Arc<dyn TerrainSource>,
    /// Samples of every upload admitted this frame, in staging order, each row-major.
    samples: Vec<f32>,
    /// Time the frame thread spent in the source's `gather` and `is_resident` this frame.
    time: Duration,
    wants: Vec<SampleWant>,
    /// Wishes from outside the plan (the host's queries), sent with the next request.
    extra: Vec<SampleWant>,
    /// Uploads refused for lack of samples this frame.
    refused: u32,
    /// With normal maps: metres between level-0 samples (x, y), and the normal texels of every
    /// level strip admitted this frame, in staging order (`render/normal_map.rs`).
    normal_spacing: Option<[f64; 2]>,
    normals: Vec<NormalTexel>,
    normal_misses: Vec<SampleRect>,
    /// Heights the normal texels are computed from (reused).
    normal_block: Vec<f32>,
    /// Time spent computing normal texels this frame (also in `time`).
    normal_time: Duration,
}

impl Gatherer {
    pub fn new(source: Arc<dyn TerrainSource>) -> Self {
        Gatherer {
            source,
            samples: Vec::new(),
            time: Duration::ZERO,
            wants: Vec::new(),
            extra: Vec::new(),
            refused: 0,
            normal_spacing: None,
            normals: Vec::new(),
            normal_misses: Vec::new(),
            normal_block: Vec::new(),
            normal_time: Duration::ZERO,
        }
    }

    /// Computes normal texels with every level strip from now on (`spacing`: metres between
    /// level-0 samples), or none.
    pub fn set_normal_maps(&mut self, spacing: Option<[f64; 2]>) {
        self.normal_spacing = spacing;
    }

    pub fn normal_maps(&self) -> bool {
        self.normal_spacing.is_some()
    }

    /// Appends the normal texels of level strip `job` (`NormalFootprint::of_level`); on
    /// `NotResident` appends nothing and keeps the rectangle it lacked for
    /// [`Self::take_normal_misses`].
    pub fn gather_normals(&mut self, job: &ImageUpload) -> Result<(), NotResident> {
        let Some(spacing) = self.normal_spacing else {
            return Ok(());
        };
        let t = Instant::now();
        let fp = NormalFootprint::of_level(job.step.trailing_zeros());
        let rect = fp.rect(job.origin_sample, job.size);
        self.normal_block.resize(rect.len(), 0.0);
        let got = self.source.gather(&rect, &mut self.normal_block);
        match got {
            Ok(()) => normal_texels(
                &fp,
                &self.normal_block,
                job.size,
                spacing,
                &mut self.normals,
            ),
            Err(_) => self.normal_misses.push(rect),
        }
        let spent = t.elapsed();
        self.time += spent;
        self.normal_time += spent;
        got
    }

    /// The rectangles normal texels lacked since the last call (for the caller to ask for).
    pub fn take_normal_misses(&mut self) -> Vec<SampleRect> {
        std::mem::take(&mut self.normal_misses)
    }

    /// Drops the samples `gather(job)` appended last (its normals could not be computed).
    pub fn ungather(&mut self, job: &ImageUpload) {
        let n = job.size[0] as usize * job.size[1] as usize;
        self.samples.truncate(self.samples.len().saturating_sub(n));
        self.refused += 1;
    }

    /// Normal texels of the level strips admitted this frame, in staging order.
    pub fn normals(&self) -> &[NormalTexel] {
        &self.normals
    }

    pub fn normal_time(&self) -> Duration {
        self.normal_time
    }

    pub fn source(&self) -> &Arc<dyn TerrainSource> {
        &self.source
    }

    /// Forgets the previous frame's samples, time and wishes.
    pub fn begin_frame(&mut self) {
        self.samples.clear();
        self.time = Duration::ZERO;
        self.wants.clear();
        self.refused = 0;
        self.normals.clear();
        self.normal_misses.clear();
        self.normal_time = Duration::ZERO;
    }

    /// Whether the source holds `rect` now (never blocks).
    pub fn is_resident(&mut self, rect: &SampleRect) -> bool {
        let t = Instant::now();
        let yes = self.source.is_resident(rect);
        self.time += t.elapsed();
        yes
    }

    /// Appends `job`'s samples; on `NotResident` appends nothing.
    pub fn gather(&mut self, job: &ImageUpload) -> Result<(), NotResident> {
        let rect = job.sample_rect();
        let start = self.samples.len();
        self.samples.resize(start + rect.len(), 0.0);
        let t = Instant::now();
        let got = self.source.gather(&rect, &mut self.samples[start..]);
        self.time += t.elapsed();
        if got.is_err() {
            self.samples.truncate(start);
            self.refused += 1;
        }
        got
    }

    /// Fills `out` with `rect`'s samples (a prefetched tile's band, kept outside the frame's
    /// samples until the tile is whole: `banded.rs`); the time counts as the frame's.
    pub fn gather_rect(&mut self, rect: &SampleRect, out: &mut [f32]) -> Result<(), NotResident> {
        let t = Instant::now();
        let got = self.source.gather(rect, out);
        self.time += t.elapsed();
        got
    }

    /// Appends samples gathered in earlier frames as the next upload's (a banded tile made
    /// whole).
    pub fn append(&mut self, samples: &[f32]) {
        let t = Instant::now();
        self.samples.extend_from_slice(samples);
        self.time += t.elapsed();
    }

    /// Asks the source for `rect` with `priority` (larger first) at the end of the frame.
    pub fn want(&mut self, rect: SampleRect, priority: f32) {
        self.wants.push(SampleWant { rect, priority });
    }

    /// Adds wishes from outside the plan to the next request (then forgotten: the asker
    /// repeats them while it still needs them).
    pub fn want_extra(&mut self, wants: &[SampleWant]) {
        self.extra.extend_from_slice(wants);
    }

    /// Passes this frame's wishes to the source (they replace the previous frame's, not
    /// started yet); none when everything was resident.
    pub fn send_requests(&mut self) {
        self.wants.append(&mut self.extra);
        if !self.wants.is_empty() {
            self.source.request(&self.wants);
        }
    }

    pub fn wants(&self) -> &[SampleWant] {
        &self.wants
    }

    pub fn samples(&self) -> &[f32] {
        &self.samples
    }

    pub fn time(&self) -> Duration {
        self.time
    }

    pub fn refused(&self) -> u32 {
        self.refused
    }

    pub fn stream_stats(&self) -> StreamStats {
        self.source.stats()
    }
}

/// Hands out the gathered samples (or normal texels) in staging order, one upload at a time.
pub struct SampleCursor<'a, T = f32> {
    samples: &'a [T],
    at: usize,
}

impl<'a, T> SampleCursor<'a, T> {
    pub fn new(samples: &'a [T]) -> Self {
        SampleCursor { samples, at: 0 }
    }

    /// The next `job`'s samples; None when fewer remain than it needs (a plan out of step with
    /// its samples, reported by the caller).
    pub fn next(&mut self, job: &ImageUpload) -> Option<&'a [T]> {
        let n = job.size[0] as usize * job.size[1] as usize;
        let s = self.samples.get(self.at..self.at + n)?;
        self.at += n;
        Some(s)
    }

    /// Samples not handed out yet.
    pub fn left(&self) -> usize {
        self.samples.len() - self.at
    }
}
