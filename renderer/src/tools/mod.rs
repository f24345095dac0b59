//! Tools around the renderer: image-space error, the review panorama, the overlay text,
//! statistics CSV and output files.

pub mod heatmap;
pub mod image_error;
pub mod output;
pub mod overlay;
pub mod panorama;
pub mod percentile;
pub mod stats_csv;
