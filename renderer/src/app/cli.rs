//! The `aerie` command line: the parser, the list of commands and the dispatch to each
//! command's module. Exit 0 on success, 2 on bad input (arguments, DEM files), 1 on runtime
//! failures (Vulkan, I/O) — see [`crate::app::failure`].

use clap::{Parser, Subcommand};

use crate::app::commands::{
    bake, bench, fly, gen_dem, import, info, listen, render, replay, run as run_cmd,
};
use crate::app::failure::Failure;

#[derive(Debug, Parser)]
#[command(
    name = "aerie",
    version,
    about = "Error-bounded Vulkan terrain image generator for flight simulators"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render one frame of a DEM from a fixed camera to a PNG (+ a JSON summary next to it,
    /// `<png>.json`).
    Render(render::RenderArgs),
    /// Fly a scripted pass (or waypoints) over a DEM headless, one camera or every channel of a
    /// config: PNGs, per-frame CSV, summary, into an empty folder (or --overwrite).
    Fly(fly::FlyArgs),
    /// Generate a deterministic synthetic DEM (raw f32 + JSON sidecar) for scale and stress tests.
    GenDem(gen_dem::GenDemArgs),
    /// Bake the per-tile error table of a dataset (file or folder of SRTM tiles).
    Bake(bake::BakeArgs),
    /// Import DEM files or folders of SRTM tiles into a tile store (`<name>.aerie`): every
    /// level in checksummed, compressed pages with their baked error.
    Import(import::ImportArgs),
    /// Print what a tile store holds: header, levels, pages, bytes, compression ratio.
    Info(info::InfoArgs),
    /// Time against measured image-space error: every LOD mode (× τ) on the same frames,
    /// results.csv, summary.csv/.md, time_vs_error.png in an empty --out (or --overwrite).
    Bench(bench::BenchArgs),
    /// Receive aircraft poses (UDP or shared memory) without rendering: progress, summary,
    /// optional recording.
    Listen(listen::ListenArgs),
    /// Send a recording's datagrams to a UDP address (original timing or --fast).
    Replay(replay::ReplayArgs),
    /// The image generator, driven by a simulator or flying the built-in pass: one window or
    /// fullscreen display per channel of a config (or only --channel NAME), or headless.
    // Boxed: the run command's flags are by far the largest variant.
    Run(Box<run_cmd::RunArgs>),
}

pub fn run(cli: Cli) -> Result<(), Failure> {
    match cli.command {
        Command::Render(a) => render::run(a),
        Command::Fly(a) => fly::run(a),
        Command::GenDem(a) => gen_dem::run(a),
        Command::Bake(a) => bake::run(a),
        Command::Import(a) => import::run(a),
        Command::Info(a) => info::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Listen(a) => listen::run(a),
        Command::Replay(a) => replay::run(a),
        Command::Run(a) => run_cmd::run(*a),
    }
}
