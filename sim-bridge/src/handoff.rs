//! Lock-free "latest value" hand-over from one producer thread to one consumer: a triple
//! buffer. The producer writes into its back slot and swaps it into the middle; the consumer
//! swaps the middle into its front slot when something new is there. Neither side ever waits
//! for the other, and the consumer always reads a complete value (never a torn one).

use std::cell::UnsafeCell;
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;

/// Set in `middle` when the middle slot holds a value the consumer has not taken yet.
const FRESH: u8 = 0b100;
const INDEX: u8 = 0b011;

struct Shared<T> {
    slots: [UnsafeCell<T>; 3],
    /// Index of the middle slot, plus [`FRESH`].
    middle: AtomicU8,
}

// Each slot is owned by exactly one side at a time — the producer's back slot, the consumer's
// front slot, and the middle slot owned by neither (only its index moves, through the `middle`
// atomic with acquire/release ordering). Values cross threads, so `T: Send`.
// SAFETY: no slot is ever reached from two threads at once.
unsafe impl<T: Send> Sync for Shared<T> {}

/// Producer side: publishes values.
pub struct Publisher<T> {
    shared: Arc<Shared<T>>,
    back: u8,
}

/// Consumer side: reads the newest published value.
pub struct Subscriber<T> {
    shared: Arc<Shared<T>>,
    front: u8,
}

/// A producer/consumer pair whose consumer initially reads `initial`.
pub fn latest<T: Clone + Send>(initial: T) -> (Publisher<T>, Subscriber<T>) {
    let shared = Arc::new(Shared {
        slots: [
            UnsafeCell::new(initial.clone()),
            UnsafeCell::new(initial.clone()),
            UnsafeCell::new(initial),
        ],
        middle: AtomicU8::new(1),
    });
    (
        Publisher {
            shared: shared.clone(),
            back: 0,
        },
        Subscriber { shared, front: 2 },
    )
}

impl<T: Send> Publisher<T> {
    /// Publishes `value`, replacing any value the consumer has not taken yet. Wait-free.
    pub fn publish(&mut self, value: T) {
        // SAFETY: the back slot is owned by this publisher (see `Shared`).
        unsafe { *self.shared.slots[usize::from(self.back)].get() = value };
        let old = self.shared.middle.swap(self.back | FRESH, Ordering::AcqRel);
        self.back = old & INDEX;
    }
}

impl<T: Send> Subscriber<T> {
    /// Takes the newest published value if there is one; returns whether it did. Wait-free.
    pub fn update(&mut self) -> bool {
        if self.shared.middle.load(Ordering::Relaxed) & FRESH == 0 {
            return false;
        }
        let old = self.shared.middle.swap(self.front, Ordering::AcqRel);
        self.front = old & INDEX;
        true
    }

    /// The value taken by the last [`update`](Self::update) (or the initial value).
    pub fn get(&self) -> &T {
        // SAFETY: the front slot is owned by this subscriber (see `Shared`).
        unsafe { &*self.shared.slots[usize::from(self.front)].get() }
    }
}

// Moving a side to another thread moves that ownership with it.
// SAFETY: each side only touches the slot it owns.
unsafe impl<T: Send> Send for Publisher<T> {}
// SAFETY: as for `Publisher`: the subscriber only touches the slot it owns.
unsafe impl<T: Send> Send for Subscriber<T> {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn newest_value_wins() {
        let (mut p, mut s) = latest(0u32);
        assert!(!s.update());
        assert_eq!(*s.get(), 0);
        p.publish(1);
        p.publish(2);
        assert!(s.update());
        assert_eq!(*s.get(), 2);
        assert!(!s.update());
        assert_eq!(*s.get(), 2);
        p.publish(3);
        assert!(s.update());
        assert_eq!(*s.get(), 3);
    }

    #[test]
    fn concurrent_values_are_never_torn_and_never_go_back() {
        // Each value is [k; 16]; a torn read would mix two k's.
        let (mut p, mut s) = latest([0u64; 16]);
        let writer = std::thread::spawn(move || {
            for k in 1..=200_000u64 {
                p.publish([k; 16]);
            }
        });
        let mut last = 0;
        let mut seen = 0;
        while last < 200_000 {
            if s.update() {
                let v = s.get();
                assert!(v.iter().all(|x| *x == v[0]), "torn: {v:?}");
                assert!(v[0] > last, "went back from {last} to {}", v[0]);
                last = v[0];
                seen += 1;
            }
        }
        writer.join().unwrap();
        assert!(seen > 0);
    }
}
