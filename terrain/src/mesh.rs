//! The tile mesh: an m×m vertex grid split into triangles along one fixed diagonal.
//! The bake (error ε against the level surface) and the GPU index buffer both use
//! [`TILE_DIAGONAL`], so the error is measured on exactly the triangles that are drawn.

/// Which diagonal splits each grid quad.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Diagonal {
    /// From the quad's south-west vertex to its north-east vertex.
    SouthWestToNorthEast,
}

/// The one diagonal used everywhere (GPU mesh, error bake, CPU oracles).
pub const TILE_DIAGONAL: Diagonal = Diagonal::SouthWestToNorthEast;

/// Triangle-list indices of a tile of `m × m` vertices, vertex `(i, j)` (i east, j north) having
/// index `j * m + i`; triangles counter-clockwise seen from above.
pub fn tile_indices(m: u32) -> Vec<u16> {
    assert!((2..=256).contains(&m), "tile side {m} outside 2..=256");
    let mut out = Vec::with_capacity(((m - 1) * (m - 1) * 6) as usize);
    for j in 0..m - 1 {
        for i in 0..m - 1 {
            let sw = (j * m + i) as u16;
            let se = sw + 1;
            let nw = sw + m as u16;
            let ne = nw + 1;
            match TILE_DIAGONAL {
                Diagonal::SouthWestToNorthEast => out.extend_from_slice(&[sw, se, ne, sw, ne, nw]),
            }
        }
    }
    out
}

