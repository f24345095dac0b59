//! The request queue: pages wished for, each once, largest priority first; a new frame's
//! wishes replace the old ones no worker has started. Pure: no threads, no I/O.

use std::cmp::Ordering;
use std::collections::{BTreeSet, HashMap, HashSet};

use crate::store::PageId;

/// How urgent a page is; larger is served first. Ties go to the coarser level (it serves
/// more of the screen), then to the lower row and column, so the order is deterministic.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Urgency {
    priority: f32,
    id: PageId,
}

impl Eq for Urgency {}

impl Ord for Urgency {
    fn cmp(&self, o: &Self) -> Ordering {
        self.priority
            .total_cmp(&o.priority)
            .then(self.id.level.cmp(&o.id.level))
            .then(o.id.py.cmp(&self.id.py))
            .then(o.id.px.cmp(&self.id.px))
    }
}

impl PartialOrd for Urgency {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// A NaN priority is the least urgent of all (it must not jump the queue).
fn clean(p: f32) -> f32 {
    if p.is_nan() {
        f32::NEG_INFINITY
    } else {
        p
    }
}

/// Pages waiting for a worker, and those a worker has taken and not finished.
#[derive(Debug, Default)]
pub struct RequestQueue {
    order: BTreeSet<Urgency>,
    pending: HashMap<PageId, f32>,
    started: HashSet<PageId>,
}

impl RequestQueue {
    pub fn new() -> Self {
        Self::default()
    }

    /// Pages waiting.
    pub fn len(&self) -> usize {
        self.pending.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pending.is_empty()
    }

    /// Pages taken by a worker and not finished.
    pub fn in_flight(&self) -> usize {
        self.started.len()
    }

    pub fn is_pending(&self, id: PageId) -> bool {
        self.pending.contains_key(&id)
    }

    pub fn is_started(&self, id: PageId) -> bool {
        self.started.contains(&id)
    }

    /// Wishes `id` at `priority`, keeping the larger of this and an earlier wish for it; a
    /// page a worker has started is not wished again.
    pub fn add(&mut self, id: PageId, priority: f32) {
        let priority = clean(priority);
        if self.started.contains(&id) {
            return;
        }
        match self.pending.get(&id) {
            Some(&p) if p >= priority => {}
            Some(&p) => {
                self.order.remove(&Urgency { priority: p, id });
                self.order.insert(Urgency { priority, id });
                self.pending.insert(id, priority);
            }
            None => {
                self.order.insert(Urgency { priority, id });
                self.pending.insert(id, priority);
            }
        }
    }

    /// Replaces every waiting wish by `wants` (deduplicated: a page wished twice keeps its
    /// larger priority); pages already started stay with their workers.
    pub fn replace(&mut self, wants: impl IntoIterator<Item = (PageId, f32)>) {
        self.order.clear();
        self.pending.clear();
        for (id, p) in wants {
            self.add(id, p);
        }
    }

    /// The most urgent waiting page, now started.
    pub fn pop(&mut self) -> Option<PageId> {
        let u = self.order.pop_last()?;
        self.pending.remove(&u.id);
        self.started.insert(u.id);
        Some(u.id)
    }

    /// A started page is done (loaded or failed): it can be wished again.
    pub fn finish(&mut self, id: PageId) {
        self.started.remove(&id);
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    fn id(level: u32, px: u32) -> PageId {
        PageId { level, px, py: 0 }
    }

    #[test]
    fn largest_first_deduplicated_and_replaced() {
        let mut q = RequestQueue::new();
        q.replace([
            (id(0, 1), 1.0),
            (id(0, 2), 5.0),
            (id(0, 1), 7.0),
            (id(0, 3), f32::NAN),
        ]);
        assert_eq!(q.len(), 3);
        assert_eq!(q.pop(), Some(id(0, 1)));
        assert_eq!(q.in_flight(), 1);
        // A new frame's wishes replace the old ones not started; the started page is not
        // wished again until it is finished.
        q.replace([(id(0, 1), 9.0), (id(1, 0), 2.0), (id(0, 4), 2.0)]);
        assert_eq!(q.len(), 2);
        assert!(!q.is_pending(id(0, 2)) && !q.is_pending(id(0, 1)));
        // Equal priorities: the coarser level first.
        assert_eq!(q.pop(), Some(id(1, 0)));
        assert_eq!(q.pop(), Some(id(0, 4)));
        assert_eq!(q.pop(), None);
        q.finish(id(0, 1));
        q.add(id(0, 1), 3.0);
        q.add(id(0, 1), 1.0);
        assert_eq!(q.len(), 1);
        assert_eq!(q.pop(), Some(id(0, 1)));
    }

    proptest! {
        /// Whatever is added, pop yields each waiting page once, in non-increasing priority,
        /// each with the largest priority it was wished at.
        #[test]
        fn pops_in_priority_order_once_each(wants in proptest::collection::vec((0u32..30, -5.0f32..5.0), 0..100)) {
            let mut q = RequestQueue::new();
            q.replace(wants.iter().map(|&(k, p)| (id(k % 3, k), p)));
            let mut best: HashMap<PageId, f32> = HashMap::new();
            for &(k, p) in &wants {
                let e = best.entry(id(k % 3, k)).or_insert(p);
                *e = e.max(p);
            }
            let mut last = f32::INFINITY;
            let mut seen = HashSet::new();
            while let Some(p) = q.pop() {
                prop_assert!(seen.insert(p));
                let pr = best[&p];
                prop_assert!(pr <= last);
                last = pr;
            }
            prop_assert_eq!(seen.len(), best.len());
        }
    }
}
