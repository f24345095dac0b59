//! Discrete level of detail for scene objects (document 004), pure: the bounding sphere's
//! projected radius in pixels picks one of three levels, with a hysteresis band around each
//! threshold so an object hovering at a threshold does not pop back and forth.
//!
//! Projected size rather than distance, as document 004 prefers: it follows the lens, so a
//! narrow-FOV channel asks for more detail than a wide one at the same range. With several
//! channels the entity gets one decision, that of the most demanding channel that sees it (the
//! terrain selection decides once for all channels the same way), so adjacent channels never
//! draw one aircraft at two levels.
//!
//! Rule (levels 0 finest … 2 coarsest, thresholds t0 > t1 px, hysteresis h):
//! - the plain level of a radius r is the first l with r ≥ t_l (level 2 below t1);
//! - an entity at level c stays there while t_c·(1−h) ≤ r < t_{c−1}·(1+h) (no lower bound for
//!   level 2, no upper bound for level 0); once outside, it takes r's plain level.
//!
//! Config validation (`aerie_config::entities::check_lod`) keeps the bands apart
//! (t1·(1+h) < t0·(1−h)), which makes the rule free of oscillation: radii that stay within a
//! ratio (1+h)/(1−h) of each other change an entity's level at most once, in one direction
//! (property-tested below).

use std::collections::HashMap;

use aerie_config::entities::LOD_LEVELS;
use aerie_config::EntitySettings;
use aerie_terrain::camera::Camera;
use glam::DVec3;

/// The LOD parameters (validated by the configuration).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodParams {
    /// Projected radius, px, at and above which level l is drawn (decreasing).
    pub thresholds_px: [f64; LOD_LEVELS - 1],
    /// Band around each threshold, fraction in [0, 1).
    pub hysteresis: f64,
}

impl Default for LodParams {
    fn default() -> Self {
        Self::from(&EntitySettings::default())
    }
}

impl From<&EntitySettings> for LodParams {
    fn from(s: &EntitySettings) -> Self {
        Self {
            thresholds_px: s.lod_thresholds_px,
            hysteresis: s.hysteresis,
        }
    }
}

impl LodParams {
    /// The level of radius `r_px` without hysteresis.
    pub fn plain_level(&self, r_px: f64) -> u8 {
        self.thresholds_px
            .iter()
            .position(|&t| r_px >= t)
            .unwrap_or(LOD_LEVELS - 1) as u8
    }

    /// The level of an entity at `current` (None: first seen) whose projected radius is now
    /// `r_px`.
    pub fn next_level(&self, current: Option<u8>, r_px: f64) -> u8 {
        let Some(c) = current else {
            return self.plain_level(r_px);
        };
        let c_us = usize::from(c).min(LOD_LEVELS - 1);
        let h = self.hysteresis;
        let low = self
            .thresholds_px
            .get(c_us)
            .map_or(f64::NEG_INFINITY, |t| t * (1.0 - h));
        let high = c_us
            .checked_sub(1)
            .map_or(f64::INFINITY, |i| self.thresholds_px[i] * (1.0 + h));
        if r_px >= low && r_px < high {
            c_us as u8
        } else {
            self.plain_level(r_px)
        }
    }
}

/// One viewpoint the decision is made for: a channel's camera and viewport.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodView {
    /// The channel's camera (world metres).
    pub camera: Camera,
    /// Its viewport, pixels.
    pub viewport: (u32, u32),
}

/// Whether a sphere (world centre, radius m) touches `camera`'s view frustum (near plane and
/// the four side planes; the far plane is at infinity).
pub fn sphere_in_frustum(camera: &Camera, centre: DVec3, radius: f64) -> bool {
    let v = camera.world_to_view_rotation() * (centre - camera.position);
    let f = &camera.frustum;
    // View axes: x right, y down, z forward; a = x/z ∈ [l, r], b = y/z ∈ [−u, −d].
    let side = |n: DVec3| n.dot(v) / n.length() <= radius;
    v.z + radius >= camera.near
        && side(DVec3::new(1.0, 0.0, -f.tan_right))
        && side(DVec3::new(-1.0, 0.0, f.tan_left))
        && side(DVec3::new(0.0, -1.0, -f.tan_up))
        && side(DVec3::new(0.0, 1.0, f.tan_down))
}

/// The radius in pixels of a sphere seen at the centre of `view`'s screen at the sphere's
/// distance: `f·R / sqrt(d² − R²)` (the tangent of its angular radius times the focal length in
/// pixels, the larger of the two axes'); infinite when the eye is inside it.
pub fn projected_radius_px(view: &LodView, centre: DVec3, radius: f64) -> f64 {
    let d2 = (centre - view.camera.position).length_squared();
    let r2 = radius * radius;
    if d2 <= r2 {
        return f64::INFINITY;
    }
    let (fx, fy) = view
        .camera
        .frustum
        .focal_px(view.viewport.0, view.viewport.1);
    fx.max(fy) * radius / (d2 - r2).sqrt()
}

