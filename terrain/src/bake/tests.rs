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
/// gives (before and after rounding up), with and without AVX2.
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
    let d = ds(300, 260, |c, r| vals[r * 300 + c]);
    for m in [3, 5, 17] {
        let params = BakeParams {
            tile_size: m,
            levels: 0,
        };
        let fast = bake_with(&d, params, &|_, _| {}, true);
        let plain = bake_with(&d, params, &|_, _| {}, false);
        assert_eq!(fast, plain, "m = {m}");
        let q = (m - 1) as usize;
        for t in &fast.levels {
            let l = t.level;
            let side = q << l;
            for ty in 0..t.tiles_y as usize {
                for tx in 0..t.tiles_x as usize {
                    let e = if l == 0 {
                        0.0
                    } else {
                        brute_eps(&d, 1 << l, side, tx, ty)
                    };
                    let i = ty * t.tiles_x as usize + tx;
                    let want = if t.terrain[i] { round_up_f32(e) } else { 0.0 };
                    assert_eq!(t.eps[i].to_bits(), want.to_bits(), "L{l} ({tx},{ty})");
                    // The tile at its parent's resolution: the level-(L+1) surface over it.
                    let Some(parent) = fast.levels.get(l as usize + 1) else {
                        assert!(t.coarse_eps.is_empty());
                        continue;
                    };
                    let e = brute_eps(&d, 2 << l, side, tx, ty);
                    let p = (ty / 2) * parent.tiles_x as usize + tx / 2;
                    let want = if parent.terrain[p] {
                        round_up_f32(e)
                    } else {
                        0.0
                    };
                    let got = t.coarse_eps[i];
                    assert_eq!(
                        got.to_bits(),
                        want.to_bits(),
                        "L{l} ({tx},{ty}) at L{}",
                        l + 1
                    );
                    assert!(got <= parent.eps[p]);
                }
            }
        }
    }
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
