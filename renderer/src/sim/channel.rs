//! Display channels as cameras (issue 7): a channel's view offset, frustum and eye offset
//! applied to the aircraft's pose, in f64. Pure CPU, no window or device, so that windowed and
//! headless channels share it and it is tested against f64 references.

use aerie_config::{Channel, ChannelFrustum, EyeOffset, ViewOffset};
use glam::{DMat3, DVec3};

use aerie_terrain::camera::{Attitude, Camera, Frustum};

/// The aircraft's pose for one frame: reference point in world ENU (metres) and attitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AircraftPose {
    pub position: DVec3,
    pub attitude: Attitude,
}

/// Forward-right-down body axes → ENU for a level aircraft heading north: the change of basis
/// between a rotation written in body (FRD) coordinates and [`Attitude::body_to_world`].
fn frd_to_enu() -> DMat3 {
    DMat3::from_cols(
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, -1.0),
    )
}

/// The view offset as a rotation in the aircraft's body frame: columns are the view's forward,
/// right and down axes in body (forward, right, down) coordinates. Heading, pitch, roll are
/// applied in that order about the body axes, like the aircraft's own attitude.
pub fn view_offset_rotation(v: &ViewOffset) -> DMat3 {
    let a = Attitude::from_degrees(v.heading_deg, v.pitch_deg, v.roll_deg);
    frd_to_enu().transpose() * a.body_to_world()
}

/// The attitude whose [`Attitude::body_to_world`] is `m` (columns forward, right, down in ENU;
/// a proper rotation). At ±90° pitch, where heading and roll are one rotation, roll is 0.
pub fn attitude_from_body_to_world(m: DMat3) -> Attitude {
    let (f, r, d) = (m.x_axis, m.y_axis, m.z_axis);
    let horizontal = (f.x * f.x + f.y * f.y).sqrt();
    let pitch = f.z.atan2(horizontal);
    if horizontal < 1e-12 {
        // Gimbal lock: right = (cos ψ, −sin ψ, 0) with roll 0.
        return Attitude {
            heading: (-r.y).atan2(r.x),
            pitch,
            roll: 0.0,
        };
    }
    Attitude {
        heading: f.x.atan2(f.y),
        pitch,
        // right.z = −sin φ cos θ, down.z = −cos φ cos θ.
        roll: (-r.z).atan2(-d.z),
    }
}

/// Eye position: the aircraft reference point plus the eye offset rotated by the aircraft's
/// attitude (the offset is in the body frame; the view offset does not move the eye).
pub fn eye_position(aircraft: &AircraftPose, eye: &EyeOffset) -> DVec3 {
    let body = DVec3::new(eye.forward_m, eye.right_m, -eye.up_m);
    aircraft.position + aircraft.attitude.body_to_world() * body
}

/// The channel's frustum. A symmetric frustum without a vertical angle takes it from `aspect`
/// (width / height of the channel's viewport, square pixels).
pub fn channel_frustum(f: &ChannelFrustum, aspect: f64) -> Frustum {
    let t = |deg: f64| deg.to_radians().tan();
    match *f {
        ChannelFrustum::Symmetric { hfov_deg, vfov_deg } => {
            let th = t(0.5 * hfov_deg);
            let tv = match vfov_deg {
                Some(v) => t(0.5 * v),
                None => th / aspect,
            };
            Frustum {
                tan_left: -th,
                tan_right: th,
                tan_down: -tv,
                tan_up: tv,
            }
        }
        ChannelFrustum::Asymmetric {
            left_deg,
            right_deg,
            down_deg,
            up_deg,
        } => Frustum {
            tan_left: t(left_deg),
            tan_right: t(right_deg),
            tan_down: t(down_deg),
            tan_up: t(up_deg),
        },
    }
}

