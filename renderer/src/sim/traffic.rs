//! Other traffic (issue 18): the IG's entity table turned into the renderer's entities each
//! frame — dead-reckoned by their Rate Control since the host last placed them, attached
//! chains followed, conformal clamped vehicles put on the terrain by the height-of-terrain
//! query (its surface normal pitches and rolls them), placed in the dataset's local metres
//! through the poses' [`GeoMapping`] — and the run's traffic statistics.
//!
//! The ownship (entity 0) is the eye and is not drawn; inactive (standby) entities are kept in
//! the table but not drawn.

use std::collections::HashMap;
use std::path::Path;

use aerie_config::EntitySettings;
use aerie_sim_bridge::geodesy::{Geodetic, LocalTangentPlane};
use aerie_sim_bridge::ig::entities::{EntityState, EntityTable, OWNSHIP_ID};
use aerie_sim_bridge::query::{Answer, Surface};
use glam::{DMat3, DVec3};

use crate::render::entity_instances::{EntityDraw, EntityFrameStats};
use crate::render::gltf_model::load_model;
use crate::render::models::ModelLibrary;
use crate::sim::pose_input::{GeoMapping, HostDatumAtPlaces, HostHeights};

/// The model library of `[entities]` (paths relative to `config_dir`): the default model
/// first, then every configured type's. A model that cannot be read is an error naming its
/// file and key.
pub fn model_library(s: &EntitySettings, config_dir: &Path) -> Result<ModelLibrary, String> {
    let mut lib = ModelLibrary::with_default();
    for (ty, path) in &s.types {
        let full = config_dir.join(path);
        let mesh = load_model(&full).map_err(|e| format!("entities.types.{ty}: {e}"))?;
        lib.add_for_type(*ty, full.display().to_string(), &mesh);
    }
    Ok(lib)
}

/// What the scene step did this frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneCounts {
    /// Entities in the table (the ownship included).
    pub known: usize,
    /// Handed to the renderer.
    pub placed: usize,
    /// Inactive (standby) ones, not drawn.
    pub inactive: usize,
    /// Clamped ones whose terrain was not there (outside the data) or not resident.
    pub unplaced: usize,
    /// Clamped entities placed on the terrain this frame.
    pub clamped: usize,
}

/// The traffic of one run: the dead-reckoning clock per entity and the statistics.
#[derive(Debug, Default)]
pub struct Traffic {
    library: ModelLibrary,
    /// Per entity: (its last placement stamp, when this IG first saw it, seconds).
    seen: HashMap<u16, (u64, f64)>,
    stats: TrafficStats,
    /// The host's altitude datum for entities not clamped to the ground.
    datum: HostDatumAtPlaces,
}

/// The run's traffic statistics (the summary's `traffic` object).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct TrafficStats {
    /// Frames with entity models set.
    pub frames: u64,
    /// Most entities known at once.
    pub known_max: usize,
    /// Entities handed to the renderer in the last frame.
    pub placed_last: usize,
    /// Drawn and culled in the last frame (its last channel).
    pub drawn_last: u32,
    pub culled_last: u32,
    /// Most drawn in a frame.
    pub drawn_max: u32,
    /// Frames in which clamped entities had no terrain under them.
    pub unplaced_frames: u64,
    /// Instances and triangles per level, summed over the frames.
    pub instances_per_level: [u64; 3],
    pub triangles_per_level: [u64; 3],
    /// Triangles had every drawn entity been drawn at level 0, summed over the frames.
    pub triangles_without_lod: u64,
    /// Level changes over the run.
    pub lod_switches: u64,
    /// CPU µs per frame: the scene (table → entities) and the renderer's decisions and
    /// instance build.
    #[serde(skip)]
    scene_us: Vec<f64>,
    #[serde(skip)]
    decide_us: Vec<f64>,
}

impl Traffic {
    /// The traffic drawn with `library`.
    pub fn new(library: ModelLibrary) -> Self {
        Self {
            library,
            ..Self::default()
        }
    }

