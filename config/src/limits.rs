//! Limits on a config file as a whole: its size and its channel count.

/// Largest config file, bytes (1 MiB: a 64-channel config is a few KiB).
pub const MAX_CONFIG_BYTES: u64 = 1 << 20;
/// Most `[[channel]]` tables a config may have (well above any projector wall).
pub const MAX_CHANNELS: usize = 64;
