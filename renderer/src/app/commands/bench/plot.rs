//! `time_vs_error.png` and `triangles_vs_error.png`: each configuration's measured max image
//! error (x, log scale) against its median frame time or triangles (y), one series per mode
//! (`bounded` joined across τ), the Pareto front marked. plotters draws into an RGB buffer with
//! the embedded DejaVu Sans subset (assets/fonts) as its only font; the PNG goes through
//! [`write_png`] like every other image.

use std::path::Path;
use std::sync::OnceLock;

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use plotters::style::FontStyle;

use super::config::mode_name;
use super::plot_labels::{label_order, place_labels, LabelToPlace};
use super::report::{pareto_front, Summary};
use crate::tools::output::write_png;
use aerie_terrain::select::LodMode;

/// DejaVu Sans, printable ASCII and a few symbols (see assets/fonts/README.md).
static FONT: &[u8] = include_bytes!("../../../../../assets/fonts/DejaVuSans-subset.ttf");
const FAMILY: &str = "sans-serif";
/// Errors below this are drawn at it (a log axis has no 0); their labels say "≤".
const ERROR_FLOOR_PX: f64 = 0.01;
const SIZE: (u32, u32) = (1200, 800);
/// The modes in the order their series are drawn (and listed in the legend).
const MODES: [LodMode; 6] = [
    LodMode::Bounded,
    LodMode::Clipmap,
    LodMode::Distance,
    LodMode::Cdlod,
    LodMode::Tessellation,
    LodMode::Full,
];
/// The points' labels' font size.
const LABEL_PX: f64 = 15.0;

fn ensure_font() -> Result<(), String> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED
        .get_or_init(|| plotters::style::register_font(FAMILY, FontStyle::Normal, FONT).is_ok());
    ok.then_some(())
        .ok_or_else(|| "embedded chart font is not a valid TrueType font".to_string())
}

/// Labels of a log axis: only 1, 2 and 5 of each decade ("0.05", "2", "10k", "1M").
fn log_tick(v: f64) -> String {
    if v.is_nan() || v <= 0.0 {
        return String::new();
    }
    let e = v.log10().floor();
    let m = v / 10f64.powf(e);
    if ![1.0, 2.0, 5.0, 10.0].iter().any(|k| (m - k).abs() < 1e-6) {
        return String::new();
    }
    let r = (v * 1e6).round() / 1e6;
    if r >= 1e6 {
        format!("{}M", r / 1e6)
    } else if r >= 1e3 {
        format!("{}k", r / 1e3)
    } else {
        format!("{r}")
    }
}

/// A point's label: its τ (and node size) for bounded, else the configuration's name; "≤" the
/// error floor where the error is drawn at it.
fn point_label(s: &Summary) -> String {
    let label = match (s.config.tau_px, s.config.tile_size) {
        (Some(t), None) => format!("τ={t}"),
        (Some(t), Some(m)) => format!("τ={t} m={m}"),
        (None, _) => s.config.label(),
    };
    if s.error_px() < ERROR_FLOOR_PX {
        format!("{label} (≤{ERROR_FLOOR_PX} px)")
    } else {
        label
    }
}

fn colour(mode: LodMode) -> RGBColor {
    match mode {
        LodMode::Bounded => RGBColor(31, 119, 180),
        LodMode::Clipmap => RGBColor(255, 127, 14),
        LodMode::Distance => RGBColor(44, 160, 44),
        LodMode::Full => RGBColor(214, 39, 40),
        LodMode::Cdlod => RGBColor(148, 103, 189),
        LodMode::Tessellation => RGBColor(140, 86, 75),
    }
}

/// Frame time (median, ms) against measured max image error.
pub(crate) fn time_vs_error(path: &Path, summaries: &[Summary]) -> Result<(), String> {
    let ys: Vec<f64> = summaries.iter().map(|s| s.frame_ms.median).collect();
    let top = ys.iter().copied().fold(0.0, f64::max).max(1e-3) * 1.15;
    chart(
        path,
        summaries,
        &ys,
        "median frame time (ms)",
        "frame time against measured max image error",
        0.0..top,
        &|v| format!("{v:.0}"),
    )
}

