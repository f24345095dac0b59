//! `aerie bench` outputs: `results.csv` (one row per frame per configuration), the per
//! configuration summaries (`summary.csv`, `summary.md`, the table printed at the end), the
//! Pareto front of time against error, and the "at equal measured error" comparisons.

use std::fmt::Write as _;

use super::config::BenchConfig;
use super::rows::FrameRow;
use crate::render::frame::FrameStats;
use crate::tools::image_error::ImageError;
use aerie_terrain::select::LodMode;

/// Nearest-rank order statistics of a sample.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Quantiles {
    pub median: f64,
    pub p95: f64,
    pub p99: f64,
    pub max: f64,
}

impl Quantiles {
    /// Of `values` (any order; NaN sorts last). All zero when empty.
    pub fn of(values: &[f64]) -> Self {
        if values.is_empty() {
            return Self::default();
        }
        let mut v = values.to_vec();
        v.sort_by(f64::total_cmp);
        let at = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
        Self {
            median: at(0.5),
            p95: at(0.95),
            p99: at(0.99),
            max: v[v.len() - 1],
        }
    }
}

/// Which points (x = error, y = time, both smaller is better) no other point beats on both:
/// `true` for the Pareto front. Points with a NaN coordinate are never on it.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|&(x, y)| {
            !x.is_nan()
                && !y.is_nan()
                && !points.iter().any(|&(x2, y2)| {
                    x2 <= x && y2 <= y && (x2 < x || y2 < y) && !x2.is_nan() && !y2.is_nan()
                })
        })
        .collect()
}

/// What the run was, for the head of `summary.md`.
#[derive(Debug, Clone)]
pub(crate) struct RunInfo {
    pub device: String,
    pub dem: String,
    pub dataset: String,
    pub size: (u32, u32),
    pub fov_deg: f64,
    pub frames: u32,
    pub warmup: u32,
    pub flight: String,
    pub validation: bool,
    pub image_error: bool,
    pub oracle_nodes: u32,
    /// The start-up fill's line (`--settle`), if there was one.
    pub startup: Option<String>,
    /// The replays' line (`--replays`), if the frames were flown more than once.
    pub replays: Option<String>,
}

/// Image error of one configuration over the measured frames.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct ImageSummary {
    /// Largest per-pixel error of any frame, confirmed by a neighbouring pixel
    /// (`ImageError::confirmed`): the headline number.
    pub max_px: f64,
    /// Largest raw per-pixel error of any frame (lone rasteriser pixels included).
    pub raw_max_px: f64,
    /// Over every measured pixel of every frame.
    pub p99_px: f64,
    pub mean_px: f64,
    pub fraction_over_tau: f64,
    pub holes_px: u64,
    pub hole_max_px: f64,
    /// Frames whose confirmed max exceeds τ + 0.5 px (DESIGN.md target; τ = 1 px for modes
    /// without τ).
    pub frames_over_target: usize,
    /// Per-frame confirmed maxima.
    pub frame_max: Quantiles,
}

/// One configuration over the measured (non-warm-up) frames.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Summary {
    pub config: BenchConfig,
    pub frames: usize,
    /// Wall time of `render` (CPU + wait for the GPU), ms.
    pub frame_ms: Quantiles,
    /// CPU stages: select + upload + record, ms.
    pub cpu_ms: Quantiles,
    /// GPU timestamps: upload + terrain passes, ms.
    pub gpu_ms: Quantiles,
    pub triangles: Quantiles,
    pub instances: Quantiles,
    pub draw_calls: Quantiles,
    pub bytes_uploaded: Quantiles,
    pub bytes_uploaded_mean: f64,
    pub tiles_drawn: u64,
    pub tiles_late: u64,
    /// The part of `tiles_late` due to streaming (samples not resident yet).
    pub tiles_late_stream: u64,
    /// The longest time the frame thread spent gathering terrain samples in one frame, µs.
    pub terrain_data_us_max: f64,
    pub tiles_unbounded: u64,
    pub image: Option<ImageSummary>,
    pub oracle_max_px: Option<f64>,
    pub bound_max_px: Option<f64>,
}

