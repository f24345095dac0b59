//! A geographic (latitude/longitude) grid placed on the WGS84 ellipsoid (DESIGN.md "The world
//! is large and round"; issue 14).
//!
//! Two coordinate systems meet here:
//! - **grid metres** `(gx, gy)`: the flat layout the clipmap, the bake and the selection index
//!   tiles by — sample (col, row) at `(col · spacing_x, row · spacing_y)`, as the loaders set
//!   the spacings. Only an index: nothing is drawn there.
//! - **world**: the local East-North-Up frame tangent to the ellipsoid at sample (0, 0), height
//!   0 (DESIGN.md "Conventions": the origin at the dataset's south-west corner). A sample at
//!   (lat, lon, h) is at its exact WGS84 position in this frame, so far from the origin the
//!   ground bends down and tilts; cameras, frusta and tile boxes live here.
//!
//! The decisions on the curved surface — a node's world box, its normal and how much the
//! normal turns over it, the interpolation slack of a drawn cell — are pure f64 math below.

use glam::{DMat3, DVec2, DVec3};

use super::projected::ProjectedGrid;
use super::utm::projected_crs;
use super::wgs84::{geodetic_to_ecef, Geodetic, LocalTangentPlane, WGS84_A, WGS84_E2};
use crate::tiles::Aabb;
use crate::GeoReference;

/// A grid on the ellipsoid — geographic, or projected (UTM, [`ProjectedGrid`]) — its
/// geo-reference, its index spacing and the world frame. See the module documentation.
///
/// On a projected grid `south_lat_deg`/`west_lon_deg` are sample (0, 0)'s latitude and
/// longitude and `dlat_deg`/`dlon_deg` are 0 (there is no constant step): go through
/// [`GeoGrid::lat_lon_of_grid`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeoGrid {
    pub south_lat_deg: f64,
    pub west_lon_deg: f64,
    pub dlat_deg: f64,
    pub dlon_deg: f64,
    /// Grid metres per column / row (the index layout, not a ground distance).
    pub spacing_x: f64,
    pub spacing_y: f64,
    /// The world frame: ENU tangent at sample (0, 0), height 0.
    pub world: LocalTangentPlane,
    /// `Some` for a projected grid: grid metres are projected metres from sample (0, 0).
    pub projected: Option<ProjectedGrid>,
}

/// What the selection needs of a node on the ellipsoid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeGeometry {
    /// World box holding every position of the node between its lowest and highest sample
    /// (the drawn triangles are convex combinations of such positions, so it holds them too).
    pub aabb: Aabb,
    /// World unit normal of the ellipsoid at the node's centre.
    pub up: DVec3,
    /// Largest angle (radians) between `up` and the normal anywhere on the node.
    pub spread: f64,
}

/// Meridional radius of curvature M(φ).
fn meridian_radius(sin_lat: f64) -> f64 {
    let w2 = 1.0 - WGS84_E2 * sin_lat * sin_lat;
    WGS84_A * (1.0 - WGS84_E2) / (w2 * w2.sqrt())
}

/// Prime-vertical radius of curvature N(φ).
fn normal_radius(sin_lat: f64) -> f64 {
    WGS84_A / (1.0 - WGS84_E2 * sin_lat * sin_lat).sqrt()
}

/// The ellipsoid normal (ECEF unit vector) at a geodetic latitude/longitude in radians.
fn normal_ecef(lat: f64, lon: f64) -> DVec3 {
    let (sp, cp) = lat.sin_cos();
    let (sl, cl) = lon.sin_cos();
    DVec3::new(cp * cl, cp * sl, sp)
}

impl GeoGrid {
    /// A geographic grid of `d`° cells from (`south`°, `west`°), its spacing taken at
    /// `lat_spacing`°: for the tests.
    #[cfg(test)]
    pub(crate) fn test_geographic(south: f64, west: f64, d: f64, lat_spacing: f64) -> Self {
        let (sx, sy) = crate::load::geographic_spacing_m(lat_spacing, d, d);
        let geo = GeoReference::Geographic {
            south_lat_deg: south,
            west_lon_deg: west,
            dlat_deg: d,
            dlon_deg: d,
        };
        Self::of(Some(&geo), sx, sy).expect("a geographic grid")
    }

