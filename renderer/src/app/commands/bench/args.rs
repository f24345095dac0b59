//! `aerie bench`'s command line.

use std::path::PathBuf;

use clap::Args;

use super::config::{
    check_tile_sizes, configurations, parse_modes, parse_positive_list, parse_taus, sizes_drawn,
    BenchConfig, Sweeps,
};
use crate::app::args::{
    read_waypoints, LookArg, NormalsArg, PassArgs, SkirtsArg, StoreArgs, Switch,
};
use crate::app::failure::{bad_input, Failure};
use crate::app::renderer_setup::{parse_view, patch_tiles, patch_tiles_of, View};
use crate::sim::flight::Waypoints;

#[derive(Debug, Clone, Args)]
pub struct BenchArgs {
    /// Elevation model (any format `render` reads); its bake is read from or written next to it.
    /// A tile store (`<name>.aerie`) is streamed to the measured configurations, and read
    /// whole besides for the oracles, the image-space error and its `full` reference.
    #[arg(long, required_unless_present = "suite")]
    pub dem: Option<PathBuf>,
    /// A bench suite (TOML: datasets × flights, the run's settings): every flight is benched
    /// into its own folder under --out, with one combined report (suite.md, ratios.csv). The
    /// options its `[run]` table sets (--size, --fov, --frames, --warmup, --settle, --fps,
    /// --modes, --tau, the sweeps, --tile-sizes, --oracle-nodes) are refused beside it; --replays
    /// replaces its `run.replays`.
    #[arg(long, conflicts_with_all = ["dem", "flight"])]
    pub suite: Option<PathBuf>,
    /// Go on with an interrupted suite in --out: a flight whose folder holds the record of a
    /// run with the same settings, dataset and flight is taken from it, the others are flown
    /// (their folders replaced), and the combined report covers them all.
    #[arg(long, requires = "suite")]
    pub resume: bool,
    /// Folder the suite's relative dataset paths start from (default: the suite file's folder).
    #[arg(long, requires = "suite")]
    pub data: Option<PathBuf>,
    #[command(flatten)]
    pub store: StoreArgs,
    /// Output folder (created, with the folders above it): results.csv, summary.csv, summary.md, time_vs_error.png, ...
    /// It must be empty unless --overwrite.
    #[arg(long)]
    pub out: PathBuf,
    /// Reuse a non-empty --out folder: first remove the files an earlier `aerie bench` wrote
    /// there (results.csv, summary.csv, summary.md, the charts, heatmap_*.png); anything else in
    /// it is kept.
    #[arg(long)]
    pub overwrite: bool,
    /// Timed waypoints (`t_s,x_m,y_m,z_m,heading,pitch,roll` per line; after a first line `geo`,
    /// `t_s,lat,lon,alt,heading,pitch,roll` on a geo-referenced dataset) instead of the built-in
    /// straight pass through the dataset's centre.
    #[arg(long)]
    pub flight: Option<PathBuf>,
    /// Measured frames (every configuration renders each).
    #[arg(long, default_value_t = 60, conflicts_with = "suite")]
    pub frames: u32,
    /// Frames rendered first and left out of the summaries (caches, pools, pipelines warm up).
    #[arg(long, default_value_t = 3, conflicts_with = "suite")]
    pub warmup: u32,
    /// Start-up fill: before the first frame every configuration renders the flight's first
    /// pose again until a frame has no late tile and no clipmap cell pending, at most this
    /// many frames (0: none) — as an IG fills its caches while the host waits for the
    /// database to load. Those frames are not measured; summary.md says how many each took.
    #[arg(long, default_value_t = 0, conflicts_with = "suite")]
    pub settle: u32,
    /// Fly the measured frames this many times, each time by fresh renderers after the same
    /// start-up fill, and time each frame by its fastest flight that did the same work (the
    /// same selection, triangles, uploads): on a shared machine the least of several times
    /// holds less of the machine's noise. 1 (the default): fly once. The image error is
    /// measured on the first flight. With --suite it replaces the suite's `run.replays` (the
    /// times change, never what is drawn or measured).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=20))]
    pub replays: Option<u32>,
    /// Simulated frame rate: frame k is the pose at k / fps seconds.
    #[arg(long, default_value_t = 30.0, conflicts_with = "suite")]
    pub fps: f64,
    #[command(flatten)]
    pub pass: PassArgs,
    #[command(flatten)]
    pub drape: crate::app::args::DrapeArgs,
    /// Output size, WxH pixels.
    #[arg(long, default_value = "1920x1080", conflicts_with = "suite")]
    pub size: String,
    /// Horizontal field of view, degrees (0 < fov < 180).
    #[arg(long, default_value_t = 90.0, conflicts_with = "suite")]
    pub fov: f64,
    /// LOD modes, comma-separated: bounded, clipmap, distance, cdlod, full.
    #[arg(
        long,
        default_value = "bounded,clipmap,distance,cdlod,full",
        conflicts_with = "suite"
    )]
    pub modes: String,
    /// τ values (px) for `bounded`, comma-separated; the other modes ignore τ and run once.
    #[arg(long, default_value = "0.5,1,2,5,10", conflicts_with = "suite")]
    pub tau: String,
    /// Clipmap patch side n in vertices (129 or 257).
    #[arg(long, default_value_t = 129)]
    pub patch: u32,
    /// Sweep `clipmap` over these patch sides n (comma-separated, each P·16+1 with P even ≥ 8,
    /// e.g. 129,257,513); empty: once at --patch.
    #[arg(long, default_value = "", conflicts_with = "suite")]
    pub clipmap_n: String,
    /// Draw every tiled mode (all but `tess` and `full`) with each of these tile sizes m
    /// (vertices a side, 2^j + 1: e.g. 9,17), so the tile size is one more knob of every
    /// mode's curve; empty: the default (17) only. --patch and each --clipmap-n must then be
    /// P·(m−1)+1 with P even ≥ 8 for every m.
    #[arg(long, default_value = "", conflicts_with = "suite")]
    pub tile_sizes: String,
    /// Sweep `distance` over these scales of its split distance (e.g. 0.5,1,2,4); empty: once
    /// at scale 1.
    #[arg(long, default_value = "", conflicts_with = "suite")]
    pub distance_scale: String,
    /// Sweep `cdlod` over these LOD ranges, in node sides of each level (e.g. 2,4,8,16); empty:
    /// once at the default (6).
    #[arg(long, default_value = "", conflicts_with = "suite")]
    pub cdlod_range: String,
    /// Sweep `tess` over these scales of its global tessellation factor (e.g.
    /// 0.25,0.5,1,2,4); empty: once at scale 1.
    #[arg(long, default_value = "", conflicts_with = "suite")]
    pub tess_density: String,
    /// Draw a flat Earth (no curvature drop).
    #[arg(long)]
    pub no_curvature: bool,
    /// Bounded: drop tiles hidden behind nearer terrain (a conservative CPU horizon).
    #[arg(long, value_enum, default_value_t = Switch::Off)]
    pub horizon_cull: Switch,
    /// Bounded, one view (plane or ellipsoid): draw a ring tile refined in an earlier frame again
    /// while a certificate says its nodes still meet τ (on), or walk every frame afresh (off).
    #[arg(long, value_enum, default_value_t = Switch::On)]
    pub carry_selection: Switch,
    /// Skirts under the tiles' edges: needed (only where the tile across is drawn at another
    /// resolution, and where it is drawn exactly one resolution coarser the finer tile fills
    /// the crack instead: the default), everywhere (every edge of every tile), none (shows the
    /// cracks). CDLOD draws none whatever this says.
    #[arg(long, value_enum, default_value_t = SkirtsArg::Needed)]
    pub skirts: SkirtsArg,
    /// Nodes per frame the CPU oracle checks by brute force (0: no oracle).
    #[arg(long, default_value_t = 12, conflicts_with = "suite")]
    pub oracle_nodes: u32,
    /// Skip the image-space error (and the `full` reference render it needs).
    #[arg(long)]
    pub no_image_error: bool,
    /// Measure the image-space error without the `full` reference render (holes, sky where
    /// the full-resolution terrain is, are then not counted): long flights at a fraction of
    /// the cost, since the reference draws every visible sample.
    #[arg(long, conflicts_with = "no_image_error")]
    pub no_holes: bool,
    /// Use the first Vulkan device whose name contains this (case-insensitive).
    #[arg(long)]
    pub gpu: Option<String>,
    /// Enable the Khronos validation layer (always on in debug builds; slows every frame).
    #[arg(long)]
    pub validate: bool,
    /// Shading of every configuration: full, plain (the cost baseline) or classes.
    #[arg(long, value_enum, default_value_t = LookArg::Full)]
    pub look: LookArg,
    /// Normal maps from the full-resolution heights on level tiles (on) or per-vertex normals.
    #[arg(long, value_enum, default_value_t = Switch::On)]
    pub normal_maps: Switch,
    /// Where the normal maps' texels are computed: cpu (full-resolution footprint means,
    /// staged) or gpu (a compute pass over each level's heights). With --feature-costs the
    /// other one is measured too, on the same frames.
    #[arg(long = "normals", value_enum, default_value_t = NormalsArg::Cpu)]
    pub normals: NormalsArg,
    /// Also draw the first configuration once with each look feature off (land cover, sky
    /// and atmosphere; normal maps; draped rasters) on the same frames: features.csv and a
    /// table in summary.md give the terrain pass's GPU time of each.
    #[arg(long)]
    pub feature_costs: bool,
}

