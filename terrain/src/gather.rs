//! Gathering the samples of a texture region from the dataset (pure CPU): clipmap strips and
//! refined tiles are regular sub-samplings of the full-resolution grid.

use super::Heightfield;

/// Fills `out` (row-major, `size[0]` per row) with samples at `origin + (i, j)·step` (in sample
/// coordinates), clamped to the grid so regions reaching past its edge repeat the edge.
pub fn gather(hf: &Heightfield, origin: [i64; 2], step: u32, size: [u32; 2], out: &mut [f32]) {
    let (w, h) = (size[0] as usize, size[1] as usize);
    assert_eq!(out.len(), w * h, "gather buffer size");
    if w == 0 || h == 0 {
        return;
    }
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

    /// Every region — inside the grid (step 1: rows copied as slices) or reaching past any
    /// edge, at steps 1 to 16, empty ones too — holds exactly the clamped samples
    /// `Heightfield::at` reads.
    #[test]
    fn every_region_holds_the_clamped_samples() {
        let hf = field();
        let mut rnd = crate::test_rng::unit(0x9e37_79b9_7f4a_7c15);
        let mut next = |m: i64| (rnd() * m as f64) as i64;
        let (mut inside, mut clamped) = (0, 0);
        for _ in 0..2000 {
            let step = 1 + next(16) as u32;
            let origin = [next(14) - 3, next(12) - 3];
            let size = [next(6) as u32, next(6) as u32];
            let mut out = vec![f32::NAN; (size[0] * size[1]) as usize];
            gather(&hf, origin, step, size, &mut out);
            for j in 0..size[1] as i64 {
                for i in 0..size[0] as i64 {
                    let c = (origin[0] + i * step as i64).clamp(0, hf.width as i64 - 1);
                    let r = (origin[1] + j * step as i64).clamp(0, hf.height as i64 - 1);
                    let got = out[(j * size[0] as i64 + i) as usize];
                    assert_eq!(
                        got,
                        hf.at(c as usize, r as usize),
                        "{origin:?} step {step} {size:?}"
                    );
                }
            }
            let last = origin[0] + (size[0] as i64 - 1) * step as i64;
            if size[0] * size[1] > 0 && origin[0] >= 0 && last < hf.width as i64 {
                inside += 1;
            } else if size[0] * size[1] > 0 {
                clamped += 1;
            }
        }
        // Regions inside the grid and past an edge were both drawn many times.
        assert!(
            inside > 100 && clamped > 100,
            "{inside} inside, {clamped} clamped"
        );
    }
}