impl Summary {
    /// Late tiles over tiles drawn.
    pub fn late_fraction(&self) -> f64 {
        if self.tiles_drawn == 0 {
            0.0
        } else {
            self.tiles_late as f64 / self.tiles_drawn as f64
        }
    }

    /// The measured max image error, or NaN without one.
    pub fn error_px(&self) -> f64 {
        self.image.map_or(f64::NAN, |i| i.max_px)
    }
}

fn cpu_ms(s: &FrameStats) -> f64 {
    (s.cpu_select_us + s.cpu_upload_us + s.cpu_record_us) / 1e3
}

fn gpu_ms(s: &FrameStats) -> f64 {
    s.gpu_upload_ms + s.gpu_terrain_ms
}

/// Summaries per configuration (index = `FrameRow::config`); `totals` are the image errors
/// accumulated over the measured frames (None without image error).
pub(crate) fn summarize(
    configs: &[BenchConfig],
    rows: &[FrameRow],
    totals: &[Option<&ImageError>],
) -> Vec<Summary> {
    configs
        .iter()
        .enumerate()
        .map(|(i, &config)| {
            let mine: Vec<&FrameRow> = rows.iter().filter(|r| r.config == i && !r.warmup).collect();
            let q = |f: &dyn Fn(&FrameRow) -> f64| {
                Quantiles::of(&mine.iter().map(|r| f(r)).collect::<Vec<_>>())
            };
            let tau = config.tau_for_error();
            let image = totals.get(i).copied().flatten().map(|t| {
                let maxima: Vec<f64> = mine
                    .iter()
                    .filter_map(|r| r.image.map(|im| im.confirmed_max_px))
                    .collect();
                ImageSummary {
                    max_px: t.confirmed_max_px(),
                    raw_max_px: t.max_px(),
                    p99_px: t.p99_px(),
                    mean_px: t.mean_px(),
                    fraction_over_tau: t.fraction_over_tau(),
                    holes_px: t.holes_px,
                    hole_max_px: t.hole_max_px,
                    frames_over_target: maxima.iter().filter(|&&m| m > tau + 0.5).count(),
                    frame_max: Quantiles::of(&maxima),
                }
            });
            let oracle: Vec<_> = mine.iter().filter_map(|r| r.oracle).collect();
            let bytes: Vec<f64> = mine.iter().map(|r| r.stats.bytes_uploaded as f64).collect();
            Summary {
                config,
                frames: mine.len(),
                frame_ms: q(&|r| r.wall_ms),
                cpu_ms: q(&|r| cpu_ms(&r.stats)),
                gpu_ms: q(&|r| gpu_ms(&r.stats)),
                triangles: q(&|r| r.stats.triangles as f64),
                instances: q(&|r| r.stats.instances as f64),
                draw_calls: q(&|r| r.stats.draw_calls as f64),
                bytes_uploaded: Quantiles::of(&bytes),
                bytes_uploaded_mean: bytes.iter().sum::<f64>() / bytes.len().max(1) as f64,
                tiles_drawn: mine.iter().map(|r| r.stats.tiles_drawn as u64).sum(),
                tiles_late: mine.iter().map(|r| r.stats.tiles_late as u64).sum(),
                tiles_late_stream: mine.iter().map(|r| r.stats.tiles_late_stream as u64).sum(),
                terrain_data_us_max: mine
                    .iter()
                    .map(|r| r.stats.cpu_terrain_data_us)
                    .fold(0.0, f64::max),
                tiles_unbounded: mine.iter().map(|r| r.stats.tiles_unbounded as u64).sum(),
                image,
                oracle_max_px: (!oracle.is_empty())
                    .then(|| oracle.iter().map(|o| o.max_px).fold(0.0, f64::max)),
                bound_max_px: (!oracle.is_empty())
                    .then(|| oracle.iter().map(|o| o.max_bound_px).fold(0.0, f64::max)),
            }
        })
        .collect()
}

