//! A prefetched refined tile gathered a band of rows per frame (pure).
//!
//! A refined tile's slot is 257² or 513² samples (0.26–1 MB): gathered from the grid in one
//! frame — cold rows, at a stride for a coarse tile — it cost that frame 50–200 µs on the frame
//! thread (Sierra Nevada cruise, 1280×720), a CPU frame's p99 by itself. A prefetch is for a
//! tile the eye needs some frames from now, so nothing forces it into one frame: a tile larger
//! than [`BandedTile::band_samples`] is gathered here at most one band a frame and uploaded
//! whole once every row is in hand, through the prefetch's usual admission (its LRU slot and
//! its staging are taken only then, so a tile still gathering holds no slot and can never be
//! drawn half-filled). A tile's samples are a pure function of its rectangle, so rows gathered
//! in earlier frames are as good as rows gathered now. A drawn tile is never banded: it is
//! needed this frame.
//!
//! Invariants (tested below and in `plan_tests.rs`):
//! - at most one band is gathered per frame, of at most `band_samples` samples, and the tile
//!   is given in a later frame than its last band;
//! - [`BandedTile::take`] gives a tile's samples only once all its rows are in, equal to what
//!   one gather of the whole rectangle gives;
//! - one tile is gathered at a time: another waits until it is taken, or until the tile in
//!   hand has not been asked for in [`STALE_FRAMES`] frames (the eye turned away).

use aerie_terrain::pool::TileKey;
use aerie_terrain::source::SampleRect;

use crate::render::gathered::Gatherer;

/// Samples a prefetch gathers for one large tile in one frame, by default: 32 Ki samples,
/// 128 KB (a 257² slot in 3 bands, a 513² one in 9).
pub const PREFETCH_BAND_SAMPLES: usize = 1 << 15;

/// Frames a tile in hand may go unasked before another takes its place.
pub const STALE_FRAMES: u64 = 30;

/// Where a large prefetched tile stands ([`BandedTile::advance`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Banded {
    /// Every row is in hand: [`BandedTile::take`] gives them.
    Ready,
    /// Rows are missing; a band was gathered this frame (or another tile's was).
    Gathering,
    /// Another tile is being gathered: this one waits.
    Waiting,
    /// The source does not hold the next band's samples now (asked for by the caller).
    NotResident,
}

/// The one large prefetched tile being gathered ([`Banded`]).
#[derive(Debug)]
pub struct BandedTile {
    /// Samples of one band at most; tiles up to this size are gathered whole.
    pub band_samples: usize,
    key: Option<TileKey>,
    rect: SampleRect,
    samples: Vec<f32>,
    /// Rows in hand, from the rectangle's first.
    rows: u32,
    /// The frame of the last band gathered, and the last frame the tile was asked for.
    banded_at: Option<u64>,
    asked_at: u64,
    /// Bands gathered so far (a statistic for the tests and the curious).
    pub bands: u64,
}

impl Default for BandedTile {
    fn default() -> Self {
        Self::new(PREFETCH_BAND_SAMPLES)
    }
}

impl BandedTile {
    pub fn new(band_samples: usize) -> Self {
        Self {
            band_samples: band_samples.max(1),
            key: None,
            rect: SampleRect {
                level: 0,
                origin: [0, 0],
                size: [0, 0],
            },
            samples: Vec::new(),
            rows: 0,
            banded_at: None,
            asked_at: 0,
            bands: 0,
        }
    }

    /// Whether a tile of `rect` is gathered in bands.
    pub fn bands_needed(&self, rect: &SampleRect) -> bool {
        rect.len() > self.band_samples
    }

    /// Moves tile `key` (its samples `rect`) on in `frame`: starts it when no other tile is in
    /// hand (or the one in hand went stale), and gathers its next band when no band was
    /// gathered this frame.
    pub fn advance(
        &mut self,
        key: TileKey,
        rect: SampleRect,
        frame: u64,
        gatherer: &mut Gatherer,
    ) -> Banded {
        if self.key != Some(key) || self.rect != rect {
            let stale = self.key.is_none() || frame >= self.asked_at + STALE_FRAMES;
            if !stale {
                return Banded::Waiting;
            }
            self.key = Some(key);
            self.rect = rect;
            self.rows = 0;
            self.samples.clear();
            self.samples.resize(rect.len(), 0.0);
        }
        self.asked_at = frame;
        // The frame that gathered a band does not also stage the tile: its last band's frame
        // would bear both.
        if self.banded_at == Some(frame) {
            return Banded::Gathering;
        }
        if self.rows == rect.size[1] {
            return Banded::Ready;
        }
        let width = rect.size[0].max(1) as usize;
        let rows = ((self.band_samples / width).max(1) as u32).min(rect.size[1] - self.rows);
        let band = SampleRect {
            level: rect.level,
            origin: [
                rect.origin[0],
                rect.origin[1] + self.rows as i64 * rect.step() as i64,
            ],
            size: [rect.size[0], rows],
        };
        let at = self.rows as usize * width;
        let out = &mut self.samples[at..at + band.len()];
        match gatherer.gather_rect(&band, out) {
            Ok(()) => {
                self.rows += rows;
                self.banded_at = Some(frame);
                self.bands += 1;
                Banded::Gathering
            }
            Err(_) => Banded::NotResident,
        }
    }

