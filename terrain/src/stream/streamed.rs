//! [`StreamedStore`]: a tile store served as a [`TerrainSource`] from the page cache, filled by
//! the loader's worker threads. `is_resident`, `gather` and `request` take the cache's lock
//! for a lookup or a queue update only (no I/O, no decompression, never a wait for a page);
//! the samples are copied after the lock is released.
//!
//! What each call does to the cache and the queue: `is_resident` and `gather` mark the pages
//! they find as used (LRU); `gather` also wishes each page it found missing, after anything
//! requested (priority 0); `request` replaces every waiting wish by its own (the pinned pages
//! not yet in stay wished, after its own) and marks the resident pages it names as used. A failed page
//! is never wished again.

use std::ops::Range;
use std::path::Path;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use aerie_io::FileSystem;

use crate::bake::ErrorBake;
use crate::query::SurfaceGrid;
use crate::source::{NotResident, SampleRect, SampleWant, SourceGrid, StreamStats, TerrainSource};
use crate::store::{
    copy_page_texels, imagery_rect, open_imagery_beside, ImageryLayer, PageId, Store, StoreError,
};

use super::loader::{spawn_workers, Loaded, Shared};
use super::rect_pages::{rect_pages, RectPages};
use super::surface::StreamedSurface;

/// How a store is streamed.
#[derive(Debug, Clone)]
pub struct StreamParams {
    /// Bytes of decoded pages the cache may hold (never exceeded).
    pub cache_bytes: u64,
    /// Worker threads that read and decode pages (≥ 1).
    pub workers: usize,
    /// Where the store is read (tests inject latency and faults).
    pub fs: Arc<dyn FileSystem>,
}

impl Default for StreamParams {
    /// 1 GiB of pages, 2 workers, the real file system.
    fn default() -> Self {
        StreamParams {
            cache_bytes: 1 << 30,
            workers: 2,
            fs: aerie_io::real(),
        }
    }
}

/// The share of the cache budget the pinned coarsest levels may take.
const PIN_SHARE: u64 = 4;
/// The budget must hold at least this many full-size pages beside the pinned ones.
const MIN_PAGES: u64 = 4;
/// Priority of the pinned pages until the first request, and of `wait_resident`'s wishes:
/// before anything drawn.
const FIRST: f32 = f32::INFINITY;
/// Priority of a page `gather` found missing, and of the pinned pages not yet in once the
/// renderer requests: after anything it asked for (what is on screen comes first; the pins
/// fill in whenever the workers are not busy with it, coarsest first on equal priority).
const LAST: f32 = 0.0;

/// The loader's own totals, beyond [`StreamStats`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct LoaderStats {
    /// Pages a worker is reading or decoding now.
    pub in_flight: u64,
    /// Stored (compressed) bytes read from the file.
    pub bytes_read: u64,
    /// Pinned pages and their decoded bytes (resident or on their way).
    pub pinned_pages: u64,
    pub pinned_bytes: u64,
    /// Pinned pages not resident yet.
    pub pinned_missing: u64,
    /// Pages read that did not fit the budget beside the pinned ones.
    pub too_large: u64,
}

/// A tile store streamed page by page (see the module documentation).
pub struct StreamedStore {
    shared: Arc<Shared>,
    grid: SourceGrid,
    pinned: Range<u32>,
    pinned_pages: u64,
    pinned_bytes: u64,
    workers: Vec<JoinHandle<()>>,
}

impl std::fmt::Debug for StreamedStore {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StreamedStore")
            .field("store", self.shared.store())
            .field("pinned", &self.pinned)
            .finish()
    }
}

