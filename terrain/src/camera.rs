//! Camera math in f64: attitude, frusta, the reversed-Z projection and the camera-relative f32
//! matrix the GPU gets. No Vulkan here, so the error bound and its oracles can use it directly.
//!
//! Frames (DESIGN.md "Conventions"): world is local ENU (x east, y north, z up), metres. View space
//! is Vulkan-style: x right, y down, z forward, so that clip space needs no axis flip. Vulkan NDC:
//! x right, y down, depth in [0, 1].

use glam::{DMat3, DMat4, DVec2, DVec3, DVec4, Mat4};

/// Near plane distance used by [`Camera::new`], metres. Reversed-Z with an infinite far plane puts
/// almost all depth precision near the eye, so this can stay small without z-fighting far away.
pub const DEFAULT_NEAR_M: f64 = 0.5;

/// Why a camera, frustum or command-line argument was refused; one line each, naming the bad part
/// (DESIGN.md "Conventions": bad input stops with a message that names the key and the reason).
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum CameraError {
    /// A frustum that would not project (angle out of range, empty or non-finite).
    #[error("invalid frustum: {0}")]
    Frustum(String),
    /// A viewport with a zero side.
    #[error("invalid viewport {width}x{height}: both sides must be at least 1 pixel")]
    Viewport { width: u32, height: u32 },
    /// The `x,y,z,heading,pitch,roll` camera argument.
    #[error("camera argument {arg:?}: {reason}")]
    CameraArg { arg: String, reason: String },
}

/// Aircraft attitude in radians: heading ψ (clockwise from north), pitch θ (nose up +), roll φ
/// (right wing down +), applied in that order (aerospace Z-Y-X, DESIGN.md "Conventions").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Attitude {
    pub heading: f64,
    pub pitch: f64,
    pub roll: f64,
}

impl Attitude {
    /// Degrees are what config files and the wire carry; radians are what the code uses.
    pub fn from_degrees(heading: f64, pitch: f64, roll: f64) -> Self {
        Self {
            heading: heading.to_radians(),
            pitch: pitch.to_radians(),
            roll: roll.to_radians(),
        }
    }

    /// True when no angle is NaN or infinite.
    pub fn is_finite(&self) -> bool {
        self.heading.is_finite() && self.pitch.is_finite() && self.roll.is_finite()
    }

    /// Columns: the body's forward, right and down axes expressed in world ENU.
    ///
    /// This is the textbook NED direction-cosine matrix `Rz(ψ)·Ry(θ)·Rx(φ)` with its rows
    /// re-ordered into ENU (east = NED y, north = NED x, up = −NED z); that change of frame has
    /// determinant +1, so the result stays a proper rotation.
    pub fn body_to_world(&self) -> DMat3 {
        let (sp, cp) = self.heading.sin_cos();
        let (st, ct) = self.pitch.sin_cos();
        let (sr, cr) = self.roll.sin_cos();
        let forward = DVec3::new(ct * sp, ct * cp, st);
        let right = DVec3::new(sr * st * sp + cr * cp, sr * st * cp - cr * sp, -sr * ct);
        let down = DVec3::new(cr * st * sp - sr * cp, cr * st * cp + sr * sp, -cr * ct);
        DMat3::from_cols(forward, right, down)
    }

    /// The attitude whose [`Attitude::body_to_world`] is `m` (a proper rotation, columns
    /// forward, right, down). At ±90° pitch heading and roll turn about the same axis: the
    /// roll is then 0 and the heading carries the whole turn.
    pub fn from_body_to_world(m: DMat3) -> Self {
        let (f, r, d) = (m.x_axis, m.y_axis, m.z_axis);
        let pitch = f.z.clamp(-1.0, 1.0).asin();
        let ct = f.x.hypot(f.y);
        if ct < 1e-12 {
            // roll = 0: right = (cos ψ, −sin ψ, 0).
            return Self {
                heading: (-r.y).atan2(r.x),
                pitch,
                roll: 0.0,
            };
        }
        Self {
            heading: f.x.atan2(f.y),
            pitch,
            roll: (-r.z).atan2(-d.z),
        }
    }

    /// This attitude taken in a local east-north-up frame whose axes, in world coordinates,
    /// are `frame`'s columns (e.g. the ENU frame at the aircraft's own position on the
    /// ellipsoid), expressed in the world frame.
    pub fn in_frame(&self, frame: DMat3) -> Self {
        Self::from_body_to_world(frame * self.body_to_world())
    }
}

