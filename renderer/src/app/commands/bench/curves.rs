//! Each mode's sweep read as a curve of cost (triangles, frame time) against measured error,
//! and the ratio of two curves at equal error. Pure: numbers in, numbers out.
//!
//! A curve keeps only its efficient settings (no other setting of the mode has both ≤ error and
//! ≤ cost): the baseline "at its best setting" for every error it reaches. Between two settings
//! the cost is interpolated piecewise-linearly in log error and log cost (work falls roughly
//! as a power of the error). Outside the errors a curve measured nothing is read: a reading
//! there is `Below`/`Above`, never an extrapolation.

/// One measured setting: (error px, cost).
pub type CurvePoint = (f64, f64);

/// A mode's efficient settings, error ascending (so cost strictly descending).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Curve {
    pub points: Vec<CurvePoint>,
}

/// A curve read at one error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Reading {
    Value(f64),
    /// Below the curve's smallest measured error (that error given).
    Below(f64),
    /// Above its largest.
    Above(f64),
    /// No usable point.
    Empty,
}

impl Curve {
    /// The curve of `points`: non-finite or non-positive values dropped (a zero error has no
    /// logarithm: such a setting shows no error at all and is left off the curve), then only the
    /// efficient ones kept.
    pub fn new(points: &[CurvePoint]) -> Self {
        let mut p: Vec<CurvePoint> = points
            .iter()
            .copied()
            .filter(|&(e, c)| e.is_finite() && c.is_finite() && e > 0.0 && c > 0.0)
            .collect();
        p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        let mut out: Vec<CurvePoint> = Vec::new();
        for q in p {
            if out.last().is_none_or(|last| q.1 < last.1) {
                out.push(q);
            }
        }
        Self { points: out }
    }

    /// The smallest and largest error measured.
    pub fn range(&self) -> Option<(f64, f64)> {
        Some((self.points.first()?.0, self.points.last()?.0))
    }

    /// The cost at `error`: exact at a point, interpolated between the two around it.
    pub fn at(&self, error: f64) -> Reading {
        let Some((lo, hi)) = self.range() else {
            return Reading::Empty;
        };
        if error < lo {
            return Reading::Below(lo);
        }
        if error > hi {
            return Reading::Above(hi);
        }
        let k = self.points.partition_point(|p| p.0 < error);
        let b = self.points[k];
        if b.0 == error || k == 0 {
            return Reading::Value(b.1);
        }
        let a = self.points[k - 1];
        let t = (error.ln() - a.0.ln()) / (b.0.ln() - a.0.ln());
        Reading::Value((a.1.ln() + t * (b.1.ln() - a.1.ln())).exp())
    }
}

/// Ours over a baseline at equal error.
#[derive(Debug, Clone, PartialEq)]
pub enum Ratio {
    /// The largest ratio over the errors both curves reach (the baseline at the error that
    /// suits it best), and that error.
    Value { ratio: f64, at_error_px: f64 },
    /// No error both curves reach, but one curve lies wholly at smaller errors and its
    /// cheapest setting costs less than the other's dearest ([`bound_across_gap`]): a bound on
    /// the ratio at every error of the gap between the two ranges, `gap_px`.
    Bound {
        /// Ours' cost over the baseline's at the gap's two ends (see `upper`).
        ratio: f64,
        /// `true`: ours lies below and costs less — `ratio` (< 1) is an upper bound. `false`:
        /// the baseline lies below and costs less — `ratio` (> 1) is a lower bound.
        upper: bool,
        gap_px: (f64, f64),
    },
    /// No error both curves reach, and neither is better across the gap; why.
    OutOfRange(String),
}

impl Ratio {
    /// The ratio read at equal error (a bound is not one).
    pub fn value(&self) -> Option<f64> {
        match self {
            Ratio::Value { ratio, .. } => Some(*ratio),
            Ratio::Bound { .. } | Ratio::OutOfRange(_) => None,
        }
    }

    /// The largest the ratio can be: the value, or an upper bound.
    pub fn at_most(&self) -> Option<f64> {
        match self {
            Ratio::Value { ratio, .. } => Some(*ratio),
            Ratio::Bound {
                ratio, upper: true, ..
            } => Some(*ratio),
            _ => None,
        }
    }
}

