//! The page cache: decoded pages by [`PageId`], least-recently-used first out, within an
//! explicit byte budget that resident pages never exceed. Pinned pages (the coarsest levels,
//! so the renderer always has something to draw) count against the budget and are never
//! evicted. Pure: no threads, no I/O, no clock (use is a counter).

use std::collections::{BTreeMap, HashMap, HashSet};

use crate::store::PageId;

struct Entry<V> {
    value: V,
    bytes: u64,
    /// Its key in the LRU order (unpinned entries only).
    stamp: u64,
}

/// What [`PageCache::insert`] did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Inserted {
    /// Resident now; these pages were evicted to make room (least recently used first).
    Yes { evicted: Vec<PageId> },
    /// Not inserted: the page and the pinned pages together exceed the budget (nothing was
    /// evicted).
    TooLarge,
}

/// Decoded pages within a byte budget (see the module documentation).
pub struct PageCache<V> {
    budget: u64,
    resident: u64,
    pinned_bytes: u64,
    entries: HashMap<PageId, Entry<V>>,
    /// Unpinned resident pages by last use, oldest first.
    lru: BTreeMap<u64, PageId>,
    pinned: HashSet<PageId>,
    tick: u64,
    evicted: u64,
}

impl<V> PageCache<V> {
    /// An empty cache that holds at most `budget` bytes of pages.
    pub fn new(budget: u64) -> Self {
        PageCache {
            budget,
            resident: 0,
            pinned_bytes: 0,
            entries: HashMap::new(),
            lru: BTreeMap::new(),
            pinned: HashSet::new(),
            tick: 0,
            evicted: 0,
        }
    }

    pub fn budget(&self) -> u64 {
        self.budget
    }

    /// Bytes of the resident pages (≤ the budget, always).
    pub fn resident_bytes(&self) -> u64 {
        self.resident
    }

    /// Bytes of the resident pinned pages.
    pub fn pinned_bytes(&self) -> u64 {
        self.pinned_bytes
    }

    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Pages evicted since the cache was made.
    pub fn evicted(&self) -> u64 {
        self.evicted
    }

    pub fn contains(&self, id: PageId) -> bool {
        self.entries.contains_key(&id)
    }

    pub fn is_pinned(&self, id: PageId) -> bool {
        self.pinned.contains(&id)
    }

    /// Pins `id` (resident or not): once resident it is never evicted.
    pub fn pin(&mut self, id: PageId) {
        if !self.pinned.insert(id) {
            return;
        }
        if let Some(e) = self.entries.get(&id) {
            self.lru.remove(&e.stamp);
            self.pinned_bytes += e.bytes;
        }
    }

    fn next_stamp(&mut self) -> u64 {
        self.tick += 1;
        self.tick
    }

    /// The page, marked as just used.
    pub fn get(&mut self, id: PageId) -> Option<&V> {
        let stamp = self.next_stamp();
        let pinned = self.pinned.contains(&id);
        let e = self.entries.get_mut(&id)?;
        if !pinned {
            self.lru.remove(&e.stamp);
            e.stamp = stamp;
            self.lru.insert(stamp, id);
        }
        Some(&e.value)
    }

    /// The page, without marking it used.
    pub fn peek(&self, id: PageId) -> Option<&V> {
        self.entries.get(&id).map(|e| &e.value)
    }

    /// Makes `value` (`bytes` long) resident as `id`, as the most recently used page, evicting
    /// least-recently-used unpinned pages until it fits (see [`Inserted`]). A page already
    /// resident under `id` is replaced.
    pub fn insert(&mut self, id: PageId, value: V, bytes: u64) -> Inserted {
        let pinned = self.pinned.contains(&id);
        let old = self.entries.get(&id).map_or(0, |e| e.bytes);
        let pinned_other = self.pinned_bytes - if pinned { old } else { 0 };
        if pinned_other + bytes > self.budget {
            return Inserted::TooLarge;
        }
        self.remove(id);
        let mut evicted = Vec::new();
        while self.resident + bytes > self.budget {
            // Fits once every unpinned page is gone (checked above), so the LRU is not empty.
            let Some((_, victim)) = self.lru.pop_first() else {
                break;
            };
            if let Some(e) = self.entries.remove(&victim) {
                self.resident -= e.bytes;
            }
            self.evicted += 1;
            evicted.push(victim);
        }
        let stamp = self.next_stamp();
        if pinned {
            self.pinned_bytes += bytes;
        } else {
            self.lru.insert(stamp, id);
        }
        self.resident += bytes;
        self.entries.insert(
            id,
            Entry {
                value,
                bytes,
                stamp,
            },
        );
        Inserted::Yes { evicted }
    }

    /// Drops `id` if resident (pinned or not; it stays pinned for its next insert).
    pub fn remove(&mut self, id: PageId) -> Option<V> {
        let e = self.entries.remove(&id)?;
        self.resident -= e.bytes;
        if self.pinned.contains(&id) {
            self.pinned_bytes -= e.bytes;
        } else {
            self.lru.remove(&e.stamp);
        }
        Some(e.value)
    }

    /// Every resident page (in no particular order), without marking any used.
    pub fn iter(&self) -> impl Iterator<Item = (PageId, &V)> {
        self.entries.iter().map(|(k, e)| (*k, &e.value))
    }

