//! Axis-aligned tile boxes and the frustum test used by tile selection. Pure CPU.

use glam::DVec3;

use crate::camera::Camera;

/// An axis-aligned box in world ENU metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb {
    pub fn corners(&self) -> [DVec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            DVec3::new(a.x, a.y, a.z),
            DVec3::new(b.x, a.y, a.z),
            DVec3::new(a.x, b.y, a.z),
            DVec3::new(b.x, b.y, a.z),
            DVec3::new(a.x, a.y, b.z),
            DVec3::new(b.x, a.y, b.z),
            DVec3::new(a.x, b.y, b.z),
            DVec3::new(b.x, b.y, b.z),
        ]
    }
}

/// True when the box lies entirely outside one plane of the camera's frustum (near plane and
/// the four side planes; the far plane is at infinity). Conservative: may keep boxes that are
/// outside near a frustum corner, never drops a visible one.
pub fn outside_frustum(camera: &Camera, aabb: &Aabb) -> bool {
    let to_view = camera.world_to_view();
    let f = camera.frustum;
    let corners = aabb.corners().map(|c| to_view.transform_point3(c));
    // View space: x right, y down, z forward. Inside means a = x/z ∈ [l, r], -y/z ∈ [down, up].
    let planes: [&dyn Fn(DVec3) -> bool; 5] = [
        &|p| p.z < camera.near,
        &|p| p.x > f.tan_right * p.z,
        &|p| p.x < f.tan_left * p.z,
        &|p| -p.y > f.tan_up * p.z,
        &|p| -p.y < f.tan_down * p.z,
    ];
    planes
        .iter()
        .any(|outside| corners.iter().all(|&c| outside(c)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Attitude, Frustum};

    #[test]
    fn culling_keeps_what_is_ahead_and_drops_what_is_behind() {
        // Eye 500 m up looking north and slightly down over a 1.6 km × 3.2 km grid of boxes.
        let cam = Camera::new(
            DVec3::new(800.0, 1600.0, 500.0),
            Attitude::from_degrees(0.0, -20.0, 0.0),
            Frustum::symmetric(60f64.to_radians(), 320, 180),
        );
        let (mut kept, mut culled) = (0, 0);
        for ty in 0..20 {
            for tx in 0..10 {
                let b = Aabb {
                    min: DVec3::new(tx as f64 * 160.0, ty as f64 * 160.0, 0.0),
                    max: DVec3::new((tx + 1) as f64 * 160.0, (ty + 1) as f64 * 160.0, 300.0),
                };
                let visible = b.corners().iter().any(|&c| {
                    cam.project_px(c, 320, 180).is_some_and(|(p, _)| {
                        p.x >= 0.0 && p.x <= 320.0 && p.y >= 0.0 && p.y <= 180.0
                    })
                });
                let out = outside_frustum(&cam, &b);
                if visible {
                    assert!(!out, "visible box {tx},{ty} was culled");
                }
                if b.max.y < 1500.0 {
                    assert!(out, "box {tx},{ty} behind the eye was kept");
                }
                if out {
                    culled += 1
                } else {
                    kept += 1
                }
            }
        }
        assert!(kept > 0 && culled > 0);
    }
}
