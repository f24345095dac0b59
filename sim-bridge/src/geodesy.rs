//! WGS84 geodesy in f64: geodetic ⇄ Earth-centred Earth-fixed (ECEF) ⇄ local East-North-Up (ENU).
//!
//! One implementation serves the poses and the terrain drawn on the ellipsoid: it lives in
//! `aerie_terrain::geodesy::wgs84` (with its tests) and is re-exported here unchanged. Angles
//! are degrees at this API (as on the wire and in config), radians inside.

pub use aerie_terrain::geodesy::wgs84::*;
