//! `aerie run` as an image generator (issue 12): at the start of every rendered frame, one
//! step of the IG session — one Start of Frame to the host, every HAT/HOT and line-of-sight
//! answer due (asked on the full-resolution surface of the dataset drawn), native query answers
//! — then what the host changed applied to the renderer: the database (loaded on a worker
//! thread, Start of Frame saying −n meanwhile), the sun from its Celestial Sphere Control, the
//! haze from its Atmosphere Control visibility.

use std::path::Path;
use std::time::Instant;

use aerie_config::Databases;
use aerie_sim_bridge::ig::{DatabaseStatus, IgFrame, IgLink, IgStats};
use aerie_sim_bridge::query::{NoTerrain, TerrainQueries};
use aerie_sim_bridge::timing::monotonic_s;
use aerie_terrain::bake::ErrorBake;
use aerie_terrain::dataset::Dataset;
use aerie_terrain::query::InMemorySource;
use aerie_terrain::source::{SampleRect, SampleWant};

/// A host's question waits on a tile: ask for it before anything the renderer draws.
const HOST_QUESTION_PRIORITY: f32 = 1.0e9;
use glam::DVec3;
use std::sync::Arc;

use crate::app::args::StoreArgs;
use crate::app::commands::run::args::RunArgs;
use crate::app::commands::run::database::{
    DatabaseAction, DatabaseChoice, DatabaseLoader, DatabaseReport, LoadedTerrain,
};
use crate::app::commands::run::plan::Plan;
use crate::app::failure::{bad_input, Failure};
use crate::app::prepare::Terrain;
use crate::render::desc::RendererDesc;
use crate::render::entity_lod::LodParams;
use crate::render::frame::{Lighting, TerrainRenderer};
use crate::sim::pose_input::{GeoMapping, SimInput};
use crate::sim::sun_clock::enu_at_to_world;
use crate::sim::terrain_queries::DatasetQueries;
use crate::sim::traffic::{model_library, Traffic};
use crate::tools::percentile::percentile;
use aerie_sim_bridge::query::Answer;
use aerie_sim_bridge::PosePosition;

/// The IG of a run whose input is UDP (CIGI and native queries arrive there); `None` for
/// shared memory or no input. `[databases]` and `[entities.types]` paths are relative to the
/// config file's folder; a model that cannot be read is bad input.
pub(crate) fn ig_driver(
    a: &RunArgs,
    plan: &Plan,
    input: Option<&SimInput>,
    terrain: &Terrain,
    desc: &RendererDesc,
) -> Result<Option<IgDriver>, Failure> {
    let Some(link) = input.and_then(SimInput::ig_link) else {
        return Ok(None);
    };
    let host_heights = input.map(SimInput::host_heights).unwrap_or_default();
    let dir = a
        .config
        .as_deref()
        .and_then(Path::parent)
        .map(Path::to_path_buf)
        .unwrap_or_default();
    // A typo in the table is told now, not when a host first asks for that database.
    for (n, p) in plan.config.databases.iter() {
        let path = dir.join(p);
        if !path.exists() {
            eprintln!(
                "warning: {}: databases.{n}: {} does not exist (a host asking for database {n} will get Start of Frame database −128, unavailable)",
                plan.source,
                path.display()
            );
        }
    }
    let entities = &plan.config.entities;
    let library =
        model_library(entities, &dir).map_err(|e| bad_input(format!("{}: {e}", plan.source)))?;
    let mut ig = IgDriver::new(
        link,
        terrain,
        plan.config.databases.clone(),
        &dir,
        &a.dem,
        DatabaseTerrain {
            desc: desc.clone(),
            store: a.store.clone(),
        },
    );
    ig.host_heights = host_heights;
    ig.queries = ig.queries.take().map(|q| q.with_host_heights(host_heights));
    ig.traffic = Some(TrafficDriver {
        traffic: Traffic::new(library).with_host_heights(host_heights),
        scale: entities.scale,
        lod: LodParams::from(entities),
        models_set: false,
        started_s: None,
    });
    Ok(Some(ig))
}

/// Other traffic of the run: the entity table drawn each frame.
struct TrafficDriver {
    traffic: Traffic,
    scale: f64,
    lod: LodParams,
    models_set: bool,
    /// The IG clock at the first frame drawn (for switches per second).
    started_s: Option<f64>,
}

/// A database load that succeeded: streamed (else in memory), and the seconds until its first
/// frame's samples were resident.
type LoadOutcome = (bool, f64);

/// What a database load needs of the run: the renderer's description (tile size, start-up
/// levels) and how stores are streamed (`--cache-mb`, workers).
pub struct DatabaseTerrain {
    pub desc: RendererDesc,
    pub store: StoreArgs,
}

