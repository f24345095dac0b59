//! Why a store cannot be written, opened or read: every variant names the file, and the field
//! or byte offset or page, and the reason.

use std::path::PathBuf;

/// Which page, for messages: "level 2 page (3, 1)".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PageId {
    pub level: u32,
    pub px: u32,
    pub py: u32,
}

impl std::fmt::Display for PageId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "level {} page ({}, {})", self.level, self.px, self.py)
    }
}

/// A store that cannot be opened or written.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// Reading the file failed (not found, permission, I/O error).
    #[error("{path}: cannot read: {reason}")]
    Io { path: PathBuf, reason: String },
    /// The header or index is not what this reader accepts; `offset` is the byte where the
    /// offending field starts.
    #[error("{path}: byte {offset} ({field}): {reason}")]
    Format {
        path: PathBuf,
        offset: u64,
        field: &'static str,
        reason: String,
    },
    /// The parameters or the data cannot make a store.
    #[error("{reason}")]
    Params { reason: String },
    /// The source could not be read while a streamed import read it (a sample out of range,
    /// a row that cannot be read); nothing was left under the final name.
    #[error("{0}")]
    Source(#[from] crate::load::DemError),
    /// Writing failed; nothing was left under the final name.
    #[error("{0}")]
    Write(#[from] aerie_io::WriteError),
}

/// A page that cannot be read; the store itself stays usable (the caller draws coarser).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PageError {
    /// No such page in the store's layout.
    #[error("{path}: {page} is not in the store ({reason})")]
    NoSuchPage {
        path: PathBuf,
        page: PageId,
        reason: String,
    },
    /// The file ends inside the page (truncated after open) or the read failed.
    #[error("{path}: {page} at bytes {offset}..{end}: cannot read: {reason}")]
    Read {
        path: PathBuf,
        page: PageId,
        offset: u64,
        end: u64,
        reason: String,
    },
    /// The page's bytes do not match the index's CRC-32.
    #[error("{path}: {page} at bytes {offset}..{end}: checksum mismatch (CRC-32 {got:#010x}, index says {want:#010x}): the page is corrupt")]
    Checksum {
        path: PathBuf,
        page: PageId,
        offset: u64,
        end: u64,
        got: u32,
        want: u32,
    },
    /// The page decompressed to something other than the header and index promise.
    #[error("{path}: {page} at bytes {offset}..{end}: {reason}")]
    Content {
        path: PathBuf,
        page: PageId,
        offset: u64,
        end: u64,
        reason: String,
    },
}