/// A frustum as tangents of the half angles (CIGI View Definition style): left < right,
/// down < up, all in tan space, so `tan_left` is negative for a symmetric frustum. Tangents make
/// asymmetric multi-channel frusta (DESIGN.md "Beyond the document": multi-channel) exact and
/// make the projection linear in them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frustum {
    pub tan_left: f64,
    pub tan_right: f64,
    pub tan_down: f64,
    pub tan_up: f64,
}

impl Frustum {
    /// Symmetric frustum from a horizontal FOV and the viewport aspect (square pixels):
    /// `tan(vfov/2) = tan(hfov/2) · h / w`, the document's γ convention (DESIGN.md Annex I notes).
    ///
    /// # Panics
    /// When `hfov_rad` is not in (0, π) or a side is 0; use [`Frustum::try_symmetric`] on user input.
    pub fn symmetric(hfov_rad: f64, width_px: u32, height_px: u32) -> Self {
        match Self::try_symmetric(hfov_rad, width_px, height_px) {
            Ok(f) => f,
            Err(e) => panic!("{e}"),
        }
    }

    /// [`Frustum::symmetric`] for untrusted input: refuses a non-finite FOV, one outside
    /// (0°, 180°), and empty viewports instead of producing NaN matrices.
    pub fn try_symmetric(
        hfov_rad: f64,
        width_px: u32,
        height_px: u32,
    ) -> Result<Self, CameraError> {
        if width_px == 0 || height_px == 0 {
            return Err(CameraError::Viewport {
                width: width_px,
                height: height_px,
            });
        }
        if !(hfov_rad.is_finite() && hfov_rad > 0.0 && hfov_rad < std::f64::consts::PI) {
            return Err(CameraError::Frustum(format!(
                "horizontal field of view {}° is not within (0°, 180°)",
                hfov_rad.to_degrees()
            )));
        }
        let th = (0.5 * hfov_rad).tan();
        let tv = th * height_px as f64 / width_px as f64;
        Ok(Self {
            tan_left: -th,
            tan_right: th,
            tan_down: -tv,
            tan_up: tv,
        })
    }

    /// From angles in radians (left and down negative for a normal frustum). Refuses
    /// non-finite angles, any |angle| ≥ 90° (the tangent blows up) and empty frusta, since
    /// those would silently draw nothing or garbage (DESIGN.md "Conventions").
    pub fn from_angles(left: f64, right: f64, down: f64, up: f64) -> Result<Self, CameraError> {
        let half_pi = std::f64::consts::FRAC_PI_2;
        for (name, v) in [("left", left), ("right", right), ("down", down), ("up", up)] {
            if !v.is_finite() || v.abs() >= half_pi {
                return Err(CameraError::Frustum(format!(
                    "{name} angle {}° is not within (-90°, 90°)",
                    v.to_degrees()
                )));
            }
        }
        if left >= right {
            return Err(CameraError::Frustum(format!(
                "left angle {}° must be less than right angle {}°",
                left.to_degrees(),
                right.to_degrees()
            )));
        }
        if down >= up {
            return Err(CameraError::Frustum(format!(
                "down angle {}° must be less than up angle {}°",
                down.to_degrees(),
                up.to_degrees()
            )));
        }
        Ok(Self {
            tan_left: left.tan(),
            tan_right: right.tan(),
            tan_down: down.tan(),
            tan_up: up.tan(),
        })
    }

    /// Largest `sqrt(1 + a² + b²)` over the frustum (a = x/z, b = y/z): the factor by which a
    /// segment off the axis projects larger than the document's centre-only formula, so the error
    /// bound stays true anywhere on screen (DESIGN.md "The terrain technique", Projection).
    /// The maximum of a convex function over the rectangle of (a, b) is at a corner.
    pub fn max_obliquity(&self) -> f64 {
        let a = self.tan_left.abs().max(self.tan_right.abs());
        let b = self.tan_down.abs().max(self.tan_up.abs());
        (1.0 + a * a + b * b).sqrt()
    }

    /// Focal lengths in pixels for a viewport: `fx = w / (tan_right − tan_left)`,
    /// `fy = h / (tan_up − tan_down)`; equal for square pixels on a symmetric frustum, the `f` of
    /// DESIGN.md's `ρ = ε·f·c / (z_min − ε)`.
    pub fn focal_px(&self, width_px: u32, height_px: u32) -> (f64, f64) {
        (
            width_px as f64 / (self.tan_right - self.tan_left),
            height_px as f64 / (self.tan_up - self.tan_down),
        )
    }
}

