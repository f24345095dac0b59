//! The static half of the hardware-tessellation baseline (seed document 001, §2.2.2): a density
//! from second differences of height, taken once at load, and projected on the edges of the base
//! mesh of triangular patches.
//!
//! Per sample (i, j) the paper's density is `D = Σ αk·[P∆k > tol]·…`, with P∆0, P∆1 the second
//! differences along the rows and columns (α = 0.293 each) and P∆2, P∆3 along the two diagonals
//! (α = 0.207 each): `D ∈ [0, 1]`, 1 where the height bends in every direction. An edge's density
//! is the largest `D` of the samples it crosses (the paper's "criterio del máximo valor"), so the
//! two patches sharing an edge read one value. The base mesh: square cells of [`TESS_PATCH`]
//! samples, each cut along its south-west → north-east diagonal (the drawn meshes' diagonal,
//! `mesh::TILE_DIAGONAL`) into two triangular patches.
//!
//! Departure: only the samples that lie on an edge are evaluated (the paper fills the whole map
//! first and projects the edges on it; the values on the edges are the same, the rest is never
//! read). A direction leaving the grid at a border sample counts as no bend.

/// Samples per side of a base-mesh cell: at the device's largest odd level (63 on lavapipe and
/// most GPUs) an edge can reach full resolution with room to spare.
pub const TESS_PATCH: u32 = 32;

/// The largest level worth asking for: one segment per sample along an edge of a cell (odd, for
/// `fractional_odd`). More adds triangles, not accuracy.
pub const TESS_LEVEL_CAP: u32 = TESS_PATCH + 1;

/// The paper's weights: along rows and columns, and along the diagonals (they sum to 1).
pub const ALPHA_AXIS: f32 = 0.293;
pub const ALPHA_DIAGONAL: f32 = 0.207;

/// Default tolerance on a second difference, metres: SRTM heights are whole metres, so any bend
/// the data can show counts.
pub const DEFAULT_TOL_M: f32 = 0.5;

/// The density of every base-mesh edge and what culling needs of each cell.
#[derive(Debug, Clone, PartialEq)]
pub struct TessDensity {
    /// Samples per cell side.
    pub patch: u32,
    /// Valid samples (columns, rows) the mesh covers.
    pub size: [u32; 2],
    /// Cells (east-west, north-south).
    pub cells: [u32; 2],
    /// Edges along rows: `(cells[1] + 1) × cells[0]`, index `row_line * cells[0] + cx`.
    pub horizontal: Vec<f32>,
    /// Edges along columns: `cells[1] × (cells[0] + 1)`, index `cy * (cells[0] + 1) + col_line`.
    pub vertical: Vec<f32>,
    /// Each cell's diagonal: `cells[1] × cells[0]`.
    pub diagonal: Vec<f32>,
    /// Heights at the cell corners: `(cells[1] + 1) × (cells[0] + 1)`.
    pub corner_h: Vec<f32>,
    /// Each cell's lowest and highest sample.
    pub cell_range: Vec<[f32; 2]>,
}

/// The paper's density at sample (col, row) of a `width`-wide grid (equations 1–6).
pub fn sample_density(
    heights: &[f32],
    width: usize,
    rows: usize,
    col: usize,
    row: usize,
    tol: f32,
) -> f32 {
    let at = |c: isize, r: isize| heights[r as usize * width + c as usize];
    let inside = |c: isize, r: isize| c >= 0 && r >= 0 && c < width as isize && r < rows as isize;
    let (c, r) = (col as isize, row as isize);
    let p = at(c, r);
    // A direction that leaves the grid shows no bend (a plane's border stays at 0).
    let second = |dc: isize, dr: isize| {
        if !inside(c + dc, r + dr) || !inside(c - dc, r - dr) {
            return 0.0;
        }
        ((at(c + dc, r + dr) - p) - (p - at(c - dc, r - dr))).abs()
    };
    let term = |d: f32, alpha: f32| if d > tol { alpha } else { 0.0 };
    term(second(1, 0), ALPHA_AXIS)
        + term(second(0, 1), ALPHA_AXIS)
        + term(second(1, 1), ALPHA_DIAGONAL)
        + term(second(1, -1), ALPHA_DIAGONAL)
}

