//! Command-line arguments several commands share: the GPU and level-of-detail options
//! ([`GpuArgs`]), the built-in straight pass ([`PassArgs`]) and the waypoint file that replaces
//! it. Each is written once and flattened into the commands that take it, so every command
//! spells, defaults and documents a flag the same way.

use std::path::PathBuf;

use clap::Args;

use crate::app::failure::{bad_input, Failure};
use crate::render::tile_instances::SkirtRule;
use crate::render::uniforms::Look;
use crate::sim::flight::Waypoints;
use aerie_terrain::select::LodMode;

#[derive(Debug, Args)]
pub struct GpuArgs {
    /// Use the first Vulkan device whose name contains this (case-insensitive).
    #[arg(long)]
    pub gpu: Option<String>,
    /// Enable the Khronos validation layer (always on in debug builds).
    #[arg(long)]
    pub validate: bool,
    /// Horizontal field of view, degrees (0 < fov < 180).
    #[arg(long, default_value_t = 90.0)]
    pub fov: f64,
    /// Output size, WxH pixels.
    #[arg(long, default_value = "1920x1080")]
    pub size: String,
    /// Screen-space error bound τ, pixels.
    #[arg(long, default_value_t = 1.0)]
    pub tau: f64,
    /// Level-of-detail decision: bounded (ours), clipmap (no refinement), full (brute force),
    /// distance (discrete LOD by distance with 10 % hysteresis), cdlod (Strugar 2009), tess
    /// (hardware tessellation by a density map × distance, document 001).
    #[arg(long, value_enum, default_value_t = LodArg::Bounded)]
    pub lod: LodArg,
    /// `--lod tess`: scale of the global tessellation factor (1: an edge of density 1 at the
    /// eye gets 32 segments, the full resolution of a 32-sample patch).
    #[arg(long, default_value_t = 1.0)]
    pub tess_density: f64,
    /// Clipmap patch side n in vertices (129 or 257; n = P(m−1)+1).
    #[arg(long, default_value_t = 129)]
    pub patch: u32,
    /// Colour tiles by clipmap level and refinement.
    #[arg(long)]
    pub debug_tiles: bool,
    /// Draw a flat Earth (no curvature drop).
    #[arg(long)]
    pub no_curvature: bool,
    /// Shading: full (land cover derived from the terrain, sky with the sun, aerial
    /// perspective), plain (colour ramp, flat sky: the cost baseline) or classes (the land-cover
    /// classes' flat colours).
    #[arg(long, value_enum, default_value_t = LookArg::Full)]
    pub look: LookArg,
    /// Light level tiles with normal maps computed from the full-resolution heights (on), or
    /// with the drawn level's per-vertex normals (off: the before/after and the cost).
    #[arg(long, value_enum, default_value_t = Switch::On)]
    pub normal_maps: Switch,
    /// Where the normal maps' texels are computed: cpu (the full-resolution footprint mean,
    /// staged with each strip) or gpu (a compute pass over each level's own heights).
    #[arg(long = "normals", value_enum, default_value_t = NormalsArg::Cpu)]
    pub normals: NormalsArg,
    #[command(flatten)]
    pub drape: DrapeArgs,
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
}

/// `--skirts`: which tile edges get a skirt.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SkirtsArg {
    Needed,
    Everywhere,
    None,
}

impl SkirtsArg {
    pub fn rule(self) -> SkirtRule {
        match self {
            SkirtsArg::Needed => SkirtRule::WhereResolutionsDiffer,
            SkirtsArg::Everywhere => SkirtRule::Everywhere,
            SkirtsArg::None => SkirtRule::None,
        }
    }
}

/// `--normals`: where the normal maps' texels are computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum NormalsArg {
    Cpu,
    Gpu,
}

impl NormalsArg {
    pub fn source(self) -> crate::render::desc::NormalSource {
        match self {
            NormalsArg::Cpu => crate::render::desc::NormalSource::Cpu,
            NormalsArg::Gpu => crate::render::desc::NormalSource::Gpu,
        }
    }
}

/// A feature turned on or off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Switch {
    On,
    Off,
}

impl Switch {
    pub fn on(self) -> bool {
        self == Switch::On
    }
}

