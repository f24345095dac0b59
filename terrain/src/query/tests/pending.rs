//! A source that withholds tiles, as a streamed store does before their pages arrive.

use std::collections::HashSet;

use glam::DVec3;

use super::oracle::{dem_window, source, Rng};
use crate::query::{
    first_hit, height_of_terrain, InMemorySource, Lookup, Ray, SurfaceGrid, SurfaceSource, TileView,
};

/// Every tile of `inner` except `missing`; counts what it was asked for.
struct Withholding {
    inner: InMemorySource,
    missing: HashSet<[u32; 2]>,
    asked: std::cell::RefCell<Vec<[u32; 2]>>,
}

impl SurfaceSource for Withholding {
    fn grid(&self) -> &SurfaceGrid {
        self.inner.grid()
    }
    fn tile_max(&self, level: u32, tx: u32, ty: u32) -> f32 {
        self.inner.tile_max(level, tx, ty)
    }
    fn tile(&self, tx: u32, ty: u32) -> Option<TileView<'_>> {
        self.asked.borrow_mut().push([tx, ty]);
        if self.missing.contains(&[tx, ty]) {
            None
        } else {
            self.inner.tile(tx, ty)
        }
    }
}

#[test]
fn a_withheld_tile_makes_only_the_answers_that_need_it_pending() {
    // 129² samples, 8 × 8 level-0 tiles of 16 quads; tile (3, 4) withheld.
    let full = source(dem_window(500, 200, 129, 129), 17);
    let src = Withholding {
        inner: full.clone(),
        missing: HashSet::from([[3, 4]]),
        asked: Default::default(),
    };
    let g = *full.grid();
    let (sx, sy) = (g.spacing_x, g.spacing_y);
    // The withheld tile's rectangle and its maximum (the bake's, always known).
    let (x0, x1) = (48.0 * sx, 64.0 * sx);
    let (y0, y1) = (64.0 * sy, 80.0 * sy);
    let top = f64::from(full.tile_max(0, 3, 4));

    // Height of terrain: pending inside it (edges of the quads it owns included), ready
    // elsewhere and equal to the full source's.
    let mut rng = Rng(29);
    for _ in 0..200 {
        let (x, y) = (rng.range(x0, x1 - 1e-6), rng.range(y0, y1 - 1e-6));
        assert_eq!(
            height_of_terrain(&src, x, y),
            Lookup::Pending { tile: [3, 4] }
        );
        let (x, y) = (rng.range(0.0, x0 - 1e-6), rng.range(0.0, 128.0 * sy));
        assert_eq!(
            height_of_terrain(&src, x, y),
            height_of_terrain(&full, x, y)
        );
    }

    let (mut pending, mut above, mut before) = (0, 0, 0);
    for _ in 0..400 {
        // Rays from the west half towards the withheld tile and beyond.
        let o = DVec3::new(
            rng.range(0.0, x0),
            rng.range(0.0, 128.0 * sy),
            rng.range(500.0, 3500.0),
        );
        let to = DVec3::new(
            rng.range(x0, 128.0 * sx),
            rng.range(y0, y1),
            rng.range(0.0, 3500.0),
        );
        let r = Ray::segment(o, to).unwrap();
        let want = first_hit(&full, &r);
        src.asked.borrow_mut().clear();
        let got = first_hit(&src, &r);
        let needed = src.asked.borrow().contains(&[3, 4]);
        match got {
            Lookup::Pending { tile } => {
                assert_eq!(tile, [3, 4]);
                pending += 1;
                // Pending only when the full answer lies at or beyond the tile: a hit in
                // front of it would have been found first.
                if let Lookup::Ready(Some(h)) = want {
                    let p = h.point;
                    let in_tile = p.x >= x0 - 1e-6
                        && p.x <= x1 + 1e-6
                        && p.y >= y0 - 1e-6
                        && p.y <= y1 + 1e-6;
                    assert!(in_tile || beyond(&r, h.range_m, (x0, x1, y0, y1)), "{h:?}");
                }
            }
            other => {
                // Ready: exactly the full source's answer, whether or not the ray crossed
                // the tile (it passed above its maximum, or stopped in front of it).
                assert_eq!(other, want);
                if !needed && crosses(&r, (x0, x1, y0, y1)) {
                    match want.ready().flatten() {
                        Some(h) if h.point.x < x0 => before += 1,
                        _ => above += 1,
                    }
                }
            }
        }
    }
    // All three kinds occur: rays that needed the tile, rays that passed above its maximum,
    // and rays stopped before it.
    assert!(
        pending > 20 && above > 20 && before > 20,
        "{pending} {above} {before} (top {top})"
    );
}

/// True when the segment's footprint crosses the rectangle.
fn crosses(r: &Ray, (x0, x1, y0, y1): (f64, f64, f64, f64)) -> bool {
    (0..=1000).any(|i| {
        let p = r.at(r.t_max() * f64::from(i) / 1000.0);
        p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1
    })
}

/// True when the ray reaches the rectangle before range `t`.
fn beyond(r: &Ray, t: f64, rect: (f64, f64, f64, f64)) -> bool {
    let clipped = Ray::new(r.origin(), r.dir(), r.t_min(), t).unwrap();
    crosses(&clipped, rect)
}
