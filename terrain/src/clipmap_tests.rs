#![allow(clippy::needless_range_loop)]

use super::*;
use proptest::prelude::*;

fn desc(q: u32, p: u32, m: u32, w: u32, h: u32) -> ClipmapDesc {
    ClipmapDesc {
        tile_quads: q,
        patch_tiles: p,
        margin_tiles: m,
        width: w,
        height: h,
    }
}

/// The definition of the brief, computed independently: smallest NL whose coarsest level's
/// vertex grid (⌈(W−1)/2^(NL−1)⌉ + 1 per axis) fits in (P + 2·margin)·q texels.
fn level_count_by_definition(q: u64, p: u64, m: u64, w: u64, h: u64) -> u32 {
    let side = (p + 2 * m) * q;
    (1..64u32)
        .find(|&nl| {
            let step = 1u64 << (nl - 1);
            (w - 1).div_ceil(step) < side && (h - 1).div_ceil(step) < side
        })
        .unwrap()
}

#[test]
fn level_count_matches_definition_for_real_sizes() {
    for (n, expected) in [(1201, 4), (4097, 6), (16385, 8)] {
        let d = desc(16, 8, 2, n, n);
        assert_eq!(d.texture_side(), 192);
        assert_eq!(
            d.level_count(),
            level_count_by_definition(16, 8, 2, n as u64, n as u64),
            "{n}²"
        );
        assert_eq!(d.level_count(), expected, "{n}²");
    }
    // Non-square: the larger axis decides.
    let d = desc(16, 8, 2, 2401, 3601);
    assert_eq!(
        d.level_count(),
        level_count_by_definition(16, 8, 2, 2401, 3601)
    );
    // A dataset that already fits one texture has a single, whole-dataset level.
    let d = desc(16, 8, 2, 100, 150);
    assert_eq!(d.level_count(), 1);
    let levels = place_levels(&d, [50.0, 50.0]);
    assert_eq!(levels.len(), 1);
    assert!(levels[0].is_coarsest);
}

#[test]
fn validate_rejects_bad_sizes() {
    assert_eq!(desc(16, 8, 2, 10, 10).validate(), Ok(()));
    assert_eq!(
        desc(12, 8, 2, 10, 10).validate(),
        Err(ClipmapDescError::TileQuads(12))
    );
    assert_eq!(
        desc(16, 6, 2, 10, 10).validate(),
        Err(ClipmapDescError::PatchTiles(6))
    );
    assert_eq!(
        desc(16, 9, 2, 10, 10).validate(),
        Err(ClipmapDescError::PatchTiles(9))
    );
    assert_eq!(
        desc(16, 8, 1, 10, 10).validate(),
        Err(ClipmapDescError::MarginTiles(1))
    );
    assert_eq!(
        desc(16, 8, 2, 1, 10).validate(),
        Err(ClipmapDescError::Dataset(1, 10))
    );
}

#[test]
fn finest_ring_is_the_whole_patch_inside_the_dataset() {
    let d = desc(16, 8, 2, 4097, 4097);
    let levels = place_levels(&d, [2000.0, 2000.0]);
    let mut out = Vec::new();
    ring_tiles(&d, &levels[0], None, &mut out);
    assert_eq!(out.len(), 64);
    // Centred: the viewer (tile 125 of 16 samples) is within one tile of the centre.
    let centre = levels[0].patch_origin[0] as f64 + 4.0;
    assert!((centre - 2000.0 / 16.0).abs() <= 1.0);
    // A middle level's ring: 8×8 minus the 4×4 hole.
    ring_tiles(&d, &levels[1], Some(&levels[0]), &mut out);
    assert_eq!(out.len(), 64 - 16);
}

#[test]
fn non_finite_viewer_does_not_panic_and_still_nests() {
    let d = desc(16, 8, 2, 16385, 16385);
    for v in [
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::MAX,
        f64::MIN,
    ] {
        let levels = place_levels(&d, [v, -v]);
        check_nesting(&d, &levels);
        let mut out = Vec::new();
        for l in 0..levels.len() {
            ring_tiles(
                &d,
                &levels[l],
                l.checked_sub(1).map(|f| &levels[f]),
                &mut out,
            );
        }
    }
}

