//! The bake section: the measured part of the store's error bake — per level ≥ 1 the ε of
//! its surface over parts of its tiles (format version 4: level 1 over each tile's quadrants,
//! levels ≥ 2 over each tile's 16 blocks; version 3 kept the quadrants of every level and
//! version 2 one ε per tile, both still read: a tile's ε at its grandparent's resolution is
//! then taken at its parent's there, and with version 2 each quadrant at its parent's ε) and
//! level 0's min/max per tile — in one zstd frame between the pages and the index, located
//! by the trailer, so a reader has the whole [`ErrorBake`] the selection needs after reading
//! ≈ 1.3 % of the file, without touching a page.
//!
//! Payload before compression: the arrays ε(level 1), …, ε(level L−1) (version 4: level 1's
//! indexed by level 0's tiles, ε of the level-1 surface over that tile, and each level L ≥ 2's
//! by level L−2's tiles, ε of the level-L surface over that tile; version 3: each indexed by
//! level L−1's tiles; version 2: by level L's tiles), min0, max0, each as
//! f32 bits XOR the previous value of the same array (0 before the first), split into 4
//! byte planes (neighbouring tiles have close values, so the high planes are nearly
//! constant: zstd compresses them to almost nothing). The lengths follow from the layout.
//! Pure: tables in, bytes out, and back.

use crate::bake::{BakeParams, ErrorBake, MeasuredBake, MeasuredEps};

use super::format::{Layout, StoreHeader};

/// Tiles of level `l`.
fn tiles(layout: &Layout, l: usize) -> usize {
    let g = layout.levels[l];
    g.tiles_x as usize * g.tiles_y as usize
}

/// The level whose tiles index level `l`'s ε array in a store of format `version`.
fn eps_of(l: usize, version: u32) -> usize {
    match version {
        4.. if l == 1 => 0,
        4.. => l - 2,
        3 => l - 1,
        _ => l,
    }
}

/// Entries of level `l`'s ε array in a store of format `version`.
fn eps_len(layout: &Layout, l: usize, version: u32) -> usize {
    tiles(layout, eps_of(l, version))
}

/// Bytes of the payload before compression in a store of format `version`.
pub fn raw_len(layout: &Layout, version: u32) -> usize {
    let eps: usize = (1..layout.levels.len())
        .map(|l| eps_len(layout, l, version))
        .sum();
    4 * (eps + 2 * tiles(layout, 0))
}

fn put_planes(values: &[f32], out: &mut Vec<u8>) {
    let n = values.len();
    let base = out.len();
    out.resize(base + 4 * n, 0);
    let mut prev = 0u32;
    for (k, v) in values.iter().enumerate() {
        let x = (v.to_bits() ^ prev).to_le_bytes();
        prev = v.to_bits();
        for (b, &byte) in x.iter().enumerate() {
            out[base + b * n + k] = byte;
        }
    }
}

fn get_planes(b: &[u8]) -> Vec<f32> {
    let n = b.len() / 4;
    let mut prev = 0u32;
    (0..n)
        .map(|k| {
            let x = u32::from_le_bytes([b[k], b[n + k], b[2 * n + k], b[3 * n + k]]) ^ prev;
            prev = x;
            f32::from_bits(x)
        })
        .collect()
}

/// The payload of `bake` (made for `layout`), before compression, in the format this build
/// writes ([`STORE_VERSION`](super::STORE_VERSION)).
pub fn encode(bake: &ErrorBake) -> Vec<u8> {
    let mut out = Vec::new();
    for l in 1..bake.levels.len() {
        let parts = match l {
            1 => &bake.levels[0].coarse_eps,
            _ => &bake.levels[l - 2].fine_eps,
        };
        put_planes(parts, &mut out);
    }
    put_planes(&bake.levels[0].min, &mut out);
    put_planes(&bake.levels[0].max, &mut out);
    out
}

/// The bake back from its decompressed payload; `Err` says what disagrees with the header's
/// layout or is not a bake number (ε negative or not finite, min > max), naming the tile.
pub fn decode(b: &[u8], h: &StoreHeader, layout: &Layout) -> Result<ErrorBake, String> {
    let want = raw_len(layout, h.version);
    if b.len() != want {
        return Err(format!(
            "decompressed to {} bytes, the layout says {want}",
            b.len()
        ));
    }
    let mut at = 0;
    let mut take = |n: usize| {
        let v = get_planes(&b[at..at + 4 * n]);
        at += 4 * n;
        v
    };
    let mut eps = vec![Vec::new()];
    for l in 1..layout.levels.len() {
        let of = eps_of(l, h.version);
        let e = take(tiles(layout, of));
        if let Some(k) = e.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
            let what = match l - of {
                0 => format!("ε of level {l}'s"),
                1 => format!("quadrant ε of level {l} over level {of}'s"),
                _ => format!("block ε of level {l} over level {of}'s"),
            };
            let tx = layout.levels[of].tiles_x as usize;
            return Err(format!(
                "{what} tile ({}, {}): {} is not a finite number ≥ 0",
                k % tx,
                k / tx,
                e[k]
            ));
        }
        eps.push(e);
    }
    let n0 = tiles(layout, 0);
    let (min0, max0) = (take(n0), take(n0));
    if let Some(k) =
        (0..n0).find(|&k| !(min0[k].is_finite() && max0[k].is_finite() && min0[k] <= max0[k]))
    {
        let tx = layout.levels[0].tiles_x as usize;
        return Err(format!(
            "level 0 tile ({}, {}): min {} and max {} are not finite with min ≤ max",
            k % tx,
            k / tx,
            min0[k],
            max0[k]
        ));
    }
    Ok(ErrorBake::from_measured(MeasuredBake {
        params: BakeParams {
            tile_size: h.tile_size,
            levels: h.levels,
        },
        width: h.width,
        height: h.height,
        valid_width: h.valid_width,
        valid_height: h.valid_height,
        spacing_x: h.spacing_x,
        spacing_y: h.spacing_y,
        source_checksum: h.source_checksum,
        min0,
        max0,
        eps: match h.version {
            4.. => MeasuredEps::Blocks(eps),
            3 => MeasuredEps::Quadrants(eps),
            _ => MeasuredEps::Tiles(eps),
        },
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn planes_round_trip_bit_for_bit() {
        let v = [0.0f32, -0.0, 1.5, 1.5, f32::MAX, -3.25e-7, 1234.5];
        let mut b = Vec::new();
        put_planes(&v, &mut b);
        assert_eq!(b.len(), 4 * v.len());
        let back = get_planes(&b);
        assert!(v.iter().zip(&back).all(|(a, b)| a.to_bits() == b.to_bits()));
    }
}
