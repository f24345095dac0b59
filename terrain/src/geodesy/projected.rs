//! A projected (UTM) grid placed on the WGS84 ellipsoid: sample (col, row) is the point
//! (easting₀ + col·spacing_x, northing₀ + row·spacing_y) of its zone, carried to (lat, lon)
//! by the projection's inverse ([`super::tmerc`]) and from there to ECEF at its height. Pure.
//!
//! The bounds [`super::GeoGrid`] needs on such a grid (how far the surface departs from a flat
//! interpolation over a cell, how much its normal turns) come from the map
//! P(E, N, h) = ECEF(φ(E, N), λ(E, N), h) having second derivatives of at most
//! [`SECOND_DERIVATIVE_PER_M`]·(1 + |h|/a) in projected metres: the ellipsoid's largest
//! curvature 1/M(0) over the squared scale (k ≥ k0 = 0.9996) for the normal part, plus the
//! tangential part from the scale's own variation, |∇k|/k ≤ |x|/R² ≤ 2.5e-8 /m within 1 000 km
//! of the central meridian (the domain [`ProjectedGrid::new`] accepts).

use glam::{DVec2, DVec3};

use super::utm::UtmZone;
use super::wgs84::{geodetic_to_ecef, Geodetic, WGS84_A, WGS84_E2};

/// Smallest radius of curvature of WGS84, M(0) = a(1 − e²), metres.
pub const MIN_CURVATURE_RADIUS_M: f64 = WGS84_A * (1.0 - WGS84_E2);

/// Bound on ‖D²P‖ per metre of easting/northing at h = 0 (see the module documentation):
/// 1/(M(0)·k0²) = 1.579e-7 plus 2.5e-8, rounded up.
pub const SECOND_DERIVATIVE_PER_M: f64 = 1.85e-7;

/// Farthest a placed grid may reach from its zone's central meridian, metres of easting (the
/// bound above holds there; UTM zones are 334 km half-wide at the equator).
pub const MAX_CENTRAL_DISTANCE_M: f64 = 1_000_000.0;

/// A UTM grid's placement: its zone and the easting/northing of sample (0, 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProjectedGrid {
    pub zone: UtmZone,
    pub easting: f64,
    pub northing: f64,
}

impl ProjectedGrid {
    /// The placement of a grid `extent` metres (east, north) from sample (0, 0), or why not: a
    /// corner outside the projection or more than [`MAX_CENTRAL_DISTANCE_M`] from the central
    /// meridian, or past 89.5° of latitude.
    pub fn new(zone: UtmZone, easting: f64, northing: f64, extent: DVec2) -> Result<Self, String> {
        let p = Self {
            zone,
            easting,
            northing,
        };
        for c in [
            DVec2::ZERO,
            DVec2::new(extent.x, 0.0),
            DVec2::new(0.0, extent.y),
            extent,
        ] {
            let (e, n) = (easting + c.x, northing + c.y);
            if (e - 500_000.0).abs() > MAX_CENTRAL_DISTANCE_M {
                return Err(format!(
                    "UTM {zone} grid reaches easting {e:.0} m, more than {:.0} km from the zone's central meridian",
                    MAX_CENTRAL_DISTANCE_M / 1000.0
                ));
            }
            let (lat, _) = zone.lat_lon(e, n)?;
            if lat.abs() > 89.5 {
                return Err(format!(
                    "UTM {zone} grid reaches latitude {lat:.2}°: too near the pole"
                ));
            }
        }
        Ok(p)
    }

    /// Grid metres → (latitude, longitude) in degrees; NaN outside the projection (a point
    /// far outside the grid).
    pub fn lat_lon(&self, g: DVec2) -> (f64, f64) {
        self.zone
            .lat_lon(self.easting + g.x, self.northing + g.y)
            .unwrap_or((f64::NAN, f64::NAN))
    }

    /// (latitude, longitude) in degrees → grid metres.
    pub fn grid_of(&self, lat_deg: f64, lon_deg: f64) -> DVec2 {
        let (e, n) = self.zone.easting_northing(lat_deg, lon_deg);
        DVec2::new(e - self.easting, n - self.northing)
    }