    /// The grid of a geographic or UTM geo-reference with the heightfield's index spacings;
    /// `None` for other projected CRSs or no reference (those stay on the flat plane; the
    /// reason: [`GeoGrid::of_projected`], which also checks the grid's extent).
    pub fn of(geo: Option<&GeoReference>, spacing_x: f64, spacing_y: f64) -> Option<Self> {
        match geo? {
            GeoReference::Geographic {
                south_lat_deg,
                west_lon_deg,
                dlat_deg,
                dlon_deg,
            } => {
                let ok = [*south_lat_deg, *west_lon_deg, *dlat_deg, *dlon_deg]
                    .iter()
                    .all(|v| v.is_finite())
                    && *dlat_deg > 0.0
                    && *dlon_deg > 0.0
                    && spacing_x > 0.0
                    && spacing_y > 0.0;
                ok.then(|| Self {
                    south_lat_deg: *south_lat_deg,
                    west_lon_deg: *west_lon_deg,
                    dlat_deg: *dlat_deg,
                    dlon_deg: *dlon_deg,
                    spacing_x,
                    spacing_y,
                    world: LocalTangentPlane::new(Geodetic::new(
                        *south_lat_deg,
                        *west_lon_deg,
                        0.0,
                    )),
                    projected: None,
                })
            }
            GeoReference::Projected { .. } => {
                Self::of_projected(geo, spacing_x, spacing_y, DVec2::ZERO).ok()?
            }
        }
    }

    /// The grid of any geo-reference the renderer places on the ellipsoid — geographic, or
    /// projected in a UTM zone on WGS84 — for a grid `extent` metres (east, north) from sample
    /// (0, 0). `Ok(None)`: no geo-reference (a local grid). `Err`: a projected grid that cannot
    /// be placed (another CRS, named by its EPSG code, or a UTM grid off its projection).
    pub fn of_projected(
        geo: Option<&GeoReference>,
        spacing_x: f64,
        spacing_y: f64,
        extent: DVec2,
    ) -> Result<Option<Self>, String> {
        let Some(GeoReference::Projected {
            crs,
            easting,
            northing,
        }) = geo
        else {
            return Ok(Self::of(geo, spacing_x, spacing_y));
        };
        let extent = extent.max(DVec2::ZERO);
        if !(spacing_x > 0.0 && spacing_y > 0.0 && easting.is_finite() && northing.is_finite()) {
            return Err(format!(
                "{crs} grid: spacing {spacing_x} × {spacing_y} m or origin ({easting}, {northing}) invalid"
            ));
        }
        let zone = projected_crs(crs)?;
        let p = ProjectedGrid::new(zone, *easting, *northing, extent)?;
        let (lat, lon) = p.lat_lon(DVec2::ZERO);
        Ok(Some(Self {
            south_lat_deg: lat,
            west_lon_deg: lon,
            dlat_deg: 0.0,
            dlon_deg: 0.0,
            spacing_x,
            spacing_y,
            world: LocalTangentPlane::new(Geodetic::new(lat, lon, 0.0)),
            projected: Some(p),
        }))
    }

    /// Grid metres → (latitude, longitude) in degrees (the longitude may pass ±180°).
    pub fn lat_lon_of_grid(&self, g: DVec2) -> (f64, f64) {
        if let Some(p) = &self.projected {
            return p.lat_lon(g);
        }
        (
            self.south_lat_deg + g.y / self.spacing_y * self.dlat_deg,
            self.west_lon_deg + g.x / self.spacing_x * self.dlon_deg,
        )
    }

    /// (latitude, longitude) in degrees → grid metres; longitudes are taken the short way
    /// round from the west edge.
    pub fn grid_of_lat_lon(&self, lat_deg: f64, lon_deg: f64) -> DVec2 {
        if let Some(p) = &self.projected {
            return p.grid_of(lat_deg, lon_deg);
        }
        let dlon = (lon_deg - self.west_lon_deg + 180.0).rem_euclid(360.0) - 180.0;
        DVec2::new(
            dlon / self.dlon_deg * self.spacing_x,
            (lat_deg - self.south_lat_deg) / self.dlat_deg * self.spacing_y,
        )
    }

    /// A geodetic position (height in the data's datum, see PROTOCOL.md) → world metres.
    pub fn world_of_geodetic(&self, g: Geodetic) -> DVec3 {
        self.world.geodetic_to_enu(g)
    }

