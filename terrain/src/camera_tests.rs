use super::*;
use glam::{DQuat, Vec3, Vec4Swizzles};
use proptest::prelude::*;

const W: u32 = 1920;
const H: u32 = 1080;

fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
    (a - b).length() <= tol
}

/// Independent construction of the body axes: start from the rest pose (forward north,
/// right east, down = −up) and compose elementary rotations intrinsically about the current
/// axes: heading about −up (clockwise seen from above), pitch about right (y→z), roll about
/// forward (x→−z).
fn reference_axes(heading: f64, pitch: f64, roll: f64) -> (DVec3, DVec3, DVec3) {
    let q = DQuat::from_rotation_z(-heading)
        * DQuat::from_rotation_x(pitch)
        * DQuat::from_rotation_y(roll);
    (q * DVec3::Y, q * DVec3::X, q * DVec3::NEG_Z)
}

fn assert_axes(att: Attitude, fwd: DVec3, right: DVec3, down: DVec3) {
    let m = att.body_to_world();
    assert!(
        close(m.x_axis, fwd, 1e-12),
        "forward {:?} vs {fwd:?}",
        m.x_axis
    );
    assert!(
        close(m.y_axis, right, 1e-12),
        "right {:?} vs {right:?}",
        m.y_axis
    );
    assert!(
        close(m.z_axis, down, 1e-12),
        "down {:?} vs {down:?}",
        m.z_axis
    );
}

#[test]
fn level_attitude_looks_north_right_is_east_down_is_minus_z() {
    assert_axes(
        Attitude::from_degrees(0.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, -1.0),
    );
}

#[test]
fn heading_90_looks_east_and_right_is_south() {
    assert_axes(
        Attitude::from_degrees(90.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, -1.0, 0.0),
        DVec3::new(0.0, 0.0, -1.0),
    );
}

#[test]
fn pitch_up_30_raises_forward() {
    let (s, c) = 30f64.to_radians().sin_cos();
    assert_axes(
        Attitude::from_degrees(0.0, 30.0, 0.0),
        DVec3::new(0.0, c, s),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, s, -c),
    );
}