/// One viewpoint: f64 eye position in world ENU, attitude and frustum. Positions stay f64 so
/// that nothing jitters far from the origin (DESIGN.md "Beyond the document": Precision).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub position: DVec3,
    pub attitude: Attitude,
    pub frustum: Frustum,
    /// Near plane, metres (> 0).
    pub near: f64,
}

impl Camera {
    /// A camera with the default near plane ([`DEFAULT_NEAR_M`]).
    pub fn new(position: DVec3, attitude: Attitude, frustum: Frustum) -> Self {
        Self {
            position,
            attitude,
            frustum,
            near: DEFAULT_NEAR_M,
        }
    }

    /// Rotation world→view (no translation): rows are right, down, forward in world coordinates,
    /// i.e. the body axes re-ordered to Vulkan's x right, y down, z forward.
    pub fn world_to_view_rotation(&self) -> DMat3 {
        let b = self.attitude.body_to_world();
        DMat3::from_cols(b.y_axis, b.z_axis, b.x_axis).transpose()
    }

    /// Full world→view transform (f64), translation included. Only for f64 CPU work: the GPU
    /// gets [`Camera::relative_world_to_clip_f32`] instead, because the translation of a far-off
    /// eye does not survive f32.
    pub fn world_to_view(&self) -> DMat4 {
        let r = self.world_to_view_rotation();
        let t = -(r * self.position);
        DMat4::from_cols(
            r.x_axis.extend(0.0),
            r.y_axis.extend(0.0),
            r.z_axis.extend(0.0),
            t.extend(1.0),
        )
    }

    /// Reversed-Z, infinite far plane, Vulkan NDC (y down): view z = near maps to depth 1 and
    /// z → ∞ to depth 0, which spends f32 depth precision evenly in log distance (DESIGN.md
    /// "Beyond the document": Precision). With a = x/z, b = y/z:
    /// `x_ndc = (2a − (r + l)) / (r − l)`, `y_ndc = (2b + (u + d)) / (u − d)` so the top of the
    /// screen (b = −tan_up, view y is down) is y_ndc = −1.
    pub fn view_to_clip(&self) -> DMat4 {
        let f = &self.frustum;
        let (l, r, d, u) = (f.tan_left, f.tan_right, f.tan_down, f.tan_up);
        let sx = 2.0 / (r - l);
        let sy = 2.0 / (u - d);
        // Column-major: each argument is one column.
        DMat4::from_cols(
            DVec4::new(sx, 0.0, 0.0, 0.0),
            DVec4::new(0.0, sy, 0.0, 0.0),
            DVec4::new(-(r + l) / (r - l), (u + d) / (u - d), 0.0, 1.0),
            DVec4::new(0.0, 0.0, self.near, 0.0),
        )
    }

    /// The matrix the GPU uses: `view_to_clip · rotation` only, as f32. It is applied to
    /// camera-relative positions (world − eye) computed in f64 and then rounded to f32, so the
    /// large translation never meets f32 arithmetic (DESIGN.md "Beyond the document": Precision).
    pub fn relative_world_to_clip_f32(&self) -> Mat4 {
        (self.view_to_clip() * DMat4::from_mat3(self.world_to_view_rotation())).as_mat4()
    }

    /// f64 reference projection of a world point to pixel coordinates (origin top-left, x right,
    /// y down, pixel centres at +0.5, so the frustum edges are at 0 and w / h) and NDC depth.
    /// None when the point is nearer than the near plane (or behind the eye). This is the oracle
    /// that image-space error measurements use (DESIGN.md "What within τ means when tested").
    pub fn project_px(&self, world: DVec3, width_px: u32, height_px: u32) -> Option<(DVec2, f64)> {
        let v = self.world_to_view_rotation() * (world - self.position);
        if !(v.z >= self.near && v.z > 0.0) {
            return None;
        }
        let f = &self.frustum;
        let a = v.x / v.z;
        let b = v.y / v.z;
        let x_ndc = (2.0 * a - (f.tan_right + f.tan_left)) / (f.tan_right - f.tan_left);
        let y_ndc = (2.0 * b + (f.tan_up + f.tan_down)) / (f.tan_up - f.tan_down);
        let px = DVec2::new(
            0.5 * (x_ndc + 1.0) * width_px as f64,
            0.5 * (y_ndc + 1.0) * height_px as f64,
        );
        Some((px, self.near / v.z))
    }

