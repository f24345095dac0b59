//! The application: the command line, one module per command, and the pieces they share
//! (arguments, renderer setup, flight plan, output paths, progress, failures, terrain
//! preparation). Imports run downwards only: `cli` → `commands` → the shared pieces.

pub mod args;
pub mod cli;
pub mod commands;
pub mod failure;
pub mod flight_plan;
pub mod out_path;
pub mod prepare;
pub mod progress;
pub mod renderer_setup;
pub mod window;