    /// Unpinned resident pages, least recently used first (the eviction order).
    pub fn lru_order(&self) -> Vec<PageId> {
        self.lru.values().copied().collect()
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    fn id(k: u32) -> PageId {
        PageId {
            level: k % 3,
            px: k,
            py: 0,
        }
    }

    #[test]
    fn least_recently_used_goes_first_and_pinned_never() {
        let mut c = PageCache::new(100);
        c.pin(id(0));
        for k in 0..4 {
            assert_eq!(c.insert(id(k), k, 25), Inserted::Yes { evicted: vec![] });
        }
        assert_eq!(c.resident_bytes(), 100);
        assert_eq!(c.lru_order(), vec![id(1), id(2), id(3)]);
        c.get(id(1));
        assert_eq!(c.lru_order(), vec![id(2), id(3), id(1)]);
        // 50 more bytes evict the two least recently used unpinned pages.
        assert_eq!(
            c.insert(id(9), 9, 50),
            Inserted::Yes {
                evicted: vec![id(2), id(3)]
            }
        );
        assert!(c.contains(id(0)) && c.contains(id(1)) && c.contains(id(9)));
        assert_eq!(c.evicted(), 2);
        // A page that cannot fit beside the pinned ones is refused and evicts nothing.
        assert_eq!(c.insert(id(7), 7, 80), Inserted::TooLarge);
        assert_eq!(c.len(), 3);
        // peek does not reorder; remove gives the bytes back.
        c.peek(id(1));
        assert_eq!(c.lru_order(), vec![id(1), id(9)]);
        assert_eq!(c.remove(id(9)), Some(9));
        assert_eq!(c.resident_bytes(), 50);
        assert_eq!(c.pinned_bytes(), 25);
    }

    #[derive(Debug, Clone)]
    enum Op {
        Insert(u32, u64),
        Get(u32),
        Pin(u32),
        Remove(u32),
    }

    fn op() -> impl Strategy<Value = Op> {
        prop_oneof![
            4 => (0u32..24, 1u64..40).prop_map(|(k, b)| Op::Insert(k, b)),
            3 => (0u32..24).prop_map(Op::Get),
            1 => (0u32..24).prop_map(Op::Pin),
            1 => (0u32..24).prop_map(Op::Remove),
        ]
    }

    proptest! {
        /// Any sequence of inserts, gets, pins and removes: resident bytes never exceed the
        /// budget, pinned pages are never evicted, and the eviction order is exactly the
        /// order of last use kept by a brute-force model.
        #[test]
        fn budget_pins_and_lru_order_hold(budget in 40u64..200, ops in proptest::collection::vec(op(), 1..200)) {
            let mut c = PageCache::new(budget);
            // The model: resident pages with bytes, and their last-use order (oldest first).
            let mut bytes: HashMap<PageId, u64> = HashMap::new();
            let mut order: Vec<PageId> = Vec::new();
            let mut pinned: HashSet<PageId> = HashSet::new();
            let touch = |order: &mut Vec<PageId>, p: PageId| {
                order.retain(|&q| q != p);
                order.push(p);
            };
            for o in ops {
                match o {
                    Op::Insert(k, b) => {
                        let p = id(k);
                        let pinned_other: u64 = bytes.iter().filter(|(q, _)| pinned.contains(q) && **q != p).map(|(_, b)| b).sum();
                        let got = c.insert(p, k, b);
                        if pinned_other + b > budget {
                            prop_assert_eq!(got, Inserted::TooLarge);
                        } else {
                            bytes.remove(&p);
                            order.retain(|&q| q != p);
                            let mut want = Vec::new();
                            let mut used: u64 = bytes.values().sum();
                            while used + b > budget {
                                let v = *order.iter().find(|q| !pinned.contains(q)).expect("an unpinned page");
                                order.retain(|&q| q != v);
                                used -= bytes.remove(&v).unwrap();
                                want.push(v);
                            }
                            prop_assert_eq!(got, Inserted::Yes { evicted: want });
                            bytes.insert(p, b);
                            touch(&mut order, p);
                        }
                    }
                    Op::Get(k) => {
                        let p = id(k);
                        prop_assert_eq!(c.get(p).is_some(), bytes.contains_key(&p));
                        if bytes.contains_key(&p) {
                            touch(&mut order, p);
                        }
                    }
                    Op::Pin(k) => {
                        c.pin(id(k));
                        pinned.insert(id(k));
                    }
                    Op::Remove(k) => {
                        prop_assert_eq!(c.remove(id(k)).is_some(), bytes.remove(&id(k)).is_some());
                        order.retain(|&q| q != id(k));
                    }
                }
                prop_assert!(c.resident_bytes() <= budget);
                prop_assert_eq!(c.resident_bytes(), bytes.values().sum::<u64>());
                let want: Vec<PageId> = order.iter().copied().filter(|q| !pinned.contains(q)).collect();
                prop_assert_eq!(c.lru_order(), want);
                for p in &pinned {
                    // A pinned page leaves only by remove, never by eviction: the model keeps it.
                    prop_assert_eq!(c.contains(*p), bytes.contains_key(p));
                }
            }
        }
    }
}