/// Two curves that share no error, compared across the gap between them. Each mode's cost
/// grows as its error falls (a curve keeps only efficient settings, cost strictly descending
/// in error), so on the gap the curve below costs at most its cheapest setting (the one at its
/// largest error) and the curve above at least its dearest (the one at its smallest error).
/// When the curve below's cheapest costs less than the curve above's dearest, the one below
/// is better at every error of the gap, by at least that factor; otherwise nothing is known.
/// Reading that bound assumes only that the curve above could not reach the gap's smaller
/// errors with fewer triangles than its own dearest setting draws — its knob's trend, not a
/// value read beyond it.
pub fn bound_across_gap(ours: &Curve, base: &Curve) -> Option<Ratio> {
    let (&(olo, olo_cost), &(ohi, ohi_cost)) = (ours.points.first()?, ours.points.last()?);
    let (&(blo, blo_cost), &(bhi, bhi_cost)) = (base.points.first()?, base.points.last()?);
    if ohi < blo && ohi_cost < blo_cost {
        return Some(Ratio::Bound {
            ratio: ohi_cost / blo_cost,
            upper: true,
            gap_px: (ohi, blo),
        });
    }
    if bhi < olo && bhi_cost < olo_cost {
        return Some(Ratio::Bound {
            ratio: olo_cost / bhi_cost,
            upper: false,
            gap_px: (bhi, olo),
        });
    }
    None
}

/// `ours` over `base` at equal error, over the errors both measured. Both costs are
/// piecewise-linear in log–log between their points, so their log-ratio is linear between the
/// union of the points and its largest value is at one of them: the largest over those points
/// in the common range is the largest anywhere in it.
pub fn ratio_at_equal_error(ours: &Curve, base: &Curve) -> Ratio {
    let (Some((olo, ohi)), Some((blo, bhi))) = (ours.range(), base.range()) else {
        return Ratio::OutOfRange("no measured error".into());
    };
    let (lo, hi) = (olo.max(blo), ohi.min(bhi));
    if lo > hi {
        if let Some(bound) = bound_across_gap(ours, base) {
            return bound;
        }
        return Ratio::OutOfRange(format!(
            "out of range (ours {} px, baseline {} px)",
            span(olo, ohi),
            span(blo, bhi)
        ));
    }
    let mut best: Option<(f64, f64)> = None;
    for &(e, _) in ours.points.iter().chain(&base.points) {
        if e < lo || e > hi {
            continue;
        }
        if let (Reading::Value(a), Reading::Value(b)) = (ours.at(e), base.at(e)) {
            let r = a / b;
            if best.is_none_or(|(br, _)| r > br) {
                best = Some((r, e));
            }
        }
    }
    match best {
        Some((ratio, at_error_px)) => Ratio::Value { ratio, at_error_px },
        None => Ratio::OutOfRange("no common error".into()),
    }
}

fn span(lo: f64, hi: f64) -> String {
    let px = |e: f64| {
        if e < 0.1 {
            format!("{e:.2e}")
        } else {
            format!("{e:.2}")
        }
    };
    if lo == hi {
        px(lo)
    } else {
        format!("{}–{}", px(lo), px(hi))
    }
}

/// The curve of a mode with several families of settings (the tile sizes of `--tile-sizes`,
/// each family a curve over the mode's own knob): at every error, the cheapest family that
/// reaches it — the pointwise minimum of the families' readings, where any covers the error.
/// Made of every family's errors and, where the cheapest family changes between two of them,
/// the error where the two cross (both are linear in log–log between consecutive errors), so
/// its own log–log reading is that minimum at every error a family covers. Taking the union
/// of the families' points instead would let a point of one family, above another family's
/// line, raise the curve there, and would draw a line from one family's point to the first
/// point of another that begins further on, below every setting either has between them.
/// Where a family ends and a dearer one goes on, the curve goes on from the last cheap point
/// as one family's curve does past a dominated setting. One family: that family's curve.
pub fn lower_envelope(families: &[Curve]) -> Curve {
    let live: Vec<&Curve> = families.iter().filter(|c| !c.points.is_empty()).collect();
    if live.len() <= 1 {
        return live.first().map(|c| (*c).clone()).unwrap_or_default();
    }
    let mut errors: Vec<f64> = live
        .iter()
        .flat_map(|c| c.points.iter().map(|p| p.0))
        .collect();
    errors.sort_by(f64::total_cmp);
    errors.dedup();
    let value = |k: usize, e: f64| match live[k].at(e) {
        Reading::Value(v) => Some(v),
        _ => None,
    };
    let cheapest = |e: f64| {
        (0..live.len())
            .filter_map(|k| value(k, e).map(|v| (v, k)))
            .min_by(|a, b| a.0.total_cmp(&b.0))
    };
    let mut pts: Vec<CurvePoint> = Vec::new();
    let mut prev: Option<(f64, usize)> = None;
    for &e in &errors {
        let Some((v, k)) = cheapest(e) else {
            prev = None;
            continue;
        };
        if let Some((pe, pk)) = prev.filter(|&(_, pk)| pk != k) {
            // Family pk was the cheaper at pe, k is at e: where both cover [pe, e], the
            // difference of their log costs is linear in log error there and changes sign once.
            if let (Some(a0), Some(a1), Some(b0), Some(b1)) =
                (value(pk, pe), value(pk, e), value(k, pe), value(k, e))
            {
                let (d0, d1) = (a0.ln() - b0.ln(), a1.ln() - b1.ln());
                if d0 < 0.0 && d1 > 0.0 {
                    let t = d0 / (d0 - d1);
                    let at = (pe.ln() + t * (e.ln() - pe.ln())).exp();
                    let cost = (a0.ln() + t * (a1.ln() - a0.ln())).exp();
                    pts.push((at, cost));
                }
            } else if value(k, pe).is_none() {
                // Family k begins at e: up to it only pk reaches these errors, so the curve
                // follows pk to just short of e and drops there, not along a line from pe.
                let before = e * (1.0 - 1e-9);
                if let Some(c) = value(pk, before) {
                    pts.push((before, c));
                }
            }
        }
        pts.push((e, v));
        prev = Some((e, k));
    }
    Curve::new(&pts)
}