#[test]
fn update_cache_first_fill_strips_jumps_and_coarsest() {
    let d = desc(16, 8, 2, 16385, 16385);
    let side = d.texture_side(); // 192
    let place = |o: [i64; 2]| LevelPlacement {
        level: 0,
        patch_origin: o,
        patch_tiles: 8,
        is_coarsest: false,
    };
    // First fill: the whole region, margin of 2 tiles before the patch.
    let (r0, up) = update_cache(&d, None, &place([10, 20]));
    assert_eq!(r0.origin, [160 - 32, 320 - 32]);
    assert_eq!(up, vec![whole(&r0)]);
    // Moving 2 tiles west stays inside the margin: nothing to upload.
    let (r1, up) = update_cache(&d, Some(&r0), &place([8, 20]));
    assert_eq!(r1, r0);
    assert!(up.is_empty());
    // Moving 2 tiles east leaves the region on x only: one vertical strip 2 tiles wide.
    let (r2, up) = update_cache(&d, Some(&r0), &place([12, 20]));
    assert_eq!(r2.origin, [192 - 32, r0.origin[1]]);
    assert_eq!(
        up,
        vec![VertexRect {
            origin: [r0.origin[0] + side as i64, r0.origin[1]],
            size: [32, side]
        }]
    );
    // Diagonal: one vertical band over the full height, one horizontal band beside it.
    let (r3, up) = update_cache(&d, Some(&r0), &place([12, 22]));
    assert_eq!(up.len(), 2);
    assert_eq!(up[0].size, [32, side]);
    assert_eq!(up[1].size, [side - 32, 32]);
    assert_eq!(r3.origin, [160, 352 - 32]);
    // A jump beyond the region re-uploads everything.
    let (r4, up) = update_cache(&d, Some(&r0), &place([100, 20]));
    assert_eq!(up, vec![whole(&r4)]);
    // The coarsest level: filled once, never again.
    let coarsest = place_levels(&d, [0.0, 0.0]).pop().unwrap();
    let (c0, up) = update_cache(&d, None, &coarsest);
    assert_eq!(c0.origin, [0, 0]);
    assert_eq!(up.len(), 1);
    let (c1, up) = update_cache(&d, Some(&c0), &coarsest);
    assert_eq!(c1, c0);
    assert!(up.is_empty());
}

#[test]
fn toroidal_pieces_split_at_the_wrap() {
    let rect = VertexRect {
        origin: [-3, 10],
        size: [8, 4],
    };
    let pieces = toroidal_pieces(&rect, 16);
    assert_eq!(
        pieces,
        vec![
            TexturePiece {
                src_offset: [0, 0],
                texel: [13, 10],
                size: [3, 4]
            },
            TexturePiece {
                src_offset: [3, 0],
                texel: [0, 10],
                size: [5, 4]
            },
        ]
    );
    assert!(toroidal_pieces(
        &VertexRect {
            origin: [5, 5],
            size: [0, 7]
        },
        16
    )
    .is_empty());
}

/// Nesting invariants of one placement (shared by the property tests).
fn check_nesting(d: &ClipmapDesc, levels: &[LevelPlacement]) {
    let count = d.level_count() as usize;
    assert_eq!(levels.len(), count);
    for (i, l) in levels.iter().enumerate() {
        assert_eq!(l.level as usize, i);
        assert_eq!(l.is_coarsest, i + 1 == count);
    }
    let coarsest = levels.last().unwrap();
    assert_eq!(coarsest.patch_origin, [0, 0]);
    // The coarsest patch covers the dataset and its tiles' vertices fit one texture.
    let t = d.tile_samples(coarsest.level);
    let covered = coarsest.patch_tiles as u64 * t;
    assert!(covered >= (d.width - 1) as u64 && covered >= (d.height - 1) as u64);
    for n in d.dataset_tiles(coarsest.level) {
        assert!(n * d.tile_quads < d.texture_side());
    }
    for l in &levels[..count - 1] {
        assert_eq!(l.patch_tiles, d.patch_tiles);
        assert!(l.patch_origin.iter().all(|o| o % 2 == 0), "{l:?}");
    }
    for pair in levels.windows(2) {
        let (fine, coarse) = (&pair[0], &pair[1]);
        // The finer patch in coarse tiles.
        let lo = fine.patch_origin.map(|o| o / 2);
        let hi = lo.map(|o| o + fine.patch_tiles as i64 / 2);
        if coarse.is_coarsest {
            // Its footprint, clipped to the dataset, lies inside the coarsest grid.
            let n = d.dataset_tiles(coarse.level);
            for a in 0..2 {
                let (clo, chi) = (lo[a].max(0), hi[a].min(n[a] as i64));
                assert!(clo >= chi || (clo >= 0 && chi <= coarse.patch_tiles as i64));
            }
        } else {
            for a in 0..2 {
                assert!(
                    lo[a] > coarse.patch_origin[a], // ≥ 1 whole tile of margin
                    "{fine:?} in {coarse:?}"
                );
                assert!(
                    hi[a] < coarse.patch_origin[a] + coarse.patch_tiles as i64,
                    "{fine:?} in {coarse:?}"
                );
            }
        }
    }
}

