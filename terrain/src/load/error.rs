//! Why a DEM could not be loaded, and the one-line messages every loader builds.

use std::path::Path;

/// File name endings `load_dem` understands, for the "unknown extension" message.
pub(super) const ACCEPTED_EXTENSIONS: &str =
    ".hgt, .hgt.zip, .zip, .tif, .tiff, .png, .f32, .r32, .raw, .u16, .r16, .npy, .npz";

/// Why a DEM could not be loaded.
///
/// One variant per kind of failure so callers can react to e.g. a missing file differently;
/// `Display` is always a single line `"<path>: <reason>"` so a CLI can print it as is.
#[derive(Debug, thiserror::Error)]
pub enum DemError {
    /// The path does not exist.
    #[error("{path}: no such file")]
    NotFound { path: String },
    /// The path exists but cannot be read (permissions, a directory, I/O error).
    #[error("{path}: cannot read: {reason}")]
    Unreadable { path: String, reason: String },
    /// The file name ends in nothing `load_dem` knows.
    #[error(
        "{path}: unknown extension `{ext}` (accepted: {})",
        ACCEPTED_EXTENSIONS
    )]
    UnknownExtension { path: String, ext: String },
    /// The byte length or sample count does not match what the format or sidecar promises.
    #[error("{path}: {reason}")]
    Size { path: String, reason: String },
    /// The content is malformed or uses an unsupported variant of the format.
    #[error("{path}: {reason}")]
    Format { path: String, reason: String },
    /// A NaN or infinity where the format has no notion of nodata.
    #[error("{path}: non-finite sample {value} at (col {col}, row {row}) in file order, byte offset {offset}")]
    NonFinite {
        path: String,
        col: usize,
        row: usize,
        offset: u64,
        value: String,
    },
    /// A JSON sidecar is missing, malformed, has an unknown key or a value of the wrong type.
    /// `path` is the sidecar's own path unless the sidecar is missing.
    #[error("{path}: {reason}")]
    Sidecar { path: String, reason: String },
    /// Every sample is nodata, so there is nothing to interpolate from.
    #[error("{path}: all {count} samples are voids (nodata)")]
    AllVoid { path: String, count: usize },
}

impl DemError {
    /// The file the error is about (the DEM, or its sidecar for sidecar content errors).
    pub fn path(&self) -> &str {
        match self {
            DemError::NotFound { path }
            | DemError::Unreadable { path, .. }
            | DemError::UnknownExtension { path, .. }
            | DemError::Size { path, .. }
            | DemError::Format { path, .. }
            | DemError::NonFinite { path, .. }
            | DemError::Sidecar { path, .. }
            | DemError::AllVoid { path, .. } => path,
        }
    }
}

/// Path as shown in messages, kept on one line whatever the file is called.
pub(crate) fn show(path: &Path) -> String {
    one_line(&path.display().to_string())
}

/// Keeps foreign error texts (I/O, zip, PNG, JSON) on one line.
pub(crate) fn one_line(s: &str) -> String {
    s.replace("\r\n", "; ").replace(['\n', '\r'], "; ")
}

pub(crate) fn format_err(path: &Path, reason: impl Into<String>) -> DemError {
    DemError::Format {
        path: show(path),
        reason: one_line(&reason.into()),
    }
}

pub(crate) fn size_err(path: &Path, reason: impl Into<String>) -> DemError {
    DemError::Size {
        path: show(path),
        reason: one_line(&reason.into()),
    }
}

pub(crate) fn io_err(path: &Path, e: &std::io::Error) -> DemError {
    if e.kind() == std::io::ErrorKind::NotFound {
        DemError::NotFound { path: show(path) }
    } else {
        DemError::Unreadable {
            path: show(path),
            reason: one_line(&e.to_string()),
        }
    }
}

/// Reads a whole file, mapping "missing" and "a directory" to their own messages.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, DemError> {
    let meta = std::fs::metadata(path).map_err(|e| io_err(path, &e))?;
    if meta.is_dir() {
        return Err(DemError::Unreadable {
            path: show(path),
            reason: "is a directory".into(),
        });
    }
    std::fs::read(path).map_err(|e| io_err(path, &e))
}
