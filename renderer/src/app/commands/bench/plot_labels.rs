//! Where the bench plots put their points' labels. A dense sweep puts a dozen settings of one
//! mode within a few pixels of each other, and labels drawn at one fixed offset pile up into an
//! unreadable block; here each label goes beside its point where it covers no label placed
//! before it and no point's marker, or is left out. Pure: pixel boxes in, placements out.

/// A label to place: its point's pixel position and its text's size in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LabelToPlace {
    pub at: (i32, i32),
    pub size: (u32, u32),
}

/// Half the side of the square a point's marker is kept clear in (the markers are circles of
/// radius 6; the Pareto front's rings, 11, may be crossed: they only circle points).
const MARKER_HALF: i32 = 7;

/// A box in pixels: left, top, right, bottom (right and bottom exclusive).
type PixelBox = (i32, i32, i32, i32);

fn overlaps(a: PixelBox, b: PixelBox) -> bool {
    a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3
}

/// The offsets tried, in order, from a point to its label's top-left corner: above right (the
/// plots' usual place), below right, above left, below left — 9 px to the side, clear of the
/// point's own marker.
fn offsets(size: (u32, u32)) -> [(i32, i32); 4] {
    let (w, h) = (size.0 as i32, size.1 as i32);
    [(9, -3 - h), (9, 3), (-9 - w, -3 - h), (-9 - w, 3)]
}

/// The label's box at `offset` from its point.
fn label_box(l: &LabelToPlace, offset: (i32, i32)) -> PixelBox {
    let (x, y) = (l.at.0 + offset.0, l.at.1 + offset.1);
    (x, y, x + l.size.0 as i32, y + l.size.1 as i32)
}

/// The order labels are placed in (the first the most wanted): the Pareto front's points, then
/// each mode's own efficient settings (the curves the ratios are read off), bounded's before the
/// baselines', then the rest; within each, by error (`x`) ascending. Per point: on the front, on
/// its mode's curve, bounded, and its error.
pub(crate) fn label_order(
    front: &[bool],
    efficient: &[bool],
    bounded: &[bool],
    x: &[f64],
) -> Vec<usize> {
    let rank = |i: usize| (!front[i], !efficient[i], !bounded[i]);
    let mut order: Vec<usize> = (0..x.len()).collect();
    order.sort_by(|&a, &b| rank(a).cmp(&rank(b)).then(x[a].total_cmp(&x[b])));
    order
}