#[test]
fn roll_right_30_lowers_right_wing() {
    let (s, c) = 30f64.to_radians().sin_cos();
    assert_axes(
        Attitude::from_degrees(0.0, 0.0, 30.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(c, 0.0, -s),
        DVec3::new(-s, 0.0, -c),
    );
}

#[test]
fn combined_attitude_applies_heading_then_pitch_then_roll() {
    // heading 90 (east), pitch 30, roll 30, by hand: forward = (c30, 0, s30); the level
    // right wing (0,-1,0) and the pitched down axis (s30, 0, -c30) rotate about forward.
    let (s, c) = 30f64.to_radians().sin_cos();
    let fwd = DVec3::new(c, 0.0, s);
    let right0 = DVec3::new(0.0, -1.0, 0.0);
    let down0 = DVec3::new(s, 0.0, -c);
    assert_axes(
        Attitude::from_degrees(90.0, 30.0, 30.0),
        fwd,
        c * right0 + s * down0,
        c * down0 - s * right0,
    );
}

#[test]
fn gimbal_edge_cases_stay_proper_rotations() {
    for (h, p, r) in [
        (0.0, 90.0, 0.0),
        (37.0, -90.0, 12.0),
        (200.0, 90.0, 180.0),
        (10.0, 20.0, 180.0),
        (359.99, 0.0, -180.0),
    ] {
        let att = Attitude::from_degrees(h, p, r);
        let m = att.body_to_world();
        assert!((m.determinant() - 1.0).abs() < 1e-12);
        assert!((m.transpose() * m).abs_diff_eq(DMat3::IDENTITY, 1e-12));
        let (f, ri, d) = reference_axes(att.heading, att.pitch, att.roll);
        assert!(close(m.x_axis, f, 1e-12) && close(m.y_axis, ri, 1e-12));
        assert!(close(m.z_axis, d, 1e-12));
    }
    // Straight up at pitch +90 whatever the heading.
    let up = Attitude::from_degrees(123.0, 90.0, 0.0)
        .body_to_world()
        .x_axis;
    assert!(close(up, DVec3::Z, 1e-12));
}

#[test]
fn heading_wraps_continuously_through_north() {
    let a = Attitude::from_degrees(359.99, 5.0, 3.0).body_to_world();
    let b = Attitude::from_degrees(0.01, 5.0, 3.0).body_to_world();
    // 0.02° apart: chord ≈ 3.5e-4 rad.
    assert!((a.x_axis - b.x_axis).length() < 4e-4);
    assert!((a.y_axis - b.y_axis).length() < 4e-4);
    assert!((a.x_axis - b.x_axis).length() > 1e-4);
}

proptest! {
    #[test]
    fn body_to_world_is_a_rotation_matching_composed_rotations(
        h in 0.0f64..360.0,
        p in -90.0f64..=90.0,
        r in -180.0f64..=180.0,
    ) {
        let att = Attitude::from_degrees(h, p, r);
        let m = att.body_to_world();
        prop_assert!((m.determinant() - 1.0).abs() < 1e-12);
        prop_assert!((m.transpose() * m).abs_diff_eq(DMat3::IDENTITY, 1e-12));
        let (f, ri, d) = reference_axes(att.heading, att.pitch, att.roll);
        prop_assert!(close(m.x_axis, f, 1e-12));
        prop_assert!(close(m.y_axis, ri, 1e-12));
        prop_assert!(close(m.z_axis, d, 1e-12));
    }
}

#[test]
fn world_to_view_maps_body_axes_to_vulkan_axes() {
    let att = Attitude::from_degrees(47.0, -12.0, 23.0);
    let eye = DVec3::new(1.0e6, -3.0e5, 2500.0);
    let cam = Camera::new(eye, att, Frustum::symmetric(1.2, W, H));
    let (f, r, d) = reference_axes(att.heading, att.pitch, att.roll);
    let m = cam.world_to_view();
    let rot = cam.world_to_view_rotation();
    for (world_dir, view) in [(r, DVec3::X), (d, DVec3::Y), (f, DVec3::Z)] {
        assert!(close(rot * world_dir, view, 1e-12));
        let p = m.transform_point3(eye + 7.0 * world_dir);
        assert!(close(p, 7.0 * view, 1e-7), "{p:?}");
    }
    assert!(close(m.transform_point3(eye), DVec3::ZERO, 1e-9));
}

#[test]
fn frustum_symmetric_and_focal_lengths() {
    let f = Frustum::symmetric(90f64.to_radians(), W, H);
    assert!((f.tan_right - 1.0).abs() < 1e-15 && (f.tan_left + 1.0).abs() < 1e-15);
    assert!((f.tan_up - 1080.0 / 1920.0).abs() < 1e-15);
    let (fx, fy) = f.focal_px(W, H);
    // Annex I: f = w / (2 tan(γ/2)); equal horizontally and vertically for square pixels.
    assert!((fx - 960.0).abs() < 1e-9 && (fy - 960.0).abs() < 1e-9);
    // DESIGN.md: the corner of a 90° view is ~2.3× (= c²) the centre for 16:9.
    let c = f.max_obliquity();
    assert!((c * c - (2.0 + (1080.0f64 / 1920.0).powi(2))).abs() < 1e-12);
    assert!(Frustum::try_symmetric(0.0, W, H).is_err());
    assert!(Frustum::try_symmetric(std::f64::consts::PI, W, H).is_err());
    assert!(Frustum::try_symmetric(f64::NAN, W, H).is_err());
    assert!(Frustum::try_symmetric(1.0, 0, H).is_err());
}

#[test]
fn frustum_from_angles_validates() {
    let d = f64::to_radians;
    let f = Frustum::from_angles(d(-10.0), d(50.0), d(-40.0), d(5.0)).unwrap();
    assert!((f.tan_right - d(50.0).tan()).abs() < 1e-15);
    assert!((f.tan_down - d(-40.0).tan()).abs() < 1e-15);
    let want = (1.0 + d(50.0).tan().powi(2) + d(40.0).tan().powi(2)).sqrt();
    assert!((f.max_obliquity() - want).abs() < 1e-12);
    // Mirrored: the widest side is now left and up.
    let g = Frustum::from_angles(d(-50.0), d(10.0), d(-5.0), d(40.0)).unwrap();
    assert!((g.max_obliquity() - want).abs() < 1e-12);

    let bad = [
        (d(10.0), d(10.0), d(-5.0), d(5.0), "left"),
        (d(20.0), d(10.0), d(-5.0), d(5.0), "left"),
        (d(-10.0), d(10.0), d(5.0), d(5.0), "down"),
        (d(-10.0), d(10.0), d(6.0), d(5.0), "down"),
        (d(-90.0), d(10.0), d(-5.0), d(5.0), "left"),
        (d(-10.0), d(90.0), d(-5.0), d(5.0), "right"),
        (d(-10.0), d(10.0), d(-95.0), d(5.0), "down"),
        (d(-10.0), d(10.0), d(-5.0), d(90.0), "up"),
        (d(-10.0), d(10.0), d(-5.0), f64::NAN, "up"),
        (f64::NEG_INFINITY, d(10.0), d(-5.0), d(5.0), "left"),
    ];
    for (l, r, dn, u, word) in bad {
        let e = Frustum::from_angles(l, r, dn, u).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains(word), "{msg}");
        assert!(!msg.contains('\n'));
    }
}

