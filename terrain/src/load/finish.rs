//! The loaders' common tail: decoded samples and their placement become a checked
//! [`Heightfield`], row 0 = south, voids filled.

use std::path::Path;

use crate::Heightfield;

use super::error::{format_err, show, size_err, DemError};
use super::placement::Placement;
use super::sidecar::{implausible_spacing, short};

/// Largest plausible height magnitude, metres (ten times Everest, and the ocean floor).
pub const MAX_HEIGHT_M: f32 = 1e5;

/// Rejects degenerate sizes with a message naming the problem (zero or below 2×2).
pub(crate) fn check_dims(path: &Path, width: usize, height: usize) -> Result<(), DemError> {
    if width == 0 || height == 0 {
        return Err(size_err(
            path,
            format!("zero-size grid ({width}×{height} samples)"),
        ));
    }
    if width < 2 || height < 2 {
        return Err(size_err(
            path,
            format!("grid {width}×{height} is smaller than the 2×2 minimum"),
        ));
    }
    Ok(())
}

/// What a format loader hands over (`samples` row-major in file row order, NaN = void;
/// `north_up` when file row 0 is the northern edge) made usable: flipped to row 0 = south,
/// checked, voids filled. Every loader ends here.
pub(crate) fn finish(
    path: &Path,
    width: usize,
    height: usize,
    mut samples: Vec<f32>,
    north_up: bool,
    place: Placement,
) -> Result<Heightfield, DemError> {
    let Placement {
        spacing_x,
        spacing_y,
        geo,
        spacing_note,
    } = place;
    check_dims(path, width, height)?;
    if width.checked_mul(height) != Some(samples.len()) {
        return Err(size_err(
            path,
            format!("{} samples for a {}×{} grid", samples.len(), width, height),
        ));
    }
    check_spacing(path, spacing_x, spacing_y, &spacing_note)?;
    check_heights(path, &samples, width, 0)?;
    if north_up {
        flip_rows(&mut samples, width);
    }
    let voids = samples.iter().filter(|v| v.is_nan()).count();
    if voids == samples.len() {
        return Err(DemError::AllVoid {
            path: show(path),
            count: voids,
        });
    }
    if voids > 0 {
        fill_voids(&mut samples, width, height, spacing_x, spacing_y);
    }
    Ok(Heightfield {
        width,
        height,
        spacing_x,
        spacing_y,
        heights: samples,
        geo,
        voids_filled: voids,
        spacing_note,
    })
}

/// Every loader names its keys first; this catches what a geo-reference computes (a lat/lon
/// step of 1e300° is finite but not a grid), naming where the spacing came from.
pub(crate) fn check_spacing(
    path: &Path,
    spacing_x: f64,
    spacing_y: f64,
    spacing_note: &str,
) -> Result<(), DemError> {
    if let Some(why) = implausible_spacing(spacing_x).or(implausible_spacing(spacing_y)) {
        return Err(format_err(
            path,
            format!(
                "{why} ({} m × {} m, {spacing_note})",
                short(spacing_x),
                short(spacing_y)
            ),
        ));
    }
    Ok(())
}

/// Refuses an infinite or implausible height among `samples`, rows of `width` in file order
/// starting at file row `first_row`, naming its column and row.
pub(crate) fn check_heights(
    path: &Path,
    samples: &[f32],
    width: usize,
    first_row: usize,
) -> Result<(), DemError> {
    if let Some(i) = samples
        .iter()
        .position(|v| v.is_infinite() || v.abs() > MAX_HEIGHT_M)
    {
        return Err(format_err(
            path,
            format!(
                "height out of range ({} m, plausible within ±{MAX_HEIGHT_M} m) at (col {}, row {}) in file order after scale/offset",
                samples[i],
                i % width,
                first_row + i / width
            ),
        ));
    }
    Ok(())
}