impl StreamedStore {
    /// Opens the store at `path` (header, index, trailer, bake section and the few pages
    /// [`Store::check_consistency`] reads: nothing proportional to the samples), starts the workers and asks for the pinned pages: the
    /// coarsest levels, from the top down, while they take at most a quarter of the budget.
    /// Returns at once, before any page arrived ([`StreamedStore::wait_pinned`] waits for
    /// them), with the store's whole error bake (shared with the loader, which checks every
    /// page's tables against it: one copy in memory, ≈ 70 MB for a 32769² store).
    pub fn open(
        path: &Path,
        params: StreamParams,
    ) -> Result<(StreamedStore, Arc<ErrorBake>), StoreError> {
        let store = Store::open_in(params.fs.clone(), path)?;
        let bake = store.read_bake()?;
        store.check_consistency(&bake)?;
        if params.workers == 0 {
            return Err(StoreError::Params {
                reason: "streaming needs at least one worker thread".into(),
            });
        }
        let layout = store.layout().clone();
        let imagery = open_imagery_beside(&params.fs, path, &store)?;
        let full = Loaded::bytes_with(
            &layout,
            imagery.as_ref(),
            PageId {
                level: 0,
                px: 0,
                py: 0,
            },
        );
        if params.cache_bytes < MIN_PAGES * full {
            return Err(StoreError::Params {
                reason: format!(
                    "a page cache of {} bytes cannot hold {MIN_PAGES} pages of {full} bytes; give it at least {} bytes",
                    params.cache_bytes,
                    MIN_PAGES * full
                ),
            });
        }
        let h = store.header().clone();
        let grid = SourceGrid {
            width: h.width,
            height: h.height,
            valid_width: h.valid_width,
            valid_height: h.valid_height,
            spacing_x: h.spacing_x,
            spacing_y: h.spacing_y,
            geo: h.geo.clone(),
            checksum: h.source_checksum,
            description: format!("{} (store of {})", path.display(), h.sources.join(", ")),
        };
        // Pin whole levels from the coarsest down while they fit a quarter of the budget.
        let level_pages = |l: u32| -> Vec<PageId> {
            let g = layout.levels[l as usize];
            (0..g.pages_y)
                .flat_map(|py| (0..g.pages_x).map(move |px| PageId { level: l, px, py }))
                .collect()
        };
        let mut pinned_bytes = 0u64;
        let mut first = h.levels;
        for l in (0..h.levels).rev() {
            let bytes: u64 = level_pages(l)
                .iter()
                .map(|&id| Loaded::bytes_with(&layout, imagery.as_ref(), id))
                .sum();
            if pinned_bytes + bytes > params.cache_bytes / PIN_SHARE {
                break;
            }
            pinned_bytes += bytes;
            first = l;
        }
        let pinned = first..h.levels;
        let bake = Arc::new(bake);
        let shared = Arc::new(Shared::new(
            store,
            bake.clone(),
            imagery,
            params.cache_bytes,
        ));
        let mut pinned_pages = 0;
        {
            let mut g = shared.lock();
            for l in pinned.clone() {
                for id in level_pages(l) {
                    g.cache.pin(id);
                    g.pinned_missing.insert(id);
                    g.queue.add(id, FIRST);
                    pinned_pages += 1;
                }
            }
        }
        let workers = spawn_workers(&shared, params.workers).map_err(|e| StoreError::Io {
            path: path.to_path_buf(),
            reason: format!("cannot start a page worker thread: {e}"),
        })?;
        shared.wake_workers();
        Ok((
            StreamedStore {
                shared,
                grid,
                pinned,
                pinned_pages,
                pinned_bytes,
                workers,
            },
            bake,
        ))
    }

    /// The opened store (header, layout, index).
    pub fn store(&self) -> &Store {
        self.shared.store()
    }

    /// The levels whose pages are pinned (never evicted), coarsest last; empty when not even
    /// the coarsest level fits a quarter of the budget.
    pub fn pinned_levels(&self) -> Range<u32> {
        self.pinned.clone()
    }

    /// A snapshot of the resident level-0 pages for the host's queries (height of terrain,
    /// line of sight): see [`StreamedSurface`]. Takes the lock once to clone the pages'
    /// `Arc`s (no samples are copied); a tile not resident answers `Pending`.
    pub fn surface(&self) -> StreamedSurface {
        let s = self.shared.store();
        let h = s.header();
        let grid = SurfaceGrid {
            width: h.width as usize,
            height: h.height as usize,
            valid_width: h.valid_width as usize,
            valid_height: h.valid_height as usize,
            spacing_x: h.spacing_x,
            spacing_y: h.spacing_y,
            tile_quads: h.tile_size as usize - 1,
            levels: h.levels,
        };
        let g = self.shared.lock();
        let pages = g
            .cache
            .iter()
            .filter(|(id, _)| id.level == 0)
            .map(|(id, p)| ((id.px, id.py), p.clone()))
            .collect();
        drop(g);
        StreamedSurface {
            grid,
            page_tiles: h.page_tiles,
            bake: self.shared.bake().clone(),
            pages,
        }
    }

    /// The loader's totals.
    pub fn loader_stats(&self) -> LoaderStats {
        let g = self.shared.lock();
        LoaderStats {
            in_flight: g.queue.in_flight() as u64,
            bytes_read: g.bytes_read,
            pinned_pages: self.pinned_pages,
            pinned_bytes: self.pinned_bytes,
            pinned_missing: g.pinned_missing.len() as u64,
            too_large: g.too_large,
        }
    }

    /// The pages that failed to load, with the reason of each (sorted by page).
    pub fn failures(&self) -> Vec<(PageId, String)> {
        let g = self.shared.lock();
        let mut v: Vec<(PageId, String)> = g.failed.iter().map(|(k, v)| (*k, v.clone())).collect();
        v.sort_by_key(|(p, _)| (p.level, p.py, p.px));
        v
    }

    fn pages_of(&self, rect: &SampleRect) -> RectPages {
        let s = self.shared.store();
        rect_pages(s.layout(), self.grid.width, self.grid.height, rect)
    }

