//! Bookkeeping of one refined-tile pool (DESIGN.md, "Pools"): a fixed number of texture-array
//! slots holding refined tiles, managed least-recently-used. Pure CPU; the renderer does the
//! uploads this decides.
//!
//! The document's worst frames came from unbounded pool uploads, so a miss is only honoured when
//! the caller's per-frame budget allows it; otherwise the tile is *late* (drawn at its best
//! resident resolution this frame). A slot handed out in a frame — drawn or being uploaded — is
//! never handed out again in that frame, so an upload never overwrites a tile a draw still reads.

use std::collections::{BTreeSet, HashMap};

/// A refined tile: level-`level` tile `(tx, ty)` drawn 2^`refinement` times finer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TileKey {
    pub level: u32,
    pub tx: u32,
    pub ty: u32,
    pub refinement: u32,
}

/// Running totals since the pool was created. Every [`RefinedTilePool::request`] counts exactly
/// one of `hits`, `misses` (upload granted) or `late`; prefetches count only in `prefetches`
/// (uploads granted) and `evictions`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PoolCounters {
    pub hits: u64,
    pub misses: u64,
    /// Resident tiles replaced, by requests and prefetches alike.
    pub evictions: u64,
    pub late: u64,
    pub prefetches: u64,
}

/// Outcome of a [`RefinedTilePool::request`] or [`RefinedTilePool::prefetch`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Request {
    /// Resident in `slot`.
    Hit { slot: u32 },
    /// The caller must upload the tile into `slot`; `evicted` was there.
    Miss { slot: u32, evicted: Option<TileKey> },
    /// No slot can be given this frame, or the caller's budget said no.
    Unavailable,
}

#[derive(Debug, Clone)]
struct Slot {
    key: Option<TileKey>,
    /// Recency stamp (global, increasing): larger is more recent.
    tick: u64,
    /// Last frame in which the tile was requested for drawing.
    drawn: Option<u64>,
    /// Handed out this frame (drawn or uploading): not evictable until the next frame.
    claimed: bool,
}

/// LRU pool of `capacity` slots. Hits are O(1) expected (hash map), misses O(log capacity): the
/// occupied slots not claimed this frame are kept ordered by recency, so the victim is the first.
#[derive(Debug, Clone)]
pub struct RefinedTilePool {
    slots: Vec<Slot>,
    map: HashMap<TileKey, u32>,
    /// Never-used slots, lowest index on top.
    free: Vec<u32>,
    /// (tick, slot) of occupied slots not claimed this frame.
    lru: BTreeSet<(u64, u32)>,
    /// Slots claimed this frame, returned to `lru` by `begin_frame`.
    claimed: Vec<u32>,
    frame: u64,
    tick: u64,
    /// Smallest `protect_frames` for which a prefetch found no victim this frame: victims only
    /// become scarcer within a frame, so larger protections need not scan again.
    prefetch_blocked: Option<u64>,
    counters: PoolCounters,
}

impl RefinedTilePool {
    pub fn new(capacity: u32) -> Self {
        Self {
            slots: vec![
                Slot {
                    key: None,
                    tick: 0,
                    drawn: None,
                    claimed: false,
                };
                capacity as usize
            ],
            map: HashMap::with_capacity(capacity as usize),
            free: (0..capacity).rev().collect(),
            lru: BTreeSet::new(),
            claimed: Vec::new(),
            frame: 0,
            tick: 0,
            prefetch_blocked: None,
            counters: PoolCounters::default(),
        }
    }

    /// Starts frame `frame` (the renderer's frame number, used for prefetch protection): slots
    /// handed out in the previous frame become evictable again.
    pub fn begin_frame(&mut self, frame: u64) {
        self.frame = frame;
        self.prefetch_blocked = None;
        for slot in self.claimed.drain(..) {
            let s = &mut self.slots[slot as usize];
            s.claimed = false;
            self.lru.insert((s.tick, slot));
        }
    }