fn opt(v: Option<f64>, digits: usize) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:.digits$}"),
        Some(x) => format!("{x}"),
        None => String::new(),
    }
}

/// `results.csv`: one row per frame per configuration (warm-up frames included, marked).
pub(crate) fn results_csv(configs: &[BenchConfig], rows: &[FrameRow]) -> String {
    let mut s = format!(
        "bench_frame,warmup,config,mode,tau_px,time_s,x_m,y_m,z_m,heading_deg,pitch_deg,roll_deg,frame_ms,cpu_ms,gpu_ms,{},img_confirmed_max_px,img_max_px,img_p99_px,img_mean_px,img_frac_over_tau,img_measured_px,img_holes_px,img_hole_max_px,img_extra_px,img_max_x,img_max_y,oracle_max_px,oracle_nodes,bound_max_px,frame_ms_first,replay_kept,replays_same,replays_differed\n",
        FrameStats::CSV_HEADER
    );
    for r in rows {
        let c = configs[r.config];
        let _ = write!(
            s,
            "{},{},{},{},{},{:.4},{:.2},{:.2},{:.2},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{},",
            r.frame,
            r.warmup as u8,
            c.key(),
            c.mode_name(),
            c.tau_px.map(|t| t.to_string()).unwrap_or_default(),
            r.time_s,
            r.position.x,
            r.position.y,
            r.position.z,
            r.attitude.heading.to_degrees(),
            r.attitude.pitch.to_degrees(),
            r.attitude.roll.to_degrees(),
            r.wall_ms,
            cpu_ms(&r.stats),
            gpu_ms(&r.stats),
            r.stats.csv_row()
        );
        match r.image {
            Some(im) => {
                let _ = write!(
                    s,
                    "{:.4},{:.4},{:.4},{:.5},{:.6},{},{},{},{},{},{},",
                    im.confirmed_max_px,
                    im.max_px,
                    im.p99_px,
                    im.mean_px,
                    im.fraction_over_tau,
                    im.measured_px,
                    im.holes_px,
                    im.hole_max_px,
                    im.extra_px,
                    im.max_at.map(|p| p.0.to_string()).unwrap_or_default(),
                    im.max_at.map(|p| p.1.to_string()).unwrap_or_default(),
                );
            }
            None => s.push_str(",,,,,,,,,,,"),
        }
        match r.oracle {
            Some(o) => {
                let _ = write!(s, "{:.4},{},{:.4},", o.max_px, o.nodes, o.max_bound_px);
            }
            None => s.push_str(",,,"),
        }
        let p = &r.replays;
        let _ = writeln!(s, "{:.3},{},{},{}", p.first_ms, p.kept, p.same, p.differed);
    }
    s
}

/// `summary.csv`: one row per configuration.
pub(crate) fn summary_csv(summaries: &[Summary]) -> String {
    let mut s = String::from(
        "config,mode,tau_px,frames,frame_ms_median,frame_ms_p95,frame_ms_p99,frame_ms_max,cpu_ms_median,cpu_ms_p95,cpu_ms_p99,cpu_ms_max,gpu_ms_median,gpu_ms_p95,gpu_ms_p99,gpu_ms_max,triangles_median,triangles_max,instances_median,instances_max,draw_calls_median,bytes_uploaded_mean,bytes_uploaded_max,tiles_drawn,tiles_late,late_fraction,tiles_unbounded,img_confirmed_max_px,img_max_px,img_p99_px,img_mean_px,img_frac_over_tau,img_holes_px,img_hole_max_px,frames_over_tau_plus_half,img_frame_max_median_px,oracle_max_px,bound_max_px,tiles_late_stream,terrain_data_us_max\n",
    );
    for m in summaries {
        let q = |q: &Quantiles| format!("{:.3},{:.3},{:.3},{:.3}", q.median, q.p95, q.p99, q.max);
        let _ = write!(
            s,
            "{},{},{},{},{},{},{},{:.0},{:.0},{:.0},{:.0},{:.0},{:.0},{:.0},{},{},{:.6},{},",
            m.config.key(),
            m.config.mode_name(),
            m.config.tau_px.map(|t| t.to_string()).unwrap_or_default(),
            m.frames,
            q(&m.frame_ms),
            q(&m.cpu_ms),
            q(&m.gpu_ms),
            m.triangles.median,
            m.triangles.max,
            m.instances.median,
            m.instances.max,
            m.draw_calls.median,
            m.bytes_uploaded_mean,
            m.bytes_uploaded.max,
            m.tiles_drawn,
            m.tiles_late,
            m.late_fraction(),
            m.tiles_unbounded,
        );
        match m.image {
            Some(i) => {
                let _ = write!(
                    s,
                    "{:.4},{:.4},{:.4},{:.5},{:.6},{},{},{},{:.4},",
                    i.max_px,
                    i.raw_max_px,
                    i.p99_px,
                    i.mean_px,
                    i.fraction_over_tau,
                    i.holes_px,
                    i.hole_max_px,
                    i.frames_over_target,
                    i.frame_max.median
                );
            }
            None => s.push_str(",,,,,,,,,"),
        }
        let _ = writeln!(
            s,
            "{},{},{},{:.1}",
            opt(m.oracle_max_px, 4),
            opt(m.bound_max_px, 4),
            m.tiles_late_stream,
            m.terrain_data_us_max
        );
    }
    s
}