    /// Bound on ‖D²P‖ at heights up to `abs_h`, per metre² of grid.
    pub fn second_derivative(abs_h: f64) -> f64 {
        SECOND_DERIVATIVE_PER_M * (1.0 + abs_h / WGS84_A)
    }

    /// Bound on the angle between the ellipsoid normals at two points `d` grid metres apart:
    /// the ground distance (at most d/k0) over the smallest radius of curvature.
    pub fn normal_turn(d: f64) -> f64 {
        d / (0.9996 * MIN_CURVATURE_RADIUS_M)
    }
}

/// A node's surface as cubic polynomials of its normalised offset from the centre
/// (u, v) ∈ [−1, 1]² (u east, v north, ±1 at the node's edges): the ECEF offset of the point
/// at height 0 from the centre's, and the ellipsoid normal there. What the vertex shader
/// evaluates in f32 on a projected grid: a sample at height h is drawn at
/// `centre + pos(u, v) + h · normal(u, v)`.
///
/// Polynomials in ECEF rather than in (lat, lon): the surface is smooth everywhere while
/// longitude is singular at the poles (a (lat, lon) fit errs by a centimetre over a 20 km node
/// at 84° N, the ECEF one by micrometres).
///
/// Coefficients of the basis [u, v, u², uv, v², u³, u²v, uv², v³] ([`cubic_basis`]); the
/// position has no constant term (the centre is exact, in f64 on the CPU), the normal's is
/// `normal0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodePolynomial {
    pub lat0_deg: f64,
    pub lon0_deg: f64,
    /// ECEF of the centre at height 0.
    pub centre_ecef: DVec3,
    pub pos: [DVec3; 9],
    pub normal0: DVec3,
    pub normal: [DVec3; 9],
}

/// The basis of [`NodePolynomial`] at (u, v).
pub fn cubic_basis(u: f64, v: f64) -> [f64; 9] {
    [
        u,
        v,
        u * u,
        u * v,
        v * v,
        u * u * u,
        u * u * v,
        u * v * v,
        v * v * v,
    ]
}

impl NodePolynomial {
    /// (ECEF offset from the centre at height `h`) at (u, v).
    pub fn eval(&self, u: f64, v: f64, h: f64) -> DVec3 {
        let b = cubic_basis(u, v);
        let mut p = DVec3::ZERO;
        let mut n = self.normal0;
        for ((pk, nk), bk) in self.pos.iter().zip(&self.normal).zip(b) {
            p += *pk * bk;
            n += *nk * bk;
        }
        p + n * h
    }
}

/// Solves the 9×9 system `a x = b` (6 right-hand sides) by Gaussian elimination with partial
/// pivoting (the normal equations of a well-conditioned fit on [−1, 1]²).
fn solve9(mut a: [[f64; 9]; 9], mut b: [[f64; 6]; 9]) -> [[f64; 6]; 9] {
    for c in 0..9 {
        let p = (c..9)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap_or(c);
        a.swap(c, p);
        b.swap(c, p);
        let (pivot, pivot_b) = (a[c], b[c]);
        for r in c + 1..9 {
            let f = a[r][c] / pivot[c];
            for (x, y) in a[r][c..].iter_mut().zip(&pivot[c..]) {
                *x -= f * y;
            }
            for (x, y) in b[r].iter_mut().zip(&pivot_b) {
                *x -= f * y;
            }
        }
    }
    let mut x = [[0.0; 6]; 9];
    for c in (0..9).rev() {
        let mut s = b[c];
        for k in c + 1..9 {
            for m in 0..6 {
                s[m] -= a[c][k] * x[k][m];
            }
        }
        x[c] = s.map(|v| v / a[c][c]);
    }
    x
}

impl ProjectedGrid {
    /// ECEF position (height 0) and unit normal of grid point `g` (grid metres).
    fn surface(&self, g: DVec2) -> (DVec3, DVec3, f64, f64) {
        let (lat, lon) = self.lat_lon(g);
        let (sp, cp) = lat.to_radians().sin_cos();
        let (sl, cl) = lon.to_radians().sin_cos();
        (
            geodetic_to_ecef(Geodetic::new(lat, lon, 0.0)),
            DVec3::new(cp * cl, cp * sl, sp),
            lat,
            lon,
        )
    }