    /// The datum of the host's entity altitudes (`--host-heights`): ellipsoidal ones lose
    /// the geoid undulation before placement, as the ownship's do; clamped entities sit on
    /// the terrain, already in the data's datum.
    pub fn with_host_heights(mut self, heights: HostHeights) -> Self {
        self.datum = HostDatumAtPlaces::new(heights);
        self
    }

    /// The models (their LOD levels for reports).
    pub fn library(&self) -> &ModelLibrary {
        &self.library
    }

    /// The entities to draw at `now_s` (the IG's clock), placed in `geo`'s local metres;
    /// `ground(lat, lon)` is the height-of-terrain query for clamped entities.
    pub fn scene(
        &mut self,
        table: &EntityTable,
        now_s: f64,
        geo: &GeoMapping,
        ground: &dyn Fn(f64, f64) -> Answer<Surface>,
        out: &mut Vec<EntityDraw>,
    ) -> SceneCounts {
        let t0 = std::time::Instant::now();
        out.clear();
        let mut counts = SceneCounts {
            known: table.len(),
            ..SceneCounts::default()
        };
        // A placement restarts the entity's clock; rates move it from there.
        for e in table.iter() {
            let entry = self.seen.entry(e.id).or_insert((e.placed, now_s));
            if entry.0 != e.placed {
                *entry = (e.placed, now_s);
            }
        }
        self.seen.retain(|id, _| table.get(*id).is_some());
        let seen = &self.seen;
        let moved = table.advanced(|e| seen.get(&e.id).map_or(0.0, |(_, t)| now_s - t));
        for e in moved.iter() {
            if e.id == OWNSHIP_ID {
                continue;
            }
            if e.state != EntityState::Active {
                counts.inactive += 1;
                continue;
            }
            let Ok(anchor) = moved.anchor(e.id, [0.0; 3]) else {
                counts.unplaced += 1;
                continue;
            };
            let clamped = matches!(
                anchor.root,
                aerie_sim_bridge::ig::entities::Root::Clamped { .. }
            );
            let Answer::Ready(mut p) = anchor.place(ground) else {
                counts.unplaced += 1;
                continue;
            };
            if !clamped {
                p.point.alt_m =
                    self.datum
                        .to_data_m(p.point.lat_deg, p.point.lon_deg, p.point.alt_m);
            }
            counts.clamped += usize::from(clamped);
            let (position, axes) = to_local(geo, p.point, p.body_to_enu());
            out.push(EntityDraw {
                id: e.id,
                model: self.library.model_for(e.entity_type),
                position,
                body_to_world: axes,
            });
        }
        counts.placed = out.len();
        self.stats.scene_us.push(t0.elapsed().as_secs_f64() * 1e6);
        self.stats.known_max = self.stats.known_max.max(counts.known);
        self.stats.placed_last = counts.placed;
        self.stats.unplaced_frames += u64::from(counts.unplaced > 0);
        counts
    }

    /// Adds what the renderer drew in a frame.
    pub fn record(&mut self, s: &EntityFrameStats) {
        let t = &mut self.stats;
        t.frames += 1;
        t.drawn_last = s.drawn;
        t.culled_last = s.culled;
        t.drawn_max = t.drawn_max.max(s.drawn);
        for l in 0..3 {
            t.instances_per_level[l] += u64::from(s.instances_per_level[l]);
            t.triangles_per_level[l] += s.triangles_per_level[l];
        }
        t.triangles_without_lod += s.triangles_without_lod;
        t.lod_switches += u64::from(s.lod_switches);
        t.decide_us.push(s.cpu_us);
    }