/// "1.23M", "45.6k", "789".
fn count(v: f64) -> String {
    if v >= 1e6 {
        format!("{:.2}M", v / 1e6)
    } else if v >= 1e4 {
        format!("{:.1}k", v / 1e3)
    } else {
        format!("{v:.0}")
    }
}

fn px(v: f64) -> String {
    if v.is_nan() {
        "–".into()
    } else if v >= 100.0 {
        format!("{v:.0}")
    } else {
        format!("{v:.2}")
    }
}

/// The per-configuration table (markdown), as in `summary.md` and printed at the end.
pub(crate) fn summary_table(summaries: &[Summary]) -> String {
    let mut s = String::from(
        "| configuration | frame ms median / p95 / p99 / max | CPU ms median / p99 | GPU ms median / p99 | triangles median | instances | draws | MB up / frame | late tiles | image err max px (raw) | p99 px | > τ | holes px / frame (max col. dist) | oracle max px |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for m in summaries {
        let (emax, ep99, over, holes) = match m.image {
            Some(i) => (
                format!("{} ({})", px(i.max_px), px(i.raw_max_px)),
                px(i.p99_px),
                format!("{:.3} %", 100.0 * i.fraction_over_tau),
                format!(
                    "{:.1} ({:.0})",
                    i.holes_px as f64 / m.frames.max(1) as f64,
                    i.hole_max_px
                ),
            ),
            None => ("–".into(), "–".into(), "–".into(), "–".into()),
        };
        let _ = writeln!(
            s,
            "| {} | {:.1} / {:.1} / {:.1} / {:.1} | {:.2} / {:.2} | {:.2} / {:.2} | {} | {} | {:.0} | {:.2} | {} ({:.2} %) | {} | {} | {} | {} | {} |",
            m.config.label(),
            m.frame_ms.median,
            m.frame_ms.p95,
            m.frame_ms.p99,
            m.frame_ms.max,
            m.cpu_ms.median,
            m.cpu_ms.p99,
            m.gpu_ms.median,
            m.gpu_ms.p99,
            count(m.triangles.median),
            count(m.instances.median),
            m.draw_calls.median,
            m.bytes_uploaded_mean / 1e6,
            m.tiles_late,
            100.0 * m.late_fraction(),
            emax,
            ep99,
            over,
            holes,
            m.oracle_max_px.map(px).unwrap_or_else(|| "–".into()),
        );
    }
    s
}

