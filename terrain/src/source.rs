//! Where the renderer's samples come from: the [`TerrainSource`] trait behind the clipmap's
//! level strips and the refined-tile pools, so a dataset held in memory and a tile store
//! streamed page by page are one path for the renderer.
//!
//! **Contract.** A request for samples is a [`SampleRect`]: `size` samples at level-0 sample
//! coordinates `origin + (i, j) · 2^level`, clamped into the grid (a rectangle reaching past
//! the edge repeats the edge, as [`crate::gather::gather`] does). Every method is non-blocking:
//! the frame thread calls them, and it never waits on I/O or decompression. A source answers
//! [`TerrainSource::gather`] only for rectangles that are wholly resident (else
//! [`NotResident`] names the first missing page and `out` is left unspecified); it loads what
//! [`TerrainSource::request`] asks on its own threads, largest priority first. An in-memory
//! source is always resident and ignores requests.

use crate::dataset::Dataset;
use crate::gather::gather;
use crate::GeoReference;

/// What a source serves, without its samples: everything the clipmap, the selection's grid,
/// the uniforms and the pose mapping need. Sizes are those of [`Dataset`] (padded to
/// `2^K + 1`, padding east/north).
#[derive(Debug, Clone, PartialEq)]
pub struct SourceGrid {
    /// Padded samples per row.
    pub width: u32,
    /// Padded rows.
    pub height: u32,
    /// Real samples per row (columns at or east of it are padding).
    pub valid_width: u32,
    /// Real rows (rows at or north of it are padding).
    pub valid_height: u32,
    /// Metres between columns (east-west) and rows (north-south).
    pub spacing_x: f64,
    pub spacing_y: f64,
    pub geo: Option<GeoReference>,
    /// [`Dataset::checksum`] of the padded level-0 samples (what a bake is checked against).
    pub checksum: u32,
    /// Where the data came from, one line.
    pub description: String,
}

/// `size` samples at level-0 sample coordinates `origin + (i, j) · 2^level`, clamped to the
/// grid (see the module documentation). This is what one upload job reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SampleRect {
    pub level: u32,
    pub origin: [i64; 2],
    pub size: [u32; 2],
}

impl SampleRect {
    /// The distance between samples in level-0 samples.
    pub fn step(&self) -> u32 {
        1 << self.level
    }

    /// Samples in the rectangle.
    pub fn len(&self) -> usize {
        self.size[0] as usize * self.size[1] as usize
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The rectangle of an upload with a power-of-two `step`; None for any other step.
    pub fn of_step(origin: [i64; 2], step: u32, size: [u32; 2]) -> Option<SampleRect> {
        step.is_power_of_two().then(|| SampleRect {
            level: step.trailing_zeros(),
            origin,
            size,
        })
    }
}

/// A wish for the samples of `rect`, most wanted first by `priority` (larger first: the
/// renderer passes the projected error in pixels the tile would remove, or the strip's
/// distance ranking for level strips; prefetches pass less than anything drawn).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleWant {
    pub rect: SampleRect,
    pub priority: f32,
}

/// [`TerrainSource::gather`] could not answer: a page it needs is not resident (it is asked
/// for when this is returned), or failed to load (a damaged page is never drawn: the renderer
/// keeps it at the best resident level and it is counted late).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("level {level} page ({px}, {py}) is not resident{}", if *.failed { " (it failed to load)" } else { "" })]
pub struct NotResident {
    pub level: u32,
    pub px: u32,
    pub py: u32,
    /// True when the page was read and refused (checksum or content): it will not come.
    pub failed: bool,
}

/// Running totals of a source since it was opened (all zero for an in-memory source).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StreamStats {
    /// Bytes of decoded pages resident now, and the budget they may not exceed.
    pub resident_bytes: u64,
    pub budget_bytes: u64,
    pub resident_pages: u64,
    /// `gather`/`is_resident` answers that found every page resident, and those that did not.
    pub hits: u64,
    pub misses: u64,
    /// Pages read from the file and decoded; pages refused (checksum, content); evicted.
    pub loaded: u64,
    pub failed: u64,
    pub evicted: u64,
    /// Requests waiting for a worker now.
    pub queued: u64,
}

