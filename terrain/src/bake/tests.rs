use std::path::Path;

use super::exact::bake_with;
use super::*;
use crate::dataset::Dataset;
use crate::mesh::quad_surface;
use crate::Heightfield;

pub(super) fn ds(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Dataset {
    let mut heights = Vec::with_capacity(w * h);
    for r in 0..h {
        for c in 0..w {
            heights.push(f(c, r));
        }
    }
    Dataset::from_heightfield(
        Heightfield {
            width: w,
            height: h,
            spacing_x: 10.0,
            spacing_y: 10.0,
            heights,
            geo: None,
            voids_filled: 0,
            spacing_note: String::new(),
        },
        "test".into(),
    )
}

#[test]
fn planes_have_zero_error_and_a_spike_shows_at_every_level() {
    let d = ds(33, 33, |c, r| 3.0 * c as f32 - 2.0 * r as f32);
    let b = bake(
        &d,
        BakeParams {
            tile_size: 5,
            levels: 0,
        },
        &|_, _| {},
    );
    assert_eq!(b.levels.len(), 4); // 32 = 2^5, m − 1 = 4 = 2^2 → levels 0..=3
    assert!(b.levels.iter().all(|t| t.eps.iter().all(|&e| e == 0.0)));
    // One needle at an odd sample: invisible to every coarse level, error = its height.
    let d = ds(33, 33, |c, r| if (c, r) == (5, 7) { 100.0 } else { 0.0 });
    let b = bake(
        &d,
        BakeParams {
            tile_size: 5,
            levels: 0,
        },
        &|_, _| {},
    );
    assert_eq!(b.eps(0, 1, 1), 0.0);
    assert_eq!(b.eps(1, 0, 0), 100.0);
    assert_eq!(b.eps(2, 0, 0), 100.0);
    assert_eq!(b.eps(3, 0, 0), 100.0);
    assert_eq!(b.eps(1, 1, 1), 0.0);
    assert_eq!(b.bounds(3, 0, 0), (0.0, 100.0));
    assert_eq!(b.eps_refined(3, 0, 0, 2), 100.0);
    assert_eq!(b.eps_refined(3, 0, 0, 3), 0.0);
    assert_eq!(b.eps_refined(3, 0, 0, 9), 0.0);
}

#[test]
fn the_diagonal_matters() {
    // Level-1 cell [2,4]² holds a plane that bends along its SW-NE diagonal: exact for the
    // mesh's diagonal (ε = 0); the other diagonal would give ĥ(3,3) = 0 and ε = 4.
    let f = |c: usize, r: usize| match (c, r) {
        (4, 4) => 8.0,
        (4, 3) | (3, 4) | (3, 3) => 4.0,
        _ => 0.0,
    };
    let b = bake(
        &ds(5, 5, f),
        BakeParams {
            tile_size: 3,
            levels: 2,
        },
        &|_, _| {},
    );
    assert_eq!(b.eps(1, 0, 0), 0.0);
    let g = |c: usize, r: usize| if (c, r) == (3, 3) { 0.0 } else { f(c, r) };
    let b = bake(
        &ds(5, 5, g),
        BakeParams {
            tile_size: 3,
            levels: 2,
        },
        &|_, _| {},
    );
    assert_eq!(b.eps(1, 0, 0), 4.0);
}

/// The bake's fast loops give bit for bit what evaluating `quad_surface` at every sample
/// gives (before and after rounding up), with and without AVX2: every tile's ε, every
/// quadrant's at its parent's resolution and every block's at its grandparent's, on grids
/// padded on both sides (tiles of 3 vertices split a level-L cell between two blocks, tiles
/// of 5 make a block one cell, coarse levels take the loops for cells of ≥ 64 samples).
#[test]
fn kernels_equal_per_sample_quad_surface() {
    let mut seed = 7u64;
    let mut rnd = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 33) as f64 / (1u64 << 31) as f64) as f32
    };
    let vals: Vec<f32> = (0..300 * 260).map(|_| rnd() * 900.0 - 100.0).collect();
    let grids = [
        ds(300, 260, |c, r| vals[r * 300 + c]),
        ds(70, 151, |c, r| {
            vals[r * 300 + c] * 0.25 + (c * r) as f32 * 0.01
        }),
    ];
    let mut blocks = 0;
    for d in &grids {
        for m in [3, 5, 17] {
            let params = BakeParams {
                tile_size: m,
                levels: 0,
            };
            let fast = bake_with(d, params, &|_, _| {}, true);
            let plain = bake_with(d, params, &|_, _| {}, false);
            assert_eq!(fast, plain, "m = {m}");
            blocks += check_against_brute_force(d, &fast);
        }
    }
    assert!(blocks > 50_000, "{blocks} blocks checked");
}