/// Reverses the row order in place.
pub(crate) fn flip_rows(samples: &mut [f32], width: usize) {
    if width == 0 {
        return;
    }
    let height = samples.len() / width;
    for r in 0..height / 2 {
        let (top, bottom) = samples.split_at_mut((height - 1 - r) * width);
        top[r * width..(r + 1) * width].swap_with_slice(&mut bottom[..width]);
    }
}

/// Fills NaN samples in place.
///
/// For each void, the nearest valid sample in each of the four axis directions (±x, ±y) is
/// found and the void gets their inverse-distance weighted mean (distance in metres, weight
/// 1/d) — along a single line this is exact linear interpolation across the gap. A void whose
/// row and column are entirely void gets nothing in the first pass; a second pass then uses
/// the values filled in the first. Every fill is a convex combination of valid samples, so it
/// lies within their min/max. O(samples) per pass, memory O(voids + width).
pub(crate) fn fill_voids(samples: &mut [f32], width: usize, height: usize, sx: f64, sy: f64) {
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for &v in samples.iter().filter(|v| !v.is_nan()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return; // all void: the caller reports it
    }
    let mut voids: Vec<usize> = (0..samples.len())
        .filter(|&i| samples[i].is_nan())
        .collect();
    let mut row_start = vec![0usize; height + 1];
    let mut last_row = vec![usize::MAX; width];
    let mut last_val = vec![0f32; width];
    while !voids.is_empty() {
        // Accumulated (Σw, Σw·v) per void, in the same row-major order as `voids`.
        let mut acc = vec![(0f64, 0f64); voids.len()];
        // row_start[r]..row_start[r+1] are the voids in row r.
        let mut k = 0;
        for (r, start) in row_start.iter_mut().enumerate() {
            while k < voids.len() && voids[k] / width < r {
                k += 1;
            }
            *start = k;
        }
        // Horizontal: nearest valid to the west and to the east.
        for r in 0..height {
            let (a, b) = (row_start[r], row_start[r + 1]);
            if a == b {
                continue;
            }
            let row = &samples[r * width..(r + 1) * width];
            let mut k = a;
            let mut last: Option<(usize, f32)> = None;
            for (c, &v) in row.iter().enumerate() {
                if v.is_nan() {
                    if let Some((lc, lv)) = last {
                        add(&mut acc[k], (c - lc) as f64 * sx, lv);
                    }
                    k += 1;
                } else {
                    last = Some((c, v));
                }
            }
            let mut k = b;
            last = None;
            for (c, &v) in row.iter().enumerate().rev() {
                if v.is_nan() {
                    k -= 1;
                    if let Some((lc, lv)) = last {
                        add(&mut acc[k], (lc - c) as f64 * sx, lv);
                    }
                } else {
                    last = Some((c, v));
                }
            }
        }
        // Vertical: nearest valid below (south-to-north sweep) and above (north-to-south).
        for pass in 0..2 {
            last_row.fill(usize::MAX);
            for i in 0..height {
                let r = if pass == 0 { i } else { height - 1 - i };
                let row = &samples[r * width..(r + 1) * width];
                let mut k = row_start[r];
                for (c, &v) in row.iter().enumerate() {
                    if v.is_nan() {
                        if last_row[c] != usize::MAX {
                            add(
                                &mut acc[k],
                                last_row[c].abs_diff(r) as f64 * sy,
                                last_val[c],
                            );
                        }
                        k += 1;
                    } else {
                        last_row[c] = r;
                        last_val[c] = v;
                    }
                }
            }
        }
        let mut remaining = Vec::new();
        for (&i, &(w, wv)) in voids.iter().zip(&acc) {
            if w > 0.0 {
                samples[i] = ((wv / w) as f32).clamp(lo, hi);
            } else {
                remaining.push(i);
            }
        }
        if remaining.len() == voids.len() {
            // Cannot happen with at least one valid sample; never loop forever regardless.
            for &i in &remaining {
                samples[i] = lo;
            }
            break;
        }
        voids = remaining;
    }
}

#[inline]
fn add(acc: &mut (f64, f64), dist: f64, v: f32) {
    let w = 1.0 / dist;
    acc.0 += w;
    acc.1 += w * v as f64;
}