fn cameras() -> Vec<Camera> {
    let d = f64::to_radians;
    let sym = Frustum::symmetric(d(90.0), W, H);
    let asym = Frustum::from_angles(d(-20.0), d(55.0), d(-35.0), d(10.0)).unwrap();
    let att = Attitude::from_degrees(131.0, -7.5, 14.0);
    vec![
        Camera::new(DVec3::ZERO, Attitude::from_degrees(0.0, 0.0, 0.0), sym),
        Camera::new(DVec3::new(3.0, -4.0, 900.0), att, sym),
        Camera::new(DVec3::new(-2.0e5, 7.0e5, 3000.0), att, asym),
    ]
}

/// World point at view direction (a, b, 1) scaled to view depth z, built from the
/// independently composed body axes rather than the camera's own matrices.
fn world_at(cam: &Camera, a: f64, b: f64, z: f64) -> DVec3 {
    let at = cam.attitude;
    let (f, r, d) = reference_axes(at.heading, at.pitch, at.roll);
    cam.position + z * (a * r + b * d + f)
}

#[test]
fn straight_ahead_projects_to_centre_of_symmetric_view() {
    for cam in &cameras()[..2] {
        let (px, depth) = cam
            .project_px(world_at(cam, 0.0, 0.0, 100.0), W, H)
            .unwrap();
        assert!((px - DVec2::new(960.0, 540.0)).length() < 1e-9, "{px:?}");
        assert!((depth - cam.near / 100.0).abs() < 1e-15);
    }
    // Level camera at the origin: straight ahead is simply +y (north).
    let cam = cameras()[0];
    let (px, _) = cam.project_px(DVec3::new(0.0, 50.0, 0.0), W, H).unwrap();
    assert!((px - DVec2::new(960.0, 540.0)).length() < 1e-12);
    // Up in the world is up on screen (smaller y), east is to the right.
    let (px, _) = cam.project_px(DVec3::new(5.0, 50.0, 5.0), W, H).unwrap();
    assert!(px.x > 960.0 && px.y < 540.0);
}

#[test]
fn frustum_edges_project_to_viewport_edges() {
    for cam in cameras() {
        let f = cam.frustum;
        let (w, h) = (W as f64, H as f64);
        // b = −tan_up is the top edge (view y is down).
        let cases = [
            (f.tan_left, -f.tan_up, DVec2::new(0.0, 0.0)),
            (f.tan_right, -f.tan_up, DVec2::new(w, 0.0)),
            (f.tan_left, -f.tan_down, DVec2::new(0.0, h)),
            (f.tan_right, -f.tan_down, DVec2::new(w, h)),
        ];
        for (a, b, want) in cases {
            for z in [1.0, 250.0, 40_000.0] {
                let (px, _) = cam.project_px(world_at(&cam, a, b, z), W, H).unwrap();
                assert!((px - want).length() < 1e-6, "{px:?} vs {want:?}");
            }
        }
    }
}

#[test]
fn asymmetric_frustum_puts_axis_off_centre() {
    let cam = cameras()[2];
    let f = cam.frustum;
    let (px, _) = cam
        .project_px(world_at(&cam, 0.0, 0.0, 10.0), W, H)
        .unwrap();
    let want_x = W as f64 * (-f.tan_left) / (f.tan_right - f.tan_left);
    let want_y = H as f64 * f.tan_up / (f.tan_up - f.tan_down);
    assert!((px - DVec2::new(want_x, want_y)).length() < 1e-9, "{px:?}");
}