    /// World metres → geodetic position.
    pub fn geodetic_of_world(&self, p: DVec3) -> Geodetic {
        self.world.enu_to_geodetic(p)
    }

    /// Grid metres and a height → world metres.
    pub fn world_of_grid(&self, g: DVec2, h: f64) -> DVec3 {
        let (lat, lon) = self.lat_lon_of_grid(g);
        self.world_of_geodetic(Geodetic::new(lat, lon, h))
    }

    /// World metres → grid metres and the height above the ellipsoid (x, y, z): where the
    /// clipmap centres its levels for an eye there.
    pub fn grid_of_world(&self, p: DVec3) -> DVec3 {
        let g = self.geodetic_of_world(p);
        self.grid_of_lat_lon(g.lat_deg, g.lon_deg).extend(g.alt_m)
    }

    /// ECEF directions → world directions.
    pub fn ecef_to_world_rotation(&self) -> DMat3 {
        self.world.enu_axes().transpose()
    }

    /// Columns: east, north and up of the local ENU frame at (lat, lon), in world axes.
    pub fn local_enu_axes(&self, lat_deg: f64, lon_deg: f64) -> DMat3 {
        let (sp, cp) = lat_deg.to_radians().sin_cos();
        let (sl, cl) = lon_deg.to_radians().sin_cos();
        let east = DVec3::new(-sl, cl, 0.0);
        let north = DVec3::new(-sp * cl, -sp * sl, cp);
        let up = DVec3::new(cp * cl, cp * sl, sp);
        self.ecef_to_world_rotation() * DMat3::from_cols(east, north, up)
    }

    /// Latitude / longitude ranges (radians) of the grid rectangle [lo, hi] (grid metres).
    fn ranges(&self, lo: DVec2, hi: DVec2) -> ([f64; 2], [f64; 2]) {
        let (la, lo_) = self.lat_lon_of_grid(lo);
        let (lb, hi_) = self.lat_lon_of_grid(hi);
        (
            [la.to_radians(), lb.to_radians()],
            [lo_.to_radians(), hi_.to_radians()],
        )
    }

    /// The node's world box, normal and normal spread (see [`NodeGeometry`]), for the grid
    /// rectangle [lo, hi] (grid metres) with heights in [min_h, max_h].
    ///
    /// The positions at the corners of a k×k lattice over the rectangle, at both heights, span
    /// a box holding their piecewise-linear interpolant; the true surface departs from that
    /// interpolant by at most [`GeoGrid::cell_sag_m`] of one lattice cell, which pads the box
    /// (positions are affine in h, so two heights suffice).
    pub fn node_geometry(&self, lo: DVec2, hi: DVec2, min_h: f32, max_h: f32) -> NodeGeometry {
        if self.projected.is_some() {
            return self.projected_node_geometry(lo, hi, min_h, max_h);
        }
        let (lat, lon) = self.ranges(lo, hi);
        let span = (lat[1] - lat[0]).max(lon[1] - lon[0]).to_degrees();
        // Lattice cells of at most 0.5°, up to 8 per side: the padding stays metres at worst;
        // nodes under 0.05° (the many near ones) take their corners alone (padding < 1.5 m).
        let k = if span <= 0.05 {
            1
        } else {
            ((span / 0.5).ceil() as usize).clamp(2, 8)
        };
        let (h0, h1) = (min_h as f64, max_h as f64);
        let to_world = self.ecef_to_world_rotation();
        let origin = self.world.origin_ecef();
        let mut bmin = DVec3::INFINITY;
        let mut bmax = DVec3::NEG_INFINITY;
        let cols: Vec<(f64, f64)> = (0..=k)
            .map(|i| (lon[0] + (lon[1] - lon[0]) * i as f64 / k as f64).sin_cos())
            .collect();
        for j in 0..=k {
            let phi = lat[0] + (lat[1] - lat[0]) * j as f64 / k as f64;
            let (sp, cp) = phi.sin_cos();
            let n = normal_radius(sp);
            for h in [h0, h1] {
                let r = (n + h) * cp;
                let z = (n * (1.0 - WGS84_E2) + h) * sp;
                for &(sl, cl) in &cols {
                    let p = to_world * (DVec3::new(r * cl, r * sl, z) - origin);
                    bmin = bmin.min(p);
                    bmax = bmax.max(p);
                }
            }
        }
        let dphi = (lat[1] - lat[0]) / k as f64;
        let dlam = (lon[1] - lon[0]) / k as f64;
        let pad = self.surface_sag(lat, dphi, dlam, h0.abs().max(h1.abs()));
        let (clat, clon) = (0.5 * (lat[0] + lat[1]), 0.5 * (lon[0] + lon[1]));
        let nc = normal_ecef(clat, clon);
        // The angle between two normals is the great-circle distance between their (φ, λ) on
        // the unit sphere, at most the path along the meridian then the parallel: half the
        // latitude span plus half the longitude span times the largest cos φ in the node.
        let cos_max = if lat[0] <= 0.0 && lat[1] >= 0.0 {
            1.0
        } else {
            lat[0].abs().min(lat[1].abs()).cos()
        };
        let spread = 0.5 * (lat[1] - lat[0]) + 0.5 * (lon[1] - lon[0]) * cos_max;
        NodeGeometry {
            aabb: Aabb {
                min: bmin - DVec3::splat(pad),
                max: bmax + DVec3::splat(pad),
            },
            up: to_world * nc,
            spread,
        }
    }