/// Every tile's ε, `coarse_eps` and `fine_eps` in `b` against [`brute_eps`]; a quadrant's ε
/// is the largest of its four blocks', each block's at most its parent's. Returns the number
/// of blocks checked.
fn check_against_brute_force(d: &Dataset, b: &ErrorBake) -> usize {
    let q = (b.params.tile_size - 1) as usize;
    let m = b.params.tile_size;
    let mut blocks = 0;
    // ε of the level-`at` surface over tile (tx, ty) of level `l`, rounded up; 0 under an
    // ancestor at level `at` that is all padding.
    let want = |l: u32, tx: usize, ty: usize, at: u32| -> f32 {
        let anc = b.level(at);
        let k = 1 << (at - l);
        if !anc.terrain[(ty / k) * anc.tiles_x as usize + tx / k] {
            return 0.0;
        }
        round_up_f32(brute_eps(d, 1 << at, q << l, tx, ty))
    };
    for t in &b.levels {
        let l = t.level;
        for ty in 0..t.tiles_y as usize {
            for tx in 0..t.tiles_x as usize {
                let i = ty * t.tiles_x as usize + tx;
                let w = if l == 0 { 0.0 } else { want(l, tx, ty, l) };
                assert_eq!(t.eps[i].to_bits(), w.to_bits(), "m {m} L{l} ({tx},{ty})");
                // The tile at its parent's resolution: the level-(L+1) surface over it.
                let Some(parent) = b.levels.get(l as usize + 1) else {
                    assert!(t.coarse_eps.is_empty() && t.fine_eps.is_empty());
                    continue;
                };
                let got = t.coarse_eps[i];
                let w = want(l, tx, ty, l + 1);
                assert_eq!(
                    got.to_bits(),
                    w.to_bits(),
                    "m {m} L{l} ({tx},{ty}) at L{}",
                    l + 1
                );
                let p = (ty / 2) * parent.tiles_x as usize + tx / 2;
                assert!(got <= parent.eps[p]);
                // At its grandparent's resolution: the level-(L+2) surface over it.
                if b.levels.get(l as usize + 2).is_none() {
                    assert!(t.fine_eps.is_empty());
                    continue;
                }
                let got = t.fine_eps[i];
                let w = want(l, tx, ty, l + 2);
                assert_eq!(
                    got.to_bits(),
                    w.to_bits(),
                    "m {m} L{l} ({tx},{ty}) at L{}",
                    l + 2
                );
                assert!(got <= parent.coarse_eps[p], "m {m} L{l} ({tx},{ty})");
                blocks += 1;
            }
        }
        // Each quadrant of a level-(L+2) tile is the largest of its four blocks, exactly.
        if l >= 1 && (l as usize + 1) < b.levels.len() {
            let f = b.level(l - 1);
            for (i, &c) in t.coarse_eps.iter().enumerate() {
                let (tx, ty) = (i % t.tiles_x as usize, i / t.tiles_x as usize);
                let fx = f.tiles_x as usize;
                let kids = [0, 1, fx, fx + 1].map(|o| f.fine_eps[2 * ty * fx + 2 * tx + o]);
                let most = kids.iter().fold(0f32, |a, &k| a.max(k));
                assert_eq!(c.to_bits(), most.to_bits(), "m {m} L{l} ({tx},{ty})");
            }
        }
    }
    blocks
}

/// max |h − ĥ| over the samples of the `side`-sample tile (tx, ty), edges included, ĥ being
/// the surface of the level whose cells are `s` samples wide, each sample evaluated with
/// `quad_surface` in the cell east and north of it (the last cell at the grid's edge).
fn brute_eps(d: &Dataset, s: usize, side: usize, tx: usize, ty: usize) -> f64 {
    let mut e = 0f64;
    for r in ty * side..=(ty + 1) * side {
        for c in tx * side..=(tx + 1) * side {
            let cx = (c / s).min((d.hf.width - 1) / s - 1);
            let cy = (r / s).min((d.hf.height - 1) / s - 1);
            let h = |c, r| f64::from(d.hf.at(c, r));
            let (c0, r0) = (cx * s, cy * s);
            let surf = quad_surface(
                h(c0, r0),
                h(c0 + s, r0),
                h(c0, r0 + s),
                h(c0 + s, r0 + s),
                (c - c0) as f64 / s as f64,
                (r - r0) as f64 / s as f64,
            );
            e = e.max((h(c, r) - surf).abs());
        }
    }
    e
}

#[test]
fn round_up_never_goes_below() {
    for x in [0.0, 1.0, 0.1, 1e-30, 3.000_000_000_100, 12_345.678_901_234] {
        let f = round_up_f32(x);
        assert!(f64::from(f) >= x);
        assert!(f64::from(f) - x <= f64::from(f) * 1.2e-7 + 1e-45);
    }
}

#[test]
fn params_are_checked() {
    let d = ds(9, 9, |_, _| 0.0);
    assert!(BakeParams {
        tile_size: 16,
        levels: 0
    }
    .resolve_levels(&d)
    .is_err());
    assert!(BakeParams {
        tile_size: 17,
        levels: 0
    }
    .resolve_levels(&d)
    .is_err());
    assert_eq!(
        BakeParams {
            tile_size: 9,
            levels: 0
        }
        .resolve_levels(&d)
        .unwrap(),
        1
    );
    let e = BakeParams {
        tile_size: 3,
        levels: 5,
    }
    .resolve_levels(&d)
    .unwrap_err();
    assert!(e.to_string().contains("only 3 fit"), "{e}");
}

#[test]
fn bake_paths() {
    assert_eq!(
        bake_path_for(Path::new("/d/N47E011.hgt.zip")),
        Path::new("/d/N47E011.hgt.zip.aerie-bake")
    );
    assert_eq!(
        bake_path_for(Path::new("/d/srtm/")),
        Path::new("/d/srtm.aerie-bake")
    );
}