/// What the GPU does: f64 (p − eye) rounded to f32, the f32 matrix, the divide, the viewport.
fn gpu_px(cam: &Camera, m: &Mat4, p: DVec3) -> (DVec2, f32) {
    let rel: Vec3 = (p - cam.position).as_vec3();
    let clip = *m * rel.extend(1.0);
    let ndc = clip.xyz() / clip.w;
    let x = (ndc.x + 1.0) * 0.5 * W as f32;
    let y = (ndc.y + 1.0) * 0.5 * H as f32;
    (DVec2::new(x as f64, y as f64), ndc.z)
}

#[test]
fn relative_f32_path_matches_f64_reference_far_from_origin() {
    let d = f64::to_radians;
    let frusta = [
        Frustum::symmetric(d(90.0), W, H),
        Frustum::from_angles(d(-20.0), d(55.0), d(-35.0), d(10.0)).unwrap(),
    ];
    let att = Attitude::from_degrees(211.0, -4.0, 9.0);
    let mut worst = 0.0f64;
    for offset in [0.0, 1.0e5, 1.0e6] {
        for frustum in frusta {
            let eye = DVec3::new(offset, -offset * 0.7, 1234.5);
            let cam = Camera::new(eye, att, frustum);
            let m = cam.relative_world_to_clip_f32();
            for dist in [10.0, 37.0, 300.0, 2_000.0, 15_000.0, 50_000.0] {
                for (ta, tb) in [(0.5, 0.5), (0.02, 0.03), (0.97, 0.1), (0.3, 0.95)] {
                    let f = &cam.frustum;
                    let a = f.tan_left + ta * (f.tan_right - f.tan_left);
                    let b = -f.tan_up + tb * (f.tan_up - f.tan_down);
                    let p = world_at(&cam, a, b, dist);
                    let (want, depth) = cam.project_px(p, W, H).unwrap();
                    let (got, gdepth) = gpu_px(&cam, &m, p);
                    let err = (got - want).length();
                    worst = worst.max(err);
                    assert!(err < 1e-3, "offset {offset} dist {dist}: {err} px");
                    assert!(((gdepth as f64) - depth).abs() <= 1e-6 * depth);
                }
            }
        }
    }
    assert!(worst < 0.125);
}

#[test]
fn f64_clip_matrix_agrees_with_project_px() {
    for cam in cameras() {
        let m = cam.view_to_clip() * cam.world_to_view();
        for (a, b, z) in [(0.3, -0.2, 5.0), (-0.9, 0.4, 800.0), (0.05, 0.5, 3.0e4)] {
            let p = world_at(&cam, a, b, z);
            let (want, depth) = cam.project_px(p, W, H).unwrap();
            let clip = m * p.extend(1.0);
            let ndc = clip.truncate() / clip.w;
            let got = DVec2::new(
                (ndc.x + 1.0) * 0.5 * W as f64,
                (ndc.y + 1.0) * 0.5 * H as f64,
            );
            assert!((got - want).length() < 1e-6, "{got:?} vs {want:?}");
            assert!((ndc.z - depth).abs() < 1e-9 * depth);
        }
    }
}

#[test]
fn reversed_z_depth_is_one_at_near_and_falls_to_zero() {
    let cam = cameras()[0]; // level, at the origin: forward is exactly +y.
    let (_, d_near) = cam
        .project_px(DVec3::new(0.0, cam.near, 0.0), W, H)
        .unwrap();
    assert_eq!(d_near, 1.0);
    assert!(cam
        .project_px(DVec3::new(0.0, cam.near * 0.999, 0.0), W, H)
        .is_none());
    assert!(cam.project_px(DVec3::new(0.0, -10.0, 0.0), W, H).is_none());

    let mut last = f64::INFINITY;
    for k in 0..40 {
        let dist = cam.near * 1.5f64.powi(k);
        let (_, depth) = cam.project_px(DVec3::new(0.3, dist, -0.2), W, H).unwrap();
        assert!(depth < last && depth > 0.0 && depth <= 1.0);
        last = depth;
    }
    let (_, far) = cam.project_px(DVec3::new(0.0, 1.0e12, 0.0), W, H).unwrap();
    assert!(far < 1e-12);

    // The clip matrix agrees: w = view z, z_clip = near.
    let clip = cam.view_to_clip() * DVec4::new(0.0, 0.0, cam.near, 1.0);
    assert_eq!(clip.z / clip.w, 1.0);
}

