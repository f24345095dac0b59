//! The suite's combined report: per flight, every mode's curve and `bounded`'s ratio to each
//! baseline at equal measured error ([`super::curves`]); `suite.md` (the ratio table, the
//! geometric means, DESIGN.md's targets flight by flight), `ratios.csv`, `curves.csv`. Each
//! flight's own folder holds its `bench` report and charts.

use std::path::Path;

use super::curves::{geometric_mean, lower_envelope, ratio_at_equal_error, Curve, Ratio, Reading};
use super::report::Summary;
use crate::app::failure::{runtime, Failure};
use crate::tools::output::write_text;
use aerie_terrain::select::LodMode;

/// One benched (dataset, flight).
pub(crate) struct FlightResult {
    pub dataset: String,
    pub flight: String,
    pub dataset_summary: String,
    pub summaries: Vec<Summary>,
}

impl FlightResult {
    pub fn key(&self) -> String {
        format!("{}-{}", self.dataset, self.flight)
    }
}

/// How the suite ran.
pub(crate) struct SuiteInfo {
    pub source: String,
    pub device: String,
    pub size: String,
    pub fov: f64,
    pub frames: u32,
    pub warmup: u32,
    pub fps: f64,
    /// `run.replays`: the measured frames flown this many times, each frame's fastest kept.
    pub replays: u32,
}

/// A cost read against an error.
pub(crate) struct Metric {
    pub key: &'static str,
    pub title: &'static str,
    pub error: fn(&Summary) -> f64,
    pub cost: fn(&Summary) -> f64,
}

fn max_px(s: &Summary) -> f64 {
    s.error_px()
}
fn p99_px(s: &Summary) -> f64 {
    s.image.map_or(f64::NAN, |i| i.p99_px)
}
fn triangles(s: &Summary) -> f64 {
    s.triangles.median
}
fn frame_ms(s: &Summary) -> f64 {
    s.frame_ms.median
}

pub(crate) const METRICS: [Metric; 3] = [
    Metric {
        key: "triangles_at_max_error",
        title: "triangles at equal max error",
        error: max_px,
        cost: triangles,
    },
    Metric {
        key: "triangles_at_p99_error",
        title: "triangles at equal p99 error",
        error: p99_px,
        cost: triangles,
    },
    Metric {
        key: "frame_ms_at_max_error",
        title: "frame time at equal max error",
        error: max_px,
        cost: frame_ms,
    },
];

pub(crate) const BASELINES: [LodMode; 4] = [
    LodMode::Clipmap,
    LodMode::Distance,
    LodMode::Cdlod,
    LodMode::Tessellation,
];

/// DESIGN.md's late-tile target: at most 0.1 % of the tiles drawn late.
pub(crate) const LATE_TARGET: f64 = 0.001;

/// A configuration whose late tiles exceed [`LATE_TARGET`]: its frames drew coarse ancestors
/// in place of what it selected (its pools or staging could not keep up), so its point says
/// what a starved renderer draws, not what its setting costs. Left out of every mode's curve
/// alike and named in `suite.md`.
pub(crate) fn starved(s: &Summary) -> bool {
    s.late_fraction() > LATE_TARGET
}

/// The curve of `mode` in one flight for `metric`: with several tile sizes (`--tile-sizes`),
/// the lower envelope of each size's curve; [`starved`] configurations left out.
pub(crate) fn curve_of(summaries: &[Summary], mode: LodMode, metric: &Metric) -> Curve {
    let mut sizes: Vec<Option<u32>> = Vec::new();
    for s in summaries
        .iter()
        .filter(|s| s.config.mode == mode && !starved(s))
    {
        if !sizes.contains(&s.config.tile_size) {
            sizes.push(s.config.tile_size);
        }
    }
    let families: Vec<Curve> = sizes
        .iter()
        .map(|&size| {
            let pts: Vec<(f64, f64)> = summaries
                .iter()
                .filter(|s| s.config.mode == mode && s.config.tile_size == size && !starved(s))
                .map(|s| ((metric.error)(s), (metric.cost)(s)))
                .collect();
            Curve::new(&pts)
        })
        .collect();
    lower_envelope(&families)
}

