//! The configuration error type: one line naming the file, the key, the position and the reason.

use std::fmt;
use std::path::PathBuf;

use crate::limits::MAX_CONFIG_BYTES;

/// A 1-based line and column (in characters) inside a config file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Location {
    /// Line, starting at 1.
    pub line: usize,
    /// Column in characters, starting at 1.
    pub column: usize,
}

impl Location {
    /// The line and column of byte `offset` in `text` (clamped to the text).
    pub fn from_offset(text: &str, offset: usize) -> Self {
        let mut offset = offset.min(text.len());
        while !text.is_char_boundary(offset) {
            offset -= 1;
        }
        let before = &text[..offset];
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        Location {
            line: before.matches('\n').count() + 1,
            column: before[line_start..].chars().count() + 1,
        }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.line, self.column)
    }
}

/// Why a configuration could not be loaded. `Display` is a single line that starts with the
/// file name.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ConfigError {
    /// The file could not be read.
    #[error("{}: cannot read config file: {source}", path.display())]
    Io {
        /// The path that was asked for.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The file (or text) is larger than [`MAX_CONFIG_BYTES`](crate::limits::MAX_CONFIG_BYTES).
    #[error("{source_name}: config file is larger than the {} KiB limit{}", MAX_CONFIG_BYTES / 1024, fmt_size(size))]
    TooLarge {
        /// The path, or the source name given to `parse`.
        source_name: String,
        /// Its size in bytes, when known (not for pipes and devices, read only up to the limit).
        size: Option<u64>,
    },
    /// The text is not valid TOML.
    #[error("{source_name}:{location}: TOML syntax error: {message}")]
    Syntax {
        /// File name (or other source name) given to `parse`.
        source_name: String,
        /// Where the parser stopped.
        location: Location,
        /// The parser's reason.
        message: String,
    },
    /// Valid TOML, but a key is unknown, has the wrong type, or its value is out of range.
    #[error("{source_name}{}: {}: {message}", fmt_location(location), fmt_key(key))]
    Invalid {
        /// File name (or other source name) given to `parse`.
        source_name: String,
        /// Dotted key path, e.g. `render.tile_size` (empty for the document itself).
        key: String,
        /// Where the key's value is, when known.
        location: Option<Location>,
        /// The reason.
        message: String,
    },
}

impl ConfigError {
    /// The dotted key the error is about, if any.
    pub fn key(&self) -> Option<&str> {
        match self {
            ConfigError::Invalid { key, .. } => Some(key),
            _ => None,
        }
    }

    /// The line and column the error is about, if known.
    pub fn location(&self) -> Option<Location> {
        match self {
            ConfigError::Syntax { location, .. } => Some(*location),
            ConfigError::Invalid { location, .. } => *location,
            ConfigError::Io { .. } | ConfigError::TooLarge { .. } => None,
        }
    }
}

fn fmt_location(location: &Option<Location>) -> String {
    location.map(|l| format!(":{l}")).unwrap_or_default()
}

fn fmt_size(size: &Option<u64>) -> String {
    size.map(|n| format!(" ({n} bytes)")).unwrap_or_default()
}

fn fmt_key(key: &str) -> &str {
    if key.is_empty() {
        "(top level)"
    } else {
        key
    }
}

/// Folds a possibly multi-line message into one line.
pub(crate) fn one_line(message: &str) -> String {
    message
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join("; ")
}
