//! DEM loaders (being written).
use std::path::Path;
use super::Heightfield;

#[derive(Debug, thiserror::Error)]
pub enum DemError {
    #[error("{path}: {reason}")]
    Invalid { path: String, reason: String },
}

pub fn load_dem(path: &Path) -> Result<Heightfield, DemError> {
    Err(DemError::Invalid { path: path.display().to_string(), reason: "loaders not written yet".into() })
}
