//! The host's terrain questions answered on the drawn dataset (issue 12 item 1): sim-bridge's
//! [`TerrainQueries`] over the terrain crate's full-resolution query service
//! ([`aerie_terrain::query`]). Geodetic points go through the same [`GeoMapping`] the poses
//! use, so a HOT answer is the ground under the aircraft exactly where it is drawn; local
//! points are the dataset's east-north-up metres as they are.

use aerie_sim_bridge::query::{Answer, LosAnswer, LosHit, Surface, TerrainQueries};
use aerie_sim_bridge::PosePosition;
use std::cell::RefCell;
use std::sync::Arc;

use aerie_terrain::query::{
    first_hit, height_of_terrain, InMemorySource, Lookup, Ray, SurfaceSource,
};
use aerie_terrain::stream::{StreamedStore, StreamedSurface};
use glam::DVec3;

use crate::sim::pose_input::{GeoMapping, HostDatumAtPlaces, HostHeights};

/// Where the answers are read: the dataset in memory, or a streamed store's resident level-0
/// pages (a snapshot taken at the start of each IG frame, [`DatasetQueries::refresh`]).
enum QuerySurface {
    Memory(InMemorySource),
    Streamed {
        store: Arc<StreamedStore>,
        snapshot: StreamedSurface,
    },
}

/// The query service of one loaded dataset.
pub struct DatasetQueries {
    source: QuerySurface,
    geo: Option<GeoMapping>,
    /// Level-0 tiles questions found not resident since the last [`Self::take_pending`].
    pending: RefCell<Vec<[u32; 2]>>,
    /// The host's height datum: geodetic query points are read in it, and answered in it.
    datum: RefCell<HostDatumAtPlaces>,
}

impl DatasetQueries {
    fn answer<T, U>(&self, l: Lookup<T>, f: impl FnOnce(T) -> U) -> Answer<U> {
        match l {
            Lookup::Ready(t) => Answer::Ready(f(t)),
            Lookup::NoTerrain => Answer::NoTerrain,
            Lookup::Pending { tile } => {
                self.pending.borrow_mut().push(tile);
                Answer::Pending
            }
        }
    }

    fn surface(&self) -> &dyn SurfaceSource {
        match &self.source {
            QuerySurface::Memory(m) => m,
            QuerySurface::Streamed { snapshot, .. } => snapshot,
        }
    }

    /// Queries on a streamed store's resident level-0 pages: a question over a tile not
    /// resident is answered pending, and the tile is listed for [`Self::take_pending`].
    pub fn streamed(store: Arc<StreamedStore>, geo: Option<GeoMapping>) -> Self {
        let snapshot = store.surface();
        Self {
            source: QuerySurface::Streamed { store, snapshot },
            geo,
            pending: RefCell::new(Vec::new()),
            datum: RefCell::default(),
        }
    }

    /// Geodetic heights asked and answered in the host's datum (`--host-heights`): an
    /// ellipsoidal host's query altitudes lose the geoid undulation N before the lookup, and
    /// the heights answered (HOT, a LOS hit's altitude) gain it back.
    pub fn with_host_heights(self, heights: HostHeights) -> Self {
        *self.datum.borrow_mut() = HostDatumAtPlaces::new(heights);
        self
    }

    /// Takes a fresh snapshot of a streamed store's resident pages (nothing in memory).
    pub fn refresh(&mut self) {
        if let QuerySurface::Streamed { store, snapshot } = &mut self.source {
            *snapshot = store.surface();
        }
    }

    /// The level-0 tiles questions were pending on since the last call (deduplicated), for the
    /// renderer to ask its source for.
    pub fn take_pending(&self) -> Vec<[u32; 2]> {
        let mut v = std::mem::take(&mut *self.pending.borrow_mut());
        v.sort_unstable();
        v.dedup();
        v
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
        Self {
            source: QuerySurface::Memory(source),
            geo,
            pending: RefCell::new(Vec::new()),
            datum: RefCell::default(),
        }
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
            } => {
                let alt = self.datum.borrow_mut().to_data_m(lat_deg, lon_deg, alt_m);
                self.geo.as_ref()?.to_local(lat_deg, lon_deg, alt)
            }
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
                    alt_m: self.datum.borrow_mut().to_host_m(lat_deg, lon_deg, alt_m),
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
        self.answer(first_hit(self.surface(), &ray), |hit| {
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
        self.answer(height_of_terrain(self.surface(), p.x, p.y), |g| Surface {
            height_m: match *at {
                PosePosition::Geodetic {
                    lat_deg, lon_deg, ..
                } => self
                    .datum
                    .borrow_mut()
                    .to_host_m(lat_deg, lon_deg, g.height_m),
                PosePosition::LocalEnu { .. } => g.height_m,
            },
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
        let geo = q.geo.unwrap();
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
        let geo = q.geo.unwrap();
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

    /// An ellipsoidal host: its query altitude loses N (EGM96 at 47° N 11° E, ≈ +47 m) before
    /// the lookup, and the HOT and LOS answers come back with N added, so a host comparing
    /// them with its own ellipsoidal heights sees the terrain where the MSL data has it.
    #[test]
    fn ellipsoidal_hosts_ask_and_are_answered_in_their_datum() {
        let msl = ramp();
        let ell = ramp().with_host_heights(HostHeights::Ellipsoidal);
        let geo = msl.geo.unwrap();
        let (lat_deg, lon_deg, _) = geo.to_geodetic(DVec3::new(123.0, 45.0, 0.0));
        let n = aerie_terrain::geodesy::egm96_undulation_m(lat_deg, lon_deg);
        assert!(n > 40.0 && n < 55.0, "{n}");
        let at = PosePosition::Geodetic {
            lat_deg,
            lon_deg,
            alt_m: 500.0,
        };
        let h_msl = msl.height_of_terrain(&at).ready().unwrap().height_m;
        let h_ell = ell.height_of_terrain(&at).ready().unwrap().height_m;
        assert!((h_msl - 123.0).abs() < 1e-6, "{h_msl}");
        assert!((h_ell - h_msl - n).abs() < 0.02, "{h_ell} vs {h_msl} + {n}");
        // Level from x = 0 at 200 m above MSL: the ellipsoidal host says 200 + N, and the hit
        // (where z = x = 200) comes back at 200 + N in its datum.
        let from = |q: &DatasetQueries, alt: f64| {
            let (lat_deg, lon_deg, _) = geo.to_geodetic(DVec3::new(0.0, 160.0, 0.0));
            let p = PosePosition::Geodetic {
                lat_deg,
                lon_deg,
                alt_m: alt,
            };
            q.line_of_sight_vector(&p, 90.0, 0.0, 0.0, 1000.0)
                .ready()
                .unwrap()
                .unwrap()
        };
        let a = from(&msl, 200.0);
        let b = from(&ell, 200.0 + n);
        assert!((a.range_m - b.range_m).abs() < 0.05, "{a:?} vs {b:?}");
        let alt = |h: &LosHit| match h.point {
            PosePosition::Geodetic { alt_m, .. } => alt_m,
            PosePosition::LocalEnu { z, .. } => z,
        };
        assert!((alt(&b) - alt(&a) - n).abs() < 0.05, "{b:?} vs {a:?}");
    }
}
