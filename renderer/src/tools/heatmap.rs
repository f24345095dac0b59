//! The heat map of a frame's per-pixel image-space errors (`image_error::measure`'s `heat`).

/// A heat map of per-pixel errors (`image_error::measure`'s `heat`): sky black, holes cyan; errors from 0
/// to `scale_px` along blue → green → yellow → red, above it magenta. RGBA8, rows top to bottom.
pub fn heatmap_rgba(errors: &[f32], scale_px: f64) -> Vec<u8> {
    let mut out = Vec::with_capacity(errors.len() * 4);
    for &e in errors {
        let rgb = if e.is_nan() {
            [0, 0, 0]
        } else if e < 0.0 {
            [0, 255, 255]
        } else if e as f64 > scale_px {
            [255, 0, 255]
        } else {
            ramp((e as f64 / scale_px).clamp(0.0, 1.0))
        };
        out.extend_from_slice(&[rgb[0], rgb[1], rgb[2], 255]);
    }
    out
}

/// 0 → dark blue, ⅓ → green, ⅔ → yellow, 1 → red.
fn ramp(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 4] = [
        [20.0, 30.0, 120.0],
        [30.0, 190.0, 60.0],
        [250.0, 230.0, 40.0],
        [230.0, 30.0, 30.0],
    ];
    let x = t * 3.0;
    let k = (x.floor() as usize).min(2);
    let f = x - k as f64;
    let c = |i: usize| (STOPS[k][i] + (STOPS[k + 1][i] - STOPS[k][i]) * f).round() as u8;
    [c(0), c(1), c(2)]
}