    /// Looks up `key` for drawing this frame. A hit is marked used. A miss takes a free slot, or
    /// else the least-recently-used slot not handed out this frame, and asks `can_upload` (the
    /// caller's per-frame byte budget) — only when such a slot exists, so a budget closure that
    /// debits bytes is charged exactly once per granted upload. No slot or no budget: the tile
    /// is late.
    pub fn request(&mut self, key: TileKey, can_upload: &mut dyn FnMut() -> bool) -> Request {
        if let Some(&slot) = self.map.get(&key) {
            self.counters.hits += 1;
            self.claim(slot);
            self.slots[slot as usize].drawn = Some(self.frame);
            return Request::Hit { slot };
        }
        let victim = self
            .free
            .last()
            .copied()
            .or_else(|| self.lru.first().map(|&(_, slot)| slot));
        match victim {
            Some(slot) if can_upload() => {
                self.counters.misses += 1;
                let evicted = self.install(slot, key, Some(self.frame));
                Request::Miss { slot, evicted }
            }
            _ => {
                self.counters.late += 1;
                Request::Unavailable
            }
        }
    }

    /// Prefetch (e.g. along the velocity vector): like [`request`](Self::request) but lower
    /// priority, so it cannot make this frame's or the next frames' draws late — it never evicts
    /// a slot drawn in the last `protect_frames` frames (`frame − drawn < protect_frames`) or
    /// handed out this frame, does not count late, and on a hit only refreshes recency (the tile
    /// is not drawn, so it stays evictable this frame).
    pub fn prefetch(
        &mut self,
        key: TileKey,
        can_upload: &mut dyn FnMut() -> bool,
        protect_frames: u64,
    ) -> Request {
        if let Some(&slot) = self.map.get(&key) {
            self.refresh(slot);
            return Request::Hit { slot };
        }
        let victim = match self.free.last() {
            Some(&slot) => Some(slot),
            None => self.prefetch_victim(protect_frames),
        };
        match victim {
            Some(slot) if can_upload() => {
                self.counters.prefetches += 1;
                let evicted = self.install(slot, key, None);
                Request::Miss { slot, evicted }
            }
            _ => Request::Unavailable,
        }
    }

    pub fn slot_of(&self, key: &TileKey) -> Option<u32> {
        self.map.get(key).copied()
    }

    pub fn is_resident(&self, key: &TileKey) -> bool {
        self.map.contains_key(key)
    }

    /// The tile held by `slot`, if any.
    pub fn key_at(&self, slot: u32) -> Option<TileKey> {
        self.slots.get(slot as usize).and_then(|s| s.key)
    }

    /// Slots holding a tile.
    pub fn occupancy(&self) -> u32 {
        self.map.len() as u32
    }

    pub fn capacity(&self) -> u32 {
        self.slots.len() as u32
    }

    pub fn counters(&self) -> PoolCounters {
        self.counters
    }

    fn next_tick(&mut self) -> u64 {
        self.tick += 1;
        self.tick
    }

    /// Marks an occupied slot handed out this frame and most recent.
    fn claim(&mut self, slot: u32) {
        let tick = self.next_tick();
        let s = &mut self.slots[slot as usize];
        if !s.claimed {
            self.lru.remove(&(s.tick, slot));
            s.claimed = true;
            self.claimed.push(slot);
        }
        s.tick = tick;
    }

    /// Makes an occupied slot most recent without claiming it.
    fn refresh(&mut self, slot: u32) {
        let tick = self.next_tick();
        let s = &mut self.slots[slot as usize];
        if !s.claimed {
            self.lru.remove(&(s.tick, slot));
            self.lru.insert((tick, slot));
        }
        s.tick = tick;
    }

    /// Least-recently-used unclaimed slot not drawn in the last `protect` frames.
    fn prefetch_victim(&mut self, protect: u64) -> Option<u32> {
        if self.prefetch_blocked.is_some_and(|p| protect >= p) {
            return None;
        }
        let frame = self.frame;
        let found = self.lru.iter().map(|&(_, slot)| slot).find(|&slot| {
            match self.slots[slot as usize].drawn {
                Some(d) => frame.saturating_sub(d) >= protect,
                None => true,
            }
        });
        if found.is_none() {
            self.prefetch_blocked = Some(self.prefetch_blocked.map_or(protect, |p| p.min(protect)));
        }
        found
    }

    /// Puts `key` into `slot` (free or unclaimed), claimed this frame; returns the evicted key.
    fn install(&mut self, slot: u32, key: TileKey, drawn: Option<u64>) -> Option<TileKey> {
        if self.free.last() == Some(&slot) {
            self.free.pop();
        } else {
            let removed = self.lru.remove(&(self.slots[slot as usize].tick, slot));
            debug_assert!(removed, "victim {slot} not in the LRU order");
        }
        let tick = self.next_tick();
        let s = &mut self.slots[slot as usize];
        let evicted = s.key.replace(key);
        s.tick = tick;
        s.drawn = drawn;
        s.claimed = true;
        self.claimed.push(slot);
        if let Some(old) = evicted {
            self.map.remove(&old);
            self.counters.evictions += 1;
        }
        self.map.insert(key, slot);
        evicted
    }

