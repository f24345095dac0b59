//! The mip chain of a draped RGBA8 sRGB raster: each level the 2×2 box average of the one
//! above in linear light, weighted by alpha (so transparent texels do not darken the edges
//! of the imagery), down to 1×1. Pure; the GPU samples the chain trilinearly.

use super::read::{GeoRaster, RasterRef};

/// sRGB byte → linear light.
fn decode(c: u8) -> f32 {
    let c = f32::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear light → sRGB byte.
fn encode(l: f32) -> u8 {
    let c = if l <= 0.003_130_8 {
        l * 12.92
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    };
    (c * 255.0).round().clamp(0.0, 255.0) as u8
}

/// Number of levels of a `w × h` chain down to 1×1.
pub fn mip_count(w: usize, h: usize) -> u32 {
    usize::BITS - w.max(h).max(1).leading_zeros()
}

/// Levels 1.. of the chain below `level0` (`w × h` RGBA8 sRGB, straight alpha), each with its
/// size.
pub fn mip_chain(w: usize, h: usize, level0: &[u8]) -> Vec<(usize, usize, Vec<u8>)> {
    let lut: Vec<f32> = (0..=255u8).map(decode).collect();
    let mut out: Vec<(usize, usize, Vec<u8>)> = Vec::new();
    let (mut pw, mut ph) = (w, h);
    let mut prev: &[u8] = level0;
    let mut owned: Vec<u8>;
    while pw > 1 || ph > 1 {
        let (nw, nh) = ((pw / 2).max(1), (ph / 2).max(1));
        let mut next = vec![0u8; nw * nh * 4];
        for y in 0..nh {
            for x in 0..nw {
                let mut acc = [0.0f32; 4];
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let sx = (2 * x + dx).min(pw - 1);
                    let sy = (2 * y + dy).min(ph - 1);
                    let p = &prev[(sy * pw + sx) * 4..][..4];
                    let a = f32::from(p[3]) / 255.0;
                    for c in 0..3 {
                        acc[c] += lut[p[c] as usize] * a;
                    }
                    acc[3] += a;
                }
                let q = &mut next[(y * nw + x) * 4..][..4];
                if acc[3] > 0.0 {
                    for c in 0..3 {
                        q[c] = encode(acc[c] / acc[3]);
                    }
                }
                q[3] = (acc[3] / 4.0 * 255.0).round() as u8;
            }
        }
        owned = next.clone();
        out.push((nw, nh, next));
        prev = &owned;
        (pw, ph) = (nw, nh);
    }
    out
}

/// The raster's own mip chain, for draping it onto texels coarser than its pixels: level 0 is
/// `raster` itself, each next one the [`mip_chain`] step of the one above (RGBA, in linear
/// light, alpha-weighted), geo-referenced at the centres of the pixels it averages, down to
/// the level whose pixels are no finer than `coarsest_m` metres or to 1×1.
pub fn raster_pyramid(raster: &GeoRaster, pixel_m: f64, coarsest_m: f64) -> Vec<GeoRaster> {
    let mut out = vec![raster.clone()];
    let mut size_m = pixel_m;
    while size_m * 2.0 <= coarsest_m {
        let last = out.last().expect("level 0");
        if last.width < 2 && last.height < 2 {
            break;
        }
        let rgba: Vec<u8> = match last.bands {
            4 => last.data.clone(),
            b => last
                .data
                .chunks_exact(b)
                .flat_map(|p| match b {
                    1 => [p[0], p[0], p[0], 255],
                    _ => [p[0], p[1], p[2], 255],
                })
                .collect(),
        };
        // One step of the chain: the first level below `rgba`.
        let (w, h, data) = mip_chain(last.width, last.height, &rgba)
            .into_iter()
            .next()
            .expect("a raster wider than one pixel has a next level");
        let g = &last.georef;
        let georef = RasterRef {
            crs: g.crs.clone(),
            x0: g.x0 + g.dx / 2.0,
            y0: g.y0 - g.dy / 2.0,
            dx: g.dx * 2.0,
            dy: g.dy * 2.0,
        };
        out.push(GeoRaster {
            path: last.path.clone(),
            width: w,
            height: h,
            bands: 4,
            data,
            georef,
        });
        size_m *= 2.0;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chain_averages_in_linear_light_and_ignores_transparent_texels() {
        assert_eq!(mip_count(1, 1), 1);
        assert_eq!(mip_count(256, 144), 9);
        assert_eq!(mip_count(5, 3), 3);
        // 4×2: left half black/white pairs, right half red beside transparent.
        let px = |r: u8, g: u8, b: u8, a: u8| [r, g, b, a];
        let mut l0 = Vec::new();
        for _ in 0..2 {
            l0.extend(px(0, 0, 0, 255));
            l0.extend(px(255, 255, 255, 255));
            l0.extend(px(200, 0, 0, 255));
            l0.extend(px(0, 0, 0, 0));
        }
        let chain = mip_chain(4, 2, &l0);
        assert_eq!(chain.len(), 2);
        let (w, h, l1) = &chain[0];
        assert_eq!((*w, *h), (2, 1));
        // Half black, half white in linear light is sRGB 188, not 128.
        assert_eq!(&l1[..4], &[188, 188, 188, 255]);
        // The transparent half does not darken the red; alpha halves.
        assert_eq!(&l1[4..], &[200, 0, 0, 128]);
        assert_eq!((chain[1].0, chain[1].1), (1, 1));
        assert_eq!(encode(decode(77)), 77);
    }
}