/// Rasters draped on the terrain (issue 17), registered by their geo-reference.
#[derive(Debug, Clone, Default, Args)]
pub struct DrapeArgs {
    /// 8-bit GeoTIFF imagery (RGB, RGBA or grey; geographic WGS84 or UTM) draped on the
    /// terrain; several files: later ones on top.
    #[arg(long, num_args = 1..)]
    pub imagery: Vec<PathBuf>,
    /// 8-bit GeoTIFF of land-cover class codes replacing the derived classes where it has one.
    #[arg(long)]
    pub landcover: Option<PathBuf>,
    /// The land-cover codes' meaning: worldcover, corine, or a TOML file with a [landcover]
    /// table (a preset and/or [landcover.codes]). Default: the run config's [landcover]
    /// table, else worldcover.
    #[arg(long)]
    pub landcover_map: Option<String>,
    /// Device memory the draped textures may take together, MiB (imagery four fifths of it
    /// when a land-cover raster shares it): past it a texture gets fewer texels per sample.
    #[arg(long, default_value_t = crate::render::drape_textures::DEFAULT_DRAPE_MIB)]
    pub drape_mb: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum LookArg {
    Full,
    Plain,
    Classes,
    /// The shading normal as colour (checking the normal maps).
    Normals,
}

impl LookArg {
    pub fn look(self) -> Look {
        match self {
            LookArg::Full => Look::Full,
            LookArg::Plain => Look::Plain,
            LookArg::Classes => Look::Classes,
            LookArg::Normals => Look::Normals,
        }
    }
}

/// How a tile store given as `--dem <name>.aerie` is read: streamed page by page within a
/// page-cache budget (the default), or read whole into memory (for comparisons).
#[derive(Debug, Clone, Args)]
pub struct StoreArgs {
    /// Page cache of a streamed tile store, MiB of decoded pages (never exceeded).
    #[arg(long, default_value_t = 1024)]
    pub cache_mb: u64,
    /// Read a tile store whole into memory instead of streaming it.
    #[arg(long)]
    pub load_whole: bool,
    /// Worker threads reading and decoding a streamed store's pages.
    #[arg(long, default_value_t = 2)]
    pub stream_workers: usize,
    /// Measurement hook: every read of a streamed store sleeps this long first (a slow or
    /// remote disk), to show that frames keep coming and only late tiles grow.
    #[arg(long, hide = true, default_value_t = 0)]
    pub stream_latency_ms: u64,
}

impl Default for StoreArgs {
    fn default() -> Self {
        StoreArgs {
            cache_mb: 1024,
            load_whole: false,
            stream_workers: 2,
            stream_latency_ms: 0,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum LodArg {
    Bounded,
    Clipmap,
    Full,
    Distance,
    Cdlod,
    Tess,
}

impl LodArg {
    pub fn mode(self) -> LodMode {
        match self {
            LodArg::Bounded => LodMode::Bounded,
            LodArg::Clipmap => LodMode::Clipmap,
            LodArg::Full => LodMode::Full,
            LodArg::Distance => LodMode::Distance,
            LodArg::Cdlod => LodMode::Cdlod,
            LodArg::Tess => LodMode::Tessellation,
        }
    }
}

/// The built-in straight-and-level pass through the dataset's centre (`fly`, `bench`).
#[derive(Debug, Clone, Args)]
pub struct PassArgs {
    /// Built-in pass: ground speed, m/s.
    #[arg(long, default_value_t = 340.0)]
    pub speed: f64,
    /// Built-in pass: metres above the highest sample of the DEM (with --follow-terrain: above
    /// the ground under the aircraft).
    #[arg(long, default_value_t = 600.0)]
    pub agl: f64,
    /// Built-in pass: fly --agl metres above the ground under the aircraft instead of above the
    /// highest sample.
    #[arg(long)]
    pub follow_terrain: bool,
    /// Built-in pass: heading, degrees clockwise from north.
    #[arg(long, default_value_t = 70.0, allow_hyphen_values = true)]
    pub heading: f64,
    /// Built-in pass: camera pitch, degrees (negative looks down).
    #[arg(long, default_value_t = -12.0, allow_hyphen_values = true)]
    pub pitch: f64,
}

impl PassArgs {
    /// Refuses a frame rate, speed or height that is not a finite positive number (speed and
    /// height may be 0) and an attitude that is not finite.
    pub fn check(&self, fps: f64) -> Result<(), Failure> {
        for (name, v) in [("--fps", fps), ("--speed", self.speed), ("--agl", self.agl)] {
            if !v.is_finite() || v < 0.0 || (name == "--fps" && v == 0.0) {
                return Err(bad_input(format!(
                    "{name}: {v} must be a finite positive number"
                )));
            }
        }
        for (name, v) in [("--heading", self.heading), ("--pitch", self.pitch)] {
            if !v.is_finite() {
                return Err(bad_input(format!("{name}: {v} is not finite")));
            }
        }
        Ok(())
    }
}

/// Reads the waypoint file given with `flag`, if any: bad input names the flag or the file's
/// line.
pub fn read_waypoints(flag: &str, path: Option<&PathBuf>) -> Result<Option<Waypoints>, Failure> {
    let Some(p) = path else {
        return Ok(None);
    };
    let text = std::fs::read_to_string(p)
        .map_err(|e| bad_input(format!("{flag} {}: {e}", p.display())))?;
    Waypoints::parse(&text, &p.display().to_string())
        .map(Some)
        .map_err(bad_input)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, clap::Parser)]
    struct Both {
        #[command(flatten)]
        pass: PassArgs,
        #[command(flatten)]
        gpu: GpuArgs,
    }

    fn parse(args: &[&str]) -> Both {
        use clap::Parser;
        Both::try_parse_from(std::iter::once("aerie").chain(args.iter().copied())).unwrap()
    }

    #[test]
    fn pass_defaults_and_negative_values_parse() {
        let d = parse(&[]);
        assert_eq!(
            (d.pass.speed, d.pass.agl, d.pass.heading, d.pass.pitch),
            (340.0, 600.0, 70.0, -12.0)
        );
        assert!(!d.pass.follow_terrain);
        assert_eq!(
            (d.gpu.size.as_str(), d.gpu.lod),
            ("1920x1080", LodArg::Bounded)
        );
        let p = parse(&["--pitch", "-30", "--heading", "-5", "--follow-terrain"]).pass;
        assert_eq!((p.pitch, p.heading, p.follow_terrain), (-30.0, -5.0, true));
    }

    #[test]
    fn pass_check_names_the_bad_flag() {
        let good = parse(&[]).pass;
        assert!(good.check(30.0).is_ok());
        assert!(PassArgs {
            speed: 0.0,
            ..good.clone()
        }
        .check(30.0)
        .is_ok());
        let cases = [
            (good.check(0.0), "--fps"),
            (
                PassArgs {
                    speed: -1.0,
                    ..good.clone()
                }
                .check(30.0),
                "--speed",
            ),
            (
                PassArgs {
                    agl: f64::NAN,
                    ..good.clone()
                }
                .check(30.0),
                "--agl",
            ),
            (
                PassArgs {
                    heading: f64::INFINITY,
                    ..good.clone()
                }
                .check(30.0),
                "--heading",
            ),
            (
                PassArgs {
                    pitch: f64::NAN,
                    ..good.clone()
                }
                .check(30.0),
                "--pitch",
            ),
        ];
        for (r, flag) in cases {
            let e = r.unwrap_err();
            assert_eq!(e.code, 2);
            assert!(e.message.starts_with(flag), "{}", e.message);
        }
    }

    #[test]
    fn lod_args_map_to_their_modes() {
        assert_eq!(LodArg::Bounded.mode(), LodMode::Bounded);
        assert_eq!(LodArg::Clipmap.mode(), LodMode::Clipmap);
        assert_eq!(LodArg::Full.mode(), LodMode::Full);
        assert_eq!(LodArg::Distance.mode(), LodMode::Distance);
        assert_eq!(LodArg::Cdlod.mode(), LodMode::Cdlod);
        assert_eq!(LodArg::Tess.mode(), LodMode::Tessellation);
    }

    #[test]
    fn waypoint_files_are_read_or_named_in_the_error() {
        assert!(read_waypoints("--path", None).unwrap().is_none());
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("wp.csv");
        let e = read_waypoints("--flight", Some(&p)).unwrap_err();
        assert!(e.message.starts_with("--flight ") && e.message.contains("wp.csv"));
        std::fs::write(&p, "0,0,0,100,0,0,0\n1,10,0,100,0,0,0\n").unwrap();
        let w = read_waypoints("--flight", Some(&p)).unwrap().unwrap();
        assert_eq!(w.pose_at(0.5).0.x, 5.0);
    }
}
