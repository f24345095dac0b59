//! Why a bake could not be made, read or written.

use std::path::Path;

use super::format::BAKE_VERSION;

/// Why a bake could not be made, read or written. `Display` is one line naming the file and,
/// for a bad file, the field or byte offset, the reason and the fix.
#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    #[error("bake parameters: {reason}")]
    Params { reason: String },
    #[error("{path}: no such file; make it with `aerie bake <dataset>`")]
    NotFound { path: String },
    #[error("{path}: cannot read: {reason}")]
    Io { path: String, reason: String },
    #[error("{path}: cannot write: {reason}")]
    Write { path: String, reason: String },
    #[error("{path}: not an aerie bake file (bytes 0..8 are {found}, expected \"AERIEBAK\"); re-run `aerie bake` (with --force to overwrite this file)")]
    BadMagic { path: String, found: String },
    #[error("{path}: format version {found} (byte offset 8) is not supported: this build reads version {BAKE_VERSION}{}; re-run `aerie bake` to rebuild it", older_note(*.found))]
    Version { path: String, found: u32 },
    #[error(
        "{path}: truncated at byte offset {offset}: {reason}; re-run `aerie bake` to rebuild it"
    )]
    Truncated {
        path: String,
        offset: u64,
        reason: String,
    },
    #[error("{path}: field `{field}` at byte offset {offset}: {reason}; re-run `aerie bake` to rebuild it")]
    Corrupt {
        path: String,
        field: String,
        offset: u64,
        reason: String,
    },
    #[error("{path}: stale: {reason}; re-run `aerie bake` to rebuild it")]
    Stale { path: String, reason: String },
    #[error("{path}: {reason}")]
    Refused { path: String, reason: String },
}

/// What an older format version lacks, for the message that replaces it.
fn older_note(found: u32) -> &'static str {
    match found {
        1 => " (version 1 kept one ε per tile, not its quadrants' nor its blocks')",
        2 => " (version 2 kept ε over each tile's quadrants, not over its 16 blocks: a tile drawn at its grandparent's resolution had only its parent's bound there)",
        _ => "",
    }
}

pub(super) fn show(p: &Path) -> String {
    p.display().to_string().replace(['\n', '\r'], " ")
}