    /// The cubic polynomials of the node centred at `centre` (grid metres) reaching `half`
    /// metres (east, north) to its edges: least squares on a 5×5 lattice.
    pub fn node_polynomial(&self, centre: DVec2, half: DVec2) -> NodePolynomial {
        let (p0, n0, lat0, lon0) = self.surface(centre);
        let mut ata = [[0.0; 9]; 9];
        let mut atb = [[0.0; 6]; 9];
        for j in 0..5 {
            for i in 0..5 {
                let (u, v) = (i as f64 / 2.0 - 1.0, j as f64 / 2.0 - 1.0);
                let b = cubic_basis(u, v);
                let (p, n, _, _) = self.surface(centre + half * DVec2::new(u, v));
                let (dp, dn) = (p - p0, n - n0);
                let rhs = [dp.x, dp.y, dp.z, dn.x, dn.y, dn.z];
                for r in 0..9 {
                    for c in 0..9 {
                        ata[r][c] += b[r] * b[c];
                    }
                    for m in 0..6 {
                        atb[r][m] += b[r] * rhs[m];
                    }
                }
            }
        }
        let x = solve9(ata, atb);
        NodePolynomial {
            lat0_deg: lat0,
            lon0_deg: lon0,
            centre_ecef: p0,
            pos: std::array::from_fn(|k| DVec3::new(x[k][0], x[k][1], x[k][2])),
            normal0: n0,
            normal: std::array::from_fn(|k| DVec3::new(x[k][3], x[k][4], x[k][5])),
        }
    }

    /// The largest distance between the polynomial's point and the exact one over a 9×9
    /// lattice on the node (the fit's 5×5 and the points between), at height `h`.
    pub fn fit_residual_m(&self, poly: &NodePolynomial, centre: DVec2, half: DVec2, h: f64) -> f64 {
        let mut worst = 0.0f64;
        for j in 0..9 {
            for i in 0..9 {
                let (u, v) = (i as f64 / 4.0 - 1.0, j as f64 / 4.0 - 1.0);
                let (lat, lon) = self.lat_lon(centre + half * DVec2::new(u, v));
                let exact = geodetic_to_ecef(Geodetic::new(lat, lon, h)) - poly.centre_ecef;
                worst = worst.max((poly.eval(u, v, h) - exact).length());
            }
        }
        worst
    }

    /// Bound on the cubic fit's error over a node of half-diagonal `r` metres at heights up to
    /// `abs_h`, anywhere the placement is accepted: the fit errs by the quartic terms, at most
    /// [`FIT_ERROR_COEFFICIENT`]·(a + |h|)·(r/a)⁴ (the coefficient measured with margin across
    /// zones, hemispheres and latitudes up to 84° in this module's tests), plus 10 µm of f64
    /// rounding.
    pub fn fit_error_bound(r: f64, abs_h: f64) -> f64 {
        FIT_ERROR_COEFFICIENT * (WGS84_A + abs_h) * (r / WGS84_A).powi(4) + 1e-5
    }
}

/// See [`ProjectedGrid::fit_error_bound`].
pub const FIT_ERROR_COEFFICIENT: f64 = 0.1;

#[cfg(test)]
mod tests {
    use super::*;

    fn zone(z: u8, north: bool) -> UtmZone {
        UtmZone { zone: z, north }
    }

    #[test]
    fn placement_refuses_grids_off_the_projection() {
        let z = zone(32, true);
        assert!(ProjectedGrid::new(z, 400_000.0, 5_000_000.0, DVec2::splat(50_000.0)).is_ok());
        let far = ProjectedGrid::new(z, 1_600_000.0, 5_000_000.0, DVec2::splat(1e3)).unwrap_err();
        assert!(far.contains("central meridian"), "{far}");
        let pole = ProjectedGrid::new(z, 500_000.0, 9_990_000.0, DVec2::splat(1e3)).unwrap_err();
        assert!(pole.contains("pole") || pole.contains("outside"), "{pole}");
    }

