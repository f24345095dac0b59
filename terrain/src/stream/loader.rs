//! The page loader: N worker threads that take the most urgent page from the queue, read it
//! ([`Store::read_page`]: one positioned read), verify it (CRC-32, content, its tables
//! against the store's bake section) and insert it into the cache. The lock is held only to
//! take a page and to insert it, never across I/O or decompression, so the frame thread's
//! `is_resident`/`gather` never wait on either.
//!
//! Positioned reads (`pread`) and not a memory map: a read of a damaged or truncated file is
//! an error value naming the page, where a mapped page would raise `SIGBUS` in whichever
//! thread touched it (possibly the frame thread); each page is read once into the cache, so a
//! map would save no copy; and the workers share one descriptor without a seek position.
//!
//! A page that fails (I/O, CRC, content) is remembered with its reason and never read again:
//! it is answered as `NotResident { failed: true }` from then on.

use std::collections::{HashMap, HashSet};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;

use crate::bake::ErrorBake;
use crate::query::hierarchy::{build_tile, fine_len};
use crate::store::{ImageryLayer, ImageryPage, Layout, Page, PageError, PageId, Store};

use super::cache::{Inserted, PageCache};
use super::queue::RequestQueue;

/// A decoded, verified page as the cache holds it.
pub struct Loaded {
    pub page: Page,
    /// Level-0 pages: each tile's fine hierarchy for the queries
    /// ([`crate::query::hierarchy::build_tile`]), `fine_len(q)` bytes a tile in the page's
    /// tile order; empty for the coarser levels.
    pub fine: Vec<u8>,
    /// The page's imagery when the store has an imagery layer and its page is intact.
    pub imagery: Option<ImageryPage>,
}

impl Loaded {
    /// Bytes the cache counts for it.
    pub fn bytes(&self) -> u64 {
        self.page.bytes() + self.fine.len() as u64 + self.imagery.as_ref().map_or(0, |i| i.bytes())
    }

    /// [`Loaded::bytes`] of a page before it is read, with its imagery when `imagery`.
    pub fn bytes_with(layout: &Layout, imagery: Option<&ImageryLayer>, id: PageId) -> u64 {
        Self::bytes_of(layout, id) + imagery.map_or(0, |l| l.page_bytes(id))
    }

    /// [`Loaded::bytes`] of a page before it is read, without imagery.
    pub fn bytes_of(layout: &Layout, id: PageId) -> u64 {
        let r = layout.rect(id.level, id.px, id.py);
        let fine = if id.level == 0 {
            r.tiles() * fine_len(layout.q as usize)
        } else {
            0
        };
        Page::bytes_of(r) + fine as u64
    }
}

/// The fine hierarchy of every tile of a level-0 page; `Err` names a tile whose samples'
/// maximum is not its stored maximum (the hierarchy would not bound it).
fn fine_of(page: &Page, q: usize) -> Result<Vec<u8>, String> {
    let r = page.rect;
    let per = fine_len(q);
    let mut out = vec![0u8; r.tiles() * per];
    let mut scratch = Vec::new();
    let cols = r.cols as usize;
    for j in 0..r.nty as usize {
        for i in 0..r.ntx as usize {
            let k = j * r.ntx as usize + i;
            let bounds = (page.min[k], page.max[k]);
            let at = j * q * cols + i * q;
            let got = build_tile(
                q,
                &page.samples[at..],
                cols,
                bounds,
                &mut out[k * per..(k + 1) * per],
                &mut scratch,
            );
            if got.to_bits() != bounds.1.to_bits() {
                return Err(format!(
                    "tile ({}, {}): its samples' maximum is {got}, its stored maximum {}",
                    r.tx0 as usize + i,
                    r.ty0 as usize + j,
                    bounds.1
                ));
            }
        }
    }
    Ok(out)
}

/// What the workers and the frame thread share, behind one lock.
pub(super) struct State {
    pub cache: PageCache<Arc<Loaded>>,
    pub queue: RequestQueue,
    /// Pages refused, with the reason (logged once, when they failed).
    pub failed: HashMap<PageId, String>,
    /// Pinned pages not yet resident (re-wished with every request until they arrive).
    pub pinned_missing: HashSet<PageId>,
    pub hits: u64,
    pub misses: u64,
    pub loaded: u64,
    /// Stored bytes read from the file by the workers.
    pub bytes_read: u64,
    /// Loaded pages that did not fit beside the pinned ones (budget too small).
    pub too_large: u64,
    /// Imagery pages refused (I/O, checksum, content), with the reason: their heights are
    /// drawn without imagery.
    pub imagery_failed: HashMap<PageId, String>,
    shutdown: bool,
}

pub(super) struct Shared {
    state: Mutex<State>,
    /// Signalled when a page is wished (workers wait on it).
    work: Condvar,
    /// Signalled when a page arrived or failed (`wait_resident` waits on it).
    done: Condvar,
    store: Store,
    bake: Arc<ErrorBake>,
    imagery: Option<ImageryLayer>,
}