/// `bounded` over `base` for `metric` in one flight; None when the flight ran no `base`.
pub(crate) fn flight_ratio(summaries: &[Summary], base: LodMode, metric: &Metric) -> Option<Ratio> {
    if !summaries.iter().any(|s| s.config.mode == base) {
        return None;
    }
    let ours = curve_of(summaries, LodMode::Bounded, metric);
    Some(ratio_at_equal_error(
        &ours,
        &curve_of(summaries, base, metric),
    ))
}

fn mode_word(m: LodMode) -> &'static str {
    super::config::mode_name(m)
}

fn cell(r: &Ratio) -> String {
    match r {
        Ratio::Value { ratio, at_error_px } => format!("{ratio:.2}× @{} px", px(*at_error_px)),
        Ratio::Bound {
            ratio,
            upper,
            gap_px: (lo, hi),
        } => format!(
            "{} {ratio:.2}× across {}–{} px",
            if *upper { "≤" } else { "≥" },
            px(*lo),
            px(*hi)
        ),
        Ratio::OutOfRange(why) => why.clone(),
    }
}

/// `curves.csv`: every configuration's point of every flight.
pub(crate) fn curves_csv(results: &[FlightResult]) -> String {
    let mut s = String::from(
        "dataset,flight,mode,config,max_error_px,p99_error_px,triangles_median,frame_ms_median,gpu_ms_median,frames_over_tau_plus_half,late_fraction,in_curve\n",
    );
    for r in results {
        for m in &r.summaries {
            s.push_str(&format!(
                "{},{},{},{},{},{},{},{},{},{},{},{}\n",
                r.dataset,
                r.flight,
                m.config.mode_name(),
                m.config.key(),
                max_px(m),
                p99_px(m),
                m.triangles.median,
                m.frame_ms.median,
                m.gpu_ms.median,
                m.image
                    .map_or(String::new(), |i| i.frames_over_target.to_string()),
                m.late_fraction(),
                !starved(m),
            ));
        }
    }
    s
}

/// `ratios.csv`: one row per flight × baseline × metric.
pub(crate) fn ratios_csv(results: &[FlightResult]) -> String {
    let mut s = String::from(
        "dataset,flight,baseline,metric,ratio,at_error_px,bound,bound_ratio,gap_from_px,gap_to_px,note\n",
    );
    for r in results {
        for base in BASELINES {
            for m in &METRICS {
                let Some(ratio) = flight_ratio(&r.summaries, base, m) else {
                    continue;
                };
                let none = String::new;
                let (v, at, bound, note) = match &ratio {
                    Ratio::Value { ratio, at_error_px } => (
                        ratio.to_string(),
                        at_error_px.to_string(),
                        ",,,".to_string(),
                        none(),
                    ),
                    Ratio::Bound {
                        ratio,
                        upper,
                        gap_px: (lo, hi),
                    } => (
                        none(),
                        none(),
                        format!(
                            "{},{ratio},{lo},{hi}",
                            if *upper { "upper" } else { "lower" }
                        ),
                        "no common error: a bound across the gap between the curves".into(),
                    ),
                    Ratio::OutOfRange(why) => {
                        (none(), none(), ",,,".to_string(), why.replace(',', ";"))
                    }
                };
                s.push_str(&format!(
                    "{},{},{},{},{v},{at},{bound},{note}\n",
                    r.dataset,
                    r.flight,
                    mode_word(base),
                    m.key
                ));
            }
        }
    }
    s
}