/// The IG side of one run.
pub struct IgDriver {
    link: IgLink,
    queries: Option<DatasetQueries>,
    geo: Option<GeoMapping>,
    choice: DatabaseChoice,
    loader: Option<DatabaseLoader>,
    /// How a database the host asks for is prepared.
    prepare: DatabaseTerrain,
    ig_frame: u32,
    /// CPU time of each frame's answering (session, queries, encoding), µs, frames with at
    /// least one question.
    answer_us: Vec<f64>,
    /// The same frames' whole IG step, sending the datagrams included, µs.
    step_us: Vec<f64>,
    /// Questions asked per frame (same frames as `answer_us`).
    questions: Vec<f64>,
    lighting: Lighting,
    /// The host set the sun / the visibility (the light is not the default one).
    host_light: (bool, bool),
    /// Database loads: (number, path, outcome: streamed or in memory, and the seconds until
    /// its first frame's samples were resident).
    loads: Vec<(i8, String, Result<LoadOutcome, String>)>,
    /// Other traffic (set by [`ig_driver`]).
    traffic: Option<TrafficDriver>,
    /// The datum of the host's geodetic heights, for its terrain queries (set by
    /// [`ig_driver`]).
    host_heights: crate::sim::pose_input::HostHeights,
}

/// The query service of the terrain drawn: on its samples in memory, or on the resident pages
/// of a streamed store (questions over tiles not resident are pending, and asked for).
fn queries_of(terrain: &Terrain) -> Option<DatasetQueries> {
    match (&terrain.dataset, &terrain.streamed) {
        (Some(ds), _) => queries_for(ds, &terrain.bake),
        (None, Some(store)) => Some(DatasetQueries::streamed(
            store.clone(),
            GeoMapping::of_source(terrain.grid()).ok(),
        )),
        (None, None) => None,
    }
}

/// One line on a terrain just prepared: the dataset's summary, or the streamed store's grid.
fn terrain_summary(terrain: &Terrain, path: &str) -> String {
    match &terrain.dataset {
        Some(ds) => ds.summary(),
        None => {
            let g = terrain.grid();
            format!(
                "{path}: {}x{} samples (padded to {}x{}), {} levels, first frame's data resident after {:.3} s",
                g.valid_width,
                g.valid_height,
                g.width,
                g.height,
                terrain.bake.levels.len(),
                terrain.prepare_s
            )
        }
    }
}

/// The query service of a dataset, or why there is none (a bake that does not match).
fn queries_for(ds: &Arc<Dataset>, bake: &Arc<ErrorBake>) -> Option<DatasetQueries> {
    match InMemorySource::new(ds.clone(), bake.clone()) {
        Ok(src) => Some(DatasetQueries::new(src, GeoMapping::of_dataset(ds).ok())),
        Err(e) => {
            tracing::error!("{}: terrain queries unavailable: {e}", ds.source);
            None
        }
    }
}

impl IgDriver {
    /// The IG for `link`, drawing `ds` (the `--dem`, database `choice`'s current one).
    pub fn new(
        link: IgLink,
        terrain: &Terrain,
        databases: Databases,
        config_dir: &Path,
        dem: &Path,
        prepare: DatabaseTerrain,
    ) -> Self {
        Self {
            link,
            queries: queries_of(terrain),
            geo: GeoMapping::of_source(terrain.grid()).ok(),
            choice: DatabaseChoice::new(databases, config_dir, dem),
            loader: None,
            prepare,
            ig_frame: 0,
            answer_us: Vec::new(),
            step_us: Vec::new(),
            questions: Vec::new(),
            lighting: Lighting::default(),
            host_light: (false, false),
            loads: Vec::new(),
            traffic: None,
            host_heights: Default::default(),
        }
    }

    fn status(&self) -> DatabaseStatus {
        match self.choice.report() {
            DatabaseReport::Ready(n) => DatabaseStatus::Ready(n),
            DatabaseReport::Loading(n) => DatabaseStatus::Loading(n),
            DatabaseReport::Unavailable => DatabaseStatus::Unavailable,
        }
    }

    /// One IG step with no terrain yet (while `aerie run` waits for its first pose): the host
    /// still gets its Start of Frame, and every question is answered "no terrain".
    pub fn idle_frame(&mut self) {
        self.step(&NoTerrain);
    }

    fn step(&mut self, terrain: &dyn TerrainQueries) {
        let frame = IgFrame {
            ig_frame: self.ig_frame,
            time_s: monotonic_s(),
            database: self.status(),
        };
        let t = Instant::now();
        let answers = self.link.begin_frame(&frame, terrain);
        let asked = answers.responses + answers.native;
        if asked > 0 {
            self.answer_us.push(answers.cpu_us);
            self.step_us.push(t.elapsed().as_secs_f64() * 1e6);
            self.questions.push(asked as f64);
        }
        self.ig_frame = self.ig_frame.wrapping_add(1);
    }