/// Each label's offset from its point (to its text's top-left corner), or `None` where it is
/// left out. Labels are placed in `order` (the first the most wanted: it gets the first of its
/// offsets that is free), each inside `area` (left, top, right, bottom), covering no marker of
/// any point and no label placed before it. Labels not in `order` are left out.
pub(crate) fn place_labels(
    labels: &[LabelToPlace],
    order: &[usize],
    area: (i32, i32, i32, i32),
) -> Vec<Option<(i32, i32)>> {
    let markers: Vec<PixelBox> = labels
        .iter()
        .map(|l| {
            let (x, y) = l.at;
            (
                x - MARKER_HALF,
                y - MARKER_HALF,
                x + MARKER_HALF + 1,
                y + MARKER_HALF + 1,
            )
        })
        .collect();
    let inside = |b: PixelBox| b.0 >= area.0 && b.1 >= area.1 && b.2 <= area.2 && b.3 <= area.3;
    let mut placed: Vec<PixelBox> = Vec::new();
    let mut out = vec![None; labels.len()];
    for &i in order {
        let Some(l) = labels.get(i) else { continue };
        if out[i].is_some() {
            continue;
        }
        let free = offsets(l.size).into_iter().find(|&o| {
            let b = label_box(l, o);
            inside(b)
                && !markers.iter().any(|&m| overlaps(b, m))
                && !placed.iter().any(|&p| overlaps(b, p))
        });
        if let Some(o) = free {
            placed.push(label_box(l, o));
            out[i] = Some(o);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const AREA: (i32, i32, i32, i32) = (0, 0, 1000, 600);

    fn label(x: i32, y: i32) -> LabelToPlace {
        LabelToPlace {
            at: (x, y),
            size: (60, 15),
        }
    }

    #[test]
    fn the_front_then_each_curve_then_bounded_then_by_error() {
        // Points: 0 dominated baseline, 1 front baseline, 2 curve baseline at a smaller
        // error than 3 (curve baseline), 4 curve bounded, 5 front bounded at a larger error
        // than 1, 6 dominated bounded.
        let front = [false, true, false, false, false, true, false];
        let efficient = [false, true, true, true, true, true, false];
        let bounded = [false, false, false, false, true, true, true];
        let x = [0.1, 0.5, 0.2, 0.3, 0.9, 0.7, 0.05];
        assert_eq!(
            label_order(&front, &efficient, &bounded, &x),
            vec![5, 1, 4, 2, 3, 6, 0]
        );
    }

    #[test]
    fn a_lone_label_goes_above_right_of_its_point() {
        let got = place_labels(&[label(500, 300)], &[0], AREA);
        assert_eq!(got, vec![Some((9, -18))]);
    }

    #[test]
    fn a_crowded_label_moves_round_its_point_then_is_left_out() {
        // Five points on one pixel: the first four labels take the four places in turn, the
        // fifth is left out.
        let labels = vec![label(500, 300); 5];
        let got = place_labels(&labels, &[0, 1, 2, 3, 4], AREA);
        assert_eq!(
            got,
            vec![
                Some((9, -18)),
                Some((9, 3)),
                Some((-69, -18)),
                Some((-69, 3)),
                None
            ]
        );
    }

    #[test]
    fn the_order_decides_who_keeps_the_usual_place() {
        let labels = [label(500, 300), label(500, 300)];
        assert_eq!(place_labels(&labels, &[1, 0], AREA)[1], Some((9, -18)));
        assert_eq!(place_labels(&labels, &[1, 0], AREA)[0], Some((9, 3)));
        // Left out of the order: left out of the plot.
        assert_eq!(place_labels(&labels, &[1], AREA)[0], None);
    }

    #[test]
    fn a_label_never_covers_another_point_nor_leaves_the_area() {
        // A point just above right of another: the other's usual place would cover it.
        let labels = [label(500, 300), label(530, 285)];
        let got = place_labels(&labels, &[0, 1], AREA);
        assert_eq!(got[0], Some((9, 3)));
        // At the area's top right corner only the places below left fit.
        let corner = [label(995, 5)];
        assert_eq!(place_labels(&corner, &[0], AREA), vec![Some((-69, 3))]);
    }

    /// A cloud of points: the placed labels never overlap each other, any marker, or the
    /// area's edge, and a label is left out only where all four places are taken.
    #[test]
    fn placed_labels_never_overlap_on_a_random_cloud() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = |m: i32| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % m as u64) as i32
        };
        let labels: Vec<LabelToPlace> = (0..200)
            .map(|_| LabelToPlace {
                at: (next(1000), next(600)),
                size: (20 + next(80) as u32, 15),
            })
            .collect();
        let order: Vec<usize> = (0..labels.len()).collect();
        let got = place_labels(&labels, &order, AREA);
        let boxes: Vec<PixelBox> = got
            .iter()
            .zip(&labels)
            .filter_map(|(o, l)| o.map(|o| label_box(l, o)))
            .collect();
        assert!(
            boxes.len() > 20 && boxes.len() < labels.len(),
            "{}",
            boxes.len()
        );
        for (i, a) in boxes.iter().enumerate() {
            assert!(a.0 >= 0 && a.1 >= 0 && a.2 <= 1000 && a.3 <= 600, "{a:?}");
            for b in &boxes[i + 1..] {
                assert!(!overlaps(*a, *b), "{a:?} {b:?}");
            }
            for l in &labels {
                let m = (l.at.0 - 7, l.at.1 - 7, l.at.0 + 8, l.at.1 + 8);
                assert!(!overlaps(*a, m), "{a:?} covers the marker at {:?}", l.at);
            }
        }
        // Every label left out had no free place: each of its four places is off the area or
        // covers a marker or a placed label.
        for (l, o) in labels.iter().zip(&got) {
            if o.is_none() {
                for off in offsets(l.size) {
                    let b = label_box(l, off);
                    let blocked = !(b.0 >= 0 && b.1 >= 0 && b.2 <= 1000 && b.3 <= 600)
                        || boxes.iter().any(|&p| overlaps(b, p))
                        || labels
                            .iter()
                            .any(|m| overlaps(b, (m.at.0 - 7, m.at.1 - 7, m.at.0 + 8, m.at.1 + 8)));
                    assert!(blocked, "a free place was left: {b:?}");
                }
            }
        }
    }
}