    /// The world point drawn at pixel (px, py) (its centre, `+ ½`) whose read-back reversed-Z
    /// depth is `depth` (`near / view z`, as [`Camera::project_px`] returns it); `None` for
    /// sky (depth 0) or a depth that is not one.
    pub fn unproject_px(
        &self,
        px: u32,
        py: u32,
        width_px: u32,
        height_px: u32,
        depth: f32,
    ) -> Option<DVec3> {
        if !(depth > 0.0 && depth.is_finite()) {
            return None;
        }
        let z = self.near / f64::from(depth);
        let f = &self.frustum;
        let x_ndc = 2.0 * (f64::from(px) + 0.5) / f64::from(width_px) - 1.0;
        let y_ndc = 2.0 * (f64::from(py) + 0.5) / f64::from(height_px) - 1.0;
        let a = 0.5 * (x_ndc * (f.tan_right - f.tan_left) + (f.tan_right + f.tan_left));
        let b = 0.5 * (y_ndc * (f.tan_up - f.tan_down) - (f.tan_up + f.tan_down));
        Some(self.position + self.world_to_view_rotation().transpose() * DVec3::new(a, b, 1.0) * z)
    }

    /// Unit world direction through pixel (px, py), the inverse of [`Camera::project_px`]; for
    /// tests and picking.
    pub fn pixel_ray(&self, px: f64, py: f64, width_px: u32, height_px: u32) -> DVec3 {
        let f = &self.frustum;
        let x_ndc = 2.0 * px / width_px as f64 - 1.0;
        let y_ndc = 2.0 * py / height_px as f64 - 1.0;
        let a = 0.5 * (x_ndc * (f.tan_right - f.tan_left) + (f.tan_right + f.tan_left));
        let b = 0.5 * (y_ndc * (f.tan_up - f.tan_down) - (f.tan_up + f.tan_down));
        let view = DVec3::new(a, b, 1.0);
        (self.world_to_view_rotation().transpose() * view).normalize()
    }
}

/// Parses `"x,y,z,heading,pitch,roll"` (metres, degrees, as on the wire: DESIGN.md "Conventions").
/// Errors name the bad field; NaN and infinities are refused so they never reach a matrix.
pub fn parse_camera_arg(s: &str) -> Result<(DVec3, Attitude), CameraError> {
    let v = parse_six(
        s,
        ["x", "y", "z", "heading", "pitch", "roll"],
        "metres, degrees",
    )?;
    Ok((
        DVec3::new(v[0], v[1], v[2]),
        Attitude::from_degrees(v[3], v[4], v[5]),
    ))
}

/// A camera given as `"lat,lon,alt,heading,pitch,roll"`: WGS84 degrees, metres above the data's
/// vertical datum, the attitude in degrees in the north-east-down frame at that point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeodeticCamera {
    pub lat_deg: f64,
    pub lon_deg: f64,
    pub alt_m: f64,
    pub attitude: Attitude,
}

/// Parses `"lat,lon,alt,heading,pitch,roll"` (degrees, metres, degrees); latitude within
/// [−90, 90], every field finite, errors name the bad field.
pub fn parse_geodetic_camera_arg(s: &str) -> Result<GeodeticCamera, CameraError> {
    let v = parse_six(
        s,
        ["lat", "lon", "alt", "heading", "pitch", "roll"],
        "degrees, metres, degrees",
    )?;
    if !(-90.0..=90.0).contains(&v[0]) {
        return Err(CameraError::CameraArg {
            arg: s.to_string(),
            reason: format!("field lat = {} is outside [-90, 90] degrees", v[0]),
        });
    }
    Ok(GeodeticCamera {
        lat_deg: v[0],
        lon_deg: v[1],
        alt_m: v[2],
        attitude: Attitude::from_degrees(v[3], v[4], v[5]),
    })
}

/// Six comma-separated finite numbers named `fields` (`units` for the message).
fn parse_six(s: &str, fields: [&str; 6], units: &str) -> Result<[f64; 6], CameraError> {
    let err = |reason: String| CameraError::CameraArg {
        arg: s.to_string(),
        reason,
    };
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != fields.len() {
        return Err(err(format!(
            "expected 6 comma-separated values {} ({units}), got {}",
            fields.join(","),
            parts.len()
        )));
    }
    let mut v = [0.0f64; 6];
    for ((slot, name), text) in v.iter_mut().zip(fields).zip(&parts) {
        let x: f64 = text
            .parse()
            .map_err(|_| err(format!("field {name} = {text:?} is not a number")))?;
        if !x.is_finite() {
            return Err(err(format!("field {name} = {text:?} is not finite")));
        }
        *slot = x;
    }
    Ok(v)
}

#[cfg(test)]
#[path = "camera_tests.rs"]
mod tests;