    /// The start of a rendered frame: a finished database load swapped in, the host's
    /// requests acted on, the frame's answers sent, the host's light applied. `eye` is where
    /// the last frame was drawn from (the clipmap is filled around it after a load).
    pub fn begin_frame(
        &mut self,
        renderer: &mut TerrainRenderer,
        input: Option<&mut SimInput>,
        eye: DVec3,
    ) -> Result<(), String> {
        self.finish_load(renderer, input, eye)?;
        let state = self.link.state();
        if let Some(n) = state.database_request {
            match self.choice.request(n) {
                DatabaseAction::None => {}
                DatabaseAction::Load(n, path) => {
                    eprintln!("CIGI host asks for database {n}: loading {}", path.display());
                    self.loader = Some(DatabaseLoader::start(
                        n,
                        path,
                        &self.prepare.desc,
                        &self.prepare.store,
                    ));
                }
                DatabaseAction::Unknown(n) => eprintln!(
                    "CIGI host asks for database {n}, which the configuration's [databases] table does not have (configured: {:?}); Start of Frame reports it unavailable",
                    self.choice.configured()
                ),
            }
        }
        match self.queries.take() {
            Some(mut q) => {
                q.refresh();
                self.step(&q);
                // What the host asked over tiles not resident comes with the next request.
                let q0 = self.prepare.desc.tile_size - 1;
                let wants: Vec<SampleWant> = q
                    .take_pending()
                    .into_iter()
                    .map(|[tx, ty]| SampleWant {
                        rect: SampleRect {
                            level: 0,
                            origin: [(tx * q0) as i64, (ty * q0) as i64],
                            size: [q0 + 1; 2],
                        },
                        priority: HOST_QUESTION_PRIORITY,
                    })
                    .collect();
                renderer.want_samples(&wants);
                self.queries = Some(q);
            }
            None => self.step(&NoTerrain),
        }
        // The host's light, at the eye's latitude and longitude.
        let env = state.environment;
        let sun = self.geo.as_ref().and_then(|g| {
            let (lat, lon, _) = g.world_to_geodetic(eye);
            let local = env.sun_direction_enu(monotonic_s(), lat, lon)?;
            // The terrain is lit in world axes (ENU at the dataset's origin): the sun's
            // direction at the eye, turned into them.
            Some(enu_at_to_world(g, lat, lon, local))
        });
        let visibility = env.visibility_m();
        self.host_light = (sun.is_some(), visibility.is_some());
        let lighting = Lighting::from_host(sun, visibility);
        if lighting != self.lighting {
            self.lighting = lighting;
            renderer.set_lighting(lighting);
        }
        self.update_traffic(renderer)
    }

    /// The host's entities handed to the renderer for this frame (the last frame's drawing
    /// counted first).
    fn update_traffic(&mut self, renderer: &mut TerrainRenderer) -> Result<(), String> {
        let (Some(t), Some(geo)) = (self.traffic.as_mut(), self.geo.as_ref()) else {
            return Ok(());
        };
        if !t.models_set {
            renderer
                .set_entity_models(t.traffic.library(), t.scale, t.lod)
                .map_err(|e| format!("entity models: {e}"))?;
            t.models_set = true;
        } else if let Some(s) = renderer.entity_stats() {
            t.traffic.record(&s);
        }
        let now = monotonic_s();
        t.started_s.get_or_insert(now);
        let q = self.queries.as_ref();
        let ground = |lat_deg, lon_deg| {
            q.map_or(Answer::NoTerrain, |q| {
                q.height_of_terrain(&PosePosition::Geodetic {
                    lat_deg,
                    lon_deg,
                    alt_m: 0.0,
                })
            })
        };
        let mut draws = Vec::new();
        t.traffic
            .scene(&self.link.entities(), now, geo, &ground, &mut draws);
        renderer.set_entities(draws);
        Ok(())
    }