impl Shared {
    pub fn new(
        store: Store,
        bake: Arc<ErrorBake>,
        imagery: Option<ImageryLayer>,
        budget: u64,
    ) -> Self {
        Shared {
            state: Mutex::new(State {
                cache: PageCache::new(budget),
                queue: RequestQueue::new(),
                failed: HashMap::new(),
                pinned_missing: HashSet::new(),
                hits: 0,
                misses: 0,
                loaded: 0,
                bytes_read: 0,
                too_large: 0,
                imagery_failed: HashMap::new(),
                shutdown: false,
            }),
            work: Condvar::new(),
            done: Condvar::new(),
            store,
            bake,
            imagery,
        }
    }

    pub fn store(&self) -> &Store {
        &self.store
    }

    pub fn imagery(&self) -> Option<&ImageryLayer> {
        self.imagery.as_ref()
    }

    pub fn bake(&self) -> &Arc<ErrorBake> {
        &self.bake
    }

    /// The state. A worker never panics while holding the lock, but if a thread ever did,
    /// the data (counters, a cache whose every operation completes) is still consistent:
    /// take it rather than propagate the panic into the frame thread.
    pub fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Wakes the workers after pages were wished.
    pub fn wake_workers(&self) {
        self.work.notify_all();
    }

    /// Waits for the next page to arrive or fail, or `timeout`; returns the guard.
    pub fn wait_done<'a>(
        &self,
        g: MutexGuard<'a, State>,
        timeout: std::time::Duration,
    ) -> MutexGuard<'a, State> {
        match self.done.wait_timeout(g, timeout) {
            Ok((g, _)) => g,
            Err(e) => e.into_inner().0,
        }
    }

    /// Stops the workers (each finishes the page it is reading).
    pub fn shut_down(&self) {
        self.lock().shutdown = true;
        self.work.notify_all();
    }

    fn next(&self) -> Option<PageId> {
        let mut g = self.lock();
        loop {
            if g.shutdown {
                return None;
            }
            if let Some(id) = g.queue.pop() {
                return Some(id);
            }
            g = match self.work.wait(g) {
                Ok(g) => g,
                Err(e) => e.into_inner(),
            };
        }
    }

    /// Reads and verifies one page, and builds the queries' hierarchy of a level-0 page (no
    /// lock held).
    fn load(&self, id: PageId) -> Result<Loaded, PageError> {
        let content = |reason: String| {
            let (offset, end) = self
                .store
                .entry(id)
                .map(|e| (e.offset, e.offset + u64::from(e.len)))
                .unwrap_or((0, 0));
            PageError::Content {
                path: self.store.path().to_path_buf(),
                page: id,
                offset,
                end,
                reason,
            }
        };
        let page = self.store.read_page(id)?;
        page.check_tables(&self.bake).map_err(content)?;
        let fine = if id.level == 0 {
            fine_of(&page, self.store.layout().q as usize).map_err(content)?
        } else {
            Vec::new()
        };
        let imagery = match self.imagery.as_ref().map(|l| l.read_page(id)) {
            None => None,
            Some(Ok(p)) => Some(p),
            Some(Err(e)) => {
                // Logged once: the heights are drawn, without this page's imagery.
                let msg = e.to_string();
                eprintln!("aerie: {msg}; this page is drawn without imagery");
                self.lock().imagery_failed.insert(id, msg);
                None
            }
        };
        Ok(Loaded {
            page,
            fine,
            imagery,
        })
    }

    fn finish(&self, id: PageId, result: Result<Loaded, PageError>) {
        let stored = self.store.entry(id).map_or(0, |e| u64::from(e.len));
        let mut g = self.lock();
        g.queue.finish(id);
        g.bytes_read += stored;
        match result {
            Ok(page) => {
                let bytes = page.bytes();
                match g.cache.insert(id, Arc::new(page), bytes) {
                    Inserted::Yes { .. } => {
                        g.loaded += 1;
                        g.pinned_missing.remove(&id);
                    }
                    Inserted::TooLarge => g.too_large += 1,
                }
            }
            Err(e) => {
                // Logged once: a failed page is never read again.
                let msg = e.to_string();
                eprintln!("aerie: {msg}; drawn coarser from now on");
                g.pinned_missing.remove(&id);
                g.failed.insert(id, msg);
            }
        }
        drop(g);
        self.done.notify_all();
    }
}

/// Starts `n` workers on `shared`; `Err` when the system refuses a thread (those started
/// are stopped first).
pub(super) fn spawn_workers(
    shared: &Arc<Shared>,
    n: usize,
) -> std::io::Result<Vec<JoinHandle<()>>> {
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let s = shared.clone();
        let h = std::thread::Builder::new()
            .name(format!("aerie-pages-{k}"))
            .spawn(move || {
                while let Some(id) = s.next() {
                    let r = s.load(id);
                    s.finish(id, r);
                }
            });
        match h {
            Ok(h) => out.push(h),
            Err(e) => {
                shared.shut_down();
                for h in out {
                    let _ = h.join();
                }
                return Err(e);
            }
        }
    }
    Ok(out)
}
