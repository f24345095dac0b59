//! The configurations of a bench run: LOD modes × τ, parsed from `--modes` and `--tau`.

use aerie_terrain::select::LodMode;

/// One configuration of the run: a mode, and τ for `bounded`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BenchConfig {
    pub mode: LodMode,
    /// τ (px) for `bounded`; None for the modes that do not use it.
    pub tau_px: Option<f64>,
}

impl BenchConfig {
    pub fn mode_name(&self) -> &'static str {
        mode_name(self.mode)
    }

    /// "bounded τ=0.5", "clipmap".
    pub fn label(&self) -> String {
        match self.tau_px {
            Some(t) => format!("{} τ={t}", self.mode_name()),
            None => self.mode_name().to_string(),
        }
    }

    /// ASCII key for CSV cells and file names: "bounded_tau0.5", "clipmap".
    pub fn key(&self) -> String {
        match self.tau_px {
            Some(t) => format!("{}_tau{t}", self.mode_name()),
            None => self.mode_name().to_string(),
        }
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
            "" => return Err(format!("--modes {s:?}: empty mode name")),
            other => {
                return Err(format!(
                "--modes {s:?}: unknown mode {other:?} (expected bounded, clipmap, distance, full)"
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

/// Every mode × τ for `bounded`, each other mode once, in the order of `modes`.
pub fn configurations(modes: &[LodMode], taus: &[f64]) -> Vec<BenchConfig> {
    let mut out = Vec::new();
    for &mode in modes {
        if mode == LodMode::Bounded {
            out.extend(taus.iter().map(|&t| BenchConfig {
                mode,
                tau_px: Some(t),
            }));
        } else {
            out.push(BenchConfig { mode, tau_px: None });
        }
    }
    out
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
        let c = configurations(&modes, &taus);
        assert_eq!(c.len(), 5);
        assert_eq!(c[0].label(), "bounded τ=0.5");
        assert_eq!(c[0].key(), "bounded_tau0.5");
        assert_eq!(c[3].key(), "clipmap");
        assert_eq!(c[4].tau_for_error(), 1.0);
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
}
