use super::*;

/// A layer of k = 2 over a 1000 × 800-sample grid (4 levels), windows of 4 × 4 cells.
fn clipmap() -> ImageryClipmap {
    let k = 2;
    let extents = (0..4)
        .map(|l| {
            (
                (1000 * k as usize).div_ceil(1 << l),
                (800 * k as usize).div_ceil(1 << l),
            )
        })
        .collect();
    ImageryClipmap::new(ImageryClipmapDesc {
        texels_per_sample: k,
        side: 4 * CELL,
        extents,
    })
    .unwrap()
}

fn fill_all(c: &mut ImageryClipmap, eye: [f64; 2]) -> Vec<CellFill> {
    let w = c.wanted(eye);
    for f in &w {
        c.filled(f);
    }
    w
}

#[test]
fn a_first_placement_wants_every_cell_coarse_levels_first_then_nearest() {
    let mut c = clipmap();
    let eye = [500.0, 400.0];
    c.place(eye);
    let w = c.wanted(eye);
    assert_eq!(w.len(), 4 * 16, "every cell of every level");
    let levels: Vec<u32> = w.iter().map(|f| f.level).collect();
    assert!(
        levels.windows(2).all(|p| p[0] >= p[1]),
        "coarse first: {levels:?}"
    );
    // Within a level, nearer cells first; the first is one of the four around the eye's texel.
    let l0: Vec<&CellFill> = w.iter().filter(|f| f.level == 0).collect();
    let t = (500.0 + 0.5) * 2.0 - 0.5; // level-0 texel of the eye, both axes ≈ 1000.5, 800.5
    let d = |f: &CellFill, a: usize, e: f64| f.cell[a] as f64 * 64.0 + 32.0 - e;
    let dist = |f: &CellFill| d(f, 0, t).hypot(d(f, 1, (400.0 + 0.5) * 2.0 - 0.5));
    assert!(l0.windows(2).all(|p| dist(p[0]) <= dist(p[1])));
    assert!(dist(l0[0]) < 64.0 * 2f64.sqrt());
    for level in 0..4 {
        assert_eq!(c.region(level), None, "nothing is filled yet");
    }
}

#[test]
fn a_cell_holds_the_texels_of_its_samples_in_its_toroidal_slot() {
    let mut c = clipmap();
    let eye = [500.0, 400.0];
    c.place(eye);
    for f in c.wanted(eye) {
        let k = 2;
        let step = 1i64 << f.level;
        // The rect's texels are [s·k, (s + n)·k) of the level, s = origin >> level: the cell.
        assert_eq!(f.rect.level, f.level);
        for a in 0..2 {
            assert_eq!(f.rect.origin[a] % step, 0);
            assert_eq!((f.rect.origin[a] >> f.level) * k, f.cell[a] * 64);
            assert_eq!(f.rect.size[a] as i64 * k, 64);
            assert_eq!(f.texel[a] as i64, f.cell[a].rem_euclid(4) * 64);
        }
    }
}

#[test]
fn filling_every_cell_makes_the_window_a_region_and_a_move_rewrites_only_what_it_uncovers() {
    let mut c = clipmap();
    let eye = [500.0, 400.0];
    c.place(eye);
    fill_all(&mut c, eye);
    let before: Vec<_> = (0..4).map(|l| c.region(l)).collect();
    for (l, r) in before.iter().enumerate() {
        let (origin, side) = r.expect("filled");
        assert_eq!(side, 256);
        assert_eq!(origin, c.window_origin(l as u32, eye).map(|o| o * 64));
        // The window is centred on the eye's texel within a cell.
        let t = ((500.0 + 0.5) * 2.0 / f64::from(1u32 << l) - 0.5) as i64;
        assert!(
            (origin[0] + 128 - t).abs() <= 32,
            "level {l}: {origin:?} around {t}"
        );
    }
    // One cell east at level 0 (32 samples = 64 texels): level 0's window moves one column;
    // level 1 by half a cell, level 2 and 3 less — they may not move at all.
    let moved = [532.0, 400.0];
    c.place(moved);
    let w = c.wanted(moved);
    let l0: Vec<&CellFill> = w.iter().filter(|f| f.level == 0).collect();
    assert_eq!(l0.len(), 4, "one new column of level 0");
    let new_col = c.window_origin(0, moved)[0] + 3;
    assert!(l0.iter().all(|f| f.cell[0] == new_col));
    // Its slots are those of the column that left (toroidal reuse).
    let left_col = c.window_origin(0, eye)[0];
    assert!(l0
        .iter()
        .all(|f| f.texel[0] as i64 == left_col.rem_euclid(4) * 64));
    assert_eq!(c.region(0), None, "level 0 waits for its new column");
    for l in 1..4 {
        let moved_l = c.window_origin(l, moved) != c.window_origin(l, eye);
        assert_eq!(c.region(l).is_none(), moved_l, "level {l}");
    }
    fill_all(&mut c, moved);
    assert_eq!(
        c.region(0).unwrap().0,
        c.window_origin(0, moved).map(|o| o * 64)
    );
}

#[test]
fn a_fill_for_a_cell_the_window_has_left_is_ignored() {
    let mut c = clipmap();
    let eye = [500.0, 400.0];
    c.place(eye);
    let stale: Vec<CellFill> = c.wanted(eye).into_iter().filter(|f| f.level == 0).collect();
    // Far away: every level-0 slot now holds another cell.
    let far = [900.0, 700.0];
    c.place(far);
    for f in &stale {
        c.filled(f);
    }
    let still = c.wanted(far).iter().filter(|f| f.level == 0).count();
    assert_eq!(
        still, 16,
        "the old cells' uploads fill none of the new ones"
    );
}

