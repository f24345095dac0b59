//! `StreamedStore` against `InMemoryTerrain` on the same data: every rectangle equal once warm,
//! nothing answered before its page arrived and nothing waited for, damaged pages failed once
//! and the rest served, the budget held, many threads at once.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

use aerie_io::{FileSystem, InFile, OutFile};

use super::*;
use crate::bake::{bake, BakeParams, ErrorBake};
use crate::dataset::Dataset;
use crate::query::{first_hit, height_of_terrain, InMemorySource, Lookup, Ray};
use crate::source::{InMemoryTerrain, SampleRect, SampleWant, TerrainSource};
use crate::store::{write_store, ImportParams, PageId, Store};
use crate::Heightfield;

const WAIT: Duration = Duration::from_secs(20);

/// A deterministic generator (tests must not depend on a random seed).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        self.0 >> 33
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
    fn range(&mut self, lo: i64, hi: i64) -> i64 {
        lo + self.below((hi - lo) as u64) as i64
    }
}

/// 150 × 70 samples (padded to 257 × 129), fractional heights with integer patches, tiles of
/// 9 vertices, pages of 2 × 2 tiles: 5 levels, 128 level-0 pages, pages cut at the edges.
fn fixture(dir: &Path) -> (PathBuf, Arc<Dataset>, ErrorBake) {
    let (w, h) = (150usize, 70usize);
    let heights = (0..h)
        .flat_map(|r| (0..w).map(move |c| (c, r)))
        .map(|(c, r)| {
            let v = (c as f32 * 0.21).sin() * 300.0 + (r as f32 * 0.13).cos() * 150.0;
            let v = v + ((c * 31 + r * 17) % 23) as f32 * 0.37;
            if (c / 20 + r / 20) % 3 == 0 {
                v.round()
            } else {
                v
            }
        })
        .collect();
    let ds = Dataset::from_heightfield(
        Heightfield {
            width: w,
            height: h,
            spacing_x: 30.0,
            spacing_y: 30.0,
            heights,
            geo: None,
            voids_filled: 0,
            spacing_note: "test".into(),
        },
        "test".into(),
    );
    let p = BakeParams {
        tile_size: 9,
        levels: 0,
    };
    let p = BakeParams {
        levels: p.resolve_levels(&ds).unwrap(),
        ..p
    };
    let b = bake(&ds, p, &|_, _| {});
    let path = dir.join("s.aerie");
    write_store(
        &path,
        &ds,
        &b,
        &ImportParams {
            sources: vec!["test".into()],
            page_tiles: 2,
            zstd_level: 3,
        },
        &|_, _| {},
    )
    .unwrap();
    (path, Arc::new(ds), b)
}

fn params(cache_bytes: u64, fs: Arc<dyn FileSystem>) -> StreamParams {
    StreamParams {
        cache_bytes,
        workers: 2,
        fs,
    }
}

/// A random rectangle of any level (one past the store's too), aligned or not, reaching past
/// every edge.
fn random_rect(g: &mut Lcg, w: i64, h: i64, levels: u32) -> SampleRect {
    let level = g.below(u64::from(levels) + 1) as u32;
    let step = 1i64 << level;
    let mut origin = [g.range(-3 * step, w + step), g.range(-3 * step, h + step)];
    if g.below(3) > 0 {
        origin = [origin[0] & !(step - 1), origin[1] & !(step - 1)];
    }
    SampleRect {
        level,
        origin,
        size: [g.range(1, 40) as u32, g.range(1, 30) as u32],
    }
}

fn gathered(
    src: &dyn TerrainSource,
    r: &SampleRect,
) -> Result<Vec<u32>, crate::source::NotResident> {
    let mut out = vec![f32::NAN; r.len()];
    src.gather(r, &mut out)?;
    Ok(out.iter().map(|v| v.to_bits()).collect())
}

