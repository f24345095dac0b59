//! Upload jobs as plain data (no Vulkan): texture regions to fill from the dataset, the byte
//! budget of one staging region, and how a list of jobs is split over submissions when it does
//! not fit one. The recording code turns each [`ImageUpload`] into a `vk::BufferImageCopy`.

use aerie_terrain::clipmap::{
    toroidal_pieces, update_cache, CacheRegion, ClipmapDesc, LevelPlacement,
};

use crate::render::normal_map::normal_bytes;

/// Bytes per texel of every height texture (R32_SFLOAT).
pub const TEXEL_BYTES: u64 = 4;

/// Headroom kept free when fitting streamed rows into a region: the alignment padding the copy
/// itself may need (staging offsets are aligned to at most 64 bytes on the devices we run on).
pub const STREAM_ROW_SLACK_BYTES: u64 = 64;

/// Reserved besides the frame's listed fixed pushes: the frame uniforms (144 bytes) and the
/// alignment padding in front of each of the fixed pushes (uniforms, indirect commands,
/// instances, overlay), so that a frame whose uploads were admitted never fails its pushes.
pub const FIXED_SLACK_BYTES: u64 = 1024;
/// Alignment padding in front of the overlay panel's pixels, on top of [`FIXED_SLACK_BYTES`].
pub const OVERLAY_SLACK_BYTES: u64 = 16;
/// Alignment padding each in-frame clipmap strip copy may add (offset alignments up to 64).
pub const STRIP_SLACK_BYTES: u64 = 64;
/// Headroom a pool upload must leave above the reserve: its own alignment padding plus that of
/// the uploads staged before it, which the reserve does not count.
pub const POOL_UPLOAD_SLACK_BYTES: u64 = 256;
/// One region of a texture to fill from the dataset: texel rectangle in `layer`, and the
/// dataset samples `origin + (i, j)·step`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImageUpload {
    pub layer: u32,
    pub texel: [u32; 2],
    pub size: [u32; 2],
    pub origin_sample: [i64; 2],
    pub step: u32,
}

impl ImageUpload {
    /// The source samples the upload reads (its step is a power of two: a level's spacing).
    pub fn sample_rect(&self) -> aerie_terrain::source::SampleRect {
        debug_assert!(self.step.is_power_of_two(), "step {}", self.step);
        aerie_terrain::source::SampleRect {
            level: self.step.trailing_zeros(),
            origin: self.origin_sample,
            size: self.size,
        }
    }

    pub fn bytes(&self) -> u64 {
        self.size[0] as u64 * self.size[1] as u64 * TEXEL_BYTES
    }

    /// Splits the upload after `rows` rows (the tail starts `rows` texels and samples later).
    pub fn split_rows(&self, rows: u32) -> (ImageUpload, Option<ImageUpload>) {
        if rows >= self.size[1] {
            return (*self, None);
        }
        let head = ImageUpload {
            size: [self.size[0], rows],
            ..*self
        };
        let tail = ImageUpload {
            texel: [self.texel[0], self.texel[1] + rows],
            size: [self.size[0], self.size[1] - rows],
            origin_sample: [
                self.origin_sample[0],
                self.origin_sample[1] + rows as i64 * self.step as i64,
            ],
            ..*self
        };
        (head, Some(tail))
    }
}

/// Why a plan cannot be carried out.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PlanError {
    /// A staging request larger than what is left of the region (the ring's own message).
    Staging(String),
    /// Anything else (the message says what).
    Other(String),
}

impl std::fmt::Display for PlanError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PlanError::Staging(m) | PlanError::Other(m) => f.write_str(m),
        }
    }
}

/// One staging region's bytes as a plan spends them: the arithmetic of the staging ring's cursor
/// (`vk::staging::RingCursor`: each allocation starts at the next multiple of `alignment`),
/// without the memory. The renderer checks that staging what the plan says uses exactly
/// [`Self::used`] bytes of the real region.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StagingBudget {
    capacity: u64,
    alignment: u64,
    used: u64,
}

impl StagingBudget {
    /// An empty region of `capacity` bytes whose allocations are aligned to `alignment` (a power
    /// of two, at least every alignment the uploads ask for).
    pub fn new(capacity: u64, alignment: u64) -> Self {
        assert!(alignment.is_power_of_two(), "alignment {alignment}");
        Self {
            capacity,
            alignment,
            used: 0,
        }
    }

    pub fn capacity(&self) -> u64 {
        self.capacity
    }
    pub fn alignment(&self) -> u64 {
        self.alignment
    }
    /// Bytes allocated so far, alignment padding included.
    pub fn used(&self) -> u64 {
        self.used
    }
    /// Bytes after the last allocation (the next one may lose up to `alignment − 1` to padding).
    pub fn remaining(&self) -> u64 {
        self.capacity.saturating_sub(self.used)
    }

    /// Spends `bytes` (after aligning the start), or says how it does not fit and spends nothing.
    pub fn take(&mut self, bytes: u64) -> Result<(), PlanError> {
        let start = self.used.div_ceil(self.alignment) * self.alignment;
        if start + bytes > self.capacity {
            return Err(PlanError::Staging(format!(
                "upload of {bytes} bytes exceeds this frame's staging budget ({} of {} bytes left)",
                self.capacity.saturating_sub(start),
                self.capacity
            )));
        }
        self.used = start + bytes;
        Ok(())
    }
}

/// Samples the frame thread gathers from the source in one frame, at most (level strips and
/// pool uploads together): the default staging region's worth (8 MiB of f32), a few
/// milliseconds of copying. A burst larger than that — every level's strips arriving at once
/// at start-up, which spill past the staging region — waits for the next frames.
pub const DEFAULT_DATA_CAP_SAMPLES: usize = 2 << 20;