/// An entity's bounding sphere, as the decision takes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodInput {
    /// Entity ID (the hysteresis memory is per ID).
    pub id: u16,
    /// Sphere centre, world metres.
    pub centre: DVec3,
    /// Sphere radius, metres.
    pub radius: f64,
}

/// The decision for one entity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodDecision {
    /// Entity ID.
    pub id: u16,
    /// Its level, `None` when no channel sees it (culled).
    pub level: Option<u8>,
    /// The largest projected radius over the channels that see it, px (0 when culled).
    pub radius_px: f64,
}

/// What one frame's decisions did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LodCounts {
    /// Entities decided.
    pub known: usize,
    /// Seen by at least one channel.
    pub drawn: usize,
    /// Seen by none.
    pub culled: usize,
    /// Entities drawn at a different level than the last time they were drawn.
    pub switches: usize,
}

/// The per-entity memory hysteresis needs: each entity's last drawn level.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LodState {
    levels: HashMap<u16, u8>,
}

impl LodState {
    /// The level last drawn for `id`.
    pub fn level(&self, id: u16) -> Option<u8> {
        self.levels.get(&id).copied()
    }

    /// Decides every entity for this frame's `views`. An entity culled in every view keeps
    /// its last level (so it comes back without a pop); entities absent from `entities` are
    /// forgotten.
    pub fn decide(
        &mut self,
        params: &LodParams,
        entities: &[LodInput],
        views: &[LodView],
        out: &mut Vec<LodDecision>,
    ) -> LodCounts {
        out.clear();
        let mut counts = LodCounts {
            known: entities.len(),
            ..LodCounts::default()
        };
        for e in entities {
            let r = views
                .iter()
                .filter(|v| sphere_in_frustum(&v.camera, e.centre, e.radius))
                .map(|v| projected_radius_px(v, e.centre, e.radius))
                .fold(None, |acc: Option<f64>, r| {
                    Some(acc.map_or(r, |a| a.max(r)))
                });
            let decision = match r {
                None => {
                    counts.culled += 1;
                    LodDecision {
                        id: e.id,
                        level: None,
                        radius_px: 0.0,
                    }
                }
                Some(r) => {
                    counts.drawn += 1;
                    let before = self.levels.get(&e.id).copied();
                    let level = params.next_level(before, r);
                    if before.is_some_and(|b| b != level) {
                        counts.switches += 1;
                    }
                    self.levels.insert(e.id, level);
                    LodDecision {
                        id: e.id,
                        level: Some(level),
                        radius_px: r,
                    }
                }
            };
            out.push(decision);
        }
        if self.levels.len() > entities.len() {
            let live: std::collections::HashSet<u16> = entities.iter().map(|e| e.id).collect();
            self.levels.retain(|id, _| live.contains(id));
        }
        counts
    }

