//! The aircraft's path through a headless flight (`fly`, `bench`): timed waypoints when a file
//! gives them, else the built-in straight pass, optionally holding its height above the ground.

use std::sync::Arc;

use glam::DVec3;

use crate::app::args::PassArgs;
use crate::sim::flight::{StraightPass, Waypoints};
use aerie_terrain::camera::Attitude;
use aerie_terrain::dataset::Dataset;

/// Where the aircraft is at every time of the flight.
pub struct FlightPlan {
    waypoints: Option<Waypoints>,
    pass: StraightPass,
    /// With `--follow-terrain`: the terrain and the height kept above it.
    follow: Option<(Arc<Dataset>, f64)>,
}

impl FlightPlan {
    /// The flight over `ds` lasting `duration_s`: along `waypoints` when given, else the pass.
    pub fn new(
        ds: &Arc<Dataset>,
        pass: &PassArgs,
        waypoints: Option<Waypoints>,
        duration_s: f64,
    ) -> Self {
        Self {
            waypoints,
            pass: StraightPass::over(
                ds,
                pass.heading,
                pass.pitch,
                pass.speed,
                pass.agl,
                duration_s,
            ),
            follow: pass.follow_terrain.then(|| (ds.clone(), pass.agl)),
        }
    }

    /// The aircraft's position and attitude `t` seconds into the flight.
    pub fn pose_at(&self, t: f64) -> (DVec3, Attitude) {
        if let Some(w) = &self.waypoints {
            return w.pose_at(t);
        }
        let (mut p, att) = self.pass.pose_at(t);
        if let Some((ds, agl)) = &self.follow {
            p.z = ds.hf.height_at_m(p.x, p.y) + agl;
        }
        (p, att)
    }
}