    fn finish_load(
        &mut self,
        renderer: &mut TerrainRenderer,
        input: Option<&mut SimInput>,
        eye: DVec3,
    ) -> Result<(), String> {
        let Some(result) = self.loader.as_ref().and_then(DatabaseLoader::poll) else {
            return Ok(());
        };
        let loader = self.loader.take().expect("polled above");
        let n = loader.number;
        let path = loader.path.display().to_string();
        match result {
            Ok(LoadedTerrain { terrain, queries }) => {
                renderer
                    .load_source(terrain.source.clone(), terrain.bake.clone(), eye)
                    .map_err(|e| format!("database {n} ({path}): {e}"))?;
                let geo = GeoMapping::of_source(terrain.grid());
                self.queries = match queries {
                    Some(Ok(src)) => Some(DatasetQueries::new(src, geo.clone().ok())),
                    Some(Err(e)) => {
                        tracing::error!("database {n}: terrain queries unavailable: {e}");
                        None
                    }
                    None => queries_of(&terrain),
                }
                .map(|q| q.with_host_heights(self.host_heights));
                self.geo = geo.clone().ok();
                if let Some(i) = input {
                    i.set_geo(geo);
                }
                let how = match &terrain.streamed {
                    Some(_) => "streamed",
                    None => "in memory",
                };
                eprintln!(
                    "database {n} ready ({how}): {}",
                    terrain_summary(&terrain, &path)
                );
                self.choice.finished(n, true);
                let outcome = (terrain.streamed.is_some(), terrain.prepare_s);
                self.loads.push((n, path, Ok(outcome)));
            }
            Err(e) => {
                eprintln!("database {n} ({path}) failed to load, keeping the current one: {e}");
                self.choice.finished(n, false);
                self.loads.push((n, path, Err(e)));
            }
        }
        Ok(())
    }

    /// The session's counters.
    pub fn stats(&self) -> IgStats {
        self.link.stats()
    }

    /// The summary's `ig` object.
    pub fn summary_json(&self) -> serde_json::Value {
        let s = self.link.stats();
        let mut us = self.answer_us.clone();
        us.sort_by(f64::total_cmp);
        let mut q = self.questions.clone();
        q.sort_by(f64::total_cmp);
        let mut step = self.step_us.clone();
        step.sort_by(f64::total_cmp);
        let packets: serde_json::Map<String, serde_json::Value> = s
            .packets
            .as_slice()
            .iter()
            .map(|&(id, n)| (id.to_string(), n.into()))
            .collect();
        serde_json::json!({
            "ig_frames": self.ig_frame,
            "messages": s.messages,
            "start_of_frames": s.start_of_frames,
            "packets": packets,
            "requests_received": s.requests_received,
            "responses_sent": s.responses_sent,
            "answered": s.answered,
            "answered_invalid": s.answered_invalid,
            "timed_out": s.timed_out,
            "native_received": s.native_received,
            "native_answered": s.native_answered,
            "latency_frames": s.latency_frames.to_vec(),
            "latency_max_frames": s.latency_max_frames,
            "answer_cpu_us": {
                "frames": us.len(),
                "median": percentile(&us, 0.5),
                "p99": percentile(&us, 0.99),
                "max": percentile(&us, 1.0),
            },
            "step_us": {
                "median": percentile(&step, 0.5),
                "p99": percentile(&step, 0.99),
                "max": percentile(&step, 1.0),
            },
            "questions_per_frame_max": percentile(&q, 1.0),
            "database": self.status().wire(),
            "databases_configured": self.choice.configured(),
            "database_loads": self.loads.iter().map(|(n, p, r)| serde_json::json!({
                "number": n, "path": p, "error": r.as_ref().err(),
                "streamed": r.as_ref().ok().map(|o| o.0),
                "ready_s": r.as_ref().ok().map(|o| o.1),
            })).collect::<Vec<_>>(),
            "lighting": {
                "sun_enu": self.lighting.sun_enu,
                "haze_distance_m": self.lighting.haze_distance_m,
                "sun_from_host": self.host_light.0,
                "visibility_from_host": self.host_light.1,
            },
            "resets": self.link.state().resets,
            "entities": self.link.state().entities,
            "traffic": self.traffic.as_ref().map(|t| {
                let seconds = t.started_s.map_or(0.0, |s| monotonic_s() - s);
                t.traffic.summary_json(seconds)
            }),
        })
    }

    /// One summary line.
    pub fn summary_line(&self) -> String {
        let s = self.link.stats();
        let mut us = self.answer_us.clone();
        us.sort_by(f64::total_cmp);
        let packets = if s.packets.is_empty() {
            "none".to_string()
        } else {
            s.packets.to_string()
        };
        format!(
            "IG: {} frames, {} Start of Frames, {} host messages (packets by ID: {}); {} requests, {} answered ({} invalid), {} native; answering median {:.0} µs, max {:.0} µs per frame; latency max {} frames; {} resets",
            self.ig_frame,
            s.start_of_frames,
            s.messages,
            packets,
            s.requests_received,
            s.answered + s.answered_invalid,
            s.answered_invalid,
            s.native_answered,
            percentile(&us, 0.5),
            percentile(&us, 1.0),
            s.latency_max_frames,
            self.link.state().resets,
        )
    }
}