    /// Panics if the internal structures disagree (tests only).
    #[cfg(test)]
    fn check_invariants(&self) {
        assert!(self.map.len() <= self.slots.len());
        for (key, &slot) in &self.map {
            assert_eq!(self.slots[slot as usize].key, Some(*key));
        }
        let occupied = self.slots.iter().filter(|s| s.key.is_some()).count();
        assert_eq!(occupied, self.map.len());
        assert_eq!(occupied + self.free.len(), self.slots.len());
        for &f in &self.free {
            assert!(self.slots[f as usize].key.is_none());
        }
        assert_eq!(self.lru.len() + self.claimed.len(), occupied);
        for &(tick, slot) in &self.lru {
            let s = &self.slots[slot as usize];
            assert!(s.key.is_some() && !s.claimed && s.tick == tick);
        }
        for &slot in &self.claimed {
            assert!(self.slots[slot as usize].claimed);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::collections::HashSet;

    fn key(i: u32) -> TileKey {
        TileKey {
            level: i % 3,
            tx: i,
            ty: i / 2,
            refinement: 1 + i % 2,
        }
    }

    fn yes() -> impl FnMut() -> bool {
        || true
    }

    fn miss(slot: u32, evicted: Option<u32>) -> Request {
        Request::Miss {
            slot,
            evicted: evicted.map(key),
        }
    }

    #[test]
    fn free_slots_first_and_capacity_never_exceeded() {
        let mut pool = RefinedTilePool::new(4);
        pool.begin_frame(1);
        for i in 0..4 {
            assert_eq!(pool.request(key(i), &mut yes()), miss(i, None));
        }
        assert_eq!(pool.occupancy(), 4);
        assert_eq!(pool.request(key(4), &mut yes()), Request::Unavailable);
        pool.begin_frame(2);
        for i in 5..50 {
            assert!(matches!(
                pool.request(key(i), &mut yes()),
                Request::Miss { .. }
            ));
            assert!(pool.occupancy() <= pool.capacity());
            pool.begin_frame(2 + i as u64);
        }
        assert_eq!(pool.occupancy(), 4);
        pool.check_invariants();
    }

    #[test]
    fn evicts_the_least_recently_used() {
        let mut pool = RefinedTilePool::new(3);
        pool.begin_frame(1);
        for i in 0..3 {
            pool.request(key(i), &mut yes());
        }
        pool.begin_frame(2);
        assert_eq!(pool.request(key(0), &mut yes()), Request::Hit { slot: 0 });
        assert_eq!(pool.request(key(2), &mut yes()), Request::Hit { slot: 2 });
        pool.begin_frame(3);
        // 1 is the least recently used.
        assert_eq!(pool.request(key(10), &mut yes()), miss(1, Some(1)));
        pool.begin_frame(4);
        // Then 0 (touched before 2 in frame 2), then 2, then 10.
        assert_eq!(pool.request(key(11), &mut yes()), miss(0, Some(0)));
        assert_eq!(pool.request(key(12), &mut yes()), miss(2, Some(2)));
        assert_eq!(pool.request(key(13), &mut yes()), miss(1, Some(10)));
        assert_eq!(pool.request(key(14), &mut yes()), Request::Unavailable);
        pool.begin_frame(5);
        // Frame 4's order: 11, 12, 13.
        assert_eq!(pool.request(key(14), &mut yes()), miss(0, Some(11)));
        assert!(!pool.is_resident(&key(11)));
        assert_eq!(pool.slot_of(&key(14)), Some(0));
        assert_eq!(pool.key_at(0), Some(key(14)));
        pool.check_invariants();
    }

    #[test]
    fn slots_used_this_frame_are_never_evicted() {
        let mut pool = RefinedTilePool::new(4);
        pool.begin_frame(1);
        for i in 0..10 {
            let r = pool.request(key(i), &mut yes());
            if i < 4 {
                assert_eq!(r, miss(i, None));
            } else {
                assert_eq!(r, Request::Unavailable);
            }
        }
        for i in 0..4 {
            assert_eq!(pool.slot_of(&key(i)), Some(i));
        }
        let c = pool.counters();
        assert_eq!((c.misses, c.late, c.evictions), (4, 6, 0));
        // Hits this frame are protected as well: a new frame, two hits, then misses can only
        // take the other two slots.
        pool.begin_frame(2);
        assert_eq!(pool.request(key(3), &mut yes()), Request::Hit { slot: 3 });
        assert_eq!(pool.request(key(0), &mut yes()), Request::Hit { slot: 0 });
        assert_eq!(pool.request(key(20), &mut yes()), miss(1, Some(1)));
        assert_eq!(pool.request(key(21), &mut yes()), miss(2, Some(2)));
        assert_eq!(pool.request(key(22), &mut yes()), Request::Unavailable);
        pool.check_invariants();
    }

    #[test]
    fn budget_refusal_is_late_and_budget_asked_only_when_a_slot_exists() {
        let mut pool = RefinedTilePool::new(2);
        pool.begin_frame(1);
        let mut asked = 0;
        let mut budget = 1; // one upload this frame
        let mut can = || {
            asked += 1;
            if budget > 0 {
                budget -= 1;
                true
            } else {
                false
            }
        };
        assert_eq!(pool.request(key(0), &mut can), miss(0, None));
        assert_eq!(pool.request(key(1), &mut can), Request::Unavailable);
        assert_eq!(pool.request(key(0), &mut can), Request::Hit { slot: 0 });
        assert_eq!(asked, 2);
        assert!(!pool.is_resident(&key(1)));
        assert_eq!(pool.counters().late, 1);
        // Full and all claimed: the budget is not consulted (and so not charged).
        let mut pool = RefinedTilePool::new(1);
        pool.begin_frame(1);
        pool.request(key(0), &mut yes());
        let mut called = false;
        let r = pool.request(key(1), &mut || {
            called = true;
            true
        });
        assert_eq!(r, Request::Unavailable);
        assert!(!called);
        assert_eq!(pool.counters().late, 1);
        // Zero capacity: everything late.
        let mut pool = RefinedTilePool::new(0);
        pool.begin_frame(1);
        assert_eq!(pool.request(key(0), &mut yes()), Request::Unavailable);
        assert_eq!(pool.prefetch(key(0), &mut yes(), 0), Request::Unavailable);
        assert_eq!(pool.counters().late, 1);
    }

    #[test]
    fn counters_exact_in_a_scripted_scenario() {
        let mut pool = RefinedTilePool::new(3);
        let no = || false;
        pool.begin_frame(1);
        pool.request(key(0), &mut yes()); // miss
        pool.request(key(1), &mut yes()); // miss
        pool.request(key(0), &mut yes()); // hit
        pool.request(key(2), &mut no.clone()); // late (budget)
        pool.prefetch(key(3), &mut yes(), 1); // prefetch into free slot 2
        pool.request(key(4), &mut yes()); // late: all 3 slots claimed
        pool.begin_frame(2);
        pool.request(key(3), &mut yes()); // hit (prefetched)
        pool.request(key(5), &mut yes()); // miss, evicts 1 (least recent)
        pool.prefetch(key(0), &mut yes(), 1); // prefetch hit: no counter
        pool.prefetch(key(6), &mut yes(), 1); // evicts 0 (drawn in frame 1, 2 − 1 ≥ 1)
        pool.prefetch(key(7), &mut yes(), 1); // unavailable: all claimed; not late
        pool.begin_frame(3);
        pool.request(key(0), &mut no.clone()); // late
        pool.request(key(6), &mut yes()); // hit
        assert_eq!(
            pool.counters(),
            PoolCounters {
                hits: 3,
                misses: 3,
                evictions: 2,
                late: 3,
                prefetches: 2,
            }
        );
        pool.check_invariants();
    }

    #[test]
    fn prefetch_never_evicts_protected_slots() {
        let mut pool = RefinedTilePool::new(2);
        pool.begin_frame(10);
        pool.request(key(0), &mut yes());
        pool.request(key(1), &mut yes());
        pool.begin_frame(11);
        pool.request(key(1), &mut yes()); // drawn in 11
                                          // Both drawn within the last 2 frames: nothing to evict, nothing late.
        assert_eq!(pool.prefetch(key(2), &mut yes(), 2), Request::Unavailable);
        assert_eq!(pool.counters().late, 0);
        pool.begin_frame(12);
        // 0 was drawn in 10 (12 − 10 ≥ 2): evictable; 1 (drawn in 11) is not.
        assert_eq!(pool.prefetch(key(2), &mut yes(), 2), miss(0, Some(0)));
        assert_eq!(pool.prefetch(key(3), &mut yes(), 2), Request::Unavailable);
        // The prefetched slot is handed out: a request cannot take it this frame either.
        pool.request(key(1), &mut yes());
        assert_eq!(pool.request(key(4), &mut yes()), Request::Unavailable);
        // With protection 0 only this frame's claims are safe.
        pool.begin_frame(13);
        pool.request(key(2), &mut yes());
        assert_eq!(pool.prefetch(key(3), &mut yes(), 0), miss(1, Some(1)));
        pool.check_invariants();
    }

    #[test]
    fn prefetch_hit_refreshes_recency_without_drawing() {
        let mut pool = RefinedTilePool::new(2);
        pool.begin_frame(1);
        pool.request(key(0), &mut yes());
        pool.request(key(1), &mut yes());
        pool.begin_frame(5);
        assert_eq!(
            pool.prefetch(key(0), &mut yes(), 3),
            Request::Hit { slot: 0 }
        );
        // 0 is now more recent than 1, so a request evicts 1.
        assert_eq!(pool.request(key(2), &mut yes()), miss(1, Some(1)));
        // 0 was not marked drawn by the prefetch hit: still unprotected (drawn in frame 1) and
        // not claimed, so a prefetch may take it this frame.
        assert_eq!(pool.prefetch(key(3), &mut yes(), 3), miss(0, Some(0)));
        pool.check_invariants();
    }

    // ---- Reference model: a Vec in recency order, front = least recent. ----

    #[derive(Debug, Clone)]
    struct Entry {
        key: TileKey,
        slot: u32,
        drawn: Option<u64>,
        claimed: bool,
    }

    #[derive(Debug)]
    struct Model {
        free: Vec<u32>,
        order: Vec<Entry>,
        frame: u64,
        late: u64,
    }

    impl Model {
        fn new(capacity: u32) -> Self {
            Self {
                free: (0..capacity).collect(),
                order: Vec::new(),
                frame: 0,
                late: 0,
            }
        }

        fn begin_frame(&mut self, frame: u64) {
            self.frame = frame;
            for e in &mut self.order {
                e.claimed = false;
            }
        }

        /// Returns the outcome and whether the budget was asked.
        fn access(&mut self, key: TileKey, budget: bool, prefetch: Option<u64>) -> (Request, bool) {
            if let Some(i) = self.order.iter().position(|e| e.key == key) {
                let mut e = self.order.remove(i);
                if prefetch.is_none() {
                    e.drawn = Some(self.frame);
                    e.claimed = true;
                }
                let slot = e.slot;
                self.order.push(e);
                return (Request::Hit { slot }, false);
            }
            let frame = self.frame;
            let evictable = |e: &Entry| {
                !e.claimed
                    && match (prefetch, e.drawn) {
                        (Some(p), Some(d)) => frame - d >= p,
                        _ => true,
                    }
            };
            let victim = if !self.free.is_empty() {
                Some(None)
            } else {
                self.order.iter().position(evictable).map(Some)
            };
            let Some(victim) = victim else {
                self.late += prefetch.is_none() as u64;
                return (Request::Unavailable, false);
            };
            if !budget {
                self.late += prefetch.is_none() as u64;
                return (Request::Unavailable, true);
            }
            let (slot, evicted) = match victim {
                None => (self.free.remove(0), None),
                Some(i) => {
                    let e = self.order.remove(i);
                    (e.slot, Some(e.key))
                }
            };
            self.order.push(Entry {
                key,
                slot,
                drawn: prefetch.is_none().then_some(self.frame),
                claimed: true,
            });
            (Request::Miss { slot, evicted }, true)
        }
    }

    #[derive(Debug, Clone)]
    enum Op {
        BeginFrame {
            skip: u64,
        },
        Request {
            key: u32,
            budget: bool,
        },
        Prefetch {
            key: u32,
            budget: bool,
            protect: u64,
        },
    }

    fn op(keys: u32) -> impl Strategy<Value = Op> {
        prop_oneof![
            1 => (1u64..4).prop_map(|skip| Op::BeginFrame { skip }),
            4 => (0..keys, prop::bool::weighted(0.8))
                .prop_map(|(key, budget)| Op::Request { key, budget }),
            2 => (0..keys, prop::bool::weighted(0.8), 0u64..4)
                .prop_map(|(key, budget, protect)| Op::Prefetch { key, budget, protect }),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        #[test]
        fn matches_reference_model(
            (capacity, ops) in (0u32..8, 1u32..20)
                .prop_flat_map(|(c, k)| (Just(c), prop::collection::vec(op(k), 0..300)))
        ) {
            let mut pool = RefinedTilePool::new(capacity);
            let mut model = Model::new(capacity);
            let mut frame = 1;
            pool.begin_frame(frame);
            model.begin_frame(frame);
            for (n, op) in ops.iter().enumerate() {
                let (got, want) = match *op {
                    Op::BeginFrame { skip } => {
                        frame += skip;
                        pool.begin_frame(frame);
                        model.begin_frame(frame);
                        continue;
                    }
                    Op::Request { key: k, budget } => {
                        let mut asked = false;
                        let r = pool.request(key(k), &mut || { asked = true; budget });
                        ((r, asked), model.access(key(k), budget, None))
                    }
                    Op::Prefetch { key: k, budget, protect } => {
                        let mut asked = false;
                        let r = pool.prefetch(key(k), &mut || { asked = true; budget }, protect);
                        ((r, asked), model.access(key(k), budget, Some(protect)))
                    }
                };
                prop_assert_eq!(got, want, "op {} {:?}", n, op);
                prop_assert_eq!(pool.counters().late, model.late);
                prop_assert_eq!(pool.occupancy() as usize, model.order.len());
                pool.check_invariants();
            }
            for e in &model.order {
                prop_assert_eq!(pool.slot_of(&e.key), Some(e.slot));
            }
        }
    }

    /// xorshift64*: a deterministic workload without another crate.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
        }
        fn below(&mut self, n: u64) -> u64 {
            self.next() % n
        }
    }

    #[test]
    fn long_random_workload_stays_consistent() {
        const CAPACITY: u32 = 64;
        let mut pool = RefinedTilePool::new(CAPACITY);
        let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
        let mut position: u64 = 0;
        let mut requests = 0u64;
        for frame in 1..=100_000u64 {
            pool.begin_frame(frame);
            // A drifting working set around `position`, sometimes larger than the pool.
            position += rng.below(3);
            let wanted = 20 + rng.below(60);
            let mut budget = rng.below(12);
            let mut can = || {
                if budget > 0 {
                    budget -= 1;
                    true
                } else {
                    false
                }
            };
            // slot → key handed out this frame: a slot never serves two keys in one frame.
            let mut handed: HashMap<u32, TileKey> = HashMap::new();
            let mut drawn_now: HashSet<u32> = HashSet::new();
            for _ in 0..wanted {
                let k = key((position + rng.below(100)) as u32);
                requests += 1;
                let r = pool.request(k, &mut can);
                match r {
                    Request::Hit { slot } | Request::Miss { slot, .. } => {
                        assert_eq!(*handed.entry(slot).or_insert(k), k, "frame {frame}");
                        assert_eq!(pool.slot_of(&k), Some(slot));
                        drawn_now.insert(slot);
                    }
                    Request::Unavailable => assert!(!pool.is_resident(&k)),
                }
                if let Request::Miss {
                    evicted: Some(e), ..
                } = r
                {
                    assert!(!pool.is_resident(&e));
                }
            }
            for _ in 0..rng.below(10) {
                let k = key((position + 100 + rng.below(40)) as u32);
                if let Request::Miss { slot, evicted } = pool.prefetch(k, &mut can, 2) {
                    assert!(!drawn_now.contains(&slot));
                    assert!(handed.insert(slot, k).is_none(), "frame {frame}");
                    if let Some(e) = evicted {
                        assert!(!pool.is_resident(&e));
                    }
                }
            }
            assert!(pool.occupancy() <= CAPACITY);
            pool.check_invariants();
        }
        let c = pool.counters();
        assert_eq!(c.hits + c.misses + c.late, requests);
        assert!(c.hits > 0 && c.misses > 0 && c.late > 0 && c.evictions > 0 && c.prefetches > 0);
    }
}