/// The bounded configuration to compare with `base` "at equal measured max error": the one with
/// the fewest triangles among those whose measured max error is ≤ the baseline's; when none
/// is, the one with the smallest error (the comparison then says so).
fn match_bounded<'a>(summaries: &'a [Summary], base: &Summary) -> Option<(&'a Summary, bool)> {
    let bounded: Vec<&Summary> = summaries
        .iter()
        .filter(|s| s.config.mode == LodMode::Bounded && !s.error_px().is_nan())
        .collect();
    let target = base.error_px();
    if target.is_nan() {
        return None;
    }
    let within = bounded
        .iter()
        .filter(|s| s.error_px() <= target)
        .min_by(|a, b| a.triangles.median.total_cmp(&b.triangles.median));
    match within {
        Some(s) => Some((s, true)),
        None => bounded
            .iter()
            .min_by(|a, b| a.error_px().total_cmp(&b.error_px()))
            .map(|s| (*s, false)),
    }
}

/// `bounded`'s median triangles and frame ms at exactly `target` px of measured max error,
/// interpolated log-log between the two bounded configurations whose measured errors bracket
/// it (work falls roughly as a power of the error). None when no pair brackets the target.
pub(crate) fn bounded_at_error(summaries: &[Summary], target: f64) -> Option<(f64, f64, f64, f64)> {
    if target.is_nan() || target <= 0.0 {
        return None;
    }
    let mut pts: Vec<(f64, f64, f64, f64)> = summaries
        .iter()
        .filter(|s| s.config.mode == LodMode::Bounded)
        .map(|s| {
            (
                s.error_px(),
                s.triangles.median,
                s.frame_ms.median,
                s.config.tau_for_error(),
            )
        })
        .filter(|p| p.0 > 0.0 && p.1 > 0.0 && p.2 > 0.0)
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let hi = pts.iter().position(|p| p.0 >= target)?;
    if pts[hi].0 == target {
        let p = pts[hi];
        return Some((p.1, p.2, p.3, p.3));
    }
    let lo = hi.checked_sub(1)?;
    let (a, b) = (pts[lo], pts[hi]);
    let t = (target.ln() - a.0.ln()) / (b.0.ln() - a.0.ln());
    let lerp = |x: f64, y: f64| (x.ln() + t * (y.ln() - x.ln())).exp();
    Some((lerp(a.1, b.1), lerp(a.2, b.2), a.3, b.3))
}

/// Sentences comparing `bounded` with each baseline at equal measured max error.
pub(crate) fn comparisons(summaries: &[Summary]) -> Vec<String> {
    let mut out = Vec::new();
    for base in summaries
        .iter()
        .filter(|s| s.config.mode != LodMode::Bounded)
    {
        let Some((b, equal)) = match_bounded(summaries, base) else {
            continue;
        };
        let ratio = |a: f64, c: f64| if c > 0.0 { a / c } else { f64::NAN };
        out.push(format!(
            "vs **{}** (max error {} px): **{}** (max error {} px{}) draws {:.3}× the triangles (median {} vs {}), {:.2}× the median frame time ({:.1} vs {:.1} ms), {:.2}× the median GPU time",
            base.config.label(),
            px(base.error_px()),
            b.config.label(),
            px(b.error_px()),
            if equal { ", ≤ the baseline's" } else { ", the smallest bounded error: not equal" },
            ratio(b.triangles.median, base.triangles.median),
            count(b.triangles.median),
            count(base.triangles.median),
            ratio(b.frame_ms.median, base.frame_ms.median),
            b.frame_ms.median,
            base.frame_ms.median,
            ratio(b.gpu_ms.median, base.gpu_ms.median),
        ));
        if let Some((tris, ms, tau_a, tau_b)) = bounded_at_error(summaries, base.error_px()) {
            let how = if tau_a == tau_b {
                format!("bounded τ={tau_a} measured exactly")
            } else {
                format!("interpolated (log-log between bounded τ={tau_a} and τ={tau_b})")
            };
            out.push(format!(
                "vs **{}**, {how} at its {} px: {:.3}× the triangles ({} vs {}), {:.2}× the median frame time ({:.1} vs {:.1} ms)",
                base.config.label(),
                px(base.error_px()),
                ratio(tris, base.triangles.median),
                count(tris),
                count(base.triangles.median),
                ratio(ms, base.frame_ms.median),
                ms,
                base.frame_ms.median,
            ));
        }
    }
    out
}