#[test]
fn cells_outside_the_raster_are_empty_and_still_clear_their_slot() {
    let mut c = clipmap();
    // At the grid's south-west corner, half of level 0's window lies west and south of it.
    let eye = [0.0, 0.0];
    c.place(eye);
    let w = c.wanted(eye);
    let l0: Vec<&CellFill> = w.iter().filter(|f| f.level == 0).collect();
    let empty = l0.iter().filter(|f| f.empty).count();
    assert!(empty > 0 && empty < 16, "{empty} of 16 cells outside");
    for f in &l0 {
        let outside = f.cell[0] < 0 || f.cell[1] < 0;
        assert_eq!(f.empty, outside, "{f:?}");
    }
    // At the far corner the east and north edges are outside too (extent 2000 × 1600 texels).
    let far = [1000.0, 800.0];
    c.place(far);
    for f in c.wanted(far).iter().filter(|f| f.level == 0) {
        let outside = f.cell[0] * 64 >= 2000 || f.cell[1] * 64 >= 1600;
        assert_eq!(f.empty, outside, "{f:?}");
    }
}

#[test]
fn a_bad_shape_is_refused_naming_it() {
    let bad = |k, side| {
        ImageryClipmap::new(ImageryClipmapDesc {
            texels_per_sample: k,
            side,
            extents: vec![(10, 10)],
        })
        .unwrap_err()
    };
    assert!(bad(3, 256).contains("3 texels per sample"));
    assert!(bad(2, 100).contains("window of 100 texels"));
    assert!(bad(2, 0).contains("window of 0 texels"));
}

/// Per level, the raster of a `w × h`-sample grid at k texels per sample (`level_extent`).
fn extents(w: usize, h: usize, k: usize, levels: u32) -> Vec<(usize, usize)> {
    (0..levels)
        .map(|l| ((w * k).div_ceil(1 << l), (h * k).div_ceil(1 << l)))
        .collect()
}

#[test]
fn a_budget_draws_level_0_whole_or_a_coarse_level_whole_and_streams_the_finer_ones() {
    let e = extents(16385, 16385, 2, 8);
    let mib = 1u64 << 20;
    // 64 MiB: level 0 (32770² · 16/3 B) is far over; of a quarter (16 MiB) level 4 (2049²,
    // 22.4 MB) is over too, so level 5 (1025², 5.6 MB) is the base; three quarters over 5
    // layers of 4 bytes a texel: 1,586² → 1,536 (24 cells).
    let p = plan_imagery_stream(&e, 2, 64 * mib, 8192).unwrap();
    assert_eq!(p.base, 5);
    let w = p.windows.clone().unwrap();
    assert_eq!((w.side, w.levels(), w.texels_per_sample), (1536, 5, 2));
    assert_eq!(w.extents, e[..5].to_vec());
    let stream_bytes = u64::from(w.side).pow(2) * 4 * u64::from(w.levels());
    let base_bytes = (e[5].0 * e[5].1) as f64 * 16.0 / 3.0;
    assert!(
        stream_bytes as f64 + base_bytes <= (64 * mib) as f64,
        "{p:?}"
    );
    // Level 0 fits whole: nothing streamed (today's path).
    let small = extents(1201, 1201, 2, 6);
    let p = plan_imagery_stream(&small, 2, 64 * mib, 8192).unwrap();
    assert_eq!(
        p,
        ImageryStreamPlan {
            base: 0,
            windows: None
        }
    );
    // The device's texture side caps the whole level like the budget does.
    let p = plan_imagery_stream(&small, 2, 64 * mib, 1024).unwrap();
    assert_eq!(p.base, 2, "{p:?}");
    assert_eq!(p.windows.unwrap().side, 1024);
    // Windows too small to stream: the finest level within the whole budget, as before.
    let p = plan_imagery_stream(&small, 2, 100_000, 8192).unwrap();
    assert_eq!(p.windows, None);
    assert_eq!(p.base, 5, "{p:?}");
    // Nothing fits: None.
    assert_eq!(plan_imagery_stream(&small, 2, 100, 8192), None);
    // Over shapes and budgets: the plan stays within its budget, a window within what level 0
    // needs (plus a cell for the snapping), and it streams exactly when level 0 is not whole.
    for (w, h, k) in [(300, 200, 1), (1000, 40, 2), (4097, 4097, 4), (150, 130, 2)] {
        let e = extents(w, h, k, 6);
        for budget in [50_000u64, 300_000, 2_000_000, 40_000_000, 400_000_000] {
            let Some(p) = plan_imagery_stream(&e, k as u32, budget, 8192) else {
                continue;
            };
            let base = e[p.base as usize];
            let mut bytes = (base.0 * base.1) as f64 * 16.0 / 3.0;
            if let Some(win) = &p.windows {
                assert!(p.base > 0 && win.levels() == p.base, "{p:?}");
                assert!(
                    win.side as usize <= e[0].0.max(e[0].1) + 2 * CELL as usize,
                    "{p:?}"
                );
                assert!(win.side.is_multiple_of(CELL) && win.side >= MIN_STREAM_SIDE);
                bytes += (u64::from(win.side).pow(2) * 4 * u64::from(win.levels())) as f64;
            }
            assert!(bytes <= budget as f64, "{w}×{h} k {k} in {budget}: {p:?}");
            let level0 = (e[0].0 * e[0].1) as f64 * 16.0 / 3.0 <= budget as f64;
            assert_eq!(p.base == 0, level0, "{w}×{h} k {k} in {budget}: {p:?}");
        }
    }
}
