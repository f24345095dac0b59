//! What the level textures hold (pure): per level, which cells of its toroidal texture hold the
//! samples of the level's current cache region. A streamed source may not have a strip's
//! samples when the level moves, so a strip is not assumed uploaded: its cells stay pending
//! (retried every frame) and the selection draws from a level tile only when
//! [`LevelContent::is_ready`] says every texel it reads is there.
//!
//! A *cell* is q×q level-L vertices `[c·q, (c+1)·q)` per axis; cache regions start on cell
//! boundaries (patch origins are whole tiles, margins whole tiles, the coarsest region at 0),
//! so every exposed strip is whole cells, and so is each piece of its toroidal split (the
//! texture side is whole cells). Slot `(cx mod C, cy mod C)` of a level holds cell (cx, cy)
//! of its region once uploaded; a move invalidates exactly the slots of the cells it exposes.

use aerie_terrain::clipmap::{CacheRegion, VertexRect};
use aerie_terrain::select::TileReadiness;

/// The valid cells of every level texture.
#[derive(Debug, Clone)]
pub struct LevelContent {
    /// q: vertices per cell side.
    quads: u32,
    /// C: cells per texture side.
    cells: u32,
    /// Per level: the region's first cell, or None before the level was placed.
    origin: Vec<Option<[i64; 2]>>,
    /// Per level, C×C slots (row-major by slot y): whether the slot holds its region cell.
    valid: Vec<Vec<bool>>,
    /// Changes whenever a slot becomes valid or invalid (the selection depends on it).
    generation: u64,
}

impl LevelContent {
    /// `levels` textures of `side` texels (a multiple of `quads`), nothing valid.
    pub fn new(levels: u32, side: u32, quads: u32) -> Self {
        debug_assert!(
            quads > 0 && side.is_multiple_of(quads),
            "side {side}, q {quads}"
        );
        let cells = side / quads;
        LevelContent {
            quads,
            cells,
            origin: vec![None; levels as usize],
            valid: vec![vec![false; (cells * cells) as usize]; levels as usize],
            generation: 0,
        }
    }

    pub fn generation(&self) -> u64 {
        self.generation
    }

    fn slot(&self, cell: [i64; 2]) -> usize {
        let c = self.cells as i64;
        (cell[1].rem_euclid(c) * c + cell[0].rem_euclid(c)) as usize
    }

    /// The cells `[lo, hi)` of a q-aligned vertex rectangle.
    fn cells_of(&self, rect: &VertexRect) -> ([i64; 2], [i64; 2]) {
        let q = self.quads as i64;
        let lo = rect.origin.map(|o| o.div_euclid(q));
        let hi = [0, 1].map(|a| (rect.origin[a] + rect.size[a] as i64).div_euclid(q));
        debug_assert!(
            rect.origin.iter().all(|o| o % q == 0) && rect.size.iter().all(|s| *s as i64 % q == 0),
            "{rect:?} is not whole cells of {q}"
        );
        (lo, hi)
    }

    fn set(&mut self, level: u32, rect: &VertexRect, valid: bool) {
        let (lo, hi) = self.cells_of(rect);
        for cy in lo[1]..hi[1] {
            for cx in lo[0]..hi[0] {
                let s = self.slot([cx, cy]);
                let v = &mut self.valid[level as usize][s];
                if *v != valid {
                    *v = valid;
                    self.generation += 1;
                }
            }
        }
    }

    /// The level's region is now `region`, `exposed` the vertex rectangles it gained (as
    /// `clipmap::update_cache` returns them): their slots no longer hold their cells.
    pub fn moved(&mut self, level: u32, region: &CacheRegion, exposed: &[VertexRect]) {
        let q = self.quads as i64;
        self.origin[level as usize] = Some(region.origin.map(|o| o.div_euclid(q)));
        for rect in exposed {
            self.set(level, rect, false);
        }
    }

    /// `rect` (whole cells of the region) was uploaded.
    pub fn filled(&mut self, level: u32, rect: &VertexRect) {
        self.set(level, rect, true);
    }

    /// `rect` was planned as uploaded but its upload was abandoned: its cells are pending again.
    pub fn unfilled(&mut self, level: u32, rect: &VertexRect) {
        self.set(level, rect, false);
    }

    /// The level's region cells not uploaded yet, as rectangles of whole cells (runs along a
    /// row of cells, merged with the same run of the rows above), south-west first.
    pub fn pending(&self, level: u32) -> Vec<VertexRect> {
        let Some(origin) = self.origin[level as usize] else {
            return Vec::new();
        };
        let (c, q) = (self.cells as i64, self.quads as i64);
        let valid = &self.valid[level as usize];
        // Open rectangles: (x0, x1, y0, rows).
        let mut open: Vec<(i64, i64, i64, i64)> = Vec::new();
        let mut out = Vec::new();
        for cy in origin[1]..origin[1] + c {
            let mut runs = Vec::new();
            let mut cx = origin[0];
            while cx < origin[0] + c {
                if valid[self.slot([cx, cy])] {
                    cx += 1;
                    continue;
                }
                let x0 = cx;
                while cx < origin[0] + c && !valid[self.slot([cx, cy])] {
                    cx += 1;
                }
                runs.push((x0, cx));
            }
            let mut next = Vec::with_capacity(runs.len());
            for r in open.drain(..) {
                if let Some(k) = runs.iter().position(|&(a, b)| (a, b) == (r.0, r.1)) {
                    runs.remove(k);
                    next.push((r.0, r.1, r.2, r.3 + 1));
                } else {
                    out.push(r);
                }
            }
            next.extend(runs.into_iter().map(|(a, b)| (a, b, cy, 1)));
            open = next;
        }
        out.extend(open);
        out.sort_by_key(|r| (r.2, r.0));
        out.into_iter()
            .map(|(x0, x1, y0, rows)| VertexRect {
                origin: [x0 * q, y0 * q],
                size: [((x1 - x0) * q) as u32, (rows * q) as u32],
            })
            .collect()
    }