/// The camera of channel `ch` for the aircraft pose `aircraft` (position, attitude): the view
/// offset composed with the aircraft's attitude in f64, the eye offset rotated by the aircraft's
/// attitude, the channel's frustum (`aspect` = viewport width / height, used by a symmetric
/// frustum given by hfov only).
pub fn channel_camera(aircraft: (DVec3, Attitude), ch: &Channel, aspect: f64) -> Camera {
    let pose = AircraftPose {
        position: aircraft.0,
        attitude: aircraft.1,
    };
    let view = pose.attitude.body_to_world() * view_offset_rotation(&ch.view);
    Camera::new(
        eye_position(&pose, &ch.eye),
        attitude_from_body_to_world(view),
        channel_frustum(&ch.frustum, aspect),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    const W: u32 = 1920;
    const H: u32 = 1080;

    fn channel(view: (f64, f64, f64), frustum: ChannelFrustum, eye: (f64, f64, f64)) -> Channel {
        Channel {
            view: ViewOffset {
                heading_deg: view.0,
                pitch_deg: view.1,
                roll_deg: view.2,
            },
            frustum,
            eye: EyeOffset {
                forward_m: eye.0,
                right_m: eye.1,
                up_m: eye.2,
            },
            ..Channel::window("test", W, H, 60.0, 1.0)
        }
    }

    fn sym(hfov: f64) -> ChannelFrustum {
        ChannelFrustum::Symmetric {
            hfov_deg: hfov,
            vfov_deg: None,
        }
    }

    /// Independent f64 reference: rotations as quaternions about world/body axes. Start at the
    /// rest pose (forward north, right east, down −up); heading about −up, pitch about the
    /// current right axis, roll about the current forward axis (intrinsic), aircraft first, then
    /// the view offset in the aircraft's frame.
    fn reference_axes(aircraft: (f64, f64, f64), offset: (f64, f64, f64)) -> [DVec3; 3] {
        let q = |h: f64, p: f64, r: f64| {
            DQuat::from_rotation_z(-h.to_radians())
                * DQuat::from_rotation_x(p.to_radians())
                * DQuat::from_rotation_y(r.to_radians())
        };
        let total = q(aircraft.0, aircraft.1, aircraft.2) * q(offset.0, offset.1, offset.2);
        [total * DVec3::Y, total * DVec3::X, total * DVec3::NEG_Z]
    }

    fn assert_close(a: DVec3, b: DVec3, tol: f64, what: &str) {
        assert!((a - b).length() <= tol, "{what}: {a:?} vs {b:?}");
    }

    fn check(aircraft: (f64, f64, f64), offset: (f64, f64, f64)) {
        let att = Attitude::from_degrees(aircraft.0, aircraft.1, aircraft.2);
        let ch = channel(offset, sym(60.0), (0.0, 0.0, 0.0));
        let cam = channel_camera((DVec3::ZERO, att), &ch, 16.0 / 9.0);
        let m = cam.attitude.body_to_world();
        let [f, r, d] = reference_axes(aircraft, offset);
        let what = format!("aircraft {aircraft:?} offset {offset:?}");
        assert_close(m.x_axis, f, 1e-12, &format!("{what} forward"));
        assert_close(m.y_axis, r, 1e-12, &format!("{what} right"));
        assert_close(m.z_axis, d, 1e-12, &format!("{what} down"));
    }

    #[test]
    fn heading_offset_of_60_on_a_level_aircraft_looks_60_degrees_right() {
        let ch = channel((60.0, 0.0, 0.0), sym(60.0), (0.0, 0.0, 0.0));
        for heading in [0.0, 45.0, 350.0] {
            let att = Attitude::from_degrees(heading, 0.0, 0.0);
            let cam = channel_camera((DVec3::new(1.0, 2.0, 3.0), att), &ch, 16.0 / 9.0);
            let h = (heading + 60.0f64).to_radians();
            let fwd = cam.attitude.body_to_world().x_axis;
            assert_close(fwd, DVec3::new(h.sin(), h.cos(), 0.0), 1e-12, "forward");
            // The centre pixel's ray is that direction; the channel's left edge is the
            // aircraft's +30°.
            let centre = cam.pixel_ray(W as f64 / 2.0, H as f64 / 2.0, W, H);
            assert_close(centre, fwd, 1e-12, "centre ray");
            let left = cam.pixel_ray(0.0, H as f64 / 2.0, W, H);
            let e = (heading + 30.0f64).to_radians();
            assert_close(left, DVec3::new(e.sin(), e.cos(), 0.0), 1e-12, "left edge");
            assert_eq!(cam.position, DVec3::new(1.0, 2.0, 3.0));
        }
    }

    #[test]
    fn composition_matches_f64_quaternion_reference() {
        for aircraft in [
            (0.0, 0.0, 0.0),
            (30.0, 10.0, 0.0),
            (123.0, -20.0, 35.0),
            (-170.0, 60.0, -80.0),
            (10.0, 89.0, 5.0),
        ] {
            for offset in [
                (0.0, 0.0, 0.0),
                (60.0, 0.0, 0.0),
                (-60.0, 0.0, 0.0),
                (-20.0, -30.0, 0.0),
                (90.0, 15.0, 10.0),
                (180.0, -45.0, 0.0),
            ] {
                check(aircraft, offset);
            }
        }
    }

    #[test]
    fn pitch_offset_on_a_rolled_aircraft_follows_the_body_not_the_world() {
        // Rolled 90° right, the body's "down" points west (heading north): a −30° pitch offset
        // (chin window) then looks 30° towards the west, level with the horizon.
        let att = Attitude::from_degrees(0.0, 0.0, 90.0);
        let ch = channel((0.0, -30.0, 0.0), sym(60.0), (0.0, 0.0, 0.0));
        let cam = channel_camera((DVec3::ZERO, att), &ch, 1.0);
        let a = 30f64.to_radians();
        let fwd = cam.attitude.body_to_world().x_axis;
        assert_close(fwd, DVec3::new(-a.sin(), a.cos(), 0.0), 1e-12, "forward");
    }

    #[test]
    fn gimbal_lock_keeps_the_rotation() {
        // Pitch +90° after composition: the extracted attitude must give the same axes.
        check((0.0, 60.0, 0.0), (0.0, 30.0, 0.0));
        check((40.0, 45.0, 0.0), (0.0, 45.0, 20.0));
        let m = Attitude::from_degrees(30.0, 90.0, 0.0).body_to_world();
        let back = attitude_from_body_to_world(m).body_to_world();
        for (a, b) in [
            (m.x_axis, back.x_axis),
            (m.y_axis, back.y_axis),
            (m.z_axis, back.z_axis),
        ] {
            assert_close(a, b, 1e-12, "gimbal");
        }
    }

    #[test]
    fn eye_offset_is_rotated_by_the_aircraft_attitude_only() {
        let att = Attitude::from_degrees(90.0, 0.0, 0.0); // heading east: right is south
        let ch = channel((-60.0, 0.0, 0.0), sym(60.0), (2.0, -0.5, 1.0));
        let cam = channel_camera((DVec3::new(100.0, 200.0, 300.0), att), &ch, 1.5);
        assert_close(
            cam.position,
            DVec3::new(102.0, 200.5, 301.0),
            1e-12,
            "eye position",
        );
        // Pitched 90° up, "forward" is up.
        let up = Attitude::from_degrees(0.0, 90.0, 0.0);
        let cam = channel_camera((DVec3::ZERO, up), &ch, 1.5);
        assert_close(
            cam.position,
            DVec3::new(-0.5, -1.0, 2.0),
            1e-12,
            "pitched up",
        );
    }

    #[test]
    fn asymmetric_frustum_projects_its_edge_angles_to_the_viewport_edges() {
        let (l, r, d, u) = (-40.0f64, 25.0f64, -15.0f64, 30.0f64);
        let f = ChannelFrustum::Asymmetric {
            left_deg: l,
            right_deg: r,
            down_deg: d,
            up_deg: u,
        };
        let aircraft = Attitude::from_degrees(33.0, 4.0, -7.0);
        let ch = channel((20.0, -10.0, 3.0), f, (0.0, 0.0, 0.0));
        let eye = DVec3::new(5e6, -3e6, 2000.0);
        let cam = channel_camera((eye, aircraft), &ch, 1.0);
        let m = cam.attitude.body_to_world();
        // A point at 1 km along the direction at (horizontal angle a, vertical angle b) from
        // the view axis, in the view's own frame.
        let at = |a: f64, b: f64| {
            let dir = m.x_axis + m.y_axis * a.to_radians().tan() - m.z_axis * b.to_radians().tan();
            cam.position + dir * 1000.0
        };
        let px = |p: DVec3| cam.project_px(p, W, H).expect("in front").0;
        assert!(
            (px(at(l, 0.0)).x - 0.0).abs() < 1e-6,
            "{:?}",
            px(at(l, 0.0))
        );
        assert!((px(at(r, 0.0)).x - W as f64).abs() < 1e-6);
        assert!((px(at(0.0, u)).y - 0.0).abs() < 1e-6);
        assert!((px(at(0.0, d)).y - H as f64).abs() < 1e-6);
        // The view axis is off-centre by the asymmetry.
        let axis = px(at(0.0, 0.0));
        let tl = l.to_radians().tan();
        let tr = r.to_radians().tan();
        assert!((axis.x - W as f64 * (-tl) / (tr - tl)).abs() < 1e-6);
        // Corners too: (left, up) is the top-left pixel corner, (right, down) the bottom-right.
        assert!(px(at(l, u)).length() < 1e-6, "{:?}", px(at(l, u)));
        let br = px(at(r, d)) - glam::DVec2::new(W as f64, H as f64);
        assert!(br.length() < 1e-6, "{br:?}");
    }

    #[test]
    fn symmetric_frustum_takes_vfov_from_aspect_or_config() {
        let f = channel_frustum(&sym(90.0), 2.0);
        assert!((f.tan_right - 1.0).abs() < 1e-15 && (f.tan_up - 0.5).abs() < 1e-15);
        let g = channel_frustum(
            &ChannelFrustum::Symmetric {
                hfov_deg: 90.0,
                vfov_deg: Some(60.0),
            },
            2.0,
        );
        assert!((g.tan_up - 30f64.to_radians().tan()).abs() < 1e-15);
        assert_eq!(g.tan_left, -g.tan_right);
        // Matches the camera module's own symmetric frustum.
        let c = Frustum::symmetric(60f64.to_radians(), W, H);
        let d = channel_frustum(&sym(60.0), W as f64 / H as f64);
        assert!((c.tan_up - d.tan_up).abs() < 1e-15 && (c.tan_right - d.tan_right).abs() < 1e-15);
    }

    #[test]
    fn wall3_neighbours_share_their_edge_ray() {
        // The last column of the left channel and the first of the centre one see the same
        // direction, for any aircraft attitude.
        let att = Attitude::from_degrees(47.0, 8.0, 12.0);
        let left = channel((-60.0, 0.0, 0.0), sym(60.0), (0.0, 0.0, 0.0));
        let centre = channel((0.0, 0.0, 0.0), sym(60.0), (0.0, 0.0, 0.0));
        let aspect = W as f64 / H as f64;
        let a = channel_camera((DVec3::ZERO, att), &left, aspect);
        let b = channel_camera((DVec3::ZERO, att), &centre, aspect);
        let ra = a.pixel_ray(W as f64, H as f64 / 2.0, W, H);
        let rb = b.pixel_ray(0.0, H as f64 / 2.0, W, H);
        assert_close(ra, rb, 1e-12, "shared edge");
    }
}
