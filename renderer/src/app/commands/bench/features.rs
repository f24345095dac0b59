//! What each look feature costs (`aerie bench --feature-costs`): the first measured
//! configuration is drawn again, on the same frames, once with each feature off — the full
//! look's land cover, sky and atmosphere (the plain look instead), the normal maps, the draped
//! rasters when given or a store's imagery layer when drawn — and the terrain pass's GPU time of each is set against the
//! configuration with everything on; with normal maps, once more with their texels computed on
//! the other side (`--normals cpu|gpu`), and each lane's normal costs (CPU time and staged bytes,
//! the GPU pass's time). Plain data in and out; the bench renders the lanes.

use crate::render::frame::{FrameStats, Look, NormalSource, RendererDesc};
use crate::tools::percentile::percentile;

/// One feature turned off.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FeatureOff {
    /// The plain look: hypsometric ramp, Lambert sun, constant haze, a flat sky.
    LookPlain,
    /// Per-vertex normals instead of the full-resolution normal maps.
    NoNormalMaps,
    /// No draped imagery or land-cover raster (nor a store's imagery layer).
    NoDrape,
    /// The normal maps' texels computed on the other side (not a feature off: the other way).
    NormalsOn(NormalSource),
}

impl FeatureOff {
    /// The feature's name in the table ("what is off").
    pub fn name(self) -> &'static str {
        match self {
            Self::LookPlain => "land cover, sky, atmosphere (plain look)",
            Self::NoNormalMaps => "normal maps",
            Self::NoDrape => "draped rasters",
            Self::NormalsOn(NormalSource::Gpu) => "normals on the GPU (instead of the CPU)",
            Self::NormalsOn(NormalSource::Cpu) => "normals on the CPU (instead of the GPU)",
        }
    }

    /// The CSV key.
    pub fn key(self) -> &'static str {
        match self {
            Self::LookPlain => "look_plain",
            Self::NoNormalMaps => "no_normal_maps",
            Self::NoDrape => "no_drape",
            Self::NormalsOn(NormalSource::Gpu) => "normals_gpu",
            Self::NormalsOn(NormalSource::Cpu) => "normals_cpu",
        }
    }

    /// The base configuration's renderer with this feature off.
    pub fn apply(self, desc: &mut RendererDesc) {
        match self {
            Self::LookPlain => desc.look = Look::Plain,
            Self::NoNormalMaps => desc.normal_maps = false,
            Self::NoDrape => {
                desc.drape = None;
                desc.drape_store_imagery = false;
            }
            Self::NormalsOn(source) => desc.normal_source = source,
        }
    }
}

/// The features the base renderer has on, each to be turned off once; `draped`: it draped
/// something (rasters given, or a store's imagery layer).
pub fn features_on(base: &RendererDesc, draped: bool) -> Vec<FeatureOff> {
    let mut v = Vec::new();
    if base.look != Look::Plain {
        v.push(FeatureOff::LookPlain);
    }
    if base.normal_maps {
        v.push(FeatureOff::NoNormalMaps);
        v.push(FeatureOff::NormalsOn(match base.normal_source {
            NormalSource::Cpu => NormalSource::Gpu,
            NormalSource::Gpu => NormalSource::Cpu,
        }));
    }
    if draped {
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
    /// Per lane (0: the base, then `off`'s order) and measured frame: the normal maps' costs.
    pub normals: Vec<Vec<NormalCost>>,
}

/// What one frame's normal texels cost.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct NormalCost {
    /// CPU milliseconds computing them (`--normals cpu`).
    pub cpu_ms: f64,
    /// Bytes of them staged through the ring.
    pub staged_bytes: u64,
    /// GPU milliseconds of the normal pass (`--normals gpu`).
    pub gpu_ms: f64,
}

impl NormalCost {
    pub fn of(s: &FrameStats) -> NormalCost {
        NormalCost {
            cpu_ms: s.cpu_normals_us / 1e3,
            staged_bytes: s.bytes_normals,
            gpu_ms: s.gpu_normals_ms,
        }
    }
}

/// Over a lane's frames: CPU ms (median, p99), staged MiB (total, per frame), GPU pass ms
/// (median, p99).
fn normal_summary(n: &[NormalCost]) -> [f64; 6] {
    let cpu: Vec<f64> = n.iter().map(|c| c.cpu_ms).collect();
    let gpu: Vec<f64> = n.iter().map(|c| c.gpu_ms).collect();
    let (c50, c99) = FeatureCosts::stats(&cpu);
    let (g50, g99) = FeatureCosts::stats(&gpu);
    let mib = n.iter().map(|c| c.staged_bytes).sum::<u64>() as f64 / (1u64 << 20) as f64;
    [c50, c99, mib, mib / n.len().max(1) as f64, g50, g99]
}

impl FeatureCosts {
    pub fn new(base_label: String, features: &[FeatureOff]) -> Self {
        Self {
            base_label,
            base_ms: Vec::new(),
            off: features.iter().map(|&f| (f, Vec::new())).collect(),
            normals: vec![Vec::new(); features.len() + 1],
        }
    }

    /// Records a measured frame of the base (`lane` None) or of variant `lane`.
    pub fn push(&mut self, lane: Option<usize>, s: &FrameStats) {
        match lane {
            Some(v) => self.off[v].1.push(s.gpu_terrain_ms),
            None => self.base_ms.push(s.gpu_terrain_ms),
        }
        self.normals[lane.map_or(0, |v| v + 1)].push(NormalCost::of(s));
    }