/// `suite.md`.
pub(crate) fn suite_md(info: &SuiteInfo, results: &[FlightResult]) -> String {
    let bases: Vec<LodMode> = BASELINES
        .into_iter()
        .filter(|b| {
            results
                .iter()
                .any(|r| r.summaries.iter().any(|s| s.config.mode == *b))
        })
        .collect();
    let mut md = format!(
        "# Bench suite {}\n\n{} flights on {}, {} px, {}° horizontal field of view, {} measured frames \
         after {} warm-up at {} fps per flight. Every mode renders the same frames; errors are \
         measured in the image against a full-resolution render of the same camera.{}\n\n",
        info.source,
        results.len(),
        info.device,
        info.size,
        info.fov,
        info.frames,
        info.warmup,
        info.fps,
        if info.replays > 1 {
            format!(
                " The measured frames were flown {} times, each time by fresh renderers after the \
                 same start-up fill; each frame is timed by its fastest flight that did the same \
                 work (the errors are those of the first).",
                info.replays
            )
        } else {
            String::new()
        }
    );
    md.push_str(
        "## Ratios: bounded over each baseline at equal measured error\n\n\
         Each cell is bounded's cost over the baseline's at the same error, read off the two \
         curves (each mode's efficient settings, piecewise-linear in log error and log cost), \
         the largest ratio over the errors both curves reach (the baseline at the error that \
         suits it best), and that error. Where the curves share no error but one lies wholly \
         at smaller errors and its cheapest setting costs less than the other's dearest, the \
         cell is a bound across the gap between them (*≤ r×*: bounded is at least that much \
         cheaper at every error of the gap; *≥ r×*: the baseline is), since a mode's cost grows \
         as its error falls; bounds are left out of the geometric means. *out of range*: the \
         curves share no error and neither bound holds (never extrapolated).\n\n",
    );
    let legend: Vec<String> = METRICS
        .iter()
        .map(|m| format!("*{}*: {}", short(m), m.title))
        .collect();
    md.push_str(&format!("Columns per baseline: {}.\n\n", legend.join("; ")));
    md.push_str("| flight |");
    for b in &bases {
        for m in &METRICS {
            md.push_str(&format!(" {} {} |", mode_word(*b), short(m)));
        }
    }
    md.push_str("\n|---|");
    for _ in 0..bases.len() * METRICS.len() {
        md.push_str("---|");
    }
    md.push('\n');
    let mut columns: Vec<Vec<f64>> = vec![Vec::new(); bases.len() * METRICS.len()];
    // Per column: cells known to be ≤ 0.8× (read or bounded above), cells known at all.
    let mut within: Vec<(usize, usize)> = vec![(0, 0); bases.len() * METRICS.len()];
    for r in results {
        md.push_str(&format!("| {} |", r.key()));
        for (bi, b) in bases.iter().enumerate() {
            for (mi, m) in METRICS.iter().enumerate() {
                let c = match flight_ratio(&r.summaries, *b, m) {
                    Some(ratio) => {
                        let col = bi * METRICS.len() + mi;
                        if let Some(v) = ratio.value() {
                            columns[col].push(v);
                        }
                        if !matches!(ratio, Ratio::OutOfRange(_)) {
                            within[col].1 += 1;
                            within[col].0 += ratio.at_most().is_some_and(|v| v <= 0.8) as usize;
                        }
                        cell(&ratio)
                    }
                    None => "—".into(),
                };
                md.push_str(&format!(" {c} |"));
            }
        }
        md.push('\n');
    }
    md.push_str("| **geometric mean** |");
    for col in &columns {
        match geometric_mean(col) {
            Some(g) => md.push_str(&format!(" **{g:.2}×** ({}/{}) |", col.len(), results.len())),
            None => md.push_str(" — |"),
        }
    }
    md.push_str("\n| **≤ 0.8× (read or bounded)** |");
    for (n, known) in &within {
        md.push_str(&format!(" {n} of {known} |"));
    }
    md.push_str("\n\n");
    md.push_str(&at_operating_point(results, &bases));
    md.push_str(&left_out(results));
    md.push_str(&targets(results));
    md.push_str("\n## Flights\n\n");
    for r in results {
        md.push_str(&format!(
            "- **{}**: {} — [`{k}/summary.md`]({k}/summary.md), [`triangles_vs_error.png`]({k}/triangles_vs_error.png), [`time_vs_error.png`]({k}/time_vs_error.png), waypoints [`flights/{k}.csv`](flights/{k}.csv)\n",
            r.key(),
            r.dataset_summary,
            k = r.key()
        ));
    }
    md.push_str(
        "\nFiles: `ratios.csv` (every cell above, with the error it was read at), `curves.csv` \
         (every configuration's point of every flight).\n",
    );
    md
}

/// The τ whose measured error [`at_operating_point`] reads the curves at: what a user runs.
pub(crate) const OPERATING_TAU_PX: f64 = 1.0;