#[test]
fn reversed_z_keeps_half_metre_order_at_50_km_in_f32() {
    for offset in [0.0, 1.0e6] {
        let mut cam = cameras()[1];
        cam.position += DVec3::new(offset, offset, 0.0);
        let m = cam.relative_world_to_clip_f32();
        let near_p = world_at(&cam, 0.1, 0.05, 50_000.0);
        let far_p = world_at(&cam, 0.1, 0.05, 50_000.5);
        let (_, dn) = gpu_px(&cam, &m, near_p);
        let (_, df) = gpu_px(&cam, &m, far_p);
        assert!(dn > df, "offset {offset}: {dn} vs {df}");
    }
}

#[test]
fn pixel_ray_inverts_project_px() {
    for cam in cameras() {
        for (px, py) in [(0.5, 0.5), (960.0, 540.0), (1919.5, 3.25), (17.0, 1079.5)] {
            let ray = cam.pixel_ray(px, py, W, H);
            assert!((ray.length() - 1.0).abs() < 1e-12);
            let (got, _) = cam.project_px(cam.position + 1234.0 * ray, W, H).unwrap();
            assert!((got - DVec2::new(px, py)).length() < 1e-7, "{got:?}");
        }
        let p = world_at(&cam, 0.2, -0.1, 321.0);
        let (px, _) = cam.project_px(p, W, H).unwrap();
        let ray = cam.pixel_ray(px.x, px.y, W, H);
        assert!(close(ray, (p - cam.position).normalize(), 1e-12));
    }
}

#[test]
fn unproject_px_inverts_project_px_at_pixel_centres() {
    for cam in cameras() {
        for (px, py, dist) in [(0u32, 0u32, 5.0), (960, 540, 1234.5), (1919, 7, 80_000.0)] {
            let ray = cam.pixel_ray(f64::from(px) + 0.5, f64::from(py) + 0.5, W, H);
            let p = cam.position + dist * ray;
            let (at, depth) = cam.project_px(p, W, H).unwrap();
            assert!((at - DVec2::new(f64::from(px) + 0.5, f64::from(py) + 0.5)).length() < 1e-6);
            let back = cam.unproject_px(px, py, W, H, depth as f32).unwrap();
            // f32 depth: a relative error of 2^-24 in the range.
            assert!((back - p).length() < dist * 1e-6, "{back:?} vs {p:?}");
        }
        assert_eq!(cam.unproject_px(1, 1, W, H, 0.0), None);
        assert_eq!(cam.unproject_px(1, 1, W, H, f32::NAN), None);
        assert_eq!(cam.unproject_px(1, 1, W, H, -0.5), None);
    }
}

#[test]
fn geodetic_camera_argument_names_its_fields() {
    let g = parse_geodetic_camera_arg("47.25, 11.4,2500,90,-90,0").unwrap();
    assert_eq!((g.lat_deg, g.lon_deg, g.alt_m), (47.25, 11.4, 2500.0));
    assert_eq!(g.attitude, Attitude::from_degrees(90.0, -90.0, 0.0));
    for (bad, says) in [
        ("47,11,2500", "expected 6"),
        ("91,11,2500,0,0,0", "lat"),
        ("47,x,2500,0,0,0", "lon"),
        ("47,11,inf,0,0,0", "alt"),
        ("47,11,2500,0,NaN,0", "pitch"),
    ] {
        let e = parse_geodetic_camera_arg(bad).unwrap_err().to_string();
        assert!(e.contains(says), "{bad:?}: {e}");
    }
    // The local form keeps its own names.
    let e = parse_camera_arg("1,2").unwrap_err().to_string();
    assert!(e.contains("x,y,z,heading,pitch,roll"), "{e}");
}

