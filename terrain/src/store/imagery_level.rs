//! One whole level of a store's imagery layer as one raster: what the renderer drapes when it
//! draws a store with a layer (the finest level that fits its texture budget), and the
//! oracle's view of a level. Level `L`'s raster is `level_extent(grid, k, L)` texels, texel
//! `t`'s centre at grid coordinate `(t + 0.5) · 2^L / k − 0.5` ([`crate::drape::levels`]).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use aerie_io::FileSystem;

use super::error::{PageError, PageId, StoreError};
use super::imagery::{imagery_path, ImageryLayer};
use super::imagery_write::store_grid;
use super::read::Store;
use crate::drape::level_extent;

/// The imagery layer beside the store at `path` ([`imagery_path`]) when that file exists; a
/// layer that exists but cannot be used is refused (naming its field), never ignored.
pub fn open_imagery_beside(
    fs: &Arc<dyn FileSystem>,
    path: &Path,
    store: &Store,
) -> Result<Option<ImageryLayer>, StoreError> {
    let at = imagery_path(path);
    match fs.open(&at) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        _ => {}
    }
    let grid = store_grid(store)?;
    ImageryLayer::open_in(fs.clone(), &at, store.header(), store.layout(), &grid).map(Some)
}

/// A level of the imagery layer, read whole.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelImagery {
    /// The layer it was read from.
    pub layer: PathBuf,
    pub level: u32,
    /// Texels per level-0 sample per axis of level 0 (the level's texels cover `2^L / k`
    /// samples each).
    pub texels_per_sample: u32,
    pub width: usize,
    pub height: usize,
    /// RGBA8, straight alpha, sRGB, row 0 south.
    pub rgba: Vec<u8>,
}

impl LevelImagery {
    /// Level-0 samples per texel per axis: `2^L / k`.
    pub fn samples_per_texel(&self) -> f64 {
        f64::from(1u32 << self.level) / f64::from(self.texels_per_sample)
    }
}

/// The finest level of `layer` whose raster fits `max_side` texels per axis and, with a full
/// mip chain (4/3 of its 4 bytes a texel), `max_bytes`; None when not even the coarsest does.
pub fn choose_level(layer: &ImageryLayer, max_bytes: u64, max_side: usize) -> Option<u32> {
    let k = layer.texels_per_sample();
    (0..layer.layout().levels.len() as u32).find(|&l| {
        let (w, h) = level_extent(layer.grid(), k, l);
        let bytes = (w * h) as f64 * 4.0 * 4.0 / 3.0;
        w.max(h) <= max_side && bytes <= max_bytes as f64
    })
}

/// Reads every page of `level` (verified as [`ImageryLayer::read_page`] does) into one raster;
/// `progress(done, pages)`. A damaged page is left transparent (drawn without imagery, as the
/// streamed loader draws it) and returned, named, with the raster.
pub fn read_level(
    layer: &ImageryLayer,
    level: u32,
    progress: &dyn Fn(u64, u64),
) -> (LevelImagery, Vec<PageError>) {
    let k = layer.texels_per_sample();
    let (w, h) = level_extent(layer.grid(), k, level);
    let mut rgba = vec![0u8; w * h * 4];
    let g = layer.layout().levels[level as usize];
    let pages = u64::from(g.pages_x) * u64::from(g.pages_y);
    let mut done = 0;
    let mut failed = Vec::new();
    for py in 0..g.pages_y {
        for px in 0..g.pages_x {
            done += 1;
            progress(done, pages);
            let p = match layer.read_page(PageId { level, px, py }) {
                Ok(p) => p,
                Err(e) => {
                    failed.push(e);
                    continue;
                }
            };
            let [ox, oy] = p.origin;
            let [pw, ph] = p.size;
            for y in 0..ph {
                let src = &p.rgba[y * pw * 4..(y + 1) * pw * 4];
                let at = ((oy + y) * w + ox) * 4;
                rgba[at..at + pw * 4].copy_from_slice(src);
            }
        }
    }
    let l = LevelImagery {
        layer: layer.path().to_path_buf(),
        level,
        texels_per_sample: k,
        width: w,
        height: h,
        rgba,
    };
    (l, failed)
}