    /// Blocks until every page of `rects` is resident or failed, asking for the missing ones
    /// before anything else; `Err` names a page that failed (`failed: true`, once the others
    /// are in) or one still missing at `timeout`. **For start-up and tests only — never on the frame thread**, which uses
    /// `is_resident`/`gather` and draws coarser what is not there.
    pub fn wait_resident(
        &self,
        rects: &[SampleRect],
        timeout: Duration,
    ) -> Result<(), NotResident> {
        let ids: Vec<PageId> = {
            let mut v: Vec<PageId> = rects
                .iter()
                .flat_map(|r| self.pages_of(r).pages().collect::<Vec<_>>())
                .collect();
            v.sort_by_key(|p| (p.level, p.py, p.px));
            v.dedup();
            v
        };
        self.wait_pages(&ids, timeout)
    }

    /// Decoded bytes that must be resident at once for `rects` to be, with the pinned levels
    /// (pages counted once) when `with_pins`: above the cache budget, [`Self::wait_resident`]
    /// on them cannot succeed, since pages read for it evict each other.
    pub fn bytes_resident_for(&self, rects: &[SampleRect], with_pins: bool) -> u64 {
        let layout = self.shared.store().layout();
        let mut ids: Vec<PageId> = rects
            .iter()
            .flat_map(|r| self.pages_of(r).pages().collect::<Vec<_>>())
            .filter(|id| !(with_pins && self.pinned.contains(&id.level)))
            .collect();
        ids.sort_by_key(|p| (p.level, p.py, p.px));
        ids.dedup();
        let pins = if with_pins { self.pinned_bytes } else { 0 };
        pins + ids
            .iter()
            .map(|&id| Loaded::bytes_with(layout, self.shared.imagery(), id))
            .sum::<u64>()
    }

    /// [`StreamedStore::wait_resident`] for the pinned levels (start-up: the renderer then
    /// always has something to draw).
    pub fn wait_pinned(&self, timeout: Duration) -> Result<(), NotResident> {
        let layout = self.shared.store().layout();
        let ids: Vec<PageId> = self
            .pinned
            .clone()
            .flat_map(|level| {
                let g = layout.levels[level as usize];
                (0..g.pages_y)
                    .flat_map(move |py| (0..g.pages_x).map(move |px| PageId { level, px, py }))
            })
            .collect();
        self.wait_pages(&ids, timeout)
    }

    fn wait_pages(&self, ids: &[PageId], timeout: Duration) -> Result<(), NotResident> {
        let deadline = Instant::now() + timeout;
        let mut g = self.shared.lock();
        loop {
            let mut missing = None;
            let mut failed = None;
            let mut wished = false;
            for &id in ids {
                if g.cache.contains(id) {
                    continue;
                }
                if g.failed.contains_key(&id) {
                    failed.get_or_insert(id);
                    continue;
                }
                missing.get_or_insert(id);
                if !g.queue.is_started(id) {
                    g.queue.add(id, FIRST);
                    wished = true;
                }
            }
            let Some(first) = missing else {
                return failed.map_or(Ok(()), |id| Err(not_resident(id, true)));
            };
            let now = Instant::now();
            if now >= deadline {
                return Err(not_resident(first, false));
            }
            if wished {
                self.shared.wake_workers();
            }
            // In slices: a `request` from another thread may have replaced these wishes.
            g = self
                .shared
                .wait_done(g, (deadline - now).min(Duration::from_millis(50)));
        }
    }
}

/// Columns `out .. out + len` of a gathered row are page column `page`'s samples `local ..`.
struct ColumnRun {
    page: usize,
    out: usize,
    local: usize,
    len: usize,
}

fn not_resident(id: PageId, failed: bool) -> NotResident {
    NotResident {
        level: id.level,
        px: id.px,
        py: id.py,
        failed,
    }
}

impl Drop for StreamedStore {
    fn drop(&mut self) {
        self.shared.shut_down();
        for h in self.workers.drain(..) {
            let _ = h.join();
        }
    }
}

impl TerrainSource for StreamedStore {
    fn grid(&self) -> &SourceGrid {
        &self.grid
    }

    fn is_resident(&self, rect: &SampleRect) -> bool {
        if rect.is_empty() {
            return true;
        }
        let m = self.pages_of(rect);
        let mut g = self.shared.lock();
        let mut all = true;
        for id in m.pages() {
            all &= g.cache.get(id).is_some();
        }
        if all {
            g.hits += 1;
        } else {
            g.misses += 1;
        }
        all
    }