impl TessDensity {
    /// The densities of the base mesh over `heights` (`size[0]` per row, south row first), with
    /// cells of `patch` samples and tolerance `tol_m`. `size` must be at least 2 × 2.
    pub fn new(heights: &[f32], size: [u32; 2], patch: u32, tol_m: f32) -> Result<Self, String> {
        let (w, h) = (size[0] as usize, size[1] as usize);
        if w < 2 || h < 2 || heights.len() != w * h || patch < 1 {
            return Err(format!(
                "tessellation density: {w}×{h} samples ({} given), patch {patch}: need at least 2×2",
                heights.len()
            ));
        }
        let p = patch as usize;
        let cells = [(w - 1).div_ceil(p), (h - 1).div_ceil(p)];
        let line = |k: usize, n: usize| (k * p).min(n - 1);
        let d = |c: usize, r: usize| sample_density(heights, w, h, c, r, tol_m);
        let max_over = |pts: &mut dyn Iterator<Item = (usize, usize)>| {
            pts.map(|(c, r)| d(c, r)).fold(0.0f32, f32::max)
        };
        let mut horizontal = Vec::with_capacity((cells[1] + 1) * cells[0]);
        for ly in 0..=cells[1] {
            let r = line(ly, h);
            for cx in 0..cells[0] {
                let (c0, c1) = (line(cx, w), line(cx + 1, w));
                horizontal.push(max_over(&mut (c0..=c1).map(|c| (c, r))));
            }
        }
        let mut vertical = Vec::with_capacity(cells[1] * (cells[0] + 1));
        let mut diagonal = Vec::with_capacity(cells[1] * cells[0]);
        let mut cell_range = Vec::with_capacity(cells[1] * cells[0]);
        for cy in 0..cells[1] {
            let (r0, r1) = (line(cy, h), line(cy + 1, h));
            for lx in 0..=cells[0] {
                let c = line(lx, w);
                vertical.push(max_over(&mut (r0..=r1).map(|r| (c, r))));
            }
            for cx in 0..cells[0] {
                let (c0, c1) = (line(cx, w), line(cx + 1, w));
                let (dc, dr) = (c1 - c0, r1 - r0);
                let steps = dc.max(dr);
                // The samples the diagonal crosses, nearest to its line.
                diagonal.push(max_over(&mut (0..=steps).map(|k| {
                    (
                        c0 + (k * dc + steps / 2) / steps,
                        r0 + (k * dr + steps / 2) / steps,
                    )
                })));
                let mut range = [f32::INFINITY, f32::NEG_INFINITY];
                for r in r0..=r1 {
                    for &v in &heights[r * w + c0..=r * w + c1] {
                        range = [range[0].min(v), range[1].max(v)];
                    }
                }
                cell_range.push(range);
            }
        }
        let mut corner_h = Vec::with_capacity((cells[1] + 1) * (cells[0] + 1));
        for ly in 0..=cells[1] {
            for lx in 0..=cells[0] {
                corner_h.push(heights[line(ly, h) * w + line(lx, w)]);
            }
        }
        Ok(Self {
            patch,
            size,
            cells: [cells[0] as u32, cells[1] as u32],
            horizontal,
            vertical,
            diagonal,
            corner_h,
            cell_range,
        })
    }

    /// The sample (col, row) of corner (lx, ly) of the cell lattice.
    pub fn corner_sample(&self, lx: u32, ly: u32) -> [u32; 2] {
        [
            (lx * self.patch).min(self.size[0] - 1),
            (ly * self.patch).min(self.size[1] - 1),
        ]
    }

    /// Height at corner (lx, ly).
    pub fn corner_height(&self, lx: u32, ly: u32) -> f32 {
        self.corner_h[(ly * (self.cells[0] + 1) + lx) as usize]
    }

    /// Density of the row edge of cell column `cx` on lattice row `ly`.
    pub fn horizontal_edge(&self, cx: u32, ly: u32) -> f32 {
        self.horizontal[(ly * self.cells[0] + cx) as usize]
    }

    /// Density of the column edge of cell row `cy` on lattice column `lx`.
    pub fn vertical_edge(&self, lx: u32, cy: u32) -> f32 {
        self.vertical[(cy * (self.cells[0] + 1) + lx) as usize]
    }

