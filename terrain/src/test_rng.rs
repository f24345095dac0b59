//! The tests' random numbers: xorshift64, so every failure reproduces from its seed.

/// Uniform numbers in [0, 1) from `seed` (non-zero), 53 bits each.
pub(crate) fn unit(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    }
}
