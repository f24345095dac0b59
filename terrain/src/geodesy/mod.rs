//! The round Earth: WGS84 geodesy in f64 ([`wgs84`]: geodetic ⇄ ECEF ⇄ local ENU) and a
//! geographic grid placed on the ellipsoid ([`grid`]: the world frame of geographic datasets,
//! node boxes and the interpolation slack the error bound needs).

pub mod geoid;
pub mod grid;
pub mod projected;
pub mod tmerc;
pub mod utm;
pub mod wgs84;

pub use geoid::{egm96_undulation_m, GeoidCache};
pub use grid::{GeoGrid, NodeGeometry};
pub use utm::{projected_crs, UtmZone};
pub use wgs84::{ecef_to_geodetic, geodetic_to_ecef, Geodetic, LocalTangentPlane};