/// Whether a job of `job` samples may be gathered after `gathered` samples this frame under a
/// cap of `cap`: it fits, or nothing was gathered yet (so one job larger than the cap still
/// moves, alone, and nothing waits forever).
pub fn within_data_cap(gathered: usize, job: usize, cap: usize) -> bool {
    gathered == 0 || gathered.saturating_add(job) <= cap
}

/// Eye position (metres) → dataset sample coordinates, the unit of clipmap placement.
pub fn eye_samples(eye: glam::DVec3, spacing: [f64; 2]) -> [f64; 2] {
    [eye.x / spacing[0], eye.y / spacing[1]]
}

/// The level-texture regions to (re)load for these placements, recording each level's new cache
/// region in `caches`. Levels that did not leave their cache yield nothing; a piece split at the
/// texture's toroidal wrap becomes one upload per piece.
pub fn strip_uploads(
    clipmap: &ClipmapDesc,
    caches: &mut [Option<CacheRegion>],
    placements: &[LevelPlacement],
) -> Vec<ImageUpload> {
    let side = clipmap.texture_side();
    let mut jobs = Vec::new();
    for p in placements {
        let (region, rects) = update_cache(clipmap, caches[p.level as usize].as_ref(), p);
        let step = 1u32 << p.level;
        for rect in &rects {
            for piece in toroidal_pieces(rect, side) {
                jobs.push(ImageUpload {
                    layer: p.level,
                    texel: piece.texel,
                    size: piece.size,
                    origin_sample: [
                        (rect.origin[0] + piece.src_offset[0] as i64) * step as i64,
                        (rect.origin[1] + piece.src_offset[1] as i64) * step as i64,
                    ],
                    step,
                });
            }
        }
        caches[p.level as usize] = Some(region);
    }
    jobs
}

/// Splits `jobs` over as many submissions as regions of `capacity` bytes need, in order: each
/// submission takes whole jobs while they fit and then as many rows of the next as fit (keeping
/// [`STREAM_ROW_SLACK_BYTES`] free), the rest going first into the next submission.
///
/// Invariants (tested): the rows of the output are exactly the rows of the input, in order;
/// every submission stages within `capacity`; only the first job of a submission may be the
/// tail of a split. A row larger than a whole region is an error.
pub fn split_into_submissions(
    jobs: &[ImageUpload],
    capacity: u64,
    alignment: u64,
) -> Result<Vec<Vec<ImageUpload>>, PlanError> {
    split_level_uploads(jobs, capacity, alignment, false)
}

/// [`split_into_submissions`] of level strips, each staged with its normal texels right after
/// its heights when `normals` ([`crate::render::normal_map::NORMAL_TEXEL_BYTES`] per texel).
pub fn split_level_uploads(
    jobs: &[ImageUpload],
    capacity: u64,
    alignment: u64,
    normals: bool,
) -> Result<Vec<Vec<ImageUpload>>, PlanError> {
    let normal_texel = normal_bytes([1, 1], normals);
    let mut pending: std::collections::VecDeque<ImageUpload> = jobs.iter().copied().collect();
    let mut submissions = Vec::new();
    while !pending.is_empty() {
        let mut budget = StagingBudget::new(capacity, alignment);
        let mut batch = Vec::new();
        while let Some(job) = pending.pop_front() {
            let row_bytes = job.size[0] as u64 * (TEXEL_BYTES + normal_texel);
            // The normals' own allocation may add one more alignment's padding.
            let slack = STREAM_ROW_SLACK_BYTES * if normals { 2 } else { 1 };
            let fit_rows = (budget.remaining().saturating_sub(slack) / row_bytes) as u32;
            if fit_rows == 0 {
                if batch.is_empty() {
                    return Err(PlanError::Staging(format!(
                        "one level-texture row ({row_bytes} bytes) exceeds the per-frame staging budget ({capacity} bytes)"
                    )));
                }
                pending.push_front(job);
                break;
            }
            let (head, tail) = job.split_rows(fit_rows.min(job.size[1]));
            budget.take(head.bytes())?;
            if normals {
                budget.take(normal_bytes(head.size, true))?;
            }
            batch.push(head);
            if let Some(tail) = tail {
                pending.push_front(tail);
                break;
            }
        }
        submissions.push(batch);
    }
    Ok(submissions)
}

/// The staging region a frame needs when its fixed pushes take `reserve` bytes of a region of
/// `region` bytes, for an upload budget of `upload_budget` (`RendererDesc::staging_budget`):
/// None while the records take at most half the region; else a region that holds them and
/// the upload budget beside them, rounded up to a power of two (so a selection that keeps
/// growing regrows the region a few times, not every frame). Without it a selection of many
/// nodes — small tiles, a small τ, a big channel — leaves no room for any pool upload, and
/// every refined tile stays late for as long as the view lasts.
pub fn staging_to_hold(region: u64, upload_budget: u64, reserve: u64) -> Option<u64> {
    (reserve > region / 2).then(|| {
        (upload_budget + reserve)
            .max(2 * reserve)
            .next_power_of_two()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_data_cap_admits_what_fits_and_always_the_first_job() {
        assert!(within_data_cap(0, 10, 100));
        assert!(within_data_cap(90, 10, 100));
        assert!(!within_data_cap(91, 10, 100));
        // A job larger than the cap still moves when it is the frame's first.
        assert!(within_data_cap(0, 1000, 100));
        assert!(!within_data_cap(1, 1000, 100));
        assert!(!within_data_cap(usize::MAX, 1, 100));
    }
}
