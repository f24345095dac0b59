//! Geographic (lat/lon) grids: their ground spacing on the WGS84 tangent plane.

/// WGS84 semi-major axis, metres.
const WGS84_A: f64 = 6_378_137.0;
/// WGS84 flattening.
const WGS84_F: f64 = 1.0 / 298.257_223_563;

/// Ground spacing in metres `(east_west, north_south)` of a lat/lon grid with steps
/// `dlat_deg` × `dlon_deg`, on the WGS84 local tangent plane at `lat_deg`.
///
/// Uses the meridian radius M(φ) for N–S and the prime-vertical radius N(φ)·cos φ for E–W, so a
/// 3" SRTM tile at 47.5°N comes out at about 62.8 m × 92.6 m instead of a square grid.
pub fn geographic_spacing_m(lat_deg: f64, dlat_deg: f64, dlon_deg: f64) -> (f64, f64) {
    let e2 = WGS84_F * (2.0 - WGS84_F);
    let phi = lat_deg.to_radians();
    let s2 = phi.sin() * phi.sin();
    let w = (1.0 - e2 * s2).sqrt();
    let m = WGS84_A * (1.0 - e2) / (w * w * w);
    let n = WGS84_A / w;
    (
        dlon_deg.to_radians() * n * phi.cos(),
        dlat_deg.to_radians() * m,
    )
}

/// Spacing and note for a geographic grid whose south-west sample is at `south_lat_deg` and
/// which has `height` rows.
pub(crate) fn geographic_spacing_with_note(
    south_lat_deg: f64,
    dlat_deg: f64,
    dlon_deg: f64,
    height: usize,
) -> (f64, f64, String) {
    let centre = south_lat_deg + dlat_deg * (height.saturating_sub(1)) as f64 / 2.0;
    let (sx, sy) = geographic_spacing_m(centre, dlat_deg, dlon_deg);
    let hemi = if centre < 0.0 { 'S' } else { 'N' };
    let step = if (dlat_deg - dlon_deg).abs() <= 1e-12 * dlat_deg.abs().max(1e-300) {
        arcsec(dlat_deg)
    } else {
        format!("{}×{}", arcsec(dlat_deg), arcsec(dlon_deg))
    };
    let note = format!(
        "geographic {step} grid, local tangent plane at {:.3}°{hemi}: {sx:.2} m E-W, {sy:.2} m N-S",
        centre.abs()
    );
    (sx, sy, note)
}

/// `3"` for 1/1200°, `1.5"` etc.
fn arcsec(deg: f64) -> String {
    let s = deg * 3600.0;
    if (s - s.round()).abs() < 1e-6 {
        format!("{}\"", s.round())
    } else {
        format!("{s:.3}\"")
    }
}
