//! Where a grid's samples lie on the ground: spacing, the note saying where it came from, and
//! the geographic reference when the file has one.

use crate::GeoReference;

use super::error::DemError;
use super::geo::geographic_spacing_with_note;
use super::sidecar::{metric_spacing, Sidecar};

/// Spacing (metres), its explanation and the geo-reference of decoded samples.
pub(crate) struct Placement {
    pub spacing_x: f64,
    pub spacing_y: f64,
    pub geo: Option<GeoReference>,
    pub spacing_note: String,
}

impl Placement {
    /// A grid without a geo-reference: the sidecar's spacing or the default.
    pub(crate) fn metric(sidecar: Option<&Sidecar>) -> Result<Self, DemError> {
        let (spacing_x, spacing_y, spacing_note) = metric_spacing(sidecar)?;
        Ok(Self {
            spacing_x,
            spacing_y,
            geo: None,
            spacing_note,
        })
    }

    /// A lat/lon grid of `rows` rows whose south-west sample is at (`south_lat_deg`,
    /// `west_lon_deg`), with steps `dlat_deg` × `dlon_deg`.
    pub(crate) fn geographic(
        south_lat_deg: f64,
        west_lon_deg: f64,
        dlat_deg: f64,
        dlon_deg: f64,
        rows: usize,
    ) -> Self {
        let (spacing_x, spacing_y, spacing_note) =
            geographic_spacing_with_note(south_lat_deg, dlat_deg, dlon_deg, rows);
        Self {
            spacing_x,
            spacing_y,
            geo: Some(GeoReference::Geographic {
                south_lat_deg,
                west_lon_deg,
                dlat_deg,
                dlon_deg,
            }),
            spacing_note,
        }
    }
}