/// Height of the piecewise-linear surface over one quad at fractional position (u, v) ∈ [0,1]²,
/// given its corner heights, split by [`TILE_DIAGONAL`].
pub fn quad_surface(sw: f64, se: f64, nw: f64, ne: f64, u: f64, v: f64) -> f64 {
    match TILE_DIAGONAL {
        Diagonal::SouthWestToNorthEast => {
            if u >= v {
                // Triangle (sw, se, ne).
                sw + u * (se - sw) + v * (ne - se)
            } else {
                // Triangle (sw, ne, nw).
                sw + v * (nw - sw) + u * (ne - nw)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn indices_cover_every_quad_with_two_ccw_triangles() {
        let m = 5u32;
        let idx = tile_indices(m);
        assert_eq!(idx.len(), (4 * 4 * 6) as usize);
        let pos = |k: u16| ((k as u32 % m) as f64, (k as u32 / m) as f64);
        let mut area = 0.0;
        for t in idx.chunks(3) {
            let (a, b, c) = (pos(t[0]), pos(t[1]), pos(t[2]));
            let cross = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
            assert!(cross > 0.0, "triangle {t:?} is not counter-clockwise");
            area += cross / 2.0;
        }
        assert_eq!(area, 16.0);
        assert!(idx.iter().all(|&k| (k as u32) < m * m));
    }

    #[test]
    fn surface_matches_the_triangles_drawn() {
        // Corner heights chosen so the two diagonals give different surfaces at the centre.
        let (sw, se, nw, ne) = (0.0, 0.0, 0.0, 10.0);
        assert_eq!(quad_surface(sw, se, nw, ne, 0.5, 0.5), 5.0); // on the SW-NE diagonal
        assert_eq!(quad_surface(sw, se, nw, ne, 1.0, 0.0), se);
        assert_eq!(quad_surface(sw, se, nw, ne, 0.0, 1.0), nw);
        assert_eq!(quad_surface(sw, se, nw, ne, 1.0, 1.0), ne);
        // Below the diagonal: plane through sw, se, ne.
        assert!((quad_surface(sw, se, nw, ne, 0.75, 0.25) - 2.5).abs() < 1e-12);
    }
}

/// Vertices of a tile with `side` vertices per side plus its skirts: `side²` grid vertices,
/// then three rings of skirt vertices, one per stride the tile is drawn at (1, 2 and 4:
/// [`SKIRT_STRIDES`]), each one vertex under each of the `4(side − 1)` perimeter vertices (see
/// [`perimeter_vertex`]; [`skirt_vertex`]).
pub fn skirted_vertex_count(side: u32) -> u32 {
    side * side + SKIRT_STRIDES * 4 * (side - 1)
}

/// Rings of skirt vertices: strides 1, 2 and 4 (the whole, quadrant and sixteenth meshes).
pub const SKIRT_STRIDES: u32 = 3;

/// Index of the skirt vertex under perimeter vertex `k` of a tile of `side` vertices drawn
/// over every `stride`-th vertex (1, 2 or 4). It hangs below the lowest of perimeter vertices
/// k − stride, k and k + stride ([`skirt_bottom`]; the vertex shader reads the three), so that
/// a skirt's bottom between two of them lies below the edge's vertices on both segments it
/// spans.
pub fn skirt_vertex(side: u32, stride: u32, k: u32) -> u32 {
    let n = side - 1;
    side * side + stride.trailing_zeros() * 4 * n + k % (4 * n)
}

/// The height of a skirt vertex: `reach` below the lowest of the perimeter vertex it hangs
/// under and its two neighbours along the perimeter at the drawn stride (`shaders/terrain.vert`
/// forms the same).
pub fn skirt_bottom(before: f32, at: f32, after: f32, reach: f32) -> f32 {
    before.min(at).min(after) - reach
}

/// Grid position (i, j) of perimeter vertex `k` ∈ [0, 4(side−1)): south edge west→east, east edge
/// south→north, north edge east→west, west edge north→south. The vertex shader walks the same way.
pub fn perimeter_vertex(side: u32, k: u32) -> (u32, u32) {
    let n = side - 1;
    let (edge, t) = (k / n, k % n);
    match edge {
        0 => (t, 0),
        1 => (n, t),
        2 => (n - t, n),
        _ => (0, n - t),
    }
}

/// Triangle-list indices of a tile of `side × side` vertices and its skirt: the grid triangles of
/// [`tile_indices`] (as u32), then each edge's skirt ([`skirt_edge_indices`]). Skirts hide the
/// cracks between neighbours drawn at different resolutions (DESIGN.md "Cracks").
pub fn skirted_tile_indices(side: u32) -> Vec<u32> {
    assert!(
        (2..=4097).contains(&side),
        "tile side {side} outside 2..=4097"
    );
    strided_skirted_indices(side, 1)
}

/// The same vertices drawn at half the tile's resolution: the triangles of a tile of
/// `(side + 1) / 2` vertices a side over the tile's even vertices (every other one, the same
/// diagonal), and skirts under its even perimeter vertices (the stride-2 ring) — what a
/// tile drawn as a quadrant at its parent's resolution shows (the vertex shader's full morph
/// folds each odd vertex onto an even one, so the odd vertices are not needed). Indices of
/// the tile's own vertex layout ([`skirted_vertex_count`]), so both draw from one vertex
/// stream; `side − 1` must be even.
pub fn skirted_coarse_tile_indices(side: u32) -> Vec<u32> {
    assert!(
        (3..=4097).contains(&side) && (side - 1).is_multiple_of(2),
        "tile side {side} is not 2k + 1 in 3..=4097"
    );
    strided_skirted_indices(side, 2)
}

/// The same vertices drawn at a quarter of the tile's resolution: the triangles of a tile of
/// `(side − 1) / 4 + 1` vertices a side over every fourth vertex, skirts under every fourth
/// perimeter vertex — what a tile drawn as a sixteenth of its grandparent at the grandparent's
/// resolution shows (those vertices lie on the grandparent's grid, where the full morph onto
/// the parent's leaves them). `side − 1` must be a multiple of 4.
pub fn skirted_sixteenth_tile_indices(side: u32) -> Vec<u32> {
    assert!(
        (5..=4097).contains(&side) && (side - 1).is_multiple_of(4),
        "tile side {side} is not 4k + 1 in 5..=4097"
    );
    strided_skirted_indices(side, 4)
}

/// The skirted triangle list over every `stride`-th vertex of a tile of `side` vertices
/// (`stride` divides `side − 1`), in the tile's own vertex layout.
fn strided_skirted_indices(side: u32, stride: u32) -> Vec<u32> {
    let n = side - 1;
    let cells = n / stride;
    let mut out = Vec::with_capacity((cells * cells * 6 + 4 * cells * 6) as usize);
    for j in (0..n).step_by(stride as usize) {
        for i in (0..n).step_by(stride as usize) {
            let sw = j * side + i;
            let se = sw + stride;
            let nw = sw + stride * side;
            let ne = nw + stride;
            match TILE_DIAGONAL {
                Diagonal::SouthWestToNorthEast => out.extend_from_slice(&[sw, se, ne, sw, ne, nw]),
            }
        }
    }
    for edge in 0..4 {
        out.extend(skirt_edge_indices(side, stride, edge));
    }
    out
}

/// The skirt of one edge of a tile of `side` vertices drawn over every `stride`-th vertex (1, 2
/// or 4), in the perimeter walk's order ([`perimeter_vertex`]: edge 0 south, 1 east, 2 north,
/// 3 west): per two segments a, b, c of the edge, three triangles — a to b over the skirt
/// vertex under a, b over the bottom from a to c, b to c over the skirt vertex under c — where
/// a strip would take four; a last odd segment two ([`skirt_edge_triangles`]). The bottom
/// needs no vertex under b because each skirt vertex hangs below its neighbours too
/// ([`skirt_bottom`]): the bottom from a to c lies `reach` below a, b and c, so every triangle
/// lies below the edge and the skirt covers at least `reach` under it everywhere. The four
/// edges in order are the skirt of [`skirted_tile_indices`] and its strided variants, so one
/// edge's skirt can be drawn alone (a node whose neighbour across the other edges is drawn at
/// its resolution).
pub fn skirt_edge_indices(side: u32, stride: u32, edge: u32) -> Vec<u32> {
    let (first, segments) = edge_at_stride(side, stride, edge);
    let grid = |k: u32| perimeter_grid_index(side, k);
    let skirt = |k: u32| skirt_vertex(side, stride, k);
    let mut out = Vec::with_capacity(skirt_edge_triangles(segments) as usize * 3);
    for pair in 0..segments / 2 {
        let a = first + 2 * pair * stride;
        let (b, c) = (a + stride, a + 2 * stride);
        let (ga, gb, gc) = (grid(a), grid(b), grid(c));
        let (sa, sc) = (skirt(a), skirt(c));
        out.extend_from_slice(&[ga, sa, gb, gb, sa, sc, gb, sc, gc]);
    }
    if segments % 2 == 1 {
        let a = first + (segments - 1) * stride;
        let (ga, gb) = (grid(a), grid(a + stride));
        let (sa, sb) = (skirt(a), skirt(a + stride));
        out.extend_from_slice(&[ga, sa, sb, ga, sb, gb]);
    }
    out
}

/// Edge `edge` of a tile of `side` vertices drawn over every `stride`-th vertex, as the edge
/// lists walk it: its first perimeter vertex ([`perimeter_vertex`]) and its segments.
fn edge_at_stride(side: u32, stride: u32, edge: u32) -> (u32, u32) {
    let n = side - 1;
    assert!(
        edge < 4 && matches!(stride, 1 | 2 | 4) && n.is_multiple_of(stride),
        "edge {edge} of stride {stride} on a tile side {side}"
    );
    (edge * n, n / stride)
}

/// The grid index of perimeter vertex `k`, taken around the perimeter (an edge's last vertex
/// is the next edge's first).
fn perimeter_grid_index(side: u32, k: u32) -> u32 {
    let (i, j) = perimeter_vertex(side, k % (4 * (side - 1)));
    j * side + i
}

/// Triangles of one edge's skirt over `segments` segments ([`skirt_edge_indices`]): three per
/// two, two for a last odd one.
pub fn skirt_edge_triangles(segments: u32) -> u32 {
    3 * (segments / 2) + 2 * (segments % 2)
}

/// Triangle-list indices that fill the crack along edge `edge` (0 south, 1 east, 2 north, 3 west)
/// of a tile of `side` vertices drawn over every `stride`-th vertex, against a neighbour drawn
/// at twice that stride whose vertices are every other one of this edge's (`select::node_skirts`'
/// fills): per two segments (a, b, c) the triangle a–b–c. Between the coarse segment a–c and the
/// fine polyline a–b–c lies exactly that triangle, whichever side of a–c vertex b is. Grid
/// vertices only (no skirt vertex); a last odd segment, which no coarse segment spans, gets none.
pub fn fill_edge_indices(side: u32, stride: u32, edge: u32) -> Vec<u32> {
    let (first, segments) = edge_at_stride(side, stride, edge);
    let grid = |k: u32| perimeter_grid_index(side, k);
    (0..segments / 2)
        .flat_map(|pair| {
            let a = first + 2 * pair * stride;
            [grid(a), grid(a + stride), grid(a + 2 * stride)]
        })
        .collect()
}

/// Triangles of one edge's fill over `segments` segments ([`fill_edge_indices`]): one per two.
pub fn fill_edge_triangles(segments: u32) -> u32 {
    segments / 2
}

#[cfg(test)]
mod skirt_tests {
    use super::*;

    #[test]
    fn perimeter_walk_visits_every_edge_vertex_once_in_order() {
        for side in [2u32, 3, 17, 33] {
            let n = side - 1;
            let walk: Vec<_> = (0..4 * n).map(|k| perimeter_vertex(side, k)).collect();
            let set: std::collections::HashSet<_> = walk.iter().copied().collect();
            assert_eq!(set.len() as u32, 4 * n, "side {side}");
            assert!(walk
                .iter()
                .all(|&(i, j)| i == 0 || j == 0 || i == n || j == n));
            // Consecutive perimeter vertices are grid neighbours (a closed loop).
            for k in 0..walk.len() {
                let (a, b) = (walk[k], walk[(k + 1) % walk.len()]);
                let d = a.0.abs_diff(b.0) + a.1.abs_diff(b.1);
                assert_eq!(d, 1, "side {side} step {k}: {a:?} → {b:?}");
            }
        }
    }

    /// The coarse (stride 2) and sixteenth (stride 4) indices are the half- and
    /// quarter-resolution tile's, vertex for vertex: mapping each of the tile's every
    /// `stride`-th vertices (and the skirts under them) to the small tile's gives exactly
    /// `skirted_tile_indices` of the small tile; no other vertex is used.
    #[test]
    fn strided_indices_are_the_lower_resolution_tile_on_every_strided_vertex() {
        type Indices = fn(u32) -> Vec<u32>;
        let cases: [(u32, Indices, &[u32]); 2] = [
            (2, skirted_coarse_tile_indices, &[3, 5, 9, 17, 33]),
            (4, skirted_sixteenth_tile_indices, &[5, 9, 17, 33]),
        ];
        for (stride, indices, sides) in cases {
            for &side in sides {
                let (n, small) = (side - 1, (side - 1) / stride + 1);
                let to_small = |v: u32| -> u32 {
                    if v < side * side {
                        let (i, j) = (v % side, v / side);
                        assert!(
                            i.is_multiple_of(stride) && j.is_multiple_of(stride),
                            "stride {stride}: vertex {v} off the coarse grid used"
                        );
                        (j / stride) * small + i / stride
                    } else {
                        let (ring, k) = ((v - side * side) / (4 * n), (v - side * side) % (4 * n));
                        assert_eq!(ring, stride.trailing_zeros(), "stride {stride}: ring");
                        assert!(
                            k.is_multiple_of(stride),
                            "stride {stride}: skirt {k} of a vertex off the coarse grid"
                        );
                        small * small + k / stride
                    }
                };
                let mapped: Vec<u32> = indices(side).iter().map(|&v| to_small(v)).collect();
                assert_eq!(
                    mapped,
                    skirted_tile_indices(small),
                    "stride {stride}, side {side}"
                );
            }
        }
    }

    /// One edge's skirt joins only that edge's grid vertices (and the skirt vertices under
    /// them) and covers each of its segments once, at every stride.
    #[test]
    fn an_edge_skirt_hangs_under_its_own_edge_only() {
        for (side, stride) in [(5u32, 1u32), (9, 2), (17, 4), (17, 1)] {
            let n = side - 1;
            for edge in 0..4 {
                let idx = skirt_edge_indices(side, stride, edge);
                assert_eq!(idx.len() as u32, skirt_edge_triangles(n / stride) * 3);
                for &v in &idx {
                    let k = if v >= side * side {
                        assert_eq!((v - side * side) / (4 * n), stride.trailing_zeros());
                        (v - side * side) % (4 * n)
                    } else {
                        let (i, j) = (v % side, v / side);
                        (0..4 * n)
                            .find(|&k| perimeter_vertex(side, k) == (i, j))
                            .expect("a perimeter vertex")
                    };
                    // Perimeter vertex k lies on this edge (its last vertex is the next
                    // edge's first).
                    let on = k / n == edge || k == ((edge + 1) * n) % (4 * n);
                    assert!(on, "side {side} edge {edge}: vertex {v} (perimeter {k})");
                }
            }
        }
    }

    #[test]
    fn skirted_indices_extend_the_grid_and_close_the_loop() {
        let side = 5;
        let idx = skirted_tile_indices(side);
        let grid: Vec<u32> = tile_indices(side).into_iter().map(u32::from).collect();
        assert_eq!(&idx[..grid.len()], &grid[..]);
        let skirts = &idx[grid.len()..];
        assert_eq!(skirts.len() as u32, 4 * skirt_edge_triangles(side - 1) * 3);
        assert!(idx.iter().all(|&k| k < skirted_vertex_count(side)));
        // Every perimeter grid vertex is joined to a skirt, and the skirt vertices used are
        // those under every other vertex of an edge (its corners included).
        for k in 0..4 * (side - 1) {
            let (i, j) = perimeter_vertex(side, k);
            assert!(skirts.contains(&(j * side + i)));
            let under = skirts.contains(&skirt_vertex(side, 1, k));
            assert_eq!(under, k % (side - 1) % 2 == 0, "skirt vertex {k}");
        }
    }

    /// Across one edge (a vertical slice at every x along it), the skirt's triangles with
    /// their bottoms at [`skirt_bottom`] cover at least `reach` below the drawn edge and never
    /// rise above it — whatever the heights (random profiles with sharp notches and spikes),
    /// at every stride, with an even and an odd number of segments. A strip's bottom under
    /// each vertex at its own height less `reach` passes the first check but the three-per-two
    /// triangles need the bottoms below the neighbours: the check catches bottoms at the
    /// vertex's own height (they rise above a notch between them).
    #[test]
    fn an_edge_skirt_covers_reach_below_the_edge_and_nothing_above() {
        let mut rnd = crate::test_rng::unit(0x5c1e7u64);
        for (side, stride) in [
            (9u32, 1u32),
            (17, 1),
            (9, 2),
            (17, 2),
            (9, 4),
            (17, 4),
            (13, 4),
        ] {
            let n = side - 1;
            for case in 0..40 {
                let heights: Vec<f32> = (0..4 * n)
                    .map(|_| (rnd() * 100.0 * if rnd() < 0.3 { 5.0 } else { 1.0 }) as f32)
                    .collect();
                let reach = (0.5 + rnd() * 20.0) as f32;
                let h = |k: u32| heights[(k % (4 * n)) as usize];
                for edge in 0..4 {
                    let first = edge * n;
                    // Each vertex of the skirt as (x along the edge, z).
                    let at = |v: u32| -> (f32, f32) {
                        if v >= side * side {
                            let k = (v - side * side) % (4 * n);
                            let x = (k + 4 * n - first) % (4 * n);
                            let z = skirt_bottom(h(k + 4 * n - stride), h(k), h(k + stride), reach);
                            (x as f32, z)
                        } else {
                            let (i, j) = (v % side, v / side);
                            let k = (0..4 * n)
                                .filter(|&k| perimeter_vertex(side, k) == (i, j))
                                .find(|&k| (k + 4 * n - first) % (4 * n) <= n)
                                .expect("a vertex of this edge");
                            (((k + 4 * n - first) % (4 * n)) as f32, h(k))
                        }
                    };
                    let tris: Vec<[(f32, f32); 3]> = skirt_edge_indices(side, stride, edge)
                        .chunks(3)
                        .map(|t| [at(t[0]), at(t[1]), at(t[2])])
                        .collect();
                    // The drawn edge: linear between every stride-th vertex.
                    let top = |x: f32| {
                        let s = stride as f32;
                        let seg = ((x / s).floor() as u32).min(n / stride - 1);
                        let (x0, x1) = (seg as f32 * s, (seg + 1) as f32 * s);
                        let (z0, z1) = (h(first + seg * stride), h(first + seg * stride + stride));
                        z0 + (z1 - z0) * (x - x0) / (x1 - x0)
                    };
                    for step in 0..=n * 16 {
                        let x = step as f32 / 16.0;
                        // The vertical extent of each triangle at x, merged.
                        let mut spans: Vec<(f32, f32)> =
                            tris.iter().filter_map(|t| slice(t, x)).collect();
                        spans.sort_by(|a, b| a.0.total_cmp(&b.0));
                        let what =
                            format!("side {side} stride {stride} case {case} edge {edge} x {x}");
                        let t = top(x);
                        let hi = spans.iter().fold(f32::NEG_INFINITY, |m, s| m.max(s.1));
                        assert!(
                            hi <= t + 1e-3,
                            "{what}: the skirt rises to {hi}, the edge is at {t}"
                        );
                        // Covered from t − reach up to t without a gap.
                        let mut reached = t - reach;
                        for &(lo, up) in &spans {
                            if lo <= reached + 1e-3 {
                                reached = reached.max(up);
                            }
                        }
                        assert!(
                            reached >= t - 1e-3,
                            "{what}: covered up to {reached} of {t}"
                        );
                    }
                }
            }
        }
    }

    /// Across one edge (a vertical slice at every x along it), the fill's triangles span
    /// exactly the gap between the drawn edge and the neighbour's edge drawn at twice the
    /// stride through every other of its vertices — from the lower of the two to the higher,
    /// nothing above or below —, whatever the heights, at every stride; and they join only
    /// this edge's grid vertices, one triangle per two segments.
    #[test]
    fn an_edge_fill_spans_exactly_the_gap_to_the_coarser_edge() {
        let mut rnd = crate::test_rng::unit(0xf111u64);
        for (side, stride) in [(9u32, 1u32), (17, 1), (9, 2), (17, 2), (9, 4), (17, 4)] {
            let n = side - 1;
            for case in 0..40 {
                let heights: Vec<f32> = (0..4 * n)
                    .map(|_| (rnd() * 100.0 * if rnd() < 0.3 { 5.0 } else { 1.0 }) as f32)
                    .collect();
                let h = |k: u32| heights[(k % (4 * n)) as usize];
                for edge in 0..4 {
                    let first = edge * n;
                    let idx = fill_edge_indices(side, stride, edge);
                    assert_eq!(idx.len() as u32, fill_edge_triangles(n / stride) * 3);
                    let at = |v: u32| -> (f32, f32) {
                        assert!(v < side * side, "a grid vertex");
                        let (i, j) = (v % side, v / side);
                        let k = (0..4 * n)
                            .filter(|&k| perimeter_vertex(side, k) == (i, j))
                            .find(|&k| (k + 4 * n - first) % (4 * n) <= n)
                            .expect("a vertex of this edge");
                        let x = (k + 4 * n - first) % (4 * n);
                        assert!(x.is_multiple_of(stride), "a vertex of the drawn stride");
                        (x as f32, h(k))
                    };
                    let tris: Vec<[(f32, f32); 3]> = idx
                        .chunks(3)
                        .map(|t| [at(t[0]), at(t[1]), at(t[2])])
                        .collect();
                    // An edge drawn linear between every `s`-th vertex.
                    let line = |s: u32, x: f32| {
                        let seg = ((x / s as f32).floor() as u32).min(n / s - 1);
                        let (x0, x1) = ((seg * s) as f32, ((seg + 1) * s) as f32);
                        let (z0, z1) = (h(first + seg * s), h(first + seg * s + s));
                        z0 + (z1 - z0) * (x - x0) / (x1 - x0)
                    };
                    for step in 0..=n * 16 {
                        let x = step as f32 / 16.0;
                        let (fine, coarse) = (line(stride, x), line(2 * stride, x));
                        let (want_lo, want_hi) = (fine.min(coarse), fine.max(coarse));
                        let spans: Vec<(f32, f32)> =
                            tris.iter().filter_map(|t| slice(t, x)).collect();
                        let what =
                            format!("side {side} stride {stride} case {case} edge {edge} x {x}");
                        let lo = spans.iter().fold(f32::INFINITY, |m, s| m.min(s.0));
                        let hi = spans.iter().fold(f32::NEG_INFINITY, |m, s| m.max(s.1));
                        assert!(
                            (lo - want_lo).abs() < 1e-3 && (hi - want_hi).abs() < 1e-3,
                            "{what}: the fill spans {lo}..{hi}, the gap {want_lo}..{want_hi}"
                        );
                    }
                }
            }
        }
    }

    /// The vertical extent of triangle `t` (x, z) at `x`, if it reaches there.
    fn slice(t: &[(f32, f32); 3], x: f32) -> Option<(f32, f32)> {
        let mut zs = Vec::new();
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            let (lo, hi) = (a.0.min(b.0), a.0.max(b.0));
            if x < lo || x > hi {
                continue;
            }
            if (b.0 - a.0).abs() < 1e-9 {
                zs.extend([a.1, b.1]);
            } else {
                zs.push(a.1 + (b.1 - a.1) * (x - a.0) / (b.0 - a.0));
            }
        }
        let lo = zs.iter().copied().fold(f32::INFINITY, f32::min);
        let hi = zs.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        (lo <= hi).then_some((lo, hi))
    }
}