    /// Forgets every entity (a host's reset).
    pub fn clear(&mut self) {
        self.levels.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use aerie_terrain::camera::{Attitude, Frustum};
    use proptest::prelude::*;

    fn params(h: f64) -> LodParams {
        LodParams {
            thresholds_px: [48.0, 12.0],
            hysteresis: h,
        }
    }

    fn view(hfov_deg: f64) -> LodView {
        let camera = Camera::new(
            DVec3::ZERO,
            Attitude::from_degrees(0.0, 0.0, 0.0),
            Frustum::symmetric(hfov_deg.to_radians(), 256, 144),
        );
        LodView {
            camera,
            viewport: (256, 144),
        }
    }

    #[test]
    fn plain_levels_follow_the_thresholds() {
        let p = params(0.1);
        assert_eq!(p.plain_level(1000.0), 0);
        assert_eq!(p.plain_level(48.0), 0);
        assert_eq!(p.plain_level(47.9), 1);
        assert_eq!(p.plain_level(12.0), 1);
        assert_eq!(p.plain_level(11.9), 2);
        assert_eq!(p.plain_level(0.0), 2);
    }

    #[test]
    fn hysteresis_holds_a_level_inside_the_band_and_releases_it_outside() {
        let p = params(0.1);
        // At level 0, shrinking through 48 px: kept down to 43.2 px, then level 1.
        assert_eq!(p.next_level(Some(0), 44.0), 0);
        assert_eq!(p.next_level(Some(0), 43.1), 1);
        // At level 1, growing through 48 px: kept up to 52.8 px.
        assert_eq!(p.next_level(Some(1), 52.0), 1);
        assert_eq!(p.next_level(Some(1), 52.9), 0);
        // A jump across two thresholds goes straight to the plain level.
        assert_eq!(p.next_level(Some(0), 3.0), 2);
        assert_eq!(p.next_level(Some(2), 500.0), 0);
        // Without hysteresis the rule is the plain one.
        let p0 = params(0.0);
        for r in [0.0, 11.99, 12.0, 47.99, 48.0, 100.0] {
            for c in 0..3 {
                assert_eq!(p0.next_level(Some(c), r), p0.plain_level(r), "{c} {r}");
            }
        }
    }

    #[test]
    fn projected_size_follows_the_lens_not_the_distance() {
        let ahead = DVec3::new(0.0, 500.0, 0.0);
        let wide = projected_radius_px(&view(90.0), ahead, 10.0);
        let narrow = projected_radius_px(&view(20.0), ahead, 10.0);
        // 256 px over 90°: f = 128 px; R/sqrt(d² − R²) = 10 / 499.9.
        assert!((wide - 128.0 * 10.0 / (500.0f64.powi(2) - 100.0).sqrt()).abs() < 1e-9);
        assert!(narrow > 5.0 * wide, "{narrow} vs {wide}");
        let p = params(0.1);
        assert_eq!(p.plain_level(wide), 2);
        assert_eq!(p.plain_level(narrow), 1);
        // Inside the sphere: infinitely large.
        assert_eq!(
            projected_radius_px(&view(90.0), DVec3::ZERO, 1.0),
            f64::INFINITY
        );
    }

    #[test]
    fn frustum_test_keeps_spheres_touching_the_view_and_culls_the_rest() {
        let c = view(90.0).camera;
        // The camera looks north (+y); 45° half-angle horizontally.
        assert!(sphere_in_frustum(&c, DVec3::new(0.0, 100.0, 0.0), 1.0));
        assert!(!sphere_in_frustum(&c, DVec3::new(0.0, -100.0, 0.0), 1.0));
        assert!(!sphere_in_frustum(&c, DVec3::new(120.0, 100.0, 0.0), 5.0));
        // Just outside the right edge by less than its radius: kept.
        assert!(sphere_in_frustum(&c, DVec3::new(103.0, 100.0, 0.0), 5.0));
        // Behind the eye but large enough to reach the near plane.
        assert!(sphere_in_frustum(&c, DVec3::new(0.0, -2.0, 0.0), 3.0));
        // Above the top edge (vertical half-angle atan(144/256) ≈ 29°).
        assert!(!sphere_in_frustum(&c, DVec3::new(0.0, 100.0, 80.0), 5.0));
        assert!(sphere_in_frustum(&c, DVec3::new(0.0, 100.0, 50.0), 5.0));
    }

    #[test]
    fn one_decision_across_channels_from_the_most_demanding() {
        let mut st = LodState::default();
        let e = [LodInput {
            id: 3,
            centre: DVec3::new(0.0, 500.0, 0.0),
            radius: 10.0,
        }];
        let mut out = Vec::new();
        let counts = st.decide(&params(0.1), &e, &[view(90.0)], &mut out);
        assert_eq!(out[0].level, Some(2));
        assert_eq!((counts.drawn, counts.culled, counts.switches), (1, 0, 0));
        let counts = st.decide(&params(0.1), &e, &[view(90.0), view(20.0)], &mut out);
        assert_eq!(out[0].level, Some(1), "the narrow channel decides");
        assert_eq!(counts.switches, 1);
        // A channel looking away sees nothing: culled, its level remembered.
        let mut away = view(20.0);
        away.camera.attitude = Attitude::from_degrees(180.0, 0.0, 0.0);
        let counts = st.decide(&params(0.1), &e, &[away], &mut out);
        assert_eq!((out[0].level, counts.culled), (None, 1));
        assert_eq!(st.level(3), Some(1));
        // Gone from the input: forgotten.
        st.decide(&params(0.1), &[], &[away], &mut out);
        assert_eq!(st.level(3), None);
    }

    proptest! {
        /// No level oscillates for a sphere whose projected size wobbles less than the band:
        /// radii within a ratio (1+h)/(1−h) of each other change the level at most once.
        #[test]
        fn no_back_and_forth_inside_the_band(
            h in 0.02f64..0.3,
            centre in 1.0f64..200.0,
            wobble in prop::collection::vec(-1.0f64..1.0, 2..80),
            start in proptest::option::of(0u8..3),
        ) {
            let p = params(h);
            prop_assume!(p.thresholds_px[1] * (1.0 + h) < p.thresholds_px[0] * (1.0 - h));
            // Radii spread over [lo, hi] with hi/lo just under (1+h)/(1−h).
            let ratio = ((1.0 + h) / (1.0 - h)).sqrt() * 0.999;
            let radii: Vec<f64> = wobble.iter().map(|w| centre * ratio.powf(*w)).collect();
            let mut level = start.map(|s| p.next_level(Some(s), radii[0]))
                .unwrap_or_else(|| p.next_level(None, radii[0]));
            let mut changes = 0;
            for &r in &radii[1..] {
                let next = p.next_level(Some(level), r);
                if next != level {
                    changes += 1;
                }
                level = next;
            }
            prop_assert!(changes <= 1, "{changes} changes over {radii:?}");
        }

        /// Outside the band the rule is never stuck: a radius far from every threshold
        /// gives its plain level whatever the level before.
        #[test]
        fn far_from_thresholds_the_plain_level_wins(
            h in 0.0f64..0.3, r in 0.0f64..1000.0, c in 0u8..3,
        ) {
            let p = params(h);
            let near = p.thresholds_px.iter().any(|t| (r / t - 1.0).abs() <= h);
            prop_assume!(!near);
            prop_assert_eq!(p.next_level(Some(c), r), p.plain_level(r));
        }
    }
}
