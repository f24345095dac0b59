//! A multiply–rotate hasher for the small integer keys of per-frame tables (node caches,
//! neighbour indices): std's SipHash costs more than the lookups it serves. Not for keys an
//! adversary chooses.

use std::hash::{BuildHasherDefault, Hasher};

/// Each word rotated into the state and multiplied by an odd constant; [`Hasher::finish`]
/// folds the high half onto the low one, because a product's low bits depend only on the
/// key's low bits and a table picks its bucket from the low bits.
#[derive(Debug, Default, Clone, Copy)]
pub struct FastHasher(u64);

impl Hasher for FastHasher {
    fn finish(&self) -> u64 {
        self.0 ^ (self.0 >> 32)
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_u32(&mut self, v: u32) {
        self.write_u64(v as u64);
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x517c_c1b7_2722_0a95);
    }
}

/// [`FastHasher`] for `HashMap::with_hasher` and friends.
pub type FastHash = BuildHasherDefault<FastHasher>;

#[cfg(test)]
mod tests {
    use std::hash::{BuildHasher, Hash};

    use super::*;

    fn hash_of(v: impl Hash) -> u64 {
        FastHash::default().hash_one(v)
    }

    /// Keys that differ only in their high bits (another tile column or level packed above the
    /// row) land in different buckets of a small table: the fold brings the high bits down.
    #[test]
    fn keys_differing_only_high_spread_over_the_low_bits() {
        let buckets: std::collections::HashSet<u64> =
            (0..256u64).map(|x| hash_of((x << 29) | 7) & 1023).collect();
        assert!(
            buckets.len() > 200,
            "{} distinct buckets of 256 keys",
            buckets.len()
        );
        // Equal keys hash equally; the order of words matters.
        assert_eq!(hash_of((3u32, 4u32)), hash_of((3u32, 4u32)));
        assert_ne!(hash_of((3u32, 4u32)), hash_of((4u32, 3u32)));
    }
}