impl BenchArgs {
    /// `--replays`, 1 when not given.
    pub fn replays(&self) -> u32 {
        self.replays.unwrap_or(1)
    }

    /// The options besides the suite file's that change what a flight draws or measures
    /// (the patch, curvature, culling, carried selection, skirts, look, normal maps, the
    /// image error and its holes), in words: a suite flight's record holds them, and
    /// `--resume` takes it only under the same ones.
    pub fn result_settings(&self) -> String {
        format!(
            "patch {} curvature {} horizon-cull {:?} carry-selection {:?} skirts {:?} \
             look {:?} normal-maps {:?} normals {:?} image-error {} holes {}",
            self.patch,
            !self.no_curvature,
            self.horizon_cull,
            self.carry_selection,
            self.skirts,
            self.look,
            self.normal_maps,
            self.normals,
            !self.no_image_error,
            !self.no_holes,
        )
    }
}

/// Validated arguments.
pub(crate) struct Plan {
    pub view: View,
    pub configs: Vec<BenchConfig>,
    pub patch_tiles: u32,
    pub waypoints: Option<Waypoints>,
}

pub(crate) fn plan(a: &BenchArgs) -> Result<Plan, Failure> {
    let view = parse_view(&a.size, a.fov)?;
    let modes = parse_modes(&a.modes).map_err(bad_input)?;
    let taus = parse_taus(&a.tau).map_err(bad_input)?;
    let tile_sizes: Vec<u32> = parse_positive_list("--tile-sizes", &a.tile_sizes)
        .map_err(bad_input)?
        .into_iter()
        .map(|m| {
            if m.fract() == 0.0 && m <= u32::MAX as f64 {
                Ok(m as u32)
            } else {
                Err(bad_input(format!(
                    "--tile-sizes {}: {m} is not a whole number of vertices",
                    a.tile_sizes
                )))
            }
        })
        .collect::<Result<_, _>>()?;
    check_tile_sizes("--tile-sizes", &tile_sizes).map_err(bad_input)?;
    // Every patch side must divide into tiles of every size drawn.
    let sizes = sizes_drawn(&tile_sizes);
    let fits = |flag: &str, given: &str, n: u32| -> Result<(), Failure> {
        for &m in &sizes {
            patch_tiles_of(n, m).map_err(|e| {
                let why = e.message.trim_start_matches("--patch: ");
                bad_input(format!("{flag} {given}: with tiles of {m}: {why}"))
            })?;
        }
        Ok(())
    };
    fits("--patch", &a.patch.to_string(), a.patch)?;
    let sweeps = Sweeps {
        clipmap_n: parse_positive_list("--clipmap-n", &a.clipmap_n)
            .map_err(bad_input)?
            .into_iter()
            .map(|n| fits("--clipmap-n", &a.clipmap_n, n as u32).map(|_| n as u32))
            .collect::<Result<_, _>>()?,
        distance_scale: parse_positive_list("--distance-scale", &a.distance_scale)
            .map_err(bad_input)?,
        cdlod_range: parse_positive_list("--cdlod-range", &a.cdlod_range).map_err(bad_input)?,
        tess_density: parse_positive_list("--tess-density", &a.tess_density).map_err(bad_input)?,
        tile_sizes,
    };
    if a.frames == 0 {
        return Err(bad_input("--frames: must be at least 1"));
    }
    if a.oracle_nodes > 4096 {
        return Err(bad_input(format!(
            "--oracle-nodes: {} is more than 4096",
            a.oracle_nodes
        )));
    }
    a.pass.check(a.fps)?;
    let patch_tiles = patch_tiles(a.patch)?;
    let waypoints = read_waypoints("--flight", a.flight.as_ref())?;
    Ok(Plan {
        view,
        configs: configurations(&modes, &taus, &sweeps),
        patch_tiles,
        waypoints,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Bench {
        #[command(flatten)]
        a: BenchArgs,
    }

    fn settings(extra: &[&str]) -> String {
        let base = ["aerie", "--suite", "s.toml", "--out", "o"];
        let args = base.iter().chain(extra).copied();
        Bench::try_parse_from(args).unwrap().a.result_settings()
    }

    /// Each option that changes what a suite's flights draw or measure changes the words
    /// their records keep; where the results go and whether the run resumes do not.
    #[test]
    fn result_settings_name_every_option_that_changes_a_flight() {
        let default = settings(&[]);
        for option in [
            &["--skirts", "everywhere"][..],
            &["--horizon-cull", "on"],
            &["--carry-selection", "off"],
            &["--no-curvature"],
            &["--patch", "257"],
            &["--look", "plain"],
            &["--normal-maps", "off"],
            &["--normals", "gpu"],
            &["--no-holes"],
            &["--no-image-error"],
        ] {
            assert_ne!(settings(option), default, "{option:?}");
        }
        assert_eq!(settings(&["--resume", "--overwrite"]), default);
    }

    /// Beside --suite, an option its `[run]` table sets is refused naming both (it would be
    /// ignored); --replays is taken, and every option parses without --suite.
    #[test]
    fn the_suites_run_options_are_refused_beside_it() {
        for (flag, value) in [
            ("--size", "320x180"),
            ("--fov", "60"),
            ("--frames", "4"),
            ("--warmup", "0"),
            ("--settle", "5"),
            ("--fps", "10"),
            ("--modes", "bounded"),
            ("--tau", "1"),
            ("--clipmap-n", "129"),
            ("--tile-sizes", "9"),
            ("--distance-scale", "2"),
            ("--cdlod-range", "4"),
            ("--tess-density", "2"),
            ("--oracle-nodes", "3"),
        ] {
            let with_suite = ["aerie", "--suite", "s.toml", "--out", "o", flag, value];
            let err = Bench::try_parse_from(with_suite)
                .err()
                .expect(flag)
                .to_string();
            assert!(
                err.contains(flag) && err.contains("--suite"),
                "{flag}: {err}"
            );
            let alone = ["aerie", "--dem", "d.hgt", "--out", "o", flag, value];
            Bench::try_parse_from(alone)
                .map_err(|e| format!("{flag}: {e}"))
                .unwrap();
        }
        let replayed = ["aerie", "--suite", "s.toml", "--out", "o", "--replays", "3"];
        assert_eq!(Bench::try_parse_from(replayed).unwrap().a.replays, Some(3));
        let plain = ["aerie", "--dem", "d.hgt", "--out", "o"];
        assert_eq!(Bench::try_parse_from(plain).unwrap().a.replays(), 1);
    }
}
