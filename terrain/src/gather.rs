//! Gathering the samples of a texture region from the dataset (pure CPU): clipmap strips and
//! refined tiles are regular sub-samplings of the full-resolution grid.

use super::Heightfield;

/// Fills `out` (row-major, `size[0]` per row) with samples at `origin + (i, j)·step` (in sample
/// coordinates), clamped to the grid so regions reaching past its edge repeat the edge.
pub fn gather(hf: &Heightfield, origin: [i64; 2], step: u32, size: [u32; 2], out: &mut [f32]) {
    let (w, h) = (size[0] as usize, size[1] as usize);
    assert_eq!(out.len(), w * h, "gather buffer size");
    let step = step as i64;
    let max_c = hf.width as i64 - 1;
    let max_r = hf.height as i64 - 1;
    let cols: Vec<usize> = (0..w as i64)
        .map(|i| (origin[0] + i * step).clamp(0, max_c) as usize)
        .collect();
    for (j, row_out) in out.chunks_exact_mut(w).enumerate() {
        let r = (origin[1] + j as i64 * step).clamp(0, max_r) as usize;
        let row = &hf.heights[r * hf.width..(r + 1) * hf.width];
        if step == 1 && cols[0] + w <= hf.width && cols[w - 1] == cols[0] + w - 1 {
            row_out.copy_from_slice(&row[cols[0]..cols[0] + w]);
        } else {
            for (o, &c) in row_out.iter_mut().zip(&cols) {
                *o = row[c];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field() -> Heightfield {
        let (w, h) = (9, 7);
        Heightfield {
            width: w,
            height: h,
            spacing_x: 1.0,
            spacing_y: 1.0,
            heights: (0..w * h).map(|k| k as f32).collect(),
            geo: None,
            voids_filled: 0,
            spacing_note: String::new(),
        }
    }

    #[test]
    fn strided_and_clamped() {
        let hf = field();
        let mut out = vec![0.0; 3 * 2];
        gather(&hf, [2, 1], 2, [3, 2], &mut out);
        assert_eq!(out, vec![11.0, 13.0, 15.0, 29.0, 31.0, 33.0]);
        // Past the north-east corner: the edge repeats.
        let mut out = vec![0.0; 4];
        gather(&hf, [7, 5], 2, [2, 2], &mut out);
        assert_eq!(out, vec![52.0, 53.0, 61.0, 62.0]);
        // Negative origin clamps to the south-west edge; step 1 fast path agrees with indexing.
        let mut out = vec![0.0; 3];
        gather(&hf, [-1, 0], 1, [3, 1], &mut out);
        assert_eq!(out, vec![0.0, 0.0, 1.0]);
        let mut out = vec![0.0; 4];
        gather(&hf, [3, 2], 1, [4, 1], &mut out);
        assert_eq!(out, vec![21.0, 22.0, 23.0, 24.0]);
    }
}
