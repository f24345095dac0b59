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