/// Bounded's triangles over `base`'s at the error bounded τ = [`OPERATING_TAU_PX`] measures
/// (the least over its tile sizes), both curves read there as the ratio table reads them:
/// (that error, the ratio — None where the baseline's curve does not reach it). None when the
/// flight has no such configuration or no `base`.
pub(crate) fn ratio_at_operating_point(
    summaries: &[Summary],
    base: LodMode,
) -> Option<(f64, Option<f64>)> {
    if !summaries.iter().any(|s| s.config.mode == base) {
        return None;
    }
    let error = summaries
        .iter()
        .filter(|s| s.config.mode == LodMode::Bounded && s.config.tau_px == Some(OPERATING_TAU_PX))
        .filter(|s| !starved(s))
        .map(max_px)
        .filter(|e| e.is_finite() && *e > 0.0)
        .reduce(f64::min)?;
    let metric = &METRICS[0];
    let read = |mode| match curve_of(summaries, mode, metric).at(error) {
        Reading::Value(v) => Some(v),
        _ => None,
    };
    Some((
        error,
        read(LodMode::Bounded).zip(read(base)).map(|(a, b)| a / b),
    ))
}

/// `suite.md`'s second table: the ratio at the error a user runs (bounded τ = 1), where the
/// ratio table's cell — the largest over every error both curves reach — is often read at a
/// baseline's coarsest setting.
fn at_operating_point(results: &[FlightResult], bases: &[LodMode]) -> String {
    let mut rows = String::new();
    let mut columns: Vec<Vec<f64>> = vec![Vec::new(); bases.len()];
    for r in results {
        let cells: Vec<Option<(f64, Option<f64>)>> = bases
            .iter()
            .map(|&b| ratio_at_operating_point(&r.summaries, b))
            .collect();
        let Some(error) = cells.iter().flatten().map(|c| c.0).next() else {
            continue;
        };
        rows.push_str(&format!("| {} | {} px |", r.key(), px(error)));
        for (col, c) in columns.iter_mut().zip(&cells) {
            match c {
                Some((_, Some(v))) => {
                    col.push(*v);
                    rows.push_str(&format!(" {v:.2}× |"));
                }
                Some((_, None)) => rows.push_str(" out of range |"),
                None => rows.push_str(" — |"),
            }
        }
        rows.push('\n');
    }
    if rows.is_empty() {
        return String::new();
    }
    let mut md = format!(
        "## At the error bounded τ = {OPERATING_TAU_PX} px measures\n\n\
         Triangles, bounded over each baseline, both curves read at the max error bounded \
         τ = {OPERATING_TAU_PX} px measures on the flight (the least over its tile sizes) — the \
         error a user runs —, as the table above reads them; *out of range*: the baseline's \
         curve does not reach that error.\n\n| flight | error |"
    );
    for b in bases {
        md.push_str(&format!(" vs {} |", mode_word(*b)));
    }
    md.push_str("\n|---|---|");
    md.push_str(&"---|".repeat(bases.len()));
    md.push('\n');
    md.push_str(&rows);
    md.push_str("| **geometric mean** | |");
    for col in &columns {
        match geometric_mean(col) {
            Some(g) => md.push_str(&format!(" **{g:.2}×** ({}) |", col.len())),
            None => md.push_str(" — |"),
        }
    }
    md.push_str("\n\n");
    md
}

/// The configurations [`starved`] leaves out of the curves, flight by flight; empty when none.
fn left_out(results: &[FlightResult]) -> String {
    let rows: Vec<String> = results
        .iter()
        .flat_map(|r| {
            r.summaries.iter().filter(|s| starved(s)).map(move |s| {
                format!(
                    "| {} | {} | {:.1} % | {} px | {:.0} |\n",
                    r.key(),
                    s.config.key(),
                    100.0 * s.late_fraction(),
                    px(s.error_px()),
                    s.triangles.median
                )
            })
        })
        .collect();
    if rows.is_empty() {
        return String::new();
    }
    let mut md = format!(
        "## Configurations left out of the curves\n\n\
         {} configuration(s) drew more than {} % of their tiles late (coarse ancestors in place \
         of what they selected, their pools or staging short): their points say what a starved \
         renderer draws, not what their setting costs, so no mode's curve takes them. Their \
         figures stay in `curves.csv` (`in_curve` false).\n\n\
         | flight | configuration | late tiles | measured max error | triangles (median) |\n|---|---|---|---|---|\n",
        rows.len(),
        LATE_TARGET * 100.0
    );
    md.extend(rows);
    md.push('\n');
    md
}