proptest! {
    /// DESIGN.md's bound: a segment of length ε starting at view depth z inside the frustum
    /// projects to at most ε·f·c/(z − ε) pixels, c = max_obliquity, f = focal length.
    #[test]
    fn obliquity_bounds_projected_segment_length(
        ta in 0.0f64..=1.0, tb in 0.0f64..=1.0, z in 1.0f64..1.0e4,
        dir in prop::array::uniform3(-1.0f64..1.0), eps in 0.01f64..0.5,
        which in 0usize..3,
    ) {
        let cam = cameras()[which];
        let f = cam.frustum;
        let a = f.tan_left + ta * (f.tan_right - f.tan_left);
        let b = -f.tan_up + tb * (f.tan_up - f.tan_down);
        let p = world_at(&cam, a, b, z);
        let u = DVec3::from_array(dir);
        prop_assume!(u.length() > 1e-3);
        let q = p + eps * u.normalize();
        let (pp, _) = cam.project_px(p, W, H).unwrap();
        let Some((qp, _)) = cam.project_px(q, W, H) else { return Ok(()) };
        // Only segments inside the frustum are covered by c.
        prop_assume!(qp.x >= 0.0 && qp.x <= W as f64 && qp.y >= 0.0 && qp.y <= H as f64);
        let (fx, fy) = f.focal_px(W, H);
        let bound = eps * fx.max(fy) * f.max_obliquity() / (z - eps);
        prop_assert!((qp - pp).length() <= bound * (1.0 + 1e-9));
    }
}

#[test]
fn parse_camera_arg_accepts_good_input() {
    let (p, a) = parse_camera_arg("100.5,-2e3,1500,270,-3.5,10").unwrap();
    assert_eq!(p, DVec3::new(100.5, -2000.0, 1500.0));
    assert_eq!(a, Attitude::from_degrees(270.0, -3.5, 10.0));
    let (p, _) = parse_camera_arg(" 1, 2 ,3,0,0,0 ").unwrap();
    assert_eq!(p, DVec3::new(1.0, 2.0, 3.0));
}

#[test]
fn parse_camera_arg_errors_name_the_bad_field() {
    for (input, word) in [
        ("1,2,3", "got 3"),
        ("1,2,3,4,5,6,7", "got 7"),
        ("a,0,0,0,0,0", "field x"),
        ("nan,0,0,0,0,0", "field x"),
        ("0,0,0,inf,0,0", "field heading"),
        ("0,0,0,0,0,-infinity", "field roll"),
        ("0,0,0,0,,0", "field pitch"),
        ("0,1e999,0,0,0,0", "field y"),
    ] {
        let e = parse_camera_arg(input).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains(word), "{input}: {msg}");
        assert!(msg.contains("camera"), "{msg}");
        assert!(!msg.contains('\n'));
    }
}

#[test]
fn attitude_back_from_its_rotation_matrix() {
    let cases = [
        (10.0, 20.0, 30.0),
        (359.0, -89.0, -179.0),
        (180.0, 45.0, 90.0),
        (-30.0, 0.0, 0.0),
        (77.0, 90.0, 0.0),
        (77.0, -90.0, 0.0),
    ];
    for (h, p, r) in cases {
        let a = Attitude::from_degrees(h, p, r);
        let back = Attitude::from_body_to_world(a.body_to_world());
        let diff = (back.body_to_world() - a.body_to_world())
            .to_cols_array()
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(diff < 1e-12, "({h}, {p}, {r}) -> {back:?}: {diff}");
    }
    // At ±90° pitch the turn is all heading.
    let a = Attitude::from_degrees(20.0, 90.0, 30.0);
    let back = Attitude::from_body_to_world(a.body_to_world());
    assert_eq!(back.roll, 0.0);
    assert!(back.body_to_world().abs_diff_eq(a.body_to_world(), 1e-9));
}

#[test]
fn attitude_in_a_rotated_local_frame() {
    let a = Attitude::from_degrees(30.0, 5.0, -10.0);
    let same = a.in_frame(DMat3::IDENTITY);
    assert!(same.body_to_world().abs_diff_eq(a.body_to_world(), 1e-12));
    // A local frame tilted 10° about world east: level flight there has its down axis along
    // that frame's −up, not world −z.
    let tilt = DMat3::from_rotation_x(10f64.to_radians());
    let level = Attitude::from_degrees(90.0, 0.0, 0.0).in_frame(tilt);
    let down = level.body_to_world().z_axis;
    assert!((down + tilt.z_axis).length() < 1e-12, "{down:?}");
}