    /// Whether the cell starting at level-L vertex `origin` lies in the level's region and is
    /// not uploaded yet.
    pub fn cell_pending(&self, level: u32, origin: [i64; 2]) -> bool {
        let Some(o) = self.origin.get(level as usize).copied().flatten() else {
            return false;
        };
        let q = self.quads as i64;
        let cell = origin.map(|v| v.div_euclid(q));
        let c = self.cells as i64;
        let inside = (0..2).all(|a| cell[a] >= o[a] && cell[a] < o[a] + c);
        inside && !self.valid[level as usize][self.slot(cell)]
    }

    /// Whether every cell of the level's region is uploaded.
    pub fn complete(&self, level: u32) -> bool {
        self.origin[level as usize].is_some() && self.valid[level as usize].iter().all(|v| *v)
    }

    /// Whether level tile (tx, ty) — vertices `[tx·q, (tx+1)·q]` plus one more on each side for
    /// its normals — can be drawn: the slots those vertices are read from hold region cells
    /// (cells tx−1 ..= tx+1 on each axis, taken toroidally as the shader reads them), and the
    /// tile's own cells lie in the region.
    pub fn tile_ready(&self, level: u32, tx: u32, ty: u32) -> bool {
        let Some(origin) = self.origin.get(level as usize).copied().flatten() else {
            return false;
        };
        let c = self.cells as i64;
        let (tx, ty) = (tx as i64, ty as i64);
        let inside = |v: i64, o: i64| v >= o && v + 1 < o + c;
        if !(inside(tx, origin[0]) && inside(ty, origin[1])) {
            return false;
        }
        let valid = &self.valid[level as usize];
        (ty - 1..=ty + 1).all(|cy| (tx - 1..=tx + 1).all(|cx| valid[self.slot([cx, cy])]))
    }
}

impl TileReadiness for LevelContent {
    fn is_ready(&self, level: u32, tx: u32, ty: u32) -> bool {
        self.tile_ready(level, tx, ty)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(x: i64, y: i64, w: u32, h: u32) -> VertexRect {
        VertexRect {
            origin: [x, y],
            size: [w, h],
        }
    }

    #[test]
    fn a_move_invalidates_what_it_exposes_and_pending_lists_it_as_rectangles() {
        // 4 cells of 16 per side.
        let mut c = LevelContent::new(1, 64, 16);
        assert!(!c.tile_ready(0, 1, 1), "nothing placed");
        let region = CacheRegion {
            origin: [0, 0],
            side: 64,
        };
        c.moved(0, &region, &[rect(0, 0, 64, 64)]);
        assert_eq!(c.pending(0), vec![rect(0, 0, 64, 64)]);
        c.filled(0, &rect(0, 0, 64, 64));
        assert!(c.pending(0).is_empty() && c.complete(0));
        assert!(c.tile_ready(0, 1, 1) && c.tile_ready(0, 2, 2));
        // The tile whose last vertex lies past the region is never ready.
        assert!(!c.tile_ready(0, 3, 1));
        // One cell east: the slots of column 0 now belong to cell 4.
        let g = c.generation();
        let moved = CacheRegion {
            origin: [16, 0],
            side: 64,
        };
        c.moved(0, &moved, &[rect(64, 0, 16, 64)]);
        assert!(c.generation() > g);
        assert_eq!(c.pending(0), vec![rect(64, 0, 16, 64)]);
        // Tile 2 reads cell 3 (valid) and cells 1, 2: ready; tile 3 reads cell 4: not.
        assert!(c.tile_ready(0, 2, 1));
        assert!(!c.tile_ready(0, 3, 1));
        // Three cells of the strip arrive: the fourth stays pending. Tile (3, 1) reads rows
        // 0..=2 (there); tile (3, 2) reads row 3, and tile (3, 0) row −1 = slot row 3 (not).
        c.filled(0, &rect(64, 0, 16, 48));
        assert_eq!(c.pending(0), vec![rect(64, 48, 16, 16)]);
        assert!(c.tile_ready(0, 3, 1));
        assert!(!c.tile_ready(0, 3, 2) && !c.tile_ready(0, 3, 0));
        c.unfilled(0, &rect(64, 0, 16, 16));
        assert_eq!(c.pending(0).len(), 2);
    }

    #[test]
    fn pending_merges_rows_with_the_same_run_and_keeps_holes_apart() {
        let mut c = LevelContent::new(1, 64, 16);
        let region = CacheRegion {
            origin: [-32, -32],
            side: 64,
        };
        c.moved(0, &region, &[rect(-32, -32, 64, 64)]);
        // Leave a 2×2-cell hole and a single cell.
        c.filled(0, &rect(-32, -32, 64, 64));
        c.unfilled(0, &rect(-16, -16, 32, 32));
        c.unfilled(0, &rect(-32, 16, 16, 16));
        let p = c.pending(0);
        assert_eq!(p, vec![rect(-16, -16, 32, 32), rect(-32, 16, 16, 16)]);
        let cells: u32 = p.iter().map(|r| (r.size[0] / 16) * (r.size[1] / 16)).sum();
        assert_eq!(cells, 5);
    }
}