/// Where the renderer's samples come from (see the module documentation).
pub trait TerrainSource: Send + Sync {
    /// The grid served.
    fn grid(&self) -> &SourceGrid;

    /// Whether [`TerrainSource::gather`] of `rect` would succeed now. Never blocks.
    fn is_resident(&self, rect: &SampleRect) -> bool;

    /// Fills `out` (row-major, `rect.size[0]` per row, south row first) when every page of
    /// `rect` is resident. Never blocks on I/O.
    fn gather(&self, rect: &SampleRect, out: &mut [f32]) -> Result<(), NotResident>;

    /// Asks for the pages of `wants` that are not resident, most wanted first; replaces the
    /// wishes of earlier calls that no worker has started. Never blocks.
    fn request(&self, wants: &[SampleWant]);

    /// Running totals.
    fn stats(&self) -> StreamStats {
        StreamStats::default()
    }

    /// Texels per level sample per axis (k) of the draped imagery served with the samples
    /// (a store's imagery layer, [`crate::drape::levels`]), or None without.
    fn imagery_texels_per_sample(&self) -> Option<u32> {
        None
    }

    /// The store's imagery layer this source serves, if any (the renderer drapes a whole level
    /// of it, [`crate::store::read_level`]).
    fn imagery_layer(&self) -> Option<&crate::store::ImageryLayer> {
        None
    }

    /// The level imagery of `rect` (a level strip: its origin on its level's grid): RGBA8
    /// texels `[s·k, (s + n)·k)` per axis of `rect.level`'s raster, `s = origin >> level`,
    /// row-major, south row first, `rect.size[0]·k` per row; texels outside the raster
    /// transparent. Succeeds exactly when [`TerrainSource::gather`] of `rect` would; never
    /// blocks. Without imagery: all transparent.
    fn gather_imagery(&self, _rect: &SampleRect, out: &mut [u8]) -> Result<(), NotResident> {
        out.fill(0);
        Ok(())
    }
}

impl Dataset {
    /// The grid this dataset serves as a [`TerrainSource`].
    pub fn source_grid(&self) -> SourceGrid {
        SourceGrid {
            width: self.hf.width as u32,
            height: self.hf.height as u32,
            valid_width: self.valid_width as u32,
            valid_height: self.valid_height as u32,
            spacing_x: self.hf.spacing_x,
            spacing_y: self.hf.spacing_y,
            geo: self.hf.geo.clone(),
            checksum: self.checksum(),
            description: self.source.clone(),
        }
    }
}

/// A dataset held whole in memory: always resident, requests ignored.
pub struct InMemoryTerrain {
    dataset: std::sync::Arc<Dataset>,
    grid: SourceGrid,
    /// The imagery layer of the store the dataset was read from (`--load-whole`).
    imagery: Option<std::sync::Arc<crate::store::ImageryLayer>>,
    /// Its pages read so far for [`TerrainSource::gather_imagery`], most recent last (at most
    /// [`WHOLE_IMAGERY_PAGES`]); None: the page is damaged (named once, drawn transparent).
    imagery_pages: std::sync::Mutex<Vec<WholeImageryPage>>,
}

/// Imagery pages an [`InMemoryTerrain`] keeps decoded: a few windows' worth of cells.
pub const WHOLE_IMAGERY_PAGES: usize = 64;

type WholeImageryPage = (
    crate::store::PageId,
    Option<std::sync::Arc<crate::store::ImageryPage>>,
);

impl InMemoryTerrain {
    /// Computes the dataset's checksum once (a pass over the samples).
    pub fn new(dataset: std::sync::Arc<Dataset>) -> Self {
        let grid = dataset.source_grid();
        InMemoryTerrain {
            dataset,
            grid,
            imagery: None,
            imagery_pages: Default::default(),
        }
    }

    /// With a checksum the caller already has (e.g. the bake's, checked against the data).
    pub fn with_checksum(dataset: std::sync::Arc<Dataset>, checksum: u32) -> Self {
        let ds = &dataset;
        let grid = SourceGrid {
            width: ds.hf.width as u32,
            height: ds.hf.height as u32,
            valid_width: ds.valid_width as u32,
            valid_height: ds.valid_height as u32,
            spacing_x: ds.hf.spacing_x,
            spacing_y: ds.hf.spacing_y,
            geo: ds.hf.geo.clone(),
            checksum,
            description: ds.source.clone(),
        };
        InMemoryTerrain {
            dataset,
            grid,
            imagery: None,
            imagery_pages: Default::default(),
        }
    }

