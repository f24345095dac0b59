//! The host's terrain questions answered on the drawn dataset (issue 12 item 1): sim-bridge's
//! [`TerrainQueries`] over the terrain crate's full-resolution query service
//! ([`aerie_terrain::query`]). Geodetic points go through the same [`GeoMapping`] the poses
//! use, so a HOT answer is the ground under the aircraft exactly where it is drawn; local
//! points are the dataset's east-north-up metres as they are.

use aerie_sim_bridge::query::{Answer, LosAnswer, LosHit, Surface, TerrainQueries};
use aerie_sim_bridge::PosePosition;
use aerie_terrain::query::{first_hit, height_of_terrain, InMemorySource, Lookup, Ray};
use glam::DVec3;

use crate::sim::pose_input::GeoMapping;

/// The query service of one loaded dataset.
pub struct DatasetQueries {
    source: InMemorySource,
    geo: Option<GeoMapping>,
}

fn answer<T, U>(l: Lookup<T>, f: impl FnOnce(T) -> U) -> Answer<U> {
    match l {
        Lookup::Ready(t) => Answer::Ready(f(t)),
        Lookup::NoTerrain => Answer::NoTerrain,
        Lookup::Pending { .. } => Answer::Pending,
    }
}

/// A unit direction in east-north-up from an azimuth (clockwise from north) and an elevation
/// (up from the horizontal), degrees.
pub fn direction_enu(azimuth_deg: f64, elevation_deg: f64) -> DVec3 {
    let (az, el) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
    DVec3::new(el.cos() * az.sin(), el.cos() * az.cos(), el.sin())
}

impl DatasetQueries {
    /// Queries on `source`; geodetic points need `geo` (else they have no terrain).
    pub fn new(source: InMemorySource, geo: Option<GeoMapping>) -> Self {
        Self { source, geo }
    }

    /// A point in the dataset's local metres, `None` when it is geodetic and the dataset has
    /// no geographic reference, or not finite.
    fn local(&self, p: &PosePosition) -> Option<DVec3> {
        let v = match *p {
            PosePosition::LocalEnu { x, y, z } => DVec3::new(x, y, z),
            PosePosition::Geodetic {
                lat_deg,
                lon_deg,
                alt_m,
            } => self.geo.as_ref()?.to_local(lat_deg, lon_deg, alt_m),
        };
        v.is_finite().then_some(v)
    }

    /// `local` back in the coordinate system of `like`.
    fn position_like(&self, like: &PosePosition, local: DVec3) -> PosePosition {
        match (like, &self.geo) {
            (PosePosition::Geodetic { .. }, Some(g)) => {
                let (lat_deg, lon_deg, alt_m) = g.to_geodetic(local);
                PosePosition::Geodetic {
                    lat_deg,
                    lon_deg,
                    alt_m,
                }
            }
            _ => PosePosition::LocalEnu {
                x: local.x,
                y: local.y,
                z: local.z,
            },
        }
    }

    fn cast(&self, from: &PosePosition, ray: Option<Ray>) -> LosAnswer {
        let Some(ray) = ray else {
            return Answer::NoTerrain;
        };
        answer(first_hit(&self.source, &ray), |hit| {
            hit.map(|h| LosHit {
                range_m: h.range_m,
                point: self.position_like(from, h.point),
                normal_enu: h.normal.to_array(),
            })
        })
    }
}

impl TerrainQueries for DatasetQueries {
    fn height_of_terrain(&self, at: &PosePosition) -> Answer<Surface> {
        let Some(p) = self.local(at) else {
            return Answer::NoTerrain;
        };
        answer(height_of_terrain(&self.source, p.x, p.y), |g| Surface {
            height_m: g.height_m,
            normal_enu: g.normal.to_array(),
        })
    }

    fn line_of_sight(&self, from: &PosePosition, to: &PosePosition) -> LosAnswer {
        let ray = match (self.local(from), self.local(to)) {
            (Some(a), Some(b)) => Ray::segment(a, b).ok(),
            _ => None,
        };
        self.cast(from, ray)
    }

