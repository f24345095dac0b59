//! The configurations of a bench run: LOD modes × their knobs (τ for `bounded`, the patch side
//! for `clipmap`, a range scale for `distance`, the LOD range for `cdlod`, a scale of the global
//! factor for `tess`), parsed from `--modes`, `--tau`, `--clipmap-n`, `--distance-scale`,
//! `--cdlod-range` and `--tess-density`; every mode drawn with tiles also × the tile sizes of
//! `--tile-sizes` (a tile's vertices a side, m: the node size of the quadtree modes).

use aerie_terrain::select::LodMode;

use crate::render::frame::DEFAULT_TILE_SIZE;

/// One configuration of the run: a mode, τ for `bounded`, the knob of a swept baseline.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BenchConfig {
    pub mode: LodMode,
    /// τ (px) for `bounded`; None for the modes that do not use it.
    pub tau_px: Option<f64>,
    /// The baseline's own knob when swept: `clipmap` patch side n (vertices), `distance` range
    /// scale (× the default split distance), `cdlod` LOD range (node sides); None: the
    /// command's `--patch` / scale 1 / the default range.
    pub knob: Option<f64>,
    /// Tiles of this many vertices a side (m) instead of the renderer's default
    /// ([`DEFAULT_TILE_SIZE`]); None: the default. Never set for `tess` and `full`, which draw
    /// no tiles of their own size.
    #[serde(default)]
    pub tile_size: Option<u32>,
}

/// The values each baseline is swept over (empty: one configuration at its default).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Sweeps {
    pub clipmap_n: Vec<u32>,
    pub distance_scale: Vec<f64>,
    pub cdlod_range: Vec<f64>,
    /// `tess`: scales of the global tessellation factor.
    pub tess_density: Vec<f64>,
    /// Tile sizes (m, vertices a side) every tiled mode is drawn with; empty: the default only.
    pub tile_sizes: Vec<u32>,
}

impl BenchConfig {
    pub fn mode_name(&self) -> &'static str {
        mode_name(self.mode)
    }

    /// "bounded τ=0.5", "clipmap", "clipmap n=257", "distance ×2", "cdlod k=4"; with another
    /// tile size than the default, " m=9" after it.
    pub fn label(&self) -> String {
        let base = match (self.tau_px, self.knob) {
            (Some(t), _) => format!("{} τ={t}", self.mode_name()),
            (None, Some(k)) => format!("{} {}{k}", self.mode_name(), knob_word(self.mode).0),
            (None, None) => self.mode_name().to_string(),
        };
        match self.tile_size {
            Some(m) => format!("{base} m={m}"),
            None => base,
        }
    }

    /// ASCII key for CSV cells and file names: "bounded_tau0.5", "clipmap", "clipmap_n257",
    /// "distance_x2", "cdlod_k4"; with another tile size than the default, "_m9" after it.
    pub fn key(&self) -> String {
        let base = match (self.tau_px, self.knob) {
            (Some(t), _) => format!("{}_tau{t}", self.mode_name()),
            (None, Some(k)) => format!("{}_{}{k}", self.mode_name(), knob_word(self.mode).1),
            (None, None) => self.mode_name().to_string(),
        };
        match self.tile_size {
            Some(m) => format!("{base}_m{m}"),
            None => base,
        }
    }

    /// The tile size (m) this configuration's renderer draws with.
    pub fn tile_size_or_default(&self) -> u32 {
        self.tile_size.unwrap_or(DEFAULT_TILE_SIZE)
    }

    /// τ the image error's "fraction above τ" and heat map use: the configuration's own, 1 px
    /// for the modes without one.
    pub fn tau_for_error(&self) -> f64 {
        self.tau_px.unwrap_or(1.0)
    }
}

pub fn mode_name(mode: LodMode) -> &'static str {
    match mode {
        LodMode::Bounded => "bounded",
        LodMode::Clipmap => "clipmap",
        LodMode::Full => "full",
        LodMode::Distance => "distance",
        LodMode::Cdlod => "cdlod",
        LodMode::Tessellation => "tess",
    }
}

/// How a mode's knob reads in a label and in a key.
fn knob_word(mode: LodMode) -> (&'static str, &'static str) {
    match mode {
        LodMode::Clipmap => ("n=", "n"),
        LodMode::Distance => ("×", "x"),
        LodMode::Cdlod => ("k=", "k"),
        LodMode::Tessellation => ("×", "x"),
        LodMode::Bounded | LodMode::Full => ("", ""),
    }
}