/// Geometric mean of the positive finite values; None when there is none.
pub fn geometric_mean(values: &[f64]) -> Option<f64> {
    let v: Vec<f64> = values
        .iter()
        .copied()
        .filter(|x| x.is_finite() && *x > 0.0)
        .collect();
    if v.is_empty() {
        return None;
    }
    Some((v.iter().map(|x| x.ln()).sum::<f64>() / v.len() as f64).exp())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curve_keeps_the_efficient_points_in_error_order() {
        let c = Curve::new(&[
            (4.0, 100.0),
            (1.0, 800.0),
            (2.0, 900.0), // dominated by (1, 800)
            (0.0, 5000.0),
            (f64::NAN, 1.0),
            (8.0, 100.0), // dominated by (4, 100)
            (1.0, 700.0),
        ]);
        assert_eq!(c.points, vec![(1.0, 700.0), (4.0, 100.0)]);
        assert_eq!(c.range(), Some((1.0, 4.0)));
    }

    #[test]
    fn reading_interpolates_log_log_and_never_extrapolates() {
        let c = Curve::new(&[(1.0, 1000.0), (4.0, 10.0)]);
        assert_eq!(c.at(1.0), Reading::Value(1000.0));
        assert_eq!(c.at(4.0), Reading::Value(10.0));
        // Half way in log error: half way in log cost, √(1000·10) = 100.
        let Reading::Value(v) = c.at(2.0) else {
            panic!()
        };
        assert!((v - 100.0).abs() < 1e-9, "{v}");
        assert_eq!(c.at(0.5), Reading::Below(1.0));
        assert_eq!(c.at(5.0), Reading::Above(4.0));
        assert_eq!(Curve::new(&[]).at(1.0), Reading::Empty);
        assert_eq!(Curve::new(&[(2.0, 3.0)]).at(2.0), Reading::Value(3.0));
    }

    #[test]
    fn ratio_is_the_largest_over_the_common_errors() {
        // Ours: cost 100 at 1 px … 10 at 4 px. Base: 400 at 2 px, 40 at 8 px.
        let ours = Curve::new(&[(1.0, 100.0), (4.0, 10.0)]);
        let base = Curve::new(&[(2.0, 400.0), (8.0, 100.0)]);
        // Common range 2..4. At 2: ours √(100·10) ≈ 31.6 over 400 = 0.079; at 4: 10 over
        // base(4) = √(400·100) = 200, 0.05. The larger is at 2 px.
        let Ratio::Value { ratio, at_error_px } = ratio_at_equal_error(&ours, &base) else {
            panic!()
        };
        assert!((ratio - 1000f64.sqrt() / 400.0).abs() < 1e-12, "{ratio}");
        assert_eq!(at_error_px, 2.0);
        let flipped = ratio_at_equal_error(&base, &ours).value().unwrap();
        assert!((flipped - 20.0).abs() < 1e-9, "{flipped}");
        // Disjoint ranges are out of range, saying both.
        let far = Curve::new(&[(10.0, 5.0), (20.0, 1.0)]);
        let r = ratio_at_equal_error(&ours, &far);
        assert!(
            matches!(&r, Ratio::OutOfRange(s) if s.contains("ours 1.00–4.00 px") && s.contains("baseline 10.00–20.00 px")),
            "{r:?}"
        );
        assert_eq!(r.value(), None);
        // A single baseline point inside our range: read exactly there.
        let one = Curve::new(&[(2.0, 50.0)]);
        let Ratio::Value { ratio, at_error_px } = ratio_at_equal_error(&ours, &one) else {
            panic!()
        };
        assert!((ratio - 1000f64.sqrt() / 50.0).abs() < 1e-12 && at_error_px == 2.0);
    }

    #[test]
    fn curves_apart_are_bounded_across_their_gap_only_when_the_lower_one_is_cheaper() {
        // Ours: 0.04 px at 600 … 8 px at 40. Base: 16 px at 300 … 18 px at 20.
        let ours = Curve::new(&[(0.04, 600.0), (2.0, 200.0), (8.0, 40.0)]);
        let base = Curve::new(&[(16.0, 300.0), (18.0, 20.0)]);
        assert_eq!(
            ratio_at_equal_error(&ours, &base),
            Ratio::Bound {
                ratio: 40.0 / 300.0,
                upper: true,
                gap_px: (8.0, 16.0)
            }
        );
        // Swapped, the baseline is the better one: a lower bound above 1.
        let r = ratio_at_equal_error(&base, &ours);
        assert_eq!(
            r,
            Ratio::Bound {
                ratio: 300.0 / 40.0,
                upper: false,
                gap_px: (8.0, 16.0)
            }
        );
        assert_eq!((r.value(), r.at_most()), (None, None));
        // The bound holds on the whole gap for any curves continuing the two trends: ours
        // costs at most 40 there, the baseline at least 300.
        for e in [8.0, 10.0, 12.0, 16.0] {
            let ours_at = 40.0 * (8.0f64 / e).powf(0.5);
            let base_at = 300.0 * (16.0f64 / e).powf(2.0);
            assert!(ours_at / base_at <= 40.0 / 300.0 + 1e-12, "{e}");
        }
        // Apart, but the curve below costs more than the one above: nothing is known.
        let dear = Curve::new(&[(0.04, 6000.0), (8.0, 400.0)]);
        assert!(matches!(
            ratio_at_equal_error(&dear, &base),
            Ratio::OutOfRange(s) if s.contains("out of range")
        ));
        assert_eq!(bound_across_gap(&ours, &Curve::new(&[])), None);
        // Curves that overlap are read, never bounded.
        assert!(matches!(
            ratio_at_equal_error(&ours, &Curve::new(&[(1.0, 500.0), (4.0, 100.0)])),
            Ratio::Value { .. }
        ));
    }

    #[test]
    fn the_envelope_of_families_reads_their_cheapest_at_every_error() {
        // Family a: 1000 at 1 px … 10 at 100 px (cost = 1000 / e). Family b: 200 at 2 px,
        // 100 at 8 px, 60 at 32 px: cheaper than a from 2 px up to where they cross.
        let a = Curve::new(&[(1.0, 1000.0), (10.0, 100.0), (100.0, 10.0)]);
        let b = Curve::new(&[(2.0, 200.0), (8.0, 100.0), (32.0, 60.0)]);
        let env = lower_envelope(&[a.clone(), b.clone()]);
        let read = |c: &Curve, e: f64| match c.at(e) {
            Reading::Value(v) => Some(v),
            _ => None,
        };
        let mut e = 1.0;
        while e <= 100.0 {
            let want = [read(&a, e), read(&b, e)]
                .into_iter()
                .flatten()
                .fold(f64::INFINITY, f64::min);
            let got = read(&env, e).unwrap();
            assert!(
                (got / want - 1.0).abs() < 1e-9,
                "at {e} px: {got} against {want}"
            );
            e *= 1.07;
        }
        // The union of the points reads too much where a point of one family drops another's
        // (a's (10, 100) behind b's (8, 100): the line from 8 to 32 px lies over a's 50 at
        // 20 px) and too little before b begins (the line from a's 1 px to b's 2 px).
        let union = Curve::new(&[a.points.clone(), b.points.clone()].concat());
        let at20 = (read(&union, 20.0).unwrap(), read(&env, 20.0).unwrap());
        assert!(at20.0 > 70.0 && (at20.1 - 50.0).abs() < 1e-6, "{at20:?}");
        let at1_5 = (read(&union, 1.5).unwrap(), read(&env, 1.5).unwrap());
        assert!(
            at1_5.0 < 400.0 && (at1_5.1 - 1000.0 / 1.5).abs() < 1e-6,
            "{at1_5:?}"
        );
        // One family, or one with empty others: that family.
        assert_eq!(lower_envelope(std::slice::from_ref(&a)), a);
        assert_eq!(lower_envelope(&[Curve::default(), b.clone()]), b);
        assert_eq!(lower_envelope(&[]), Curve::default());
    }

    #[test]
    fn geometric_mean_of_the_positive_values() {
        assert_eq!(geometric_mean(&[]), None);
        assert_eq!(geometric_mean(&[f64::NAN, 0.0]), None);
        let g = geometric_mean(&[0.25, 4.0, 1.0, f64::NAN]).unwrap();
        assert!((g - 1.0).abs() < 1e-12);
        let g = geometric_mean(&[2.0, 8.0]).unwrap();
        assert!((g - 4.0).abs() < 1e-12);
    }
}
