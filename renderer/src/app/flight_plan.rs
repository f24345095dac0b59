//! The aircraft's path through a headless flight (`fly`, `bench`): timed waypoints when a file
//! gives them, else the built-in straight pass, optionally holding its height above the ground.

use std::sync::Arc;

use glam::DVec3;

use crate::app::args::PassArgs;
use crate::app::prepare::Terrain;
use crate::sim::flight::{StraightPass, Waypoints};
use aerie_terrain::bake::ErrorBake;
use aerie_terrain::camera::Attitude;
use aerie_terrain::dataset::Dataset;

/// The ground a `--follow-terrain` pass keeps its height above.
enum Ground {
    /// The full-resolution surface.
    Samples(Arc<Dataset>),
    /// A streamed store: the highest sample of the level-0 tile under the aircraft (from the
    /// bake), never below the surface.
    TileMaxima(Arc<ErrorBake>),
}

impl Ground {
    fn height_at(&self, x: f64, y: f64) -> f64 {
        match self {
            Ground::Samples(ds) => ds.hf.height_at_m(x, y),
            Ground::TileMaxima(b) => {
                let q = (b.params.tile_size - 1) as f64;
                let t = &b.levels[0];
                let tx = (x / (b.spacing_x * q))
                    .floor()
                    .clamp(0.0, (t.tiles_x - 1) as f64);
                let ty = (y / (b.spacing_y * q))
                    .floor()
                    .clamp(0.0, (t.tiles_y - 1) as f64);
                b.bounds(0, tx as u32, ty as u32).1 as f64
            }
        }
    }
}

/// Where the aircraft is at every time of the flight.
pub struct FlightPlan {
    waypoints: Option<Waypoints>,
    pass: StraightPass,
    /// With `--follow-terrain`: the terrain and the height kept above it.
    follow: Option<(Ground, f64)>,
}

impl FlightPlan {
    /// The flight over `terrain` lasting `duration_s`: along `waypoints` when given (geo
    /// waypoints placed on the terrain's ellipsoid; `Err` when it has no geo-reference), else
    /// the pass.
    pub fn new(
        terrain: &Terrain,
        pass: &PassArgs,
        waypoints: Option<Waypoints>,
        duration_s: f64,
    ) -> Result<Self, String> {
        let g = terrain.grid();
        let waypoints = waypoints.map(|w| w.placed_on(g)).transpose()?;
        let extent = [
            (g.valid_width - 1) as f64 * g.spacing_x,
            (g.valid_height - 1) as f64 * g.spacing_y,
        ];
        // In memory, the highest sample itself (as before streaming); streamed, the bake's.
        let top = match &terrain.dataset {
            Some(ds) => ds.hf.min_max().1 as f64,
            None => terrain.top_height(),
        };
        let ground = match &terrain.dataset {
            Some(ds) => Ground::Samples(ds.clone()),
            None => Ground::TileMaxima(terrain.bake.clone()),
        };
        Ok(Self {
            waypoints,
            pass: StraightPass::over_extent(
                extent,
                top,
                pass.heading,
                pass.pitch,
                pass.speed,
                pass.agl,
                duration_s,
            ),
            follow: pass.follow_terrain.then_some((ground, pass.agl)),
        })
    }

    /// The aircraft's position and attitude `t` seconds into the flight.
    pub fn pose_at(&self, t: f64) -> (DVec3, Attitude) {
        if let Some(w) = &self.waypoints {
            return w.pose_at(t);
        }
        let (mut p, att) = self.pass.pose_at(t);
        if let Some((ground, agl)) = &self.follow {
            p.z = ground.height_at(p.x, p.y) + agl;
        }
        (p, att)
    }
}