    fn gather(&self, rect: &SampleRect, out: &mut [f32]) -> Result<(), NotResident> {
        if rect.is_empty() {
            return Ok(());
        }
        let m = self.pages_of(rect);
        let (nc, nr) = (m.page_cols.len(), m.page_rows.len());
        let mut pages: Vec<Arc<Loaded>> = Vec::with_capacity(nc * nr);
        {
            let mut g = self.shared.lock();
            let mut missing: Option<NotResident> = None;
            for id in m.pages() {
                match g.cache.get(id) {
                    Some(p) => pages.push(p.clone()),
                    None => {
                        let failed = g.failed.contains_key(&id);
                        if !failed {
                            // The contract: a page found missing is asked for.
                            g.queue.add(id, LAST);
                        }
                        missing.get_or_insert(not_resident(id, failed));
                    }
                }
            }
            if let Some(e) = missing {
                g.misses += 1;
                drop(g);
                self.shared.wake_workers();
                return Err(e);
            }
            g.hits += 1;
        }
        // Copy with the lock released: the Arcs keep the pages alive even if evicted now.
        let w = rect.size[0] as usize;
        assert_eq!(out.len(), rect.len(), "gather buffer size");
        let col_at = |p: u32| m.page_cols.binary_search(&p).unwrap_or(0);
        // Runs of columns read from one page at consecutive positions: one copy per run and
        // row (a level strip is one or two runs; clamped edges are runs of one).
        let mut runs: Vec<ColumnRun> = Vec::new();
        for (i, &(p, lc)) in m.cols.iter().enumerate() {
            let (c, lc) = (col_at(p), lc as usize);
            match runs.last_mut() {
                Some(r) if r.page == c && r.local + r.len == lc => r.len += 1,
                _ => runs.push(ColumnRun {
                    page: c,
                    out: i,
                    local: lc,
                    len: 1,
                }),
            }
        }
        for (j, &(pr, lr)) in m.rows.iter().enumerate() {
            let r = m.page_rows.binary_search(&pr).unwrap_or(0);
            let row = &mut out[j * w..(j + 1) * w];
            for run in &runs {
                let page = &pages[r * nc + run.page].page;
                let at = lr as usize * page.rect.cols as usize + run.local;
                row[run.out..run.out + run.len].copy_from_slice(&page.samples[at..at + run.len]);
            }
        }
        Ok(())
    }

    fn request(&self, wants: &[SampleWant]) {
        let mut ids: Vec<(PageId, f32)> = Vec::new();
        for w in wants {
            if w.rect.is_empty() {
                continue;
            }
            ids.extend(self.pages_of(&w.rect).pages().map(|id| (id, w.priority)));
        }
        let mut g = self.shared.lock();
        let mut list: Vec<(PageId, f32)> = Vec::with_capacity(ids.len());
        for (id, p) in ids {
            // A wished page that is resident is in use: keep it from eviction.
            if g.cache.get(id).is_some() || g.failed.contains_key(&id) {
                continue;
            }
            list.push((id, p));
        }
        list.extend(g.pinned_missing.iter().map(|&id| (id, LAST)));
        g.queue.replace(list);
        let any = !g.queue.is_empty();
        drop(g);
        if any {
            self.shared.wake_workers();
        }
    }

    fn imagery_texels_per_sample(&self) -> Option<u32> {
        self.shared.imagery().map(|l| l.texels_per_sample())
    }

    fn imagery_layer(&self) -> Option<&ImageryLayer> {
        self.shared.imagery()
    }

    fn gather_imagery(&self, rect: &SampleRect, out: &mut [u8]) -> Result<(), NotResident> {
        out.fill(0);
        let Some(layer) = self.shared.imagery() else {
            return Ok(());
        };
        let valid = [self.grid.valid_width, self.grid.valid_height];
        let r = imagery_rect(
            self.shared.store().layout(),
            layer.texels_per_sample(),
            valid,
            (rect.level, rect.origin, rect.size),
        );
        let mut pages = Vec::with_capacity(r.pages.len());
        {
            let mut st = self.shared.lock();
            for &id in &r.pages {
                match st.cache.get(id) {
                    Some(p) => pages.push(p.clone()),
                    None => {
                        let failed = st.failed.contains_key(&id);
                        if !failed {
                            st.queue.add(id, LAST);
                        }
                        drop(st);
                        self.shared.wake_workers();
                        return Err(not_resident(id, failed));
                    }
                }
            }
        }
        for p in &pages {
            if let Some(img) = &p.imagery {
                copy_page_texels(&r, img, out);
            }
        }
        Ok(())
    }

    fn stats(&self) -> StreamStats {
        let g = self.shared.lock();
        StreamStats {
            resident_bytes: g.cache.resident_bytes(),
            budget_bytes: g.cache.budget(),
            resident_pages: g.cache.len() as u64,
            hits: g.hits,
            misses: g.misses,
            loaded: g.loaded,
            failed: g.failed.len() as u64,
            evicted: g.cache.evicted(),
            queued: g.queue.len() as u64,
        }
    }
}