#[test]
fn every_rect_gathered_warm_equals_the_in_memory_source() {
    let dir = tempfile::tempdir().unwrap();
    let (path, ds, b) = fixture(dir.path());
    let mem = InMemoryTerrain::new(ds.clone());
    let (s, bake_back) = StreamedStore::open(&path, StreamParams::default()).unwrap();
    assert_eq!(*bake_back, b, "the store's bake section is the bake");
    let grid = crate::source::SourceGrid {
        description: mem.grid().description.clone(),
        ..s.grid().clone()
    };
    assert_eq!(&grid, mem.grid());
    assert!(s.grid().description.contains("s.aerie"));
    let levels = b.levels.len() as u32;
    let mut g = Lcg(7);
    for k in 0..600 {
        let r = random_rect(&mut g, 257, 129, levels);
        s.wait_resident(&[r], WAIT).unwrap();
        assert!(s.is_resident(&r));
        assert_eq!(gathered(&s, &r), gathered(&mem, &r), "rect {k}: {r:?}");
    }
    // Empty rectangles are trivially resident.
    let e = SampleRect {
        level: 0,
        origin: [0, 0],
        size: [0, 5],
    };
    assert!(s.is_resident(&e) && s.gather(&e, &mut []).is_ok());
    let st = s.stats();
    assert_eq!(st.failed, 0);
    assert!(st.loaded > 0 && st.resident_bytes <= st.budget_bytes);
}

/// Reads by the page workers block until the gate lets them pass (reads on other threads,
/// such as `open`'s, pass at once): `allow(n)` lets n more through, `release` all.
#[derive(Debug, Clone, Default)]
struct GateFs {
    permits: Arc<(Mutex<u64>, Condvar)>,
    blocked: Arc<AtomicUsize>,
}

impl GateFs {
    fn allow(&self, n: u64) {
        let mut p = self.permits.0.lock().unwrap();
        *p = p.saturating_add(n);
        self.permits.1.notify_all();
    }
    fn release(&self) {
        self.allow(u64::MAX);
    }
    /// Waits until `n` workers are stuck inside a read (panics after `WAIT`: a test must fail,
    /// never hang).
    fn wait_blocked(&self, n: usize) {
        let start = std::time::Instant::now();
        while self.blocked.load(Ordering::SeqCst) < n {
            assert!(
                start.elapsed() < WAIT,
                "{} of {n} workers blocked after {WAIT:?}",
                self.blocked.load(Ordering::SeqCst)
            );
            std::thread::sleep(Duration::from_millis(1));
        }
    }
    /// Waits until every permit is spent and `n` workers wait at the gate for more: each has
    /// finished (and cached) the page it read before, so counts read now are settled. Both
    /// numbers are read under the gate's lock, where the workers change them.
    fn wait_at_rest(&self, n: usize) {
        let start = std::time::Instant::now();
        loop {
            let (p, b) = {
                let g = self.permits.0.lock().unwrap();
                (*g, self.blocked.load(Ordering::SeqCst))
            };
            if p == 0 && b == n {
                return;
            }
            assert!(
                start.elapsed() < WAIT,
                "{p} permits left and {b} of {n} workers at the gate after {WAIT:?}"
            );
            std::thread::sleep(Duration::from_millis(1));
        }
    }
    /// A guard that opens the gate for good when dropped. Declared after the `StreamedStore`,
    /// it is dropped first, also while a failed assertion unwinds: the store's drop joins its
    /// workers, and a worker held at the gate would otherwise make that join wait forever.
    fn opened_on_drop(&self) -> OpenOnDrop {
        OpenOnDrop(self.clone())
    }
}

struct OpenOnDrop(GateFs);

impl Drop for OpenOnDrop {
    fn drop(&mut self) {
        self.0.release();
    }
}

struct GatedIn {
    inner: Box<dyn InFile>,
    fs: GateFs,
}

impl InFile for GatedIn {
    fn read_at(&self, buf: &mut [u8], offset: u64) -> std::io::Result<usize> {
        let worker = std::thread::current()
            .name()
            .is_some_and(|n| n.starts_with("aerie-pages"));
        if worker {
            let (m, c) = &*self.fs.permits;
            let mut p = m.lock().unwrap();
            self.fs.blocked.fetch_add(1, Ordering::SeqCst);
            while *p == 0 {
                p = c.wait(p).unwrap();
            }
            *p -= 1;
            self.fs.blocked.fetch_sub(1, Ordering::SeqCst);
        }
        self.inner.read_at(buf, offset)
    }
    fn len(&self) -> std::io::Result<u64> {
        self.inner.len()
    }
}