/// Parses `--modes`: a comma-separated list of mode names, duplicates dropped, order kept.
pub fn parse_modes(s: &str) -> Result<Vec<LodMode>, String> {
    let mut out = Vec::new();
    for part in s.split(',').map(str::trim) {
        let mode = match part {
            "bounded" => LodMode::Bounded,
            "clipmap" => LodMode::Clipmap,
            "distance" => LodMode::Distance,
            "full" => LodMode::Full,
            "cdlod" => LodMode::Cdlod,
            "tess" => LodMode::Tessellation,
            "" => return Err(format!("--modes {s:?}: empty mode name")),
            other => {
                return Err(format!(
                "--modes {s:?}: unknown mode {other:?} (expected bounded, clipmap, distance, cdlod, tess, full)"
            ))
            }
        };
        if !out.contains(&mode) {
            out.push(mode);
        }
    }
    Ok(out)
}

/// Parses `--tau`: comma-separated positive pixel values, duplicates dropped, order kept.
pub fn parse_taus(s: &str) -> Result<Vec<f64>, String> {
    let mut out: Vec<f64> = Vec::new();
    for part in s.split(',').map(str::trim) {
        let t: f64 = part
            .parse()
            .map_err(|_| format!("--tau {s:?}: {part:?} is not a number"))?;
        if !(t.is_finite() && t > 0.0) {
            return Err(format!(
                "--tau {s:?}: {part} must be a positive number of pixels"
            ));
        }
        if !out.contains(&t) {
            out.push(t);
        }
    }
    Ok(out)
}

/// Parses a comma-separated list of positive numbers for `flag` (empty: none), duplicates
/// dropped, order kept.
pub fn parse_positive_list(flag: &str, s: &str) -> Result<Vec<f64>, String> {
    let mut out: Vec<f64> = Vec::new();
    if s.trim().is_empty() {
        return Ok(out);
    }
    for part in s.split(',').map(str::trim) {
        let v: f64 = part
            .parse()
            .map_err(|_| format!("{flag} {s:?}: {part:?} is not a number"))?;
        if !(v.is_finite() && v > 0.0) {
            return Err(format!("{flag} {s:?}: {part} must be a positive number"));
        }
        if !out.contains(&v) {
            out.push(v);
        }
    }
    Ok(out)
}

/// Every mode × its knob values, in the order of `modes`: `bounded` × τ, a baseline × its
/// sweep (once at its default when the sweep is empty), `full` once; each tiled mode (all but
/// `tess` and `full`) once per tile size of `sweeps.tile_sizes`, in that order (the default
/// size is `None`, so its keys stay as without the sweep).
pub fn configurations(modes: &[LodMode], taus: &[f64], sweeps: &Sweeps) -> Vec<BenchConfig> {
    let sizes: Vec<Option<u32>> = if sweeps.tile_sizes.is_empty() {
        vec![None]
    } else {
        let mut v: Vec<Option<u32>> = Vec::new();
        for &m in &sweeps.tile_sizes {
            let s = (m != DEFAULT_TILE_SIZE).then_some(m);
            if !v.contains(&s) {
                v.push(s);
            }
        }
        v
    };
    let mut out = Vec::new();
    for &mode in modes {
        let tiled = !matches!(mode, LodMode::Tessellation | LodMode::Full);
        let mode_sizes = if tiled { &sizes[..] } else { &[None][..] };
        for &tile_size in mode_sizes {
            let config = |tau_px: Option<f64>, knob: Option<f64>| BenchConfig {
                mode,
                tau_px,
                knob,
                tile_size,
            };
            let knobs: Vec<f64> = match mode {
                LodMode::Bounded => {
                    out.extend(taus.iter().map(|&t| config(Some(t), None)));
                    continue;
                }
                LodMode::Clipmap => sweeps.clipmap_n.iter().map(|&n| n as f64).collect(),
                LodMode::Distance => sweeps.distance_scale.clone(),
                LodMode::Cdlod => sweeps.cdlod_range.clone(),
                LodMode::Tessellation => sweeps.tess_density.clone(),
                LodMode::Full => Vec::new(),
            };
            if knobs.is_empty() {
                out.push(config(None, None));
            }
            out.extend(knobs.into_iter().map(|k| config(None, Some(k))));
        }
    }
    out
}

/// The tile sizes a run draws: `sizes`, or the default alone when none are given.
pub fn sizes_drawn(sizes: &[u32]) -> Vec<u32> {
    if sizes.is_empty() {
        vec![DEFAULT_TILE_SIZE]
    } else {
        sizes.to_vec()
    }
}