/// Triangles (median) against measured max image error, log–log.
pub(crate) fn triangles_vs_error(path: &Path, summaries: &[Summary]) -> Result<(), String> {
    let ys: Vec<f64> = summaries
        .iter()
        .map(|s| s.triangles.median.max(1.0))
        .collect();
    let lo = ys.iter().copied().fold(f64::INFINITY, f64::min).min(1e12) / 2.0;
    let hi = ys.iter().copied().fold(1.0, f64::max) * 2.0;
    chart(
        path,
        summaries,
        &ys,
        "median triangles per frame",
        "triangles against measured max image error",
        (lo..hi).log_scale(),
        &|&v| log_tick(v),
    )
}

fn chart<Y>(
    path: &Path,
    summaries: &[Summary],
    ys: &[f64],
    y_desc: &str,
    title: &str,
    y_range: Y,
    y_fmt: &dyn Fn(&f64) -> String,
) -> Result<(), String>
where
    Y: AsRangedCoord<Value = f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    ensure_font()?;
    let err = |e: &dyn std::fmt::Display| format!("{}: cannot draw chart: {e}", path.display());
    let (w, h) = SIZE;
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        // (x, y, summary index) of the configurations with a measured error.
        let pts: Vec<(f64, f64, usize)> = summaries
            .iter()
            .enumerate()
            .filter(|(_, s)| s.error_px().is_finite())
            .map(|(i, s)| (s.error_px().max(ERROR_FLOOR_PX), ys[i], i))
            .collect();
        if pts.is_empty() {
            root.draw(&Text::new(
                "no image error was measured (--no-image-error)",
                (40, 40),
                (FAMILY, 24),
            ))
            .map_err(|e| err(&e))?;
            root.present().map_err(|e| err(&e))?;
        } else {
            let xmin = pts.iter().map(|p| p.0).fold(f64::INFINITY, f64::min) / 2.0;
            let xmax = pts.iter().map(|p| p.0).fold(0.0, f64::max) * 2.0;
            let mut c = ChartBuilder::on(&root)
                .caption(format!("aerie bench: {title}"), (FAMILY, 26))
                .margin(20)
                .x_label_area_size(55)
                .y_label_area_size(80)
                .build_cartesian_2d((xmin..xmax).log_scale(), y_range)
                .map_err(|e| err(&e))?;
            c.configure_mesh()
                .x_desc("measured max image-space error, confirmed by a neighbouring pixel (px, log scale)")
                .y_desc(y_desc)
                .label_style((FAMILY, 16))
                .axis_desc_style((FAMILY, 18))
                .light_line_style(RGBColor(235, 235, 235))
                .x_label_formatter(&|&v| log_tick(v))
                .y_label_formatter(y_fmt)
                .draw()
                .map_err(|e| err(&e))?;
            // The points' labels, placed where they cover no other label or point, in
            // `label_order`'s order.
            let front = pareto_front(&pts.iter().map(|p| (p.0, p.1)).collect::<Vec<_>>());
            let mode_of = |i: usize| summaries[pts[i].2].config.mode;
            let mut efficient = vec![false; pts.len()];
            for mode in MODES {
                let idx: Vec<usize> = (0..pts.len()).filter(|&i| mode_of(i) == mode).collect();
                let own = pareto_front(
                    &idx.iter()
                        .map(|&i| (pts[i].0, pts[i].1))
                        .collect::<Vec<_>>(),
                );
                for (&i, f) in idx.iter().zip(own) {
                    efficient[i] = f;
                }
            }
            let texts: Vec<String> = pts.iter().map(|p| point_label(&summaries[p.2])).collect();
            let font: TextStyle = (FAMILY, LABEL_PX).into();
            let labels: Vec<LabelToPlace> = pts
                .iter()
                .zip(&texts)
                .map(|(p, t)| LabelToPlace {
                    at: c.backend_coord(&(p.0, p.1)),
                    // Padded: the estimate is the glyphs' box, the text drawn a little taller.
                    size: root
                        .estimate_text_size(t, &font)
                        .map_or((8 * t.len() as u32, 15), |(w, h)| (w + 2, h + 5)),
                })
                .collect();
            let bounded: Vec<bool> = (0..pts.len())
                .map(|i| mode_of(i) == LodMode::Bounded)
                .collect();
            let x: Vec<f64> = pts.iter().map(|p| p.0).collect();
            let order = label_order(&front, &efficient, &bounded, &x);
            let (xs, ys) = c.plotting_area().get_pixel_range();
            let placed = place_labels(&labels, &order, (xs.start, ys.start, xs.end, ys.end));
            // Placement by summary index (the series below walk the points mode by mode).
            let mut label_of: Vec<Option<(String, (i32, i32))>> = vec![None; summaries.len()];
            for ((p, t), o) in pts.iter().zip(&texts).zip(&placed) {
                label_of[p.2] = o.map(|o| (t.clone(), o));
            }
            let left_out = placed.iter().filter(|o| o.is_none()).count();
            for mode in MODES {
                let col = colour(mode);
                let mut mine: Vec<&(f64, f64, usize)> = pts
                    .iter()
                    .filter(|p| summaries[p.2].config.mode == mode)
                    .collect();
                if mine.is_empty() {
                    continue;
                }
                mine.sort_by(|a, b| a.0.total_cmp(&b.0));
                // One line per tile size (`--tile-sizes`): the default's thick, others thin.
                let mut sizes: Vec<Option<u32>> = Vec::new();
                for p in &mine {
                    if !sizes.contains(&summaries[p.2].config.tile_size) {
                        sizes.push(summaries[p.2].config.tile_size);
                    }
                }
                for size in sizes {
                    let family: Vec<(f64, f64)> = mine
                        .iter()
                        .filter(|p| summaries[p.2].config.tile_size == size)
                        .map(|p| (p.0, p.1))
                        .collect();
                    if family.len() > 1 {
                        let width = if size.is_none() { 2 } else { 1 };
                        c.draw_series(LineSeries::new(family, col.stroke_width(width)))
                            .map_err(|e| err(&e))?;
                    }
                }
                c.draw_series(mine.iter().map(|p| {
                    let marker =
                        EmptyElement::at((p.0, p.1)) + Circle::new((0, 0), 6, col.filled());
                    let (text, at) = label_of[p.2].clone().unwrap_or_default();
                    marker + Text::new(text, at, (FAMILY, LABEL_PX))
                }))
                .map_err(|e| err(&e))?
                .label(mode_name(mode))
                .legend(move |(x, y)| Circle::new((x + 8, y), 6, col.filled()));
            }
            let mut on: Vec<(f64, f64)> = pts
                .iter()
                .zip(&front)
                .filter(|(_, &f)| f)
                .map(|(p, _)| (p.0, p.1))
                .collect();
            on.sort_by(|a, b| a.0.total_cmp(&b.0));
            c.draw_series(DashedLineSeries::new(
                on.iter().copied(),
                6,
                5,
                BLACK.stroke_width(1),
            ))
            .map_err(|e| err(&e))?;
            c.draw_series(
                on.iter()
                    .map(|&p| Circle::new(p, 11, BLACK.stroke_width(2))),
            )
            .map_err(|e| err(&e))?
            .label("Pareto front")
            .legend(|(x, y)| Circle::new((x + 8, y), 8, BLACK.stroke_width(2)));
            if left_out > 0 {
                let note = format!(
                    "{left_out} of {} labels left out where they would cover another; every point is in summary.csv",
                    pts.len()
                );
                root.draw(&Text::new(
                    note,
                    (xs.start + 6, ys.end - 22),
                    (FAMILY, LABEL_PX),
                ))
                .map_err(|e| err(&e))?;
            }
            c.configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .label_font((FAMILY, 16))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()
                .map_err(|e| err(&e))?;
            root.present().map_err(|e| err(&e))?;
        }
    }
    let rgba: Vec<u8> = rgb
        .chunks_exact(3)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    write_png(path, w, h, &rgba)
}