    /// The second-derivative bound holds: second differences of the exact f64 map, with steps
    /// of 2 km, over zone centres and edges from the equator to 84° N, at 0 and 8 km height,
    /// stay under it (the largest is reported).
    #[test]
    fn the_second_derivative_bound_holds_across_a_zone() {
        let z = zone(33, true);
        let p = ProjectedGrid::new(z, 0.0, 0.0, DVec2::ZERO).unwrap();
        let s = 2_000.0;
        let mut worst = 0.0f64;
        for n in [0.0, 1_000_000.0, 5_200_000.0, 7_000_000.0, 9_300_000.0] {
            for e in [170_000.0, 330_000.0, 500_000.0, 670_000.0, 830_000.0] {
                for h in [0.0, 8_000.0] {
                    let at = |de: f64, dn: f64| {
                        let (lat, lon) = p.lat_lon(DVec2::new(e + de, n + dn));
                        geodetic_to_ecef(Geodetic::new(lat, lon, h))
                    };
                    let c = at(0.0, 0.0);
                    let pee = (at(s, 0.0) - 2.0 * c + at(-s, 0.0)) / (s * s);
                    let pnn = (at(0.0, s) - 2.0 * c + at(0.0, -s)) / (s * s);
                    let pen = (at(s, s) - at(s, -s) - at(-s, s) + at(-s, -s)) / (4.0 * s * s);
                    // ‖D²P‖ = the largest second derivative along a unit direction.
                    let norm = (0..64)
                        .map(|i| {
                            let (sn, cs) = (i as f64 * std::f64::consts::PI / 64.0).sin_cos();
                            (cs * cs * pee + 2.0 * sn * cs * pen + sn * sn * pnn).length()
                        })
                        .fold(0.0, f64::max);
                    let ratio = norm / ProjectedGrid::second_derivative(h);
                    worst = worst.max(ratio);
                }
            }
        }
        eprintln!("UTM ‖D²P‖ at most {worst:.3} of the bound");
        assert!(worst < 1.0, "‖D²P‖ exceeds the bound: {worst}");
        assert!(worst > 0.5, "the bound is loose by more than 2×: {worst}");
    }

    /// The fit reproduces the surface over nodes from 2 km to 300 km across, at a zone's
    /// centre and edges, north and south, up to 84°, at 0 and 9 km height: the residual stays
    /// under [`ProjectedGrid::fit_error_bound`] (the worst ratio is reported).
    #[test]
    fn node_polynomials_fit_within_their_bound() {
        let mut worst = 0.0f64;
        let mut worst_50km = 0.0f64;
        for (z, north) in [(33u8, true), (19, false)] {
            let p = ProjectedGrid::new(zone(z, north), 0.0, 0.0, DVec2::ZERO).unwrap();
            for n in [
                100_000.0,
                2_000_000.0,
                5_200_000.0,
                7_500_000.0,
                9_300_000.0,
            ] {
                for e in [166_000.0, 330_000.0, 500_000.0, 834_000.0] {
                    for half in [1_000.0, 10_000.0, 50_000.0, 150_000.0] {
                        let c = DVec2::new(e, n);
                        let poly = p.node_polynomial(c, DVec2::splat(half));
                        for h in [0.0, 9_000.0] {
                            let r = p.fit_residual_m(&poly, c, DVec2::splat(half), h);
                            let bound = ProjectedGrid::fit_error_bound(half * 2f64.sqrt(), h);
                            worst = worst.max(r / bound);
                            if half == 50_000.0 {
                                worst_50km = worst_50km.max(r);
                            }
                            assert!(
                                r <= bound,
                                "zone {z} ({e}, {n}) half {half} h {h}: residual {r} m, bound {bound} m"
                            );
                        }
                    }
                }
            }
        }
        eprintln!(
            "UTM node fit: residual at most {worst:.3} of its bound; {worst_50km:.2e} m over 100 km nodes"
        );
    }
}