/// `summary.md`: the run, the table, the comparisons, DESIGN.md's targets, how it was measured.
pub(crate) fn summary_md(info: &RunInfo, summaries: &[Summary]) -> String {
    let mut s = String::from("# aerie bench\n\n");
    let _ = writeln!(s, "- device: {}", info.device);
    let _ = writeln!(s, "- DEM: `{}` — {}", info.dem, info.dataset);
    let _ = writeln!(
        s,
        "- {}×{} px, {}° horizontal FOV; {} measured frames after {} warm-up frames; flight: {}",
        info.size.0, info.size.1, info.fov_deg, info.frames, info.warmup, info.flight
    );
    if let Some(line) = &info.startup {
        let _ = writeln!(s, "- {line}");
    }
    if let Some(line) = &info.replays {
        let _ = writeln!(s, "- {line}");
    }
    let _ = writeln!(
        s,
        "- validation layer {}",
        if info.validation {
            "on (timings include it)"
        } else {
            "off"
        }
    );
    s.push('\n');
    s.push_str(&summary_table(summaries));
    let cmp = comparisons(summaries);
    if !cmp.is_empty() {
        s.push_str("\n## At equal measured max error\n\n");
        for c in &cmp {
            let _ = writeln!(s, "- {c}");
        }
    }
    s.push_str("\n## DESIGN.md targets\n\n");
    let points: Vec<(f64, f64)> = summaries
        .iter()
        .map(|m| (m.error_px(), m.frame_ms.median))
        .collect();
    let front = pareto_front(&points);
    for (m, on_front) in summaries.iter().zip(front) {
        let target = match (m.config.tau_px, m.image) {
            (Some(t), Some(i)) => format!(
                "max error ≤ τ + 0.5 = {} px on {}/{} frames (worst {} px, median frame {} px)",
                t + 0.5,
                m.frames - i.frames_over_target,
                m.frames,
                px(i.max_px),
                px(i.frame_max.median)
            ),
            _ => String::from("no τ"),
        };
        let _ = writeln!(
            s,
            "- {}: {target}; late tiles {:.3} % of drawn (target ≤ 0.1 %); worst frame {:.2}× the median (target ≤ 2×){}",
            m.config.label(),
            100.0 * m.late_fraction(),
            if m.frame_ms.median > 0.0 {
                m.frame_ms.max / m.frame_ms.median
            } else {
                f64::NAN
            },
            if on_front { "; on the time/error Pareto front" } else { "" }
        );
    }
    s.push_str("\n## How it was measured\n\n");
    s.push_str("- Every configuration has its own renderer (own caches, pools, hysteresis) and renders the same camera each frame; the order of configurations rotates by one every frame.\n");
    s.push_str("- frame ms: wall time of `TerrainRenderer::render` — selection, uploads, recording, submission and the wait for the GPU (headless: the frame and its read-back copy). CPU ms: selection + upload + record stages. GPU ms: timestamp queries around the upload and terrain passes.\n");
    if info.image_error {
        s.push_str("- image error: from each frame's read-back depth, each pixel's drawn world point (view z = near / depth) and the full-resolution surface point under it (SW–NE diagonal, per-vertex curvature drop, as `full` draws it) are projected with the frame's camera; the error is their distance in px (CPU, all cores). Silhouettes are included: a crest drawn too low measures how far the true crest is above it. max: over all frames, each pixel's error capped by the largest among its 8 neighbours (a lone pixel above all its neighbours is the rasteriser's: a sub-pixel triangle seen edge-on at the horizon is covered on snapped vertex positions and its plane's depth then belongs to a point outside it — `full`, which draws the true surface, shows such pixels); (raw): without that cap; p99 and mean: over every terrain pixel of every frame; > τ: fraction of those pixels above τ (1 px for modes without τ). Holes: pixels that are sky in the frame but terrain in the `full` render of the same camera (silhouettes drawn a fraction of a pixel low flip whole pixels; cracks would show here), per frame, with the largest distance along a column to the frame's terrain (an upper bound of the silhouette's displacement, whole pixels); they are not in the error columns. The measurement runs on the CPU from the read-back depth (a GPU compute pass is future work).\n");
    }
    if info.oracle_nodes > 0 {
        let _ = writeln!(
            s,
            "- oracle: the CPU selection of the same camera, {} nodes per frame (half with the largest bound ρ, half at random) checked by brute force against the full-resolution samples (nodes above level 3 on a subsample); it does not see tiles the renderer drew coarser because their upload was late.",
            info.oracle_nodes
        );
    }
    s
}