    /// How far the true surface can be from its linear interpolation over one triangle of a
    /// cell Δφ × Δλ (radians) within the latitudes `lat` (radians), at heights up to `abs_h`.
    ///
    /// Linear interpolation over a triangle of a C² map errs by at most ‖D²‖·ρ²/2, ρ the radius
    /// of the smallest ball holding it (half the cell diagonal). With Kφφ ≥ |∂²P/∂φ²| ≈ M,
    /// Kλλ ≥ |∂²P/∂λ²| = (N+h)·cos φ and Kφλ ≥ |∂²P/∂φ∂λ| = (M+h)·|sin φ|: in the coordinates
    /// (√Kφφ·φ, √Kλλ·λ) the bound's norm is 1 + Kφλ/√(KφφKλλ) over a diagonal² of
    /// Kφφ·Δφ² + Kλλ·Δλ² (at the equator the flat path's w²/8R; at 60° the parallels' own
    /// curvature makes it ≈ 2.2 times that); in plain (φ, λ) it is the largest row sum over
    /// Δφ² + Δλ², which stays finite at the poles. The smaller of the two holds.
    fn surface_sag(&self, lat: [f64; 2], dphi: f64, dlam: f64, abs_h: f64) -> f64 {
        let sin_max = lat[0]
            .abs()
            .max(lat[1].abs())
            .min(std::f64::consts::FRAC_PI_2)
            .sin();
        let cos_max = if lat[0] <= 0.0 && lat[1] >= 0.0 {
            1.0
        } else {
            lat[0].abs().min(lat[1].abs()).cos()
        };
        // h and the variation of M, N across the node: 2 % (|dM/dφ| ≤ 1.5·e²·M ≈ 1 % of M).
        let slack = 1.02 * (1.0 + abs_h / WGS84_A);
        let m = meridian_radius(sin_max).max(meridian_radius(0.0));
        let k_pp = m * slack;
        let k_ll = (normal_radius(sin_max) * cos_max * slack).max(1e-3);
        let k_pl = m * sin_max * slack;
        let scaled =
            (1.0 + k_pl / (k_pp * k_ll).sqrt()) * (k_pp * dphi * dphi + k_ll * dlam * dlam);
        let plain = (k_pp + k_pl).max(k_pl + k_ll) * (dphi * dphi + dlam * dlam);
        scaled.min(plain) / 8.0
    }

    /// How far a drawn cell of `step` samples can put a sample of the node [lo, hi] (grid
    /// metres, heights in [min_h, max_h]) from its true position, in any direction, besides
    /// the vertical error ε along the normal: the surface's own sag over the cell
    /// ([`Self::surface_sag`]) plus the turn of the normal between the cell's vertices
    /// (heights interpolated along different normals: the height range times the cell's
    /// angle, and the largest height times half its square). Zero at full resolution: the
    /// level-0 surface's vertices are the samples themselves, the reference every error is
    /// measured against.
    pub fn cell_sag_m(&self, lo: DVec2, hi: DVec2, step: u32, min_h: f32, max_h: f32) -> f64 {
        if step <= 1 {
            return 0.0;
        }
        if self.projected.is_some() {
            return self.projected_cell_sag_m(lo, hi, step, min_h, max_h);
        }
        let (lat, _) = self.ranges(lo, hi);
        let dphi = (self.dlat_deg * step as f64).to_radians();
        let dlam = (self.dlon_deg * step as f64).to_radians();
        let abs_h = (min_h as f64).abs().max((max_h as f64).abs());
        let angle = dphi.hypot(dlam);
        self.surface_sag(lat, dphi, dlam, abs_h)
            + (max_h as f64 - min_h as f64).max(0.0) * angle
            + abs_h * angle * angle / 2.0
    }