/// Checks `--tile-sizes` (or the suite's `run.tile_sizes`, named by `flag`): each m is 2^j + 1
/// in 3..=257, as the renderer takes it.
pub fn check_tile_sizes(flag: &str, sizes: &[u32]) -> Result<(), String> {
    for (i, &m) in sizes.iter().enumerate() {
        if !(3..=257).contains(&m) || !(m - 1).is_power_of_two() {
            return Err(format!(
                "{flag}[{i}]: tile size {m} must be 2^j + 1 in 3..=257 (e.g. 9, 17, 33)"
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn modes_and_taus_parse_and_expand() {
        let modes = parse_modes("bounded, clipmap,full,bounded").unwrap();
        assert_eq!(
            modes,
            vec![LodMode::Bounded, LodMode::Clipmap, LodMode::Full]
        );
        let taus = parse_taus("0.5,1,2,1").unwrap();
        assert_eq!(taus, vec![0.5, 1.0, 2.0]);
        let c = configurations(&modes, &taus, &Sweeps::default());
        assert_eq!(c.len(), 5);
        assert_eq!(c[0].label(), "bounded τ=0.5");
        assert_eq!(c[0].key(), "bounded_tau0.5");
        assert_eq!(c[3].key(), "clipmap");
        assert_eq!(c[4].tau_for_error(), 1.0);
        let sweeps = Sweeps {
            clipmap_n: vec![129, 257],
            distance_scale: vec![0.5],
            cdlod_range: vec![4.0, 8.0],
            tess_density: vec![0.5, 2.0],
            tile_sizes: Vec::new(),
        };
        let modes = parse_modes("clipmap,distance,cdlod,tess,full").unwrap();
        let keys: Vec<String> = configurations(&modes, &[1.0], &sweeps)
            .iter()
            .map(BenchConfig::key)
            .collect();
        assert_eq!(
            keys,
            [
                "clipmap_n129",
                "clipmap_n257",
                "distance_x0.5",
                "cdlod_k4",
                "cdlod_k8",
                "tess_x0.5",
                "tess_x2",
                "full"
            ]
        );
        assert_eq!(
            configurations(&modes[2..3], &[], &sweeps)[1].label(),
            "cdlod k=8"
        );
        assert_eq!(parse_positive_list("--x", " ").unwrap(), Vec::<f64>::new());
        let e = parse_positive_list("--distance-scale", "1,-2").unwrap_err();
        assert!(
            e.contains("--distance-scale") && e.contains("positive"),
            "{e}"
        );
        for (bad, word) in [("bounded,fast", "fast"), ("", "empty"), ("full,,", "empty")] {
            let e = parse_modes(bad).unwrap_err();
            assert!(e.contains(word) && e.contains("--modes"), "{e}");
        }
        for (bad, word) in [
            ("1,x", "\"x\""),
            ("0", "positive"),
            ("-1", "positive"),
            ("nan", "positive"),
        ] {
            let e = parse_taus(bad).unwrap_err();
            assert!(e.contains(word) && e.contains("--tau"), "{e}");
        }
    }

    #[test]
    fn tile_sizes_repeat_every_tiled_mode_and_name_the_others() {
        let sweeps = Sweeps {
            clipmap_n: vec![129],
            distance_scale: vec![1.0],
            cdlod_range: vec![4.0],
            tess_density: vec![1.0],
            tile_sizes: vec![DEFAULT_TILE_SIZE, 9, DEFAULT_TILE_SIZE],
        };
        let modes = parse_modes("bounded,clipmap,distance,cdlod,tess,full").unwrap();
        let c = configurations(&modes, &[1.0], &sweeps);
        let keys: Vec<String> = c.iter().map(BenchConfig::key).collect();
        assert_eq!(
            keys,
            [
                "bounded_tau1",
                "bounded_tau1_m9",
                "clipmap_n129",
                "clipmap_n129_m9",
                "distance_x1",
                "distance_x1_m9",
                "cdlod_k4",
                "cdlod_k4_m9",
                "tess_x1",
                "full"
            ]
        );
        assert_eq!(c[1].label(), "bounded τ=1 m=9");
        assert_eq!(c[1].tile_size_or_default(), 9);
        assert_eq!(c[0].tile_size_or_default(), DEFAULT_TILE_SIZE);
        // Without the sweep, nothing changes.
        let plain = configurations(
            &modes,
            &[1.0],
            &Sweeps {
                tile_sizes: vec![],
                ..sweeps.clone()
            },
        );
        assert!(plain.iter().all(|c| c.tile_size.is_none()));
        assert_eq!(plain.len(), 6);
        assert!(check_tile_sizes("--tile-sizes", &[9, 17, 33]).is_ok());
        for bad in [0, 2, 16, 18, 513] {
            let e = check_tile_sizes("--tile-sizes", &[17, bad]).unwrap_err();
            assert!(
                e.starts_with("--tile-sizes[1]") && e.contains(&bad.to_string()),
                "{e}"
            );
        }
    }
}