/// An error in pixels with two decimals, three significant digits below 0.1 px.
fn px(e: f64) -> String {
    if e < 0.1 {
        format!("{e:.2e}")
    } else {
        format!("{e:.2}")
    }
}

fn short(m: &Metric) -> &'static str {
    match m.key {
        "triangles_at_max_error" => "tri @max",
        "triangles_at_p99_error" => "tri @p99",
        _ => "time @max",
    }
}

/// DESIGN.md's per-flight targets for `bounded`: every frame within τ + 0.5 px, late tiles ≤
/// 0.1 %, worst frame ≤ 1.5× the median. Beside the last, the same spread of the triangles
/// drawn: the frame's work, which the view decides and no timer's noise touches.
fn targets(results: &[FlightResult]) -> String {
    let mut md = String::from(
        "## Targets, flight by flight (bounded, every τ)\n\n\
         The last column is not a target: the worst frame's triangles over the median's, the \
         spread of the work itself (what the views ask for), beside the spread of the time.\n\n\
         | flight | frames over τ + 0.5 px | late tiles (worst τ) | worst / median frame time (worst τ) | worst / median triangles (worst τ) |\n|---|---|---|---|---|\n",
    );
    for r in results {
        let b: Vec<&Summary> = r
            .summaries
            .iter()
            .filter(|s| s.config.mode == LodMode::Bounded)
            .collect();
        let over: usize = b
            .iter()
            .filter_map(|s| s.image.map(|i| i.frames_over_target))
            .sum();
        let frames: usize = b.iter().map(|s| s.frames).sum();
        let late = b.iter().map(|s| s.late_fraction()).fold(0.0, f64::max);
        let spread = b
            .iter()
            .map(|s| s.frame_ms.max / s.frame_ms.median.max(1e-9))
            .fold(0.0, f64::max);
        let work = b
            .iter()
            .map(|s| s.triangles.max / s.triangles.median.max(1.0))
            .fold(0.0, f64::max);
        md.push_str(&format!(
            "| {} | {over} of {frames} {} | {:.3} % {} | {spread:.2}× {} | {work:.2}× |\n",
            r.key(),
            if over == 0 { "✓" } else { "✗" },
            late * 100.0,
            if late <= 0.001 { "✓" } else { "✗" },
            if spread <= 1.5 { "✓" } else { "✗" },
        ));
    }
    md
}

