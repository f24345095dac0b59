//! One row of `results.csv`: a frame of one configuration with its measurements.

use glam::DVec3;

use super::replays::FrameReplays;
use crate::render::frame::FrameStats;
use crate::tools::image_error::{ImageError, OracleResult};
use aerie_terrain::camera::Attitude;

/// One frame of one configuration, as written to `results.csv`.
#[derive(Debug, Clone)]
pub(crate) struct FrameRow {
    pub frame: u32,
    pub warmup: bool,
    pub time_s: f64,
    pub position: DVec3,
    pub attitude: Attitude,
    pub config: usize,
    pub wall_ms: f64,
    pub stats: FrameStats,
    pub image: Option<ImageRow>,
    pub oracle: Option<OracleResult>,
    /// `--replays`: the first flight's time and which flight's timings the row keeps.
    pub replays: FrameReplays,
}

/// The image error of one frame, reduced to what a CSV row holds.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ImageRow {
    pub max_px: f64,
    /// Largest error confirmed by a neighbouring pixel ([`ImageError::confirmed`]).
    pub confirmed_max_px: f64,
    pub p99_px: f64,
    pub mean_px: f64,
    pub fraction_over_tau: f64,
    pub measured_px: u64,
    pub holes_px: u64,
    pub hole_max_px: f64,
    pub extra_px: u64,
    pub max_at: Option<(u32, u32)>,
}

impl ImageRow {
    pub fn of(e: &ImageError) -> Self {
        Self {
            max_px: e.max_px(),
            confirmed_max_px: e.confirmed_max_px(),
            p99_px: e.p99_px(),
            mean_px: e.mean_px(),
            fraction_over_tau: e.fraction_over_tau(),
            measured_px: e.hist.count(),
            holes_px: e.holes_px,
            hole_max_px: e.hole_max_px,
            extra_px: e.extra_px,
            max_at: e.max_at,
        }
    }
}
