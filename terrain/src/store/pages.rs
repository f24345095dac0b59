//! Cutting a level's page out of the dataset and its bake, and the lossless coding of its
//! samples. Pure: slices in, bytes out, and back; a decode failure says what was wrong.

use crate::bake::ErrorBake;
use crate::dataset::Dataset;

use super::error::PageId;
use super::format::{Coding, Layout, PageRect, PAYLOAD_PREFIX};

/// One page, decoded: its level-`L` samples and its tiles' bake numbers.
#[derive(Debug, Clone, PartialEq)]
pub struct Page {
    pub id: PageId,
    pub rect: PageRect,
    pub coding: Coding,
    /// `rect.rows × rect.cols` level-`L` samples, row-major, row 0 south: sample (i, j) is
    /// level-0 sample `((tx0·q + i)·2^L, (ty0·q + j)·2^L)`.
    pub samples: Vec<f32>,
    /// Per tile of the page (row-major, `rect.ntx` per row): the bake's ε, min and max.
    pub eps: Vec<f32>,
    pub min: Vec<f32>,
    pub max: Vec<f32>,
}

impl Page {
    /// Sample (i, j) of the page.
    pub fn at(&self, i: u32, j: u32) -> f32 {
        self.samples[(j * self.rect.cols + i) as usize]
    }

    /// Bytes the decoded page holds (samples and tables; what a page cache counts).
    pub fn bytes(&self) -> u64 {
        (std::mem::size_of::<Page>()
            + 4 * (self.samples.len() + self.eps.len() + self.min.len() + self.max.len()))
            as u64
    }

    /// [`Page::bytes`] of the page that covers `rect`, before it is read.
    pub fn bytes_of(rect: PageRect) -> u64 {
        (std::mem::size_of::<Page>() + 4 * (rect.samples() + 3 * rect.tiles())) as u64
    }