    /// With the imagery layer of the store the dataset was read from.
    pub fn with_imagery(mut self, layer: crate::store::ImageryLayer) -> Self {
        self.imagery = Some(std::sync::Arc::new(layer));
        self
    }

    pub fn dataset(&self) -> &std::sync::Arc<Dataset> {
        &self.dataset
    }
}

impl TerrainSource for InMemoryTerrain {
    fn grid(&self) -> &SourceGrid {
        &self.grid
    }

    fn imagery_layer(&self) -> Option<&crate::store::ImageryLayer> {
        self.imagery.as_deref()
    }

    fn is_resident(&self, _rect: &SampleRect) -> bool {
        true
    }

    fn gather(&self, rect: &SampleRect, out: &mut [f32]) -> Result<(), NotResident> {
        gather(&self.dataset.hf, rect.origin, rect.step(), rect.size, out);
        Ok(())
    }

    fn request(&self, _wants: &[SampleWant]) {}

    fn imagery_texels_per_sample(&self) -> Option<u32> {
        self.imagery.as_ref().map(|l| l.texels_per_sample())
    }

    /// Reads the pages on the spot (the store was asked to be held whole; a page is a few
    /// tens of KB), keeping the last [`WHOLE_IMAGERY_PAGES`]; always succeeds.
    fn gather_imagery(&self, rect: &SampleRect, out: &mut [u8]) -> Result<(), NotResident> {
        out.fill(0);
        let Some(layer) = self.imagery.as_deref() else {
            return Ok(());
        };
        let valid = [self.grid.valid_width, self.grid.valid_height];
        let r = crate::store::imagery_rect(
            layer.layout(),
            layer.texels_per_sample(),
            valid,
            (rect.level, rect.origin, rect.size),
        );
        let mut kept = self.imagery_pages.lock().unwrap_or_else(|e| e.into_inner());
        for &id in &r.pages {
            let page = match kept.iter().position(|(p, _)| *p == id) {
                Some(i) => {
                    let e = kept.remove(i);
                    kept.push(e.clone());
                    e.1
                }
                None => {
                    let page = match layer.read_page(id) {
                        Ok(p) => Some(std::sync::Arc::new(p)),
                        Err(e) => {
                            eprintln!("warning: {e}; drawn without imagery there");
                            None
                        }
                    };
                    if kept.len() == WHOLE_IMAGERY_PAGES {
                        kept.remove(0);
                    }
                    kept.push((id, page.clone()));
                    page
                }
            };
            if let Some(p) = page {
                crate::store::copy_page_texels(&r, &p, out);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::Heightfield;

    #[test]
    fn in_memory_source_gathers_as_gather_does() {
        let (w, h) = (9usize, 9usize);
        let hf = Heightfield {
            width: w,
            height: h,
            spacing_x: 2.0,
            spacing_y: 3.0,
            heights: (0..w * h).map(|k| (k * 7 % 13) as f32).collect(),
            geo: None,
            voids_filled: 0,
            spacing_note: String::new(),
        };
        let ds = Arc::new(Dataset::from_heightfield(hf, "test".into()));
        let src = InMemoryTerrain::new(ds.clone());
        assert_eq!(src.grid().width, 9);
        assert_eq!(src.grid().checksum, ds.checksum());
        let rect = SampleRect::of_step([-2, 3], 2, [4, 3]).unwrap();
        assert_eq!(rect.level, 1);
        assert!(src.is_resident(&rect));
        let mut a = vec![0.0; rect.len()];
        let mut b = vec![0.0; rect.len()];
        src.gather(&rect, &mut a).unwrap();
        gather(&ds.hf, [-2, 3], 2, [4, 3], &mut b);
        assert_eq!(a, b);
        assert!(SampleRect::of_step([0, 0], 3, [1, 1]).is_none());
    }
}