    /// The summary's `traffic` object; `seconds` is the run's length (for switches per second).
    pub fn summary_json(&self, seconds: f64) -> serde_json::Value {
        let t = &self.stats;
        let mut v = serde_json::to_value(t).unwrap_or_default();
        let per_s = if seconds > 0.0 {
            t.lod_switches as f64 / seconds
        } else {
            0.0
        };
        v["lod_switches_per_s"] = per_s.into();
        v["scene_cpu_us"] = percentile_of(&t.scene_us);
        v["lod_and_instances_cpu_us"] = percentile_of(&t.decide_us);
        v["models"] = self
            .library
            .models
            .iter()
            .map(|m| {
                serde_json::json!({
                    "name": m.name,
                    "triangles_per_level": m.levels.iter().map(|l| l.triangles()).collect::<Vec<_>>(),
                    "error_m_per_level": m.levels.iter().map(|l| l.error_m).collect::<Vec<_>>(),
                    "radius_m": m.radius,
                })
            })
            .collect::<Vec<_>>()
            .into();
        v
    }
}

/// A placed point and its body axes in `geo`'s local metres. The axes go through the mapping
/// by finite differences (1 m along each), so they hold for whatever projection it is.
fn to_local(geo: &GeoMapping, point: Geodetic, body_to_enu: DMat3) -> (DVec3, DMat3) {
    let here = geo.to_local(point.lat_deg, point.lon_deg, point.alt_m);
    let ltp = LocalTangentPlane::new(point);
    let axis = |v: DVec3| {
        let q = ltp.enu_to_geodetic(v);
        geo.to_local(q.lat_deg, q.lon_deg, q.alt_m) - here
    };
    let x = axis(body_to_enu.x_axis).normalize_or(DVec3::Y);
    let y0 = axis(body_to_enu.y_axis);
    let y = (y0 - y0.dot(x) * x).normalize_or(DVec3::X);
    (here, DMat3::from_cols(x, y, x.cross(y)))
}

