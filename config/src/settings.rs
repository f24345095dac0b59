//! The `[render]` and `[dem]` tables, validated, and their limits.

use std::path::PathBuf;

use serde::Serialize;

/// Allowed tile sizes `m = 2^j + 1` (vertices per tile side).
pub const TILE_SIZES: [u32; 8] = [3, 5, 9, 17, 33, 65, 129, 257];
/// Largest accepted per-frame staging budget, MiB.
pub const MAX_STAGING_BUDGET_MIB: u32 = 1024;

/// Renderer settings (`[render]`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RenderSettings {
    /// Viewport width, pixels (`size = "WxH"` or `width`), 1..=[`MAX_DIMENSION`](crate::MAX_DIMENSION).
    pub width: u32,
    /// Viewport height, pixels (`size = "WxH"` or `height`), 1..=[`MAX_DIMENSION`](crate::MAX_DIMENSION).
    pub height: u32,
    /// Horizontal field of view, degrees, in (0, 180).
    pub fov_deg: f64,
    /// Screen-space error bound τ, pixels, finite and > 0.
    pub tau_px: f64,
    /// Vertices per tile side, one of [`TILE_SIZES`].
    pub tile_size: u32,
    /// Per-frame upload budget through the staging ring, MiB, 1..=[`MAX_STAGING_BUDGET_MIB`].
    pub staging_budget_mib: u32,
    /// Enable the Khronos validation layer.
    pub validation: bool,
    /// Pick the first GPU whose name contains this substring; `None` lets aerie choose.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gpu: Option<String>,
    /// `aerie run --headless` frame rate, frames/s in (0, 1000]; `None`: the `--fps` default.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fps: Option<f64>,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 1920,
            height: 1080,
            fov_deg: 90.0,
            tau_px: 1.0,
            tile_size: 17,
            staging_budget_mib: 8,
            validation: false,
            gpu: None,
            fps: None,
        }
    }
}

impl RenderSettings {
    /// The staging budget in bytes.
    pub fn staging_budget_bytes(&self) -> u64 {
        u64::from(self.staging_budget_mib) << 20
    }
}

/// Elevation dataset settings (`[dem]`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct DemSettings {
    /// Path of the elevation dataset, as written in the file (not resolved).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub path: Option<PathBuf>,
}

/// True if `m` is an allowed tile size (`2^j + 1`, 3..=257).
pub fn is_valid_tile_size(m: u32) -> bool {
    TILE_SIZES.contains(&m)
}
