//! Every file aerie writes goes through here.
//!
//! - [`AtomicFile`] / [`write_atomic`]: a temporary file in the destination's folder, every
//!   write checked, `fsync` of the file before the rename and of the folder after it, the
//!   temporary removed on any failure or drop. A reader sees the old file or the complete new
//!   one, never a 0-byte or cut file; errors name the final path and the OS reason.
//! - [`AtomicFile::map_preallocated`]: files filled through a memory map get their blocks
//!   reserved first (`posix_fallocate`), so a full disk is an error, never `SIGBUS`.
//! - [`FileSystem`]: the few operations the writer (and readers of pages) need, with the real
//!   implementation [`RealFs`] and the fault-injecting [`FaultyFs`] for tests.
//! - [`tmpfs::SmallTmpfs`]: a really full disk for tests, when running as root.

mod atomic;
mod fault;
mod fs;
pub mod tmpfs;

pub use atomic::{write_atomic, write_atomic_in, AtomicFile, WriteError};
pub use fault::{Faults, FaultyFs};
pub use fs::{real, FileSystem, InFile, OutFile, RealFs};

#[cfg(test)]
mod tests;