    fn line_of_sight_vector(
        &self,
        from: &PosePosition,
        azimuth_deg: f64,
        elevation_deg: f64,
        min_range_m: f64,
        max_range_m: f64,
    ) -> LosAnswer {
        let ray = self.local(from).and_then(|o| {
            Ray::new(
                o,
                direction_enu(azimuth_deg, elevation_deg),
                min_range_m,
                max_range_m,
            )
            .ok()
        });
        self.cast(from, ray)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use aerie_terrain::bake::{bake, BakeParams};
    use aerie_terrain::dataset::Dataset;
    use aerie_terrain::{GeoReference, Heightfield};
    use std::sync::Arc;

    /// A 33×33 grid, 10 m apart, rising 1 m per metre eastwards: h = x.
    fn ramp() -> DatasetQueries {
        let n = 33;
        let heights: Vec<f32> = (0..n * n).map(|i| ((i % n) * 10) as f32).collect();
        let hf = Heightfield {
            width: n,
            height: n,
            spacing_x: 10.0,
            spacing_y: 10.0,
            heights,
            geo: Some(GeoReference::Geographic {
                south_lat_deg: 47.0,
                west_lon_deg: 11.0,
                dlat_deg: 1.0 / 1200.0,
                dlon_deg: 1.0 / 1200.0,
            }),
            voids_filled: 0,
            spacing_note: String::new(),
        };
        let ds = Arc::new(Dataset::from_heightfield(hf, "ramp".into()));
        let params = BakeParams {
            tile_size: 9,
            levels: 0,
        };
        let b = Arc::new(bake(&ds, params, &|_, _| {}));
        let geo = GeoMapping::of_dataset(&ds).unwrap();
        DatasetQueries::new(InMemorySource::new(ds, b).unwrap(), Some(geo))
    }

    #[test]
    fn geodetic_and_local_points_ask_the_same_ground() {
        let q = ramp();
        let local = PosePosition::LocalEnu {
            x: 123.0,
            y: 45.0,
            z: 500.0,
        };
        let s = q.height_of_terrain(&local).ready().unwrap();
        assert!((s.height_m - 123.0).abs() < 1e-9, "{s:?}");
        // The normal of z = x leans west: (−1, 0, 1)/√2.
        assert!((s.normal_enu[0] + 0.5f64.sqrt()).abs() < 1e-9, "{s:?}");
        let geo = GeoMapping::of_dataset(q.source.dataset()).unwrap();
        let (lat_deg, lon_deg, alt_m) = geo.to_geodetic(DVec3::new(123.0, 45.0, 500.0));
        let g = PosePosition::Geodetic {
            lat_deg,
            lon_deg,
            alt_m,
        };
        let sg = q.height_of_terrain(&g).ready().unwrap();
        assert!((sg.height_m - s.height_m).abs() < 1e-6);
        // Outside the grid: no terrain.
        let out = PosePosition::LocalEnu {
            x: -5.0,
            y: 0.0,
            z: 0.0,
        };
        assert_eq!(q.height_of_terrain(&out), Answer::NoTerrain);
    }

    #[test]
    fn lines_of_sight_hit_where_the_ramp_rises() {
        let q = ramp();
        // From (0, 160, 200) looking east, level: the ground z = x reaches 200 at x = 200.
        let from = PosePosition::LocalEnu {
            x: 0.0,
            y: 160.0,
            z: 200.0,
        };
        let hit = q
            .line_of_sight_vector(&from, 90.0, 0.0, 0.0, 1000.0)
            .ready()
            .unwrap()
            .unwrap();
        assert!((hit.range_m - 200.0).abs() < 1e-6, "{hit:?}");
        // Shorter than that: clear.
        assert_eq!(
            q.line_of_sight_vector(&from, 90.0, 0.0, 0.0, 150.0),
            Answer::Ready(None)
        );
        // The same as a segment, in geodetic points: the hit comes back geodetic.
        let geo = GeoMapping::of_dataset(q.source.dataset()).unwrap();
        let g = |x: f64, y: f64, z: f64| {
            let (lat_deg, lon_deg, alt_m) = geo.to_geodetic(DVec3::new(x, y, z));
            PosePosition::Geodetic {
                lat_deg,
                lon_deg,
                alt_m,
            }
        };
        let hit = q
            .line_of_sight(&g(0.0, 160.0, 200.0), &g(300.0, 160.0, 200.0))
            .ready()
            .unwrap()
            .unwrap();
        assert!((hit.range_m - 200.0).abs() < 1e-6, "{hit:?}");
        assert!(
            matches!(hit.point, PosePosition::Geodetic { alt_m, .. } if (alt_m - 200.0).abs() < 1e-6)
        );
    }

    #[test]
    fn directions_follow_azimuth_and_elevation() {
        let e = direction_enu(90.0, 0.0);
        assert!((e - DVec3::X).length() < 1e-12);
        let n_up = direction_enu(0.0, 45.0);
        assert!((n_up - DVec3::new(0.0, 0.5f64.sqrt(), 0.5f64.sqrt())).length() < 1e-12);
    }
}