/// Writes `suite.md`, `ratios.csv`, `curves.csv` into `out` and prints the table.
pub(crate) fn write_report(
    out: &Path,
    info: &SuiteInfo,
    results: &[FlightResult],
) -> Result<(), Failure> {
    let md = suite_md(info, results);
    for (name, text) in [
        ("ratios.csv", ratios_csv(results)),
        ("curves.csv", curves_csv(results)),
        ("suite.md", md.clone()),
    ] {
        let path = out.join(name);
        write_text(&path, &text).map_err(|e| runtime(format!("{}: {e}", path.display())))?;
    }
    println!("{md}");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn info(replays: u32) -> SuiteInfo {
        SuiteInfo {
            source: "s.toml".into(),
            device: "llvmpipe".into(),
            size: "160x90".into(),
            fov: 90.0,
            frames: 4,
            warmup: 1,
            fps: 5.0,
            replays,
        }
    }

    #[test]
    fn the_head_says_how_often_the_frames_were_flown() {
        let md = suite_md(&info(3), &[]);
        assert!(md.contains("flown 3 times"), "{md}");
        assert!(md.contains("timed by its fastest flight that did the same work"));
        let once = suite_md(&info(1), &[]);
        assert!(!once.contains("flown"), "{once}");
    }

    /// A flight where bounded's finest τ is starved (1 % of its tiles late): its cheap, coarse
    /// point would otherwise reach an error the clipmap's curve also reaches.
    fn starved_flight(late: u64) -> FlightResult {
        use super::super::report::test_summary;
        let mut fine = test_summary(LodMode::Bounded, Some(0.1), 80.0, 1_000.0, 10.0);
        fine.tiles_drawn = 1000;
        fine.tiles_late = late;
        FlightResult {
            dataset: "mixed".into(),
            flight: "approach".into(),
            dataset_summary: String::new(),
            summaries: vec![
                fine,
                test_summary(LodMode::Bounded, Some(1.0), 1.0, 50_000.0, 10.0),
                test_summary(LodMode::Bounded, Some(4.0), 3.0, 20_000.0, 10.0),
                test_summary(LodMode::Clipmap, None, 60.0, 4_000.0, 10.0),
                test_summary(LodMode::Clipmap, None, 100.0, 2_000.0, 10.0),
            ],
        }
    }

    #[test]
    fn a_configuration_over_the_late_target_is_left_out_of_the_curves_and_named() {
        let tris = &METRICS[0];
        // At the target (0.1 %) it is a reading like any other: the curves meet at 80 px.
        let kept = starved_flight(1);
        let r = flight_ratio(&kept.summaries, LodMode::Clipmap, tris).unwrap();
        assert!(r.value().is_some(), "{r:?}");
        assert!(!suite_md(&info(1), &[kept]).contains("left out of the curves"));

        // Over it, bounded's curve ends at 3 px: no error in common with the clipmap's 60–100 px,
        // bounded lies wholly below and its dearest point costs more than the clipmap's
        // cheapest, so the cell says so instead of reading the starved point.
        let starved_one = starved_flight(10);
        let r = flight_ratio(&starved_one.summaries, LodMode::Clipmap, tris).unwrap();
        assert!(r.value().is_none(), "{r:?}");
        let md = suite_md(&info(1), &[starved_one]);
        assert!(
            md.contains("## Configurations left out of the curves"),
            "{md}"
        );
        assert!(
            md.contains("| mixed-approach | bounded_tau0.1 | 1.0 % | 80.00 px | 1000 |"),
            "{md}"
        );
        let csv = curves_csv(&[starved_flight(10)]);
        let row = csv.lines().find(|l| l.contains("bounded_tau0.1")).unwrap();
        assert!(row.ends_with(",0.01,false"), "{row}");
        assert!(
            csv.lines().filter(|l| l.ends_with(",true")).count() == 4,
            "{csv}"
        );
    }

    #[test]
    fn the_operating_point_reads_both_curves_at_bounded_tau_one() {
        use super::super::report::test_summary;
        let s = vec![
            test_summary(LodMode::Bounded, Some(1.0), 1.0, 50_000.0, 10.0),
            test_summary(LodMode::Bounded, Some(4.0), 3.0, 20_000.0, 10.0),
            test_summary(LodMode::Clipmap, None, 0.5, 200_000.0, 10.0),
            test_summary(LodMode::Clipmap, None, 2.0, 40_000.0, 10.0),
            test_summary(LodMode::Cdlod, None, 2.0, 30_000.0, 10.0),
            test_summary(LodMode::Cdlod, None, 6.0, 9_000.0, 10.0),
        ];
        // The clipmap at 1 px: halfway between 0.5 and 2 px in log error, √(200k · 40k).
        let (e, r) = ratio_at_operating_point(&s, LodMode::Clipmap).unwrap();
        assert_eq!(e, 1.0);
        let want = 50_000.0 / (200_000.0f64 * 40_000.0).sqrt();
        assert!((r.unwrap() - want).abs() < 1e-12, "{r:?}");
        // CDLOD's curve starts at 2 px: it does not reach 1 px.
        assert_eq!(
            ratio_at_operating_point(&s, LodMode::Cdlod),
            Some((1.0, None))
        );
        assert_eq!(ratio_at_operating_point(&s, LodMode::Distance), None);
        let flight = FlightResult {
            dataset: "inn".into(),
            flight: "cruise".into(),
            dataset_summary: String::new(),
            summaries: s,
        };
        let md = suite_md(&info(1), &[flight]);
        assert!(
            md.contains("## At the error bounded τ = 1 px measures"),
            "{md}"
        );
        assert!(
            md.contains("| inn-cruise | 1.00 px | 0.56× | out of range |"),
            "{md}"
        );
        assert!(
            md.contains("| **geometric mean** | | **0.56×** (1) | — |"),
            "{md}"
        );
    }
}
