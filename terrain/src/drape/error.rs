//! Why a raster could not be draped: one line naming the file.

/// Why a raster could not be draped, one line: `"<file>: <reason>"`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{path}: {reason}")]
pub struct DrapeError {
    /// The raster file, as shown to the user.
    pub path: String,
    pub reason: String,
}

impl DrapeError {
    pub fn new(path: &std::path::Path, reason: impl Into<String>) -> Self {
        Self {
            path: path.display().to_string().replace(['\n', '\r'], " "),
            reason: reason.into().replace(['\n', '\r'], "; "),
        }
    }
}

impl From<crate::DemError> for DrapeError {
    fn from(e: crate::DemError) -> Self {
        let path = e.path().to_string();
        let text = e.to_string();
        let reason = text
            .strip_prefix(&format!("{path}: "))
            .unwrap_or(&text)
            .to_string();
        Self { path, reason }
    }
}
