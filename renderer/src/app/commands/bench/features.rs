//! What each look feature costs (`aerie bench --feature-costs`): the first measured
//! configuration is drawn again, on the same frames, once with each feature off — the full
//! look's land cover, sky and atmosphere (the plain look instead), the normal maps, the draped
//! rasters when given — and the terrain pass's GPU time of each is set against the
//! configuration with everything on. Plain data in and out; the bench renders the lanes.

use crate::render::frame::{Look, RendererDesc};
use crate::tools::percentile::percentile;

/// One feature turned off.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FeatureOff {
    /// The plain look: hypsometric ramp, Lambert sun, constant haze, a flat sky.
    LookPlain,
    /// Per-vertex normals instead of the full-resolution normal maps.
    NoNormalMaps,
    /// No draped imagery or land-cover raster.
    NoDrape,
}

impl FeatureOff {
    /// The feature's name in the table ("what is off").
    pub fn name(self) -> &'static str {
        match self {
            Self::LookPlain => "land cover, sky, atmosphere (plain look)",
            Self::NoNormalMaps => "normal maps",
            Self::NoDrape => "draped rasters",
        }
    }

    /// The CSV key.
    pub fn key(self) -> &'static str {
        match self {
            Self::LookPlain => "look_plain",
            Self::NoNormalMaps => "no_normal_maps",
            Self::NoDrape => "no_drape",
        }
    }

    /// The base configuration's renderer with this feature off.
    pub fn apply(self, desc: &mut RendererDesc) {
        match self {
            Self::LookPlain => desc.look = Look::Plain,
            Self::NoNormalMaps => desc.normal_maps = false,
            Self::NoDrape => desc.drape = None,
        }
    }
}

/// The features the base renderer has on, each to be turned off once.
pub fn features_on(base: &RendererDesc) -> Vec<FeatureOff> {
    let mut v = Vec::new();
    if base.look != Look::Plain {
        v.push(FeatureOff::LookPlain);
    }
    if base.normal_maps {
        v.push(FeatureOff::NoNormalMaps);
    }
    if base.drape.is_some() {
        v.push(FeatureOff::NoDrape);
    }
    v
}

/// The terrain pass's GPU milliseconds per measured frame: the base's and each variant's.
#[derive(Debug, Clone, Default)]
pub struct FeatureCosts {
    pub base_label: String,
    pub base_ms: Vec<f64>,
    pub off: Vec<(FeatureOff, Vec<f64>)>,
}

impl FeatureCosts {
    pub fn new(base_label: String, features: &[FeatureOff]) -> Self {
        Self {
            base_label,
            base_ms: Vec::new(),
            off: features.iter().map(|&f| (f, Vec::new())).collect(),
        }
    }

    /// (median, p99) of sorted copies.
    fn stats(ms: &[f64]) -> (f64, f64) {
        let mut s = ms.to_vec();
        s.sort_by(f64::total_cmp);
        (percentile(&s, 0.5), percentile(&s, 0.99))
    }

    /// One row per feature: what is off, the GPU terrain ms (median, p99) with it off, and the
    /// feature's cost = the base's median − that median (negative: within the noise).
    pub fn rows(&self) -> Vec<(FeatureOff, f64, f64, f64)> {
        let (base, _) = Self::stats(&self.base_ms);
        self.off
            .iter()
            .map(|(f, ms)| {
                let (median, p99) = Self::stats(ms);
                (*f, median, p99, base - median)
            })
            .collect()
    }

    /// `features.csv`: the base first (feature "none"), then a row per feature turned off.
    pub fn csv(&self) -> String {
        let (base, base_p99) = Self::stats(&self.base_ms);
        let mut out = String::from(
            "configuration,feature_off,frames,gpu_terrain_ms_median,gpu_terrain_ms_p99,feature_cost_ms\n",
        );
        out.push_str(&format!(
            "{},none,{},{base:.4},{base_p99:.4},0\n",
            self.base_label,
            self.base_ms.len()
        ));
        for ((f, median, p99, cost), (_, ms)) in self.rows().into_iter().zip(&self.off) {
            out.push_str(&format!(
                "{},{},{},{median:.4},{p99:.4},{cost:.4}\n",
                self.base_label,
                f.key(),
                ms.len()
            ));
        }
        out
    }

    /// The section of summary.md.
    pub fn markdown(&self) -> String {
        let (base, base_p99) = Self::stats(&self.base_ms);
        let mut md = format!(
            "\n## What each feature costs\n\n{}, the same frames with one feature off; GPU time of the terrain pass (median over {} frames).\n\n| off | GPU terrain ms (median) | p99 | the feature costs |\n|---|---|---|---|\n| nothing (all on) | {base:.3} | {base_p99:.3} | |\n",
            self.base_label,
            self.base_ms.len()
        );
        for (f, median, p99, cost) in self.rows() {
            let share = if base > 0.0 { cost / base * 100.0 } else { 0.0 };
            md.push_str(&format!(
                "| {} | {median:.3} | {p99:.3} | {cost:+.3} ms ({share:+.0} %) |\n",
                f.name()
            ));
        }
        md
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_feature_on_is_turned_off_once_and_costs_are_differences() {
        let mut desc = RendererDesc {
            look: Look::Full,
            normal_maps: true,
            ..RendererDesc::default()
        };
        assert_eq!(
            features_on(&desc),
            [FeatureOff::LookPlain, FeatureOff::NoNormalMaps]
        );
        let mut plain = RendererDesc {
            look: Look::Plain,
            normal_maps: false,
            ..RendererDesc::default()
        };
        assert!(features_on(&plain).is_empty());
        FeatureOff::NoNormalMaps.apply(&mut desc);
        FeatureOff::LookPlain.apply(&mut desc);
        assert!(!desc.normal_maps && desc.look == Look::Plain);
        FeatureOff::NoDrape.apply(&mut plain);
        assert!(plain.drape.is_none());

        let mut c = FeatureCosts::new(
            "bounded τ=1".into(),
            &[FeatureOff::LookPlain, FeatureOff::NoNormalMaps],
        );
        c.base_ms = vec![10.0, 12.0, 11.0];
        c.off[0].1 = vec![8.0, 8.5, 7.5];
        c.off[1].1 = vec![11.5, 11.0, 10.5];
        let rows = c.rows();
        assert_eq!(rows[0].0, FeatureOff::LookPlain);
        assert!((rows[0].1 - 8.0).abs() < 1e-12 && (rows[0].3 - 3.0).abs() < 1e-12);
        assert!((rows[1].3 - 0.0).abs() < 1e-12);
        let csv = c.csv();
        assert_eq!(csv.lines().count(), 4, "{csv}");
        assert!(csv.contains("bounded τ=1,look_plain,3,8.0000"), "{csv}");
        let md = c.markdown();
        assert!(
            md.contains("| normal maps |") && md.contains("+3.000 ms (+27 %)"),
            "{md}"
        );
    }
}