    /// `Err` naming the first tile whose ε, min or max differs (bit for bit) from `bake`'s:
    /// a page that disagrees with the store's bake section is not drawn.
    pub fn check_tables(&self, bake: &ErrorBake) -> Result<(), String> {
        let t = bake
            .levels
            .get(self.id.level as usize)
            .ok_or_else(|| format!("the bake has no level {}", self.id.level))?;
        let r = self.rect;
        for j in 0..r.nty {
            for i in 0..r.ntx {
                let k = (j * r.ntx + i) as usize;
                let (tx, ty) = (r.tx0 + i, r.ty0 + j);
                if tx >= t.tiles_x || ty >= t.tiles_y {
                    return Err(format!("tile ({tx}, {ty}) is outside the bake's level"));
                }
                let b = (ty * t.tiles_x + tx) as usize;
                for (what, page, bake) in [
                    ("ε", self.eps[k], t.eps[b]),
                    ("min", self.min[k], t.min[b]),
                    ("max", self.max[k], t.max[b]),
                ] {
                    if page.to_bits() != bake.to_bits() {
                        return Err(format!(
                            "tile ({tx}, {ty}): {what} {page} in the page, {bake} in the bake section"
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

/// The page's level-`L` samples from the padded dataset: the exact power-of-two subsampling.
pub fn cut_samples(ds: &Dataset, layout: &Layout, id: PageId) -> Vec<f32> {
    let r = layout.rect(id.level, id.px, id.py);
    let step = 1usize << id.level;
    let (c0, r0) = (
        r.tx0 as usize * layout.q as usize * step,
        r.ty0 as usize * layout.q as usize * step,
    );
    let w = ds.hf.width;
    let mut out = Vec::with_capacity(r.samples());
    for j in 0..r.rows as usize {
        let row = &ds.hf.heights[(r0 + j * step) * w..][..w];
        out.extend((0..r.cols as usize).map(|i| row[c0 + i * step]));
    }
    out
}

/// The page's tiles' ε, min, max from the bake (the same tables `bake()` made).
pub fn cut_tables(bake: &ErrorBake, layout: &Layout, id: PageId) -> [Vec<f32>; 3] {
    let r = layout.rect(id.level, id.px, id.py);
    let t = bake.level(id.level);
    let mut out = [Vec::new(), Vec::new(), Vec::new()];
    for ty in r.ty0..r.ty0 + r.nty {
        let at = (ty * t.tiles_x + r.tx0) as usize..(ty * t.tiles_x + r.tx0 + r.ntx) as usize;
        out[0].extend_from_slice(&t.eps[at.clone()]);
        out[1].extend_from_slice(&t.min[at.clone()]);
        out[2].extend_from_slice(&t.max[at]);
    }
    out
}

/// `h` as i16 when that is exactly `h` (bits included: -0.0 is not 0).
#[inline]
fn as_i16(h: f32) -> Option<i16> {
    let i = h as i16;
    (f32::from(i).to_bits() == h.to_bits()).then_some(i)
}

#[inline]
fn zigzag(v: i16) -> u16 {
    ((v << 1) ^ (v >> 15)) as u16
}

#[inline]
fn unzigzag(v: u16) -> i16 {
    ((v >> 1) as i16) ^ -((v & 1) as i16)
}

/// The value a sample is predicted from, by its already-coded neighbours (wrapping i16:
/// a bijection, so the residual is lossless whatever it is).
#[inline]
fn predict(s: &[i16], cols: usize, i: usize, j: usize) -> i16 {
    match (i, j) {
        (0, 0) => 0,
        (_, 0) => s[i - 1],
        (0, _) => s[(j - 1) * cols],
        _ => s[j * cols + i - 1]
            .wrapping_add(s[(j - 1) * cols + i])
            .wrapping_sub(s[(j - 1) * cols + i - 1]),
    }
}

/// Pages with more exceptions than one sample in this many are coded as f32 (8 bytes an
/// exception against ≈ 2 more bytes a sample).
const MAX_EXCEPTION_SHARE: usize = 8;

/// `h` rounded into i16 (the value the predictor sees for an exception).
#[inline]
fn rounded_i16(h: f32) -> i16 {
    h.round().clamp(-32768.0, 32767.0) as i16
}

/// The payload (before compression): prefix, tables, coded samples. The coding is i16 when
/// every sample is an exact i16, i16 with exceptions when few are not, else f32.
pub fn encode_payload(
    id: PageId,
    rect: PageRect,
    samples: &[f32],
    tables: &[Vec<f32>; 3],
) -> (Coding, Vec<u8>) {
    debug_assert_eq!(samples.len(), rect.samples());
    let exceptions: Vec<usize> = (0..samples.len())
        .filter(|&k| as_i16(samples[k]).is_none())
        .collect();
    let coding = match exceptions.len() {
        0 => Coding::I16Gradient,
        n if n * MAX_EXCEPTION_SHARE <= samples.len() => Coding::I16Exceptions,
        _ => Coding::F32Xor,
    };
    let ints: Option<Vec<i16>> =
        (coding != Coding::F32Xor).then(|| samples.iter().map(|&h| rounded_i16(h)).collect());
    let mut out = Vec::with_capacity(
        PAYLOAD_PREFIX + 12 * rect.tiles() + coding.bytes_per_sample() * samples.len(),
    );
    for v in [id.level, id.px, id.py, coding.code()] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for t in tables {
        debug_assert_eq!(t.len(), rect.tiles());
        for v in t {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    let cols = rect.cols as usize;
    match ints {
        Some(s) => {
            for j in 0..rect.rows as usize {
                for i in 0..cols {
                    let r = s[j * cols + i].wrapping_sub(predict(&s, cols, i, j));
                    out.extend_from_slice(&zigzag(r).to_le_bytes());
                }
            }
            if coding == Coding::I16Exceptions {
                out.extend_from_slice(&(exceptions.len() as u32).to_le_bytes());
                for &k in &exceptions {
                    out.extend_from_slice(&(k as u32).to_le_bytes());
                    out.extend_from_slice(&samples[k].to_bits().to_le_bytes());
                }
            }
        }
        None => {
            let n = samples.len();
            let base = out.len();
            out.resize(base + 4 * n, 0);
            for k in 0..n {
                let (i, j) = (k % cols, k / cols);
                let prev = match (i, j) {
                    (0, 0) => 0,
                    (0, _) => samples[k - cols].to_bits(),
                    _ => samples[k - 1].to_bits(),
                };
                let x = (samples[k].to_bits() ^ prev).to_le_bytes();
                for (b, &byte) in x.iter().enumerate() {
                    out[base + b * n + k] = byte;
                }
            }
        }
    }
    (coding, out)
}

/// A payload back into a page; `Err` says what does not match the layout and the index.
pub fn decode_payload(
    b: &[u8],
    layout: &Layout,
    id: PageId,
    coding: Coding,
) -> Result<Page, String> {
    let rect = layout.rect(id.level, id.px, id.py);
    let count = rect.samples();
    let base = PAYLOAD_PREFIX + 12 * rect.tiles();
    let fixed = base + coding.bytes_per_sample() * count;
    let want = match coding {
        Coding::I16Exceptions if b.len() >= fixed + 4 => {
            let k = u32::from_le_bytes(b[fixed..fixed + 4].try_into().expect("4")) as usize;
            if k > count {
                return Err(format!("{k} exceptions for {count} samples"));
            }
            fixed + 4 + 8 * k
        }
        Coding::I16Exceptions => fixed + 4,
        _ => fixed,
    };
    if b.len() != want {
        return Err(format!(
            "decompressed to {} bytes, the layout says {want}",
            b.len()
        ));
    }
    let u = |k: usize| u32::from_le_bytes(b[k..k + 4].try_into().expect("4"));
    let named = (u(0), u(4), u(8));
    if named != (id.level, id.px, id.py) {
        return Err(format!(
            "the page's own header names level {} page ({}, {})",
            named.0, named.1, named.2
        ));
    }
    if u(12) != coding.code() {
        return Err(format!(
            "coded {} in the page, {} in the index",
            u(12),
            coding.code()
        ));
    }
    let n = rect.tiles();
    let f = |k: usize| f32::from_le_bytes(b[k..k + 4].try_into().expect("4"));
    let table = |t: usize| -> Vec<f32> {
        (0..n)
            .map(|i| f(PAYLOAD_PREFIX + 4 * (t * n + i)))
            .collect()
    };
    let (eps, min, max) = (table(0), table(1), table(2));
    let cols = rect.cols as usize;
    let samples = match coding {
        Coding::I16Gradient | Coding::I16Exceptions => {
            let mut s = vec![0i16; count];
            for k in 0..count {
                let (i, j) = (k % cols, k / cols);
                let r = unzigzag(u16::from_le_bytes([b[base + 2 * k], b[base + 2 * k + 1]]));
                s[k] = predict(&s, cols, i, j).wrapping_add(r);
            }
            let mut s: Vec<f32> = s.into_iter().map(f32::from).collect();
            if coding == Coding::I16Exceptions {
                let mut prev = None;
                for e in b[fixed + 4..].chunks_exact(8) {
                    let k = u32::from_le_bytes(e[..4].try_into().expect("4")) as usize;
                    if k >= count || prev.is_some_and(|p| k <= p) {
                        return Err(format!(
                            "exception at sample {k}: not increasing within 0..{count}"
                        ));
                    }
                    prev = Some(k);
                    s[k] = f32::from_bits(u32::from_le_bytes(e[4..].try_into().expect("4")));
                }
            }
            s
        }
        Coding::F32Xor => {
            let mut s: Vec<f32> = Vec::with_capacity(count);
            for k in 0..count {
                let (i, j) = (k % cols, k / cols);
                let prev = match (i, j) {
                    (0, 0) => 0,
                    (0, _) => s[k - cols].to_bits(),
                    _ => s[k - 1].to_bits(),
                };
                let x = u32::from_le_bytes([
                    b[base + k],
                    b[base + count + k],
                    b[base + 2 * count + k],
                    b[base + 3 * count + k],
                ]);
                s.push(f32::from_bits(x ^ prev));
            }
            s
        }
    };
    if let Some(k) = samples.iter().position(|h| !h.is_finite()) {
        return Err(format!("sample ({}, {}) is not finite", k % cols, k / cols));
    }
    Ok(Page {
        id,
        rect,
        coding,
        samples,
        eps,
        min,
        max,
    })
}