/// Median, p99 and max of `v` (nearest rank), for the summary.
fn percentile_of(v: &[f64]) -> serde_json::Value {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let at = |q: f64| -> f64 {
        if s.is_empty() {
            return 0.0;
        }
        let i = ((q * s.len() as f64).ceil() as usize).clamp(1, s.len()) - 1;
        s[i]
    };
    serde_json::json!({"frames": s.len(), "median": at(0.5), "p99": at(0.99), "max": at(1.0)})
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::terrain_queries::DatasetQueries;
    use aerie_sim_bridge::ig::entities::EntityControlUpdate;
    use aerie_sim_bridge::query::TerrainQueries;
    use aerie_sim_bridge::PosePosition;
    use aerie_terrain::bake::{bake, BakeParams};
    use aerie_terrain::dataset::Dataset;
    use aerie_terrain::query::InMemorySource;
    use aerie_terrain::{GeoReference, Heightfield};
    use std::sync::Arc;

    /// 65×65 samples 30 m apart from 47°N 11°E (a degree of latitude is 111 171 m there, of
    /// longitude 76 056 m): a slope rising 10 % to the east with a ripple, so every triangle
    /// has its own height and normal.
    fn queries() -> (DatasetQueries, GeoMapping) {
        let (w, h) = (65usize, 65usize);
        let heights = (0..w * h)
            .map(|i| {
                let (c, r) = ((i % w) as f32, (i / w) as f32);
                600.0 + 3.0 * c + 5.0 * (0.3 * r).sin()
            })
            .collect();
        let (dlat, dlon) = (30.0 / 111_171.0, 30.0 / 76_056.0);
        let hf = Heightfield {
            width: w,
            height: h,
            spacing_x: 30.0,
            spacing_y: 30.0,
            heights,
            geo: Some(GeoReference::Geographic {
                south_lat_deg: 47.0,
                west_lon_deg: 11.0,
                dlat_deg: dlat,
                dlon_deg: dlon,
            }),
            voids_filled: 0,
            spacing_note: "test".into(),
        };
        let ds = Arc::new(Dataset::from_heightfield(hf, "slope".into()));
        let params = BakeParams {
            tile_size: 17,
            levels: 0,
        };
        let b = Arc::new(bake(&ds, params, &|_, _| {}));
        let geo = GeoMapping::of_dataset(&ds).unwrap();
        let src = InMemorySource::new(ds, b).unwrap();
        (DatasetQueries::new(src, Some(geo)), geo)
    }

    #[test]
    fn clamped_vehicles_sit_at_the_height_of_terrain_answer_with_its_slope() {
        let (q, geo) = queries();
        let hot = |lat_deg, lon_deg| {
            q.height_of_terrain(&PosePosition::Geodetic {
                lat_deg,
                lon_deg,
                alt_m: 0.0,
            })
        };
        let mut table = EntityTable::default();
        // Three trucks facing east (up the slope), one facing north (across it).
        let spots = [
            (47.003, 11.004, 90.0),
            (47.011, 11.019, 90.0),
            (47.007, 11.01, 0.0),
        ];
        for (i, &(lat, lon, yaw)) in spots.iter().enumerate() {
            table.apply_clamped(10 + i as u16, yaw, lat, lon, 1);
        }
        // An inactive aircraft and the ownship are not drawn.
        let parked = EntityControlUpdate {
            id: 20,
            state: 0,
            attached: false,
            parent: 0,
            entity_type: 1,
            alpha: 255,
            lat_or_x: 47.005,
            lon_or_y: 11.005,
            alt_or_z: 2000.0,
            attitude_deg: [0.0; 3],
        };
        table.apply_control(&parked, 1);
        table.apply_control(
            &EntityControlUpdate {
                id: 0,
                state: 1,
                ..parked
            },
            1,
        );
        let mut t = Traffic::new(ModelLibrary::with_default());
        let mut out = Vec::new();
        let counts = t.scene(&table, 0.0, &geo, &hot, &mut out);
        assert_eq!(
            (counts.known, counts.placed, counts.inactive, counts.clamped),
            (5, 3, 1, 3)
        );
        for (d, &(lat, lon, yaw)) in out.iter().zip(&spots) {
            let Answer::Ready(s) = hot(lat, lon) else {
                panic!("no terrain at {lat}, {lon}")
            };
            // The height the host would be told (to the nanometres of the tangent-plane round
            // trip), where the host put it.
            assert!(
                (d.position.z - s.height_m).abs() < 1e-6,
                "{d:?} vs {}",
                s.height_m
            );
            let want = geo.to_local(lat, lon, 0.0);
            assert!((d.position.truncate() - want.truncate()).length() < 1e-6);
            // Body z (down) is minus the surface normal; facing up the 10 % slope the nose is
            // up by the slope's angle there, facing across it there is no pitch. (The grid's
            // axes and the east-north-up axes at the point differ by the meridians'
            // convergence over the 300 m from the grid's corner: 1e-4 rad at most.)
            let n = DVec3::from_array(s.normal_enu);
            assert!((d.body_to_world.z_axis + n).length() < 1e-4, "{d:?} {n}");
            let pitch = d.body_to_world.x_axis.z.asin().to_degrees();
            // The heading's direction projected on the surface: its rise over its length.
            let rise = |a: f64| (-a * n.z / (1.0 - a * a).sqrt()).asin().to_degrees();
            let slope_east = rise(n.x);
            if yaw == 90.0 {
                assert!((pitch - slope_east).abs() < 0.01, "{pitch} vs {slope_east}");
                assert!(pitch > 5.0, "{pitch}");
            } else {
                assert!((pitch - rise(n.y)).abs() < 0.01, "{pitch} vs {}", rise(n.y));
            }
        }
        // Outside the data: not placed, counted.
        table.apply_clamped(30, 0.0, 46.0, 11.0, 2);
        let counts = t.scene(&table, 0.0, &geo, &hot, &mut out);
        assert_eq!((counts.placed, counts.unplaced), (3, 1));
    }

    #[test]
    fn configured_models_are_loaded_and_bad_ones_named() {
        let dir = tempfile::tempdir().unwrap();
        let mesh = crate::render::models::default_aircraft();
        let glb = crate::render::gltf_model::write_glb(&mesh);
        aerie_io::write_atomic(&dir.path().join("c172.glb"), &glb).unwrap();
        let mut s = EntitySettings::default();
        s.types.insert(1234, "c172.glb".into());
        let lib = model_library(&s, dir.path()).unwrap();
        assert_eq!(lib.models.len(), 2);
        assert_eq!(lib.model_for(1234), 1);
        assert_eq!(lib.model_for(7), 0, "unknown types draw the default model");
        assert_eq!(
            lib.models[1].levels[0].triangles() as usize,
            mesh.triangles()
        );
        s.types.insert(99, "missing.glb".into());
        let e = model_library(&s, dir.path()).unwrap_err();
        assert!(
            e.contains("entities.types.99") && e.contains("missing.glb"),
            "{e}"
        );
    }

    #[test]
    fn rates_move_an_entity_from_when_the_host_placed_it() {
        let (q, geo) = queries();
        let hot = |lat_deg, lon_deg| {
            q.height_of_terrain(&PosePosition::Geodetic {
                lat_deg,
                lon_deg,
                alt_m: 0.0,
            })
        };
        let mut table = EntityTable::default();
        let plane = EntityControlUpdate {
            id: 4,
            state: 1,
            attached: false,
            parent: 0,
            entity_type: 9,
            alpha: 255,
            lat_or_x: 47.005,
            lon_or_y: 11.005,
            alt_or_z: 1500.0,
            attitude_deg: [0.0; 3],
        };
        table.apply_control(&plane, 1);
        table.apply_rates(
            4,
            aerie_sim_bridge::ig::entities::EntityRates {
                linear_m_s: [60.0, 0.0, 0.0],
                angular_deg_s: [0.0; 3],
                world_frame: false,
            },
            1,
        );
        let mut t = Traffic::new(ModelLibrary::with_default());
        let mut out = Vec::new();
        t.scene(&table, 100.0, &geo, &hot, &mut out);
        let y0 = out[0].position.y;
        // Half a second later, 30 m further north (the same placement).
        t.scene(&table, 100.5, &geo, &hot, &mut out);
        assert!(
            (out[0].position.y - y0 - 30.0).abs() < 0.05,
            "{}",
            out[0].position.y - y0
        );
        // The host places it again: the clock restarts there.
        table.apply_control(&plane, 2);
        t.scene(&table, 101.0, &geo, &hot, &mut out);
        assert!((out[0].position.y - y0).abs() < 1e-6);
    }

    /// With `--host-heights ellipsoidal` an entity flying at h above the ellipsoid is drawn at
    /// h − N (N ≈ 47 m at 47° N 11° E), as the ownship is; an entity clamped to the ground
    /// stays on it.
    #[test]
    fn ellipsoidal_entity_altitudes_lose_the_geoid_undulation() {
        let (q, geo) = queries();
        let hot = |lat_deg, lon_deg| {
            q.height_of_terrain(&PosePosition::Geodetic {
                lat_deg,
                lon_deg,
                alt_m: 0.0,
            })
        };
        let mut table = EntityTable::default();
        let plane = EntityControlUpdate {
            id: 4,
            state: 1,
            attached: false,
            parent: 0,
            entity_type: 9,
            alpha: 255,
            lat_or_x: 47.005,
            lon_or_y: 11.005,
            alt_or_z: 1500.0,
            attitude_deg: [0.0; 3],
        };
        table.apply_control(&plane, 1);
        let n = aerie_terrain::geodesy::egm96_undulation_m(47.005, 11.005);
        assert!(n > 40.0 && n < 55.0, "{n}");
        let mut out = Vec::new();
        Traffic::new(ModelLibrary::with_default()).scene(&table, 1.0, &geo, &hot, &mut out);
        let msl = out[0].position;
        Traffic::new(ModelLibrary::with_default())
            .with_host_heights(HostHeights::Ellipsoidal)
            .scene(&table, 1.0, &geo, &hot, &mut out);
        let ell = out[0].position;
        assert!((msl.z - ell.z - n).abs() < 0.02, "{msl} vs {ell}, N {n}");
        assert!((msl.truncate() - ell.truncate()).length() < 1e-6);
    }
}