fn desc_strategy(max_side: u32) -> impl Strategy<Value = ClipmapDesc> {
    (
        prop::sample::select(vec![1u32, 2, 4, 8, 16]),
        prop::sample::select(vec![8u32, 10, 12, 16]),
        prop::sample::select(vec![2u32, 4]),
        2..=max_side,
        2..=max_side,
    )
        .prop_map(|(q, p, m, w, h)| desc(q, p, m, w, h))
}

/// Viewer coordinates: inside, on the edges, just outside, far outside and absurd.
fn coord(extent: u32) -> impl Strategy<Value = f64> {
    let e = extent as f64;
    prop_oneof![
        4 => -0.5 * e..1.5 * e,
        1 => prop::sample::select(vec![0.0, e - 1.0, e, -1e-9, e - 1.0 + 1e-9]),
        1 => -1e9..1e9f64,
        1 => prop::sample::select(vec![1e15, -1e15, 1e300, -1e300, f64::MAX, -f64::MAX]),
    ]
}

fn desc_and_viewer(max_side: u32) -> impl Strategy<Value = (ClipmapDesc, [f64; 2])> {
    desc_strategy(max_side).prop_flat_map(|d| {
        let (w, h) = (d.width, d.height);
        (Just(d), coord(w), coord(h)).prop_map(|(d, x, y)| (d, [x, y]))
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn levels_nest_snap_and_centre((d, viewer) in desc_and_viewer(40_000)) {
        let levels = place_levels(&d, viewer);
        check_nesting(&d, &levels);
        // Centred within one level-L tile, hence within one level-(L+1) tile.
        if viewer.iter().all(|v| v.abs() <= VIEWER_LIMIT) {
            for l in &levels[..levels.len() - 1] {
                let t = d.tile_samples(l.level) as f64;
                for a in 0..2 {
                    let centre = (l.patch_origin[a] as f64 + l.patch_tiles as f64 / 2.0) * t;
                    prop_assert!((centre - viewer[a]).abs() <= t * (1.0 + 1e-9),
                        "level {} axis {a}: centre {centre} viewer {}", l.level, viewer[a]);
                }
            }
        }
    }

    #[test]
    fn level_count_is_minimal(d in desc_strategy(70_000)) {
        let nl = d.level_count();
        let side = d.texture_side();
        let fits = |level: u32| d.dataset_tiles(level).iter().all(|&n| n * d.tile_quads < side);
        prop_assert!(fits(nl - 1));
        prop_assert!(nl == 1 || !fits(nl - 2));
        // Never fewer levels than the literal definition (equal for 2^K + 1 datasets).
        let lit = level_count_by_definition(
            d.tile_quads as u64, d.patch_tiles as u64, d.margin_tiles as u64,
            d.width as u64, d.height as u64);
        prop_assert!(nl >= lit);
        let k = 32 - (d.width.max(d.height) - 1).leading_zeros();
        let padded = desc(d.tile_quads, d.patch_tiles, d.margin_tiles, (1 << k) + 1, (1 << k) + 1);
        prop_assert_eq!(padded.level_count(), level_count_by_definition(
            d.tile_quads as u64, d.patch_tiles as u64, d.margin_tiles as u64,
            (1 << k) + 1, (1 << k) + 1));
    }

    #[test]
    fn rings_cover_the_dataset_exactly_once(
        (d, viewer) in desc_strategy(400)
            .prop_filter("cells", |d| d.tile_quads <= 4)
            .prop_flat_map(|d| {
                let (w, h) = (d.width, d.height);
                (Just(d), coord(w), coord(h)).prop_map(|(d, x, y)| (d, [x, y]))
            })
    ) {
        let levels = place_levels(&d, viewer);
        let (w, h) = ((d.width - 1) as i64, (d.height - 1) as i64);
        let mut count = vec![0u8; (w * h) as usize];
        let mut tiles = Vec::new();
        for (i, l) in levels.iter().enumerate() {
            let finer = if i == 0 { None } else { Some(&levels[i - 1]) };
            ring_tiles(&d, l, finer, &mut tiles);
            let t = d.tile_samples(l.level) as i64;
            for &[tx, ty] in &tiles {
                let (x0, y0) = (tx as i64 * t, ty as i64 * t);
                // Every returned tile overlaps the dataset.
                prop_assert!(x0 < w && y0 < h, "tile {tx},{ty} of level {} outside", l.level);
                for y in y0..(y0 + t).min(h) {
                    for x in x0..(x0 + t).min(w) {
                        count[(y * w + x) as usize] += 1;
                    }
                }
            }
        }
        if let Some(i) = count.iter().position(|&c| c != 1) {
            prop_assert!(false, "cell ({}, {}) covered {} times", i as i64 % w, i as i64 / w, count[i]);
        }
    }

    #[test]
    fn toroidal_pieces_cover_rect_once(
        side in 1u32..40,
        ox in -1_000_000i64..1_000_000,
        oy in prop::sample::select(vec![i64::MIN / 4, -17, 0, 3, 1 << 40]),
        fw in 0.0..=1.0f64,
        fh in 0.0..=1.0f64,
    ) {
        let size = [(fw * side as f64) as u32, (fh * side as f64) as u32];
        let rect = VertexRect { origin: [ox, oy], size };
        let pieces = toroidal_pieces(&rect, side);
        prop_assert!(pieces.len() <= 4);
        let mut seen = vec![0u8; (side * side) as usize];
        for p in &pieces {
            prop_assert!(p.size[0] > 0 && p.size[1] > 0);
            for a in 0..2 {
                prop_assert!(p.texel[a] + p.size[a] <= side, "wraps: {p:?}");
                prop_assert!(p.src_offset[a] + p.size[a] <= size[a], "outside rect: {p:?}");
            }
            for dy in 0..p.size[1] {
                for dx in 0..p.size[0] {
                    let texel = [p.texel[0] + dx, p.texel[1] + dy];
                    let vertex = [
                        ox + (p.src_offset[0] + dx) as i64,
                        oy + (p.src_offset[1] + dy) as i64,
                    ];
                    prop_assert_eq!(toroidal_texel(vertex, side), texel);
                    seen[(texel[1] * side + texel[0]) as usize] += 1;
                }
            }
        }
        // Each texel at most once, and as many as the rect has vertices: exactly once.
        prop_assert!(seen.iter().all(|&c| c <= 1));
        let total: u64 = seen.iter().map(|&c| c as u64).sum();
        prop_assert_eq!(total, size[0] as u64 * size[1] as u64);
    }

    #[test]
    fn toroidal_texel_round_trips(
        side in 1u32..5000,
        origin in -(1i64 << 50)..(1i64 << 50),
        du in 0.0..1.0f64,
        dv in 0.0..1.0f64,
    ) {
        // Any vertex of a region [origin, origin + side) is recovered from its texel.
        let v = [origin + (du * side as f64) as i64, origin - 7 + (dv * side as f64) as i64];
        let region = [origin, origin - 7];
        let t = toroidal_texel(v, side);
        for a in 0..2 {
            prop_assert!(t[a] < side);
            let base = toroidal_texel([region[a], 0], side)[0] as i64;
            let back = region[a] + (t[a] as i64 - base).rem_euclid(side as i64);
            prop_assert_eq!(back, v[a]);
        }
    }
}

/// One level texture simulated texel by texel: which vertex each texel holds.
struct SimTexture {
    side: u32,
    texels: Vec<Option<[i64; 2]>>,
}

impl SimTexture {
    fn apply(&mut self, rect: &VertexRect) {
        for p in toroidal_pieces(rect, self.side) {
            for dy in 0..p.size[1] {
                for dx in 0..p.size[0] {
                    let t = ((p.texel[1] + dy) * self.side + p.texel[0] + dx) as usize;
                    self.texels[t] = Some([
                        rect.origin[0] + (p.src_offset[0] + dx) as i64,
                        rect.origin[1] + (p.src_offset[1] + dy) as i64,
                    ]);
                }
            }
        }
    }
}

fn contains(region: &CacheRegion, v: [i64; 2]) -> bool {
    (0..2).all(|a| v[a] >= region.origin[a] && v[a] < region.origin[a] + region.side as i64)
}

fn flight_strategy() -> impl Strategy<Value = (ClipmapDesc, [f64; 2], Vec<[f64; 2]>)> {
    (
        prop::sample::select(vec![2u32, 4]),
        prop::sample::select(vec![8u32, 12]),
        prop::sample::select(vec![2u32, 4]),
        50u32..700,
        50u32..700,
    )
        .prop_flat_map(|(q, p, m, w, h)| {
            let d = desc(q, p, m, w, h);
            let step = q as f64; // at most one level-0 tile per frame
            (
                Just(d),
                (-(w as f64)..2.0 * w as f64, -(h as f64)..2.0 * h as f64),
                prop::collection::vec((-step..=step, -step..=step), 1..40),
            )
                .prop_map(|(d, (x, y), steps)| {
                    (d, [x, y], steps.into_iter().map(|(a, b)| [a, b]).collect())
                })
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    /// A flight of small steps: every level's texture, updated only through the uploaded
    /// rects, holds exactly the vertices of its new region; only strips are uploaded, exactly
    /// the part of the new region the old one did not hold; levels that did not move and the
    /// coarsest level upload nothing.
    #[test]
    fn flight_uploads_exactly_the_exposed_strips((d, start, steps) in flight_strategy()) {
        let side = d.texture_side();
        let q = d.tile_quads as i64;
        let mut viewer = start;
        let mut state: Vec<(LevelPlacement, CacheRegion, SimTexture)> = Vec::new();
        for frame in 0..=steps.len() {
            if frame > 0 {
                viewer = [viewer[0] + steps[frame - 1][0], viewer[1] + steps[frame - 1][1]];
            }
            let levels = place_levels(&d, viewer);
            for (i, l) in levels.iter().enumerate() {
                let old = state.get(i).map(|s| s.1.clone());
                let (region, uploads) = update_cache(&d, old.as_ref(), l);
                prop_assert_eq!(region.side, side);
                // The patch lies inside the region.
                for a in 0..2 {
                    let lo = l.patch_origin[a] * q;
                    let hi = lo + l.patch_tiles as i64 * q;
                    prop_assert!(lo >= region.origin[a] && hi < region.origin[a] + side as i64);
                }
                if l.is_coarsest {
                    prop_assert_eq!(region.origin, [0, 0]);
                }
                match &old {
                    None => {
                        prop_assert_eq!(uploads.clone(), vec![whole(&region)]);
                        state.push((l.clone(), region.clone(), SimTexture {
                            side,
                            texels: vec![None; (side * side) as usize],
                        }));
                    }
                    Some(old) => {
                        if state[i].0 == *l {
                            prop_assert!(uploads.is_empty(), "level {} did not move", i);
                            prop_assert_eq!(&region, old);
                        }
                        if l.is_coarsest {
                            prop_assert!(uploads.is_empty());
                        }
                        // Strips only: ≤ 2 rects, inside the new region, outside the old,
                        // disjoint, and together exactly new − old.
                        prop_assert!(uploads.len() <= 2);
                        let overlap: u64 = (0..2)
                            .map(|a| (side as i64 - (region.origin[a] - old.origin[a]).abs()).max(0) as u64)
                            .product();
                        // Small steps never force a full re-upload.
                        prop_assert!(overlap > 0, "level {} re-uploaded whole", i);
                        let mut area = 0u64;
                        for (k, r) in uploads.iter().enumerate() {
                            area += r.size[0] as u64 * r.size[1] as u64;
                            for dy in 0..r.size[1] as i64 {
                                for dx in 0..r.size[0] as i64 {
                                    let v = [r.origin[0] + dx, r.origin[1] + dy];
                                    prop_assert!(contains(&region, v) && !contains(old, v));
                                    for other in &uploads[k + 1..] {
                                        prop_assert!(!(0..2).all(|a| v[a] >= other.origin[a]
                                            && v[a] < other.origin[a] + other.size[a] as i64));
                                    }
                                }
                            }
                        }
                        prop_assert_eq!(area, (side as u64).pow(2) - overlap);
                        state[i].0 = l.clone();
                    }
                }
                state[i].1 = region.clone();
                let tex = &mut state[i].2;
                for r in &uploads {
                    tex.apply(r);
                }
                for y in region.origin[1]..region.origin[1] + side as i64 {
                    for x in region.origin[0]..region.origin[0] + side as i64 {
                        let t = toroidal_texel([x, y], side);
                        let held = tex.texels[(t[1] * side + t[0]) as usize];
                        prop_assert_eq!(held, Some([x, y]), "level {} frame {}", i, frame);
                    }
                }
            }
        }
    }
}