impl FileSystem for GateFs {
    fn create_new(&self, path: &Path) -> std::io::Result<Box<dyn OutFile>> {
        aerie_io::real().create_new(path)
    }
    fn create(&self, path: &Path) -> std::io::Result<Box<dyn OutFile>> {
        aerie_io::real().create(path)
    }
    fn open(&self, path: &Path) -> std::io::Result<Box<dyn InFile>> {
        Ok(Box::new(GatedIn {
            inner: aerie_io::real().open(path)?,
            fs: self.clone(),
        }))
    }
    fn rename(&self, from: &Path, to: &Path) -> std::io::Result<()> {
        aerie_io::real().rename(from, to)
    }
    fn remove_file(&self, path: &Path) -> std::io::Result<()> {
        aerie_io::real().remove_file(path)
    }
    fn sync_dir(&self, dir: &Path) -> std::io::Result<()> {
        aerie_io::real().sync_dir(dir)
    }
}

#[test]
fn nothing_is_answered_before_its_page_arrives_and_nothing_waits_for_it() {
    let dir = tempfile::tempdir().unwrap();
    let (path, ds, _) = fixture(dir.path());
    let mem = InMemoryTerrain::new(ds);
    let gate = GateFs::default();
    let (s, _) = StreamedStore::open(&path, params(1 << 20, Arc::new(gate.clone()))).unwrap();
    let _open = gate.opened_on_drop();
    // The pinned levels are asked for at open: both workers are now stuck inside a read.
    gate.wait_blocked(2);
    assert_eq!(s.loader_stats().in_flight, 2);
    let r = SampleRect {
        level: 0,
        origin: [40, 20],
        size: [20, 10],
    };
    // With every read in flight, the frame thread's calls answer at once: not resident.
    for _ in 0..100 {
        assert!(!s.is_resident(&r));
        let e = gathered(&s, &r).unwrap_err();
        assert_eq!((e.level, e.failed), (0, false), "{e}");
    }
    s.request(&[SampleWant {
        rect: r,
        priority: 5.0,
    }]);
    assert!(s.stats().queued > 0);
    assert_eq!(s.stats().loaded, 0);
    let st = s.stats();
    assert_eq!((st.hits, st.misses), (0, 200));
    gate.release();
    s.wait_resident(&[r], WAIT).unwrap();
    assert!(s.is_resident(&r));
    assert_eq!(gathered(&s, &r), gathered(&mem, &r));
    s.wait_pinned(WAIT).unwrap();
    assert_eq!(s.loader_stats().pinned_missing, 0);
}