    /// Density of cell (cx, cy)'s diagonal.
    pub fn diagonal_edge(&self, cx: u32, cy: u32) -> f32 {
        self.diagonal[(cy * self.cells[0] + cx) as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Vec<f32> {
        (0..h)
            .flat_map(|r| (0..w).map(move |c| (c, r)))
            .map(|(c, r)| f(c, r))
            .collect()
    }

    #[test]
    fn a_plane_has_no_density_and_a_bend_has_it_in_its_directions() {
        // A tilted plane: every second difference is 0.
        let plane = grid(9, 9, |c, r| 3.0 * c as f32 - 2.0 * r as f32);
        for (c, r) in [(0, 0), (4, 4), (8, 3)] {
            assert_eq!(sample_density(&plane, 9, 9, c, r, 0.5), 0.0);
        }
        // A ridge along the columns (height bends east-west only): rows and both diagonals see
        // it, the column direction does not.
        let ridge = grid(9, 9, |c, _| -((c as f32 - 4.0).abs()) * 10.0);
        let d = sample_density(&ridge, 9, 9, 4, 4, 0.5);
        assert!(
            (d - (ALPHA_AXIS + 2.0 * ALPHA_DIAGONAL)).abs() < 1e-6,
            "{d}"
        );
        // A peak bends in every direction: the full weight, 1.
        let peak = grid(9, 9, |c, r| {
            -((c as f32 - 4.0).abs() + (r as f32 - 4.0).abs()) * 10.0
        });
        let d = sample_density(&peak, 9, 9, 4, 4, 0.5);
        assert!((d - 1.0).abs() < 1e-6, "{d}");
        // Below the tolerance nothing counts.
        assert_eq!(sample_density(&peak, 9, 9, 4, 4, 50.0), 0.0);
    }

    #[test]
    fn edges_take_the_largest_density_they_cross() {
        // 9×9 samples, cells of 4: 2×2 cells. One bump at sample (4, 2): on the vertical line
        // col 4 (between the two lower cells) only.
        let mut h = vec![0.0f32; 81];
        h[2 * 9 + 4] = 5.0;
        let t = TessDensity::new(&h, [9, 9], 4, 0.5).unwrap();
        assert_eq!(t.cells, [2, 2]);
        assert_eq!(t.vertical_edge(1, 0), 1.0);
        // The other column lines and the row lines (rows 0 and 4) are two samples or more away.
        assert_eq!(t.vertical_edge(0, 0), 0.0);
        assert_eq!(t.vertical_edge(2, 0), 0.0);
        assert_eq!(t.vertical_edge(1, 1), 0.0);
        assert_eq!(t.horizontal_edge(0, 0), 0.0);
        assert_eq!(t.horizontal_edge(1, 1), 0.0);
        // Cell (0, 0)'s diagonal crosses (3, 3), whose anti-diagonal neighbour is the bump.
        assert!(t.diagonal_edge(0, 0) > 0.0);
        assert_eq!(t.diagonal_edge(1, 1), 0.0);
        assert_eq!(t.cell_range[0], [0.0, 5.0]);
        assert_eq!(t.corner_height(1, 0), 0.0);
    }

    #[test]
    fn partial_cells_end_at_the_last_sample() {
        let h = grid(10, 6, |c, r| (c * r) as f32);
        let t = TessDensity::new(&h, [10, 6], 4, 0.5).unwrap();
        assert_eq!(t.cells, [3, 2]);
        assert_eq!(t.corner_sample(3, 2), [9, 5]);
        assert_eq!(t.corner_height(3, 2), 45.0);
        assert_eq!(t.horizontal.len(), 3 * 3);
        assert_eq!(t.vertical.len(), 2 * 4);
        assert!(TessDensity::new(&h, [10, 5], 4, 0.5).is_err());
    }

    /// The load-time cost on a 16385² grid (the size), reported, not asserted:
    /// `cargo test -p aerie-terrain --release --lib density_time -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn density_time_on_16385_squared() {
        let n = 16385usize;
        let h: Vec<f32> = (0..n * n)
            .map(|i| {
                ((i % n) as f32 * 0.013).sin() * 300.0 + ((i / n) as f32 * 0.007).cos() * 200.0
            })
            .collect();
        let t0 = std::time::Instant::now();
        let d = TessDensity::new(&h, [n as u32, n as u32], TESS_PATCH, DEFAULT_TOL_M).unwrap();
        println!(
            "density of {n}² ({} cells): {:.0} ms",
            d.cells[0] * d.cells[1],
            t0.elapsed().as_secs_f64() * 1e3
        );
    }
}
