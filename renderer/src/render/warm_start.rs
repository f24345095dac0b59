//! The first frame after a load also selects the views around the eye (pure): the eye's own
//! field of view turned to eight headings 45° apart, level and 30° down. The selections are
//! made into the frame's own [`Selection`] — before the frame's, which replaces their items —
//! so that every node they meet has its camera-independent values in the selection's node
//! cache, and their refined tiles are what the first frame's plan prefetches
//! (`plan.rs`, `PlanState::warm_start`, set from `RendererDesc::warm_start`: `fly`, `run` and
//! `bench` ask for it, a still image does not). They are made without carrying (no record of a
//! view nobody drew), so what the first frames draw is what they draw without them.
//!
//! Why: a flight that starts turning meets, in its first frames, nodes and refined tiles the
//! start-up never made. The Inn manoeuvre (1280×720, τ = 1, `fly --no-draw`, 3 runs each,
//! each frame's least): frames 2 and 3 597 / 534 → 540 / 498 µs of selection + plan; the
//! Northern England manoeuvre's pool misses over the flight 102 → 53. The first frame pays
//! for it (Inn 4.0 → 11.2 ms, Northern England 2.2 → 17.0 ms: 16 selections and up to the
//! staging region's bytes of prefetched tiles), as a load does.

use std::collections::HashSet;

use aerie_terrain::bake::ErrorBake;
use aerie_terrain::camera::Camera;
use aerie_terrain::clipmap::{ClipmapDesc, LevelPlacement};
use aerie_terrain::select::{
    select_tiles_multi_ready, DrawItem, SelectParams, Selection, TileReadiness, View,
};

/// Headings the views around the eye take, 360° / this apart.
pub const WARM_HEADINGS: u32 = 8;

/// Their pitches, degrees (nose up +): level and looking down.
pub const WARM_PITCHES_DEG: [f64; 2] = [0.0, -30.0];

/// What the views around the eye are selected with: the frame's own inputs.
pub struct WarmViews<'a> {
    pub bake: &'a ErrorBake,
    pub clipmap: &'a ClipmapDesc,
    pub placements: &'a [LevelPlacement],
    pub viewport: (u32, u32),
    pub tau_px: f64,
    pub params: &'a SelectParams,
    pub content: &'a dyn TileReadiness,
}

impl WarmViews<'_> {
    /// Selects every view around `camera` into `out` (its node cache kept, its items replaced)
    /// and returns one item of each refined ring tile they draw, in the order first drawn
    /// (neighbouring views share most of theirs).
    pub fn refined_items(&self, camera: &Camera, out: &mut Selection) -> Vec<DrawItem> {
        let params = SelectParams {
            carry: false,
            ..*self.params
        };
        let mut items = Vec::new();
        let mut seen = HashSet::new();
        for cam in views_around(camera) {
            let view = View {
                camera: &cam,
                viewport: self.viewport,
                tau_px: self.tau_px,
            };
            select_tiles_multi_ready(
                self.bake,
                self.clipmap,
                self.placements,
                &[view],
                &params,
                self.content,
                out,
            );
            items.extend(
                out.items.iter().copied().filter(|i| {
                    i.refinement > 0 && seen.insert((i.level, i.tx, i.ty, i.refinement))
                }),
            );
        }
        items
    }
}

/// The views around `camera`: its position, field of view and near plane, at every heading of
/// [`WARM_HEADINGS`] from its own and every pitch of [`WARM_PITCHES_DEG`], unrolled.
pub fn views_around(camera: &Camera) -> impl Iterator<Item = Camera> + '_ {
    (0..WARM_HEADINGS).flat_map(move |k| {
        WARM_PITCHES_DEG.map(move |pitch| {
            let mut c = *camera;
            c.attitude.heading += f64::from(k) * std::f64::consts::TAU / f64::from(WARM_HEADINGS);
            c.attitude.pitch = pitch.to_radians();
            c.attitude.roll = 0.0;
            c
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use aerie_terrain::camera::{Attitude, Frustum};
    use glam::DVec3;

    #[test]
    fn the_views_around_turn_the_eye_to_every_heading_at_each_pitch() {
        let eye = Camera::new(
            DVec3::new(10.0, -20.0, 1500.0),
            Attitude::from_degrees(160.0, -10.0, 25.0),
            Frustum::symmetric(70f64.to_radians(), 1280, 720),
        );
        let views: Vec<Camera> = views_around(&eye).collect();
        assert_eq!(
            views.len(),
            (WARM_HEADINGS as usize) * WARM_PITCHES_DEG.len()
        );
        let mut headings: Vec<i64> = Vec::new();
        for v in &views {
            assert_eq!(v.position, eye.position);
            assert_eq!(v.frustum, eye.frustum);
            assert_eq!(v.near, eye.near);
            assert_eq!(v.attitude.roll, 0.0);
            assert!(WARM_PITCHES_DEG
                .iter()
                .any(|p| (v.attitude.pitch - p.to_radians()).abs() < 1e-12));
            let h = (v.attitude.heading.to_degrees() - 160.0).rem_euclid(360.0);
            headings.push(h.round() as i64);
        }
        headings.sort();
        headings.dedup();
        assert_eq!(headings, vec![0, 45, 90, 135, 180, 225, 270, 315]);
    }
}