    /// The ECEF position of a grid sample (col, row) at height h: the f64 reference the drawn
    /// positions are measured against.
    pub fn ecef_of_sample(&self, col: f64, row: f64, h: f64) -> DVec3 {
        if self.projected.is_some() {
            let (lat, lon) =
                self.lat_lon_of_grid(DVec2::new(col * self.spacing_x, row * self.spacing_y));
            return geodetic_to_ecef(Geodetic::new(lat, lon, h));
        }
        geodetic_to_ecef(Geodetic::new(
            self.south_lat_deg + row * self.dlat_deg,
            self.west_lon_deg + col * self.dlon_deg,
            h,
        ))
    }
}

/// The node geometry and cell slack on a projected grid (see [`super::projected`] for the
/// bounds used).
impl GeoGrid {
    fn projected_node_geometry(
        &self,
        lo: DVec2,
        hi: DVec2,
        min_h: f32,
        max_h: f32,
    ) -> NodeGeometry {
        let span = (hi - lo).max_element();
        // Lattice cells of at most 50 km, up to 8 per side; nodes under 5 km take their corners
        // alone (padding < 0.6 m).
        let k = if span <= 5_000.0 {
            1
        } else {
            ((span / 50_000.0).ceil() as usize).clamp(2, 8)
        };
        let (h0, h1) = (min_h as f64, max_h as f64);
        let to_world = self.ecef_to_world_rotation();
        let origin = self.world.origin_ecef();
        let mut bmin = DVec3::INFINITY;
        let mut bmax = DVec3::NEG_INFINITY;
        for j in 0..=k {
            for i in 0..=k {
                let g = lo + (hi - lo) * DVec2::new(i as f64, j as f64) / k as f64;
                let (lat, lon) = self.lat_lon_of_grid(g);
                for h in [h0, h1] {
                    let p = to_world * (geodetic_to_ecef(Geodetic::new(lat, lon, h)) - origin);
                    bmin = bmin.min(p);
                    bmax = bmax.max(p);
                }
            }
        }
        // Linear interpolation over a lattice triangle errs by at most ‖D²P‖·ρ²/2, ρ half the
        // cell's diagonal.
        let cell = (hi - lo).length() / k as f64;
        let abs_h = h0.abs().max(h1.abs());
        // Plus the drawn polynomial's own error (the vertex shader's cubic fit).
        let pad = ProjectedGrid::second_derivative(abs_h) * cell * cell / 8.0
            + ProjectedGrid::fit_error_bound(0.5 * (hi - lo).length(), abs_h);
        let (clat, clon) = self.lat_lon_of_grid(0.5 * (lo + hi));
        NodeGeometry {
            aabb: Aabb {
                min: bmin - DVec3::splat(pad),
                max: bmax + DVec3::splat(pad),
            },
            up: to_world * normal_ecef(clat.to_radians(), clon.to_radians()),
            spread: ProjectedGrid::normal_turn(0.5 * (hi - lo).length()),
        }
    }

    /// As the geographic slack, plus the drawn polynomial's error over the node (which, unlike
    /// the rest, does not vanish at full resolution: it is added by the callers of
    /// [`GeoGrid::node_geometry`] through the box, and here for coarser cells).
    fn projected_cell_sag_m(&self, lo: DVec2, hi: DVec2, step: u32, min_h: f32, max_h: f32) -> f64 {
        let d = DVec2::new(self.spacing_x, self.spacing_y).length() * step as f64;
        let abs_h = (min_h as f64).abs().max((max_h as f64).abs());
        let angle = ProjectedGrid::normal_turn(d);
        ProjectedGrid::fit_error_bound(0.5 * (hi - lo).length(), abs_h)
            + ProjectedGrid::second_derivative(abs_h) * d * d / 8.0
            + (max_h as f64 - min_h as f64).max(0.0) * angle
            + abs_h * angle * angle / 2.0
    }
}

#[cfg(test)]
#[path = "grid_tests.rs"]
mod tests;
