//! `aerie run`: the image generator. Opens one window (or fullscreen display) per channel of a
//! config (`config/presets/*.toml`), all in one process on one device, or only the channels
//! named with `--channel` (one process per channel, e.g. one machine per projector, sharing the
//! config); or, with `--headless`, renders the same channels offscreen. Runs until Esc, a closed
//! window, `--frames` or `--seconds`; prints a summary (frames, frame times, per-channel
//! presentation, pose input, validation) and writes it as JSON with `--json`.
//!
//! The aircraft pose comes from a [`PoseSource`](crate::app::window::pose_source::PoseSource): the built-in pass ([`StraightPassSource`])
//! without input, else the simulator stream ([`RunPoses`] over a
//! [`SimInput`](crate::sim::pose_input::SimInput)): with `--listen`, `--protocol`, `--multicast` or
//! `--shm-name`, each frame draws `PoseReader::pose_at(predicted display time)` (carried forward
//! at most `--max-extrapolation-ms`), or with `--sync-frames k` the pose of host frame
//! newest − k exactly (one process per channel on one stream). `--stats` writes the pose used
//! per frame ([`crate::tools::stats_csv`]).

pub mod args;
pub mod database;
pub mod headless;
pub mod ig;
pub mod plan;
pub mod poses;
pub mod settings;
pub mod windowed;

pub use args::RunArgs;
pub use poses::{open_input, open_stats, RunPoses, StraightPassSource};
pub use settings::{
    resolve_settings, RunSettings, DEFAULT_FPS, DEFAULT_MAX_EXTRAPOLATION_MS, DEFAULT_WAIT_POSE_S,
};
pub use windowed::run_on;

use crate::app::failure::{runtime, Failure};
use crate::app::window::display::new_event_loop;

/// `aerie run`: opens the display, runs, exits.
pub fn run(a: RunArgs) -> Result<(), Failure> {
    // Arguments and config first: nothing opens when they are bad.
    plan::plan(&a)?;
    if a.headless {
        return headless::run(&a).map(|_| ());
    }
    let mut event_loop = new_event_loop(false).map_err(runtime)?;
    run_on(&mut event_loop, &a).map(|_| ())
}

#[cfg(test)]
mod tests;