    /// The tile in hand, if any.
    pub fn key(&self) -> Option<TileKey> {
        self.key
    }

    /// Forgets the tile in hand (it became resident another way: a frame drew it).
    pub fn forget(&mut self) {
        self.key = None;
    }

    /// The samples of tile `key` when every row is in hand (row-major, its rectangle's), for
    /// the caller to stage; then the tile is forgotten.
    pub fn take(&mut self, key: TileKey) -> Option<&[f32]> {
        if self.key != Some(key) || self.rows != self.rect.size[1] {
            return None;
        }
        self.key = None;
        Some(&self.samples)
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use aerie_terrain::dataset::Dataset;
    use aerie_terrain::source::{InMemoryTerrain, TerrainSource};
    use aerie_terrain::Heightfield;

    use super::*;

    fn source() -> Arc<dyn TerrainSource> {
        let n = 300;
        let hf = Heightfield {
            width: n,
            height: n,
            spacing_x: 10.0,
            spacing_y: 10.0,
            heights: (0..n * n).map(|k| (k % 977) as f32 * 0.5).collect(),
            geo: None,
            voids_filled: 0,
            spacing_note: String::new(),
        };
        Arc::new(InMemoryTerrain::new(Arc::new(Dataset::from_heightfield(
            hf,
            "bands".into(),
        ))))
    }

    fn key(tx: u32) -> TileKey {
        TileKey {
            level: 3,
            tx,
            ty: 1,
            refinement: 2,
        }
    }

    /// A 65 × 65 tile at stride 2 in bands of 1,000 samples: one band a frame (15 rows), asked
    /// twice in a frame still one band, its samples withheld while rows are missing, ready the
    /// frame after its last band with exactly the samples one gather of the rectangle gives;
    /// another tile waits meanwhile and starts once it is taken.
    #[test]
    fn a_tile_comes_a_band_a_frame_and_equals_one_gather() {
        let src = source();
        let mut g = Gatherer::new(src.clone());
        let mut b = BandedTile::new(1000);
        let rect = SampleRect {
            level: 1,
            origin: [10, 20],
            size: [65, 65],
        };
        assert!(b.bands_needed(&rect));
        let other = SampleRect {
            origin: [140, 20],
            ..rect
        };
        let mut frames = 0;
        for frame in 0..10 {
            g.begin_frame();
            let state = b.advance(key(0), rect, frame, &mut g);
            assert_eq!(b.advance(key(0), rect, frame, &mut g), state, "asked again");
            assert_eq!(b.advance(key(5), other, frame, &mut g), Banded::Waiting);
            assert!(b.take(key(5)).is_none());
            if state == Banded::Ready {
                break;
            }
            assert_eq!(state, Banded::Gathering);
            if frame < 4 {
                assert!(b.take(key(0)).is_none(), "frame {frame}: rows missing");
            }
            frames += 1;
        }
        assert_eq!((frames, b.bands), (5, 5), "65 rows of 15");
        let mut whole = vec![0.0; rect.len()];
        src.gather(&rect, &mut whole).unwrap();
        assert_eq!(b.take(key(0)).unwrap(), whole.as_slice());
        assert!(b.take(key(0)).is_none(), "taken once");
        assert_eq!(b.advance(key(5), other, 11, &mut g), Banded::Gathering);
    }

    /// A tile in hand that is no longer asked for gives way after STALE_FRAMES frames.
    #[test]
    fn a_tile_left_unasked_gives_way() {
        let mut g = Gatherer::new(source());
        let mut b = BandedTile::new(1000);
        let rect = SampleRect {
            level: 0,
            origin: [0, 0],
            size: [100, 100],
        };
        assert_eq!(b.advance(key(0), rect, 0, &mut g), Banded::Gathering);
        let other = SampleRect {
            origin: [150, 0],
            ..rect
        };
        assert_eq!(
            b.advance(key(1), other, STALE_FRAMES - 1, &mut g),
            Banded::Waiting
        );
        assert_eq!(
            b.advance(key(1), other, STALE_FRAMES, &mut g),
            Banded::Gathering
        );
        assert!(b.take(key(0)).is_none());
    }
}