#[test]
fn injected_read_latency_never_makes_the_frame_thread_wait() {
    let dir = tempfile::tempdir().unwrap();
    let (path, ds, _) = fixture(dir.path());
    let mem = InMemoryTerrain::new(ds);
    let fs = aerie_io::FaultyFs::new(aerie_io::Faults {
        latency: Some(Duration::from_millis(40)),
        ..Default::default()
    });
    let store = Store::open(&path).unwrap();
    let full = Loaded::bytes_of(
        store.layout(),
        PageId {
            level: 0,
            px: 0,
            py: 0,
        },
    );
    // A small budget pins only the coarsest pages: the wished ones are read soon.
    let (s, _) = StreamedStore::open(&path, params(32 * full, fs.shared())).unwrap();
    let rects: Vec<SampleRect> = (0..6)
        .map(|k| SampleRect {
            level: 0,
            origin: [k * 20, 8],
            size: [16, 16],
        })
        .collect();
    s.request(
        &rects
            .iter()
            .map(|&rect| SampleWant {
                rect,
                priority: 1.0,
            })
            .collect::<Vec<_>>(),
    );
    // Count the answers given while a slow read was in flight: they were all "not resident"
    // (a call that waited for its page would have answered with samples).
    let mut while_in_flight = 0;
    let mut answered = 0;
    while rects.iter().any(|r| !s.is_resident(r)) {
        for r in &rects {
            let before = s.loader_stats();
            match gathered(&s, r) {
                Ok(v) => {
                    assert_eq!(Ok(v), gathered(&mem, r));
                    answered += 1;
                }
                Err(e) => {
                    assert!(!e.failed);
                    if before.in_flight > 0 {
                        while_in_flight += 1;
                    }
                }
            }
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    assert!(
        while_in_flight > 0,
        "no answer seen while a read was in flight"
    );
    assert!(s.stats().loaded > 0);
    let _ = answered;
}

#[test]
fn a_corrupt_page_fails_once_and_everything_else_is_served() {
    let dir = tempfile::tempdir().unwrap();
    let (path, ds, _) = fixture(dir.path());
    let mem = InMemoryTerrain::new(ds);
    // Flip a byte inside level-0 page (2, 1).
    let store = Store::open(&path).unwrap();
    let bad = PageId {
        level: 0,
        px: 2,
        py: 1,
    };
    let e = *store.entry(bad).unwrap();
    drop(store);
    let mut bytes = std::fs::read(&path).unwrap();
    bytes[(e.offset + u64::from(e.len) / 2) as usize] ^= 0x20;
    std::fs::write(&path, &bytes).unwrap();
    let (s, _) = StreamedStore::open(&path, StreamParams::default()).unwrap();
    // Level-0 page (2, 1) holds samples 32..=48 × 16..=32 (q = 8, 2 tiles a page).
    let inside = SampleRect {
        level: 0,
        origin: [35, 20],
        size: [4, 4],
    };
    let e = s.wait_resident(&[inside], WAIT).unwrap_err();
    assert_eq!((e.level, e.px, e.py, e.failed), (0, 2, 1, true), "{e}");
    let e = gathered(&s, &inside).unwrap_err();
    assert!(e.failed, "{e}");
    assert!(e.to_string().contains("failed to load"), "{e}");
    let f = s.failures();
    assert_eq!(f.len(), 1);
    assert_eq!(f[0].0, bad);
    assert!(f[0].1.contains("checksum mismatch"), "{}", f[0].1);
    // Once the pinned levels (here: every page) are in, asked again, it is not read again.
    let e = s.wait_pinned(WAIT).unwrap_err();
    assert_eq!((e.px, e.py, e.failed), (2, 1, true));
    s.request(&[SampleWant {
        rect: inside,
        priority: 9.0,
    }]);
    let st = s.stats();
    assert_eq!((st.failed, st.queued), (1, 0));
    assert_eq!(s.loader_stats().in_flight, 0);
    // Every other page is served, equal to the source.
    let mut g = Lcg(3);
    let mut served = 0;
    for _ in 0..200 {
        let r = random_rect(&mut g, 257, 129, 5);
        match s.wait_resident(&[r], WAIT) {
            Ok(()) => {
                assert_eq!(gathered(&s, &r), gathered(&mem, &r), "{r:?}");
                served += 1;
            }
            Err(e) => assert_eq!((e.level, e.px, e.py, e.failed), (0, 2, 1, true)),
        }
    }
    assert!(served > 150, "{served}");
    assert_eq!(s.stats().failed, 1);
    assert_eq!(s.failures().len(), 1);
}

#[test]
fn resident_bytes_never_exceed_the_budget_and_pinned_pages_stay() {
    let dir = tempfile::tempdir().unwrap();
    let (path, ds, _) = fixture(dir.path());
    let mem = InMemoryTerrain::new(ds);
    let store = Store::open(&path).unwrap();
    let full = Loaded::bytes_of(
        store.layout(),
        PageId {
            level: 0,
            px: 0,
            py: 0,
        },
    );
    // Room for ~ 24 full pages: far less than the store (≈ 170 pages).
    let budget = 24 * full;
    let (s, _) = StreamedStore::open(&path, params(budget, aerie_io::real())).unwrap();
    s.wait_pinned(WAIT).unwrap();
    let pinned = s.pinned_levels();
    assert!(!pinned.is_empty() && pinned.end == 5, "{pinned:?}");
    let lp = s.loader_stats();
    assert!(lp.pinned_bytes <= budget / 4);
    let top = SampleRect {
        level: pinned.start,
        origin: [0, 0],
        size: [300, 300],
    };
    let mut g = Lcg(11);
    for k in 0..400 {
        let r = random_rect(&mut g, 257, 129, 2);
        // At most 3 × 3 pages (level-2 steps over level-0 pages): well within the budget.
        let r = SampleRect {
            size: [r.size[0].min(8), r.size[1].min(8)],
            ..r
        };
        if k % 3 == 0 {
            s.request(&[SampleWant {
                rect: r,
                priority: 1.0,
            }]);
        } else {
            s.wait_resident(&[r], WAIT).unwrap();
            // It may be evicted again before the gather (other wishes are loading): then it
            // is not resident, never wrong.
            if let Ok(v) = gathered(&s, &r) {
                assert_eq!(Ok(v), gathered(&mem, &r));
            }
        }
        let st = s.stats();
        assert!(st.resident_bytes <= budget, "{st:?}");
        // The pinned levels never leave.
        assert!(s.is_resident(&top), "step {k}");
    }
    let st = s.stats();
    assert!(st.evicted > 0, "the budget was never tight: {st:?}");
    assert!(st.resident_bytes <= budget);
}

#[test]
fn a_budget_too_small_for_a_few_pages_is_refused_with_the_sizes() {
    let dir = tempfile::tempdir().unwrap();
    let (path, _, _) = fixture(dir.path());
    let e = StreamedStore::open(&path, params(1000, aerie_io::real())).unwrap_err();
    assert!(e.to_string().contains("cannot hold 4 pages"), "{e}");
    let e = StreamedStore::open(
        &path,
        StreamParams {
            workers: 0,
            ..StreamParams::default()
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("worker"), "{e}");
}

#[test]
fn many_threads_gather_while_others_request() {
    let dir = tempfile::tempdir().unwrap();
    let (path, ds, _) = fixture(dir.path());
    let mem = InMemoryTerrain::new(ds);
    let store = Store::open(&path).unwrap();
    let full = Loaded::bytes_of(
        store.layout(),
        PageId {
            level: 0,
            px: 0,
            py: 0,
        },
    );
    let (s, _) = StreamedStore::open(&path, params(40 * full, aerie_io::real())).unwrap();
    s.wait_pinned(WAIT).unwrap();
    let calls = AtomicUsize::new(0);
    let ok = AtomicUsize::new(0);
    std::thread::scope(|sc| {
        for t in 0..4u64 {
            let (s, mem, calls, ok) = (&s, &mem, &calls, &ok);
            sc.spawn(move || {
                let mut g = Lcg(100 + t);
                for _ in 0..300 {
                    let r = random_rect(&mut g, 257, 129, 5);
                    if t % 2 == 0 {
                        s.request(&[SampleWant {
                            rect: r,
                            priority: g.below(10) as f32,
                        }]);
                    }
                    calls.fetch_add(1, Ordering::Relaxed);
                    if let Ok(v) = gathered(s, &r) {
                        assert_eq!(Ok(v), gathered(mem, &r), "{r:?}");
                        ok.fetch_add(1, Ordering::Relaxed);
                    }
                }
            });
        }
    });
    let st = s.stats();
    assert_eq!(
        (st.hits + st.misses) as usize,
        calls.load(Ordering::Relaxed)
    );
    assert_eq!(st.hits as usize, ok.load(Ordering::Relaxed));
    assert!(st.resident_bytes <= st.budget_bytes && st.failed == 0);
    assert!(ok.load(Ordering::Relaxed) > 0);
}

#[test]
fn queries_on_the_streamed_pages_answer_as_in_memory_or_pending() {
    let dir = tempfile::tempdir().unwrap();
    let (path, ds, b) = fixture(dir.path());
    let mem = InMemorySource::new(ds, Arc::new(b)).unwrap();
    let store = Store::open(&path).unwrap();
    let full = Loaded::bytes_of(
        store.layout(),
        PageId {
            level: 0,
            px: 0,
            py: 0,
        },
    );
    let (s, _) = StreamedStore::open(&path, params(64 * full, aerie_io::real())).unwrap();
    // The south-west part resident (level-0 samples 0..=80 × 0..=48).
    let sw = SampleRect {
        level: 0,
        origin: [0, 0],
        size: [81, 49],
    };
    s.wait_resident(&[sw], WAIT).unwrap();
    let surf = s.surface();
    assert!(surf.pages() >= 5 * 3, "{}", surf.pages());
    let (ex, ny) = (149.0 * 30.0, 69.0 * 30.0);
    let mut g = Lcg(5);
    let mut next = || g.below(1_000_000) as f64 / 1e6;
    let (mut ready, mut pending) = (0, 0);
    for _ in 0..400 {
        let (x, y) = (next() * ex, next() * ny);
        match height_of_terrain(&surf, x, y) {
            Lookup::Pending { .. } => pending += 1,
            got => {
                assert_eq!(got, height_of_terrain(&mem, x, y), "HOT at ({x}, {y})");
                ready += 1;
            }
        }
    }
    assert!(
        ready > 40 && pending > 40,
        "{ready} ready, {pending} pending"
    );
    let rays: Vec<Ray> = (0..300)
        .map(|_| {
            let o = glam::DVec3::new(next() * ex, next() * ny, 200.0 + next() * 400.0);
            let d = glam::DVec3::new(next() - 0.5, next() - 0.5, -next() * 0.3);
            Ray::new(o, d, 0.0, 3000.0).unwrap()
        })
        .collect();
    let (mut ready, mut pending) = (0, 0);
    for r in &rays {
        match first_hit(&surf, r) {
            Lookup::Pending { .. } => pending += 1,
            got => {
                assert_eq!(got, first_hit(&mem, r), "{r:?}");
                ready += 1;
            }
        }
    }
    assert!(
        ready > 20 && pending > 20,
        "{ready} ready, {pending} pending"
    );
}

#[test]
fn what_the_renderer_requests_comes_before_the_pins_still_missing() {
    let dir = tempfile::tempdir().unwrap();
    let (path, _, _) = fixture(dir.path());
    let store = Store::open(&path).unwrap();
    let full = Loaded::bytes_of(
        store.layout(),
        PageId {
            level: 0,
            px: 0,
            py: 0,
        },
    );
    let gate = GateFs::default();
    // 64 pages of budget pin levels 2..5 (11 pages); level 0 is not pinned.
    let (s, _) = StreamedStore::open(&path, params(64 * full, Arc::new(gate.clone()))).unwrap();
    let _open = gate.opened_on_drop();
    let pinned = s.loader_stats().pinned_pages;
    assert_eq!((s.pinned_levels(), pinned), (2..5, 11));
    gate.wait_blocked(2);
    // Two pinned pages are in flight; the renderer now wants 2 × 2 level-0 pages.
    let r = SampleRect {
        level: 0,
        origin: [20, 20],
        size: [20, 20],
    };
    s.request(&[SampleWant {
        rect: r,
        priority: 5.0,
    }]);
    // Exactly the two reads in flight and the four wished pages may pass: if a pinned page
    // went first, the wished ones could not all arrive.
    gate.allow(2 + 4);
    s.wait_resident(&[r], WAIT).unwrap();
    // Six permits spent and both workers back at the gate, each on a pinned page now: every
    // page read so far is in the cache, so the count below cannot race a worker still decoding.
    gate.wait_at_rest(2);
    let ls = s.loader_stats();
    assert_eq!(ls.pinned_missing, pinned - 2, "{ls:?}");
    gate.release();
    s.wait_pinned(WAIT).unwrap();
    assert_eq!(s.loader_stats().pinned_missing, 0);
}