    /// The lanes drawn with normal maps: name, GPU terrain ms median, then [`normal_summary`].
    fn normal_rows(&self) -> Vec<(String, f64, [f64; 6])> {
        let base = ("nothing (all on)".to_string(), &self.base_ms);
        let lanes =
            std::iter::once(base).chain(self.off.iter().map(|(f, ms)| (f.name().into(), ms)));
        lanes
            .zip(&self.normals)
            .filter(|((name, _), _)| name != FeatureOff::NoNormalMaps.name())
            .map(|((name, ms), n)| (name, Self::stats(ms).0, normal_summary(n)))
            .collect()
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
            "configuration,feature_off,frames,gpu_terrain_ms_median,gpu_terrain_ms_p99,feature_cost_ms,cpu_normals_ms_median,cpu_normals_ms_p99,normals_staged_mib,gpu_normals_ms_median,gpu_normals_ms_p99\n",
        );
        let n = |lane: usize| {
            let [c50, c99, mib, _, g50, g99] = normal_summary(&self.normals[lane]);
            format!("{c50:.4},{c99:.4},{mib:.3},{g50:.4},{g99:.4}")
        };
        out.push_str(&format!(
            "{},none,{},{base:.4},{base_p99:.4},0,{}\n",
            self.base_label,
            self.base_ms.len(),
            n(0)
        ));
        for (k, ((f, median, p99, cost), (_, ms))) in
            self.rows().into_iter().zip(&self.off).enumerate()
        {
            out.push_str(&format!(
                "{},{},{},{median:.4},{p99:.4},{cost:.4},{}\n",
                self.base_label,
                f.key(),
                ms.len(),
                n(k + 1)
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
        md.push_str("\nNormal maps, per frame: CPU time computing their texels and MiB staged (`--normals cpu`), the GPU normal pass (`--normals gpu`).\n\n| lane | GPU terrain ms | CPU normals ms (median) | p99 | staged MiB per frame | in all | GPU normal pass ms (median) | p99 |\n|---|---|---|---|---|---|---|---|\n");
        for (name, terrain, [c50, c99, mib, per, g50, g99]) in self.normal_rows() {
            md.push_str(&format!(
                "| {name} | {terrain:.3} | {c50:.3} | {c99:.3} | {per:.3} | {mib:.1} | {g50:.3} | {g99:.3} |\n"
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
            features_on(&desc, false),
            [
                FeatureOff::LookPlain,
                FeatureOff::NoNormalMaps,
                FeatureOff::NormalsOn(NormalSource::Gpu)
            ]
        );
        let mut gpu = desc.clone();
        FeatureOff::NormalsOn(NormalSource::Gpu).apply(&mut gpu);
        assert_eq!(gpu.normal_source, NormalSource::Gpu);
        assert_eq!(
            features_on(&gpu, false).last(),
            Some(&FeatureOff::NormalsOn(NormalSource::Cpu))
        );
        let mut plain = RendererDesc {
            look: Look::Plain,
            normal_maps: false,
            ..RendererDesc::default()
        };
        assert!(features_on(&plain, false).is_empty());
        assert_eq!(features_on(&plain, true), [FeatureOff::NoDrape]);
        FeatureOff::NoNormalMaps.apply(&mut desc);
        FeatureOff::LookPlain.apply(&mut desc);
        assert!(!desc.normal_maps && desc.look == Look::Plain);
        FeatureOff::NoDrape.apply(&mut plain);
        assert!(plain.drape.is_none() && !plain.drape_store_imagery);

        let mut c = FeatureCosts::new(
            "bounded τ=1".into(),
            &[FeatureOff::LookPlain, FeatureOff::NoNormalMaps],
        );
        for (k, (a, b, n)) in [(10.0, 8.0, 11.5), (12.0, 8.5, 11.0), (11.0, 7.5, 10.5)]
            .into_iter()
            .enumerate()
        {
            let cpu = FrameStats {
                gpu_terrain_ms: a,
                cpu_normals_us: 1000.0 * (k + 1) as f64,
                bytes_normals: 1 << 20,
                ..FrameStats::default()
            };
            c.push(None, &cpu);
            let plain = FrameStats {
                gpu_terrain_ms: b,
                ..cpu
            };
            c.push(Some(0), &plain);
            c.push(
                Some(1),
                &FrameStats {
                    gpu_terrain_ms: n,
                    ..FrameStats::default()
                },
            );
        }
        let rows = c.rows();
        assert_eq!(rows[0].0, FeatureOff::LookPlain);
        assert!((rows[0].1 - 8.0).abs() < 1e-12 && (rows[0].3 - 3.0).abs() < 1e-12);
        assert!((rows[1].3 - 0.0).abs() < 1e-12);
        let csv = c.csv();
        assert_eq!(csv.lines().count(), 4, "{csv}");
        assert!(csv.contains("bounded τ=1,look_plain,3,8.0000"), "{csv}");
        // The base's normals: 1, 2, 3 ms on the CPU, 1 MiB staged a frame.
        assert!(
            csv.contains(",0,2.0000,3.0000,3.000,0.0000,0.0000\n"),
            "{csv}"
        );
        let md = c.markdown();
        assert!(
            md.contains("| normal maps |") && md.contains("+3.000 ms (+27 %)"),
            "{md}"
        );
    }
}