/// A summary of one frame at `err` px measured, `tris` triangles and `ms` ms, none late: the
/// report tests' point.
#[cfg(test)]
pub(crate) fn test_summary(
    mode: LodMode,
    tau: Option<f64>,
    err: f64,
    tris: f64,
    ms: f64,
) -> Summary {
    let q = |v: f64| Quantiles {
        median: v,
        p95: v,
        p99: v,
        max: v,
    };
    Summary {
        config: BenchConfig {
            mode,
            tau_px: tau,
            knob: None,
            tile_size: None,
        },
        frames: 1,
        frame_ms: q(ms),
        cpu_ms: q(0.0),
        gpu_ms: q(ms),
        triangles: q(tris),
        instances: q(1.0),
        draw_calls: q(1.0),
        bytes_uploaded: q(0.0),
        bytes_uploaded_mean: 0.0,
        tiles_drawn: 1,
        tiles_late: 0,
        tiles_late_stream: 0,
        terrain_data_us_max: 0.0,
        tiles_unbounded: 0,
        image: Some(ImageSummary {
            max_px: err,
            ..Default::default()
        }),
        oracle_max_px: None,
        bound_max_px: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_nearest_rank() {
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        let q = Quantiles::of(&v);
        assert_eq!((q.median, q.p95, q.p99, q.max), (51.0, 95.0, 99.0, 100.0));
        assert_eq!(Quantiles::of(&[]), Quantiles::default());
        assert_eq!(Quantiles::of(&[3.0]).p99, 3.0);
    }

    #[test]
    fn pareto_front_keeps_the_undominated() {
        let pts = [
            (0.5, 30.0),
            (1.0, 20.0),
            (2.0, 25.0), // dominated by (1, 20)
            (5.0, 10.0),
            (0.01, 200.0),
            (f64::NAN, 1.0),
            (1.0, 20.0), // a tie with an equal point stays on the front
        ];
        assert_eq!(
            pareto_front(&pts),
            vec![true, true, false, true, true, false, true]
        );
    }

    #[test]
    fn bounded_work_is_interpolated_log_log_at_the_baselines_error() {
        let s = vec![
            test_summary(LodMode::Bounded, Some(5.0), 2.0, 400_000.0, 400.0),
            test_summary(LodMode::Bounded, Some(20.0), 8.0, 25_000.0, 100.0),
            test_summary(LodMode::Bounded, Some(10.0), 4.0, 100_000.0, 200.0),
            test_summary(LodMode::Clipmap, None, 5.0, 50_000.0, 150.0),
        ];
        // 5 px lies between 4 px (τ=10) and 8 px (τ=20): t = ln(5/4)/ln 2.
        let (tris, ms, a, b) = bounded_at_error(&s, 5.0).expect("bracketed");
        let t = (5.0f64 / 4.0).ln() / 2f64.ln();
        assert!((tris - 100_000.0 * 0.25f64.powf(t)).abs() < 1e-6, "{tris}");
        assert!((ms - 200.0 * 0.5f64.powf(t)).abs() < 1e-9, "{ms}");
        assert_eq!((a, b), (10.0, 20.0));
        // Exactly on a point, and outside the measured range.
        assert_eq!(bounded_at_error(&s, 4.0).map(|r| r.0), Some(100_000.0));
        assert_eq!(bounded_at_error(&s, 1.0), None);
        assert_eq!(bounded_at_error(&s, 9.0), None);
        let text = comparisons(&s).join("\n");
        assert!(text.contains("interpolated"), "{text}");
    }
}
