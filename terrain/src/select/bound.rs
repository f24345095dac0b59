//! The error bound: tile boxes with the curvature drop, view depths, the vertical-error gain
//! on screen and the projected error in pixels.

use glam::{DMat4, DVec2, DVec3};

use crate::camera::{Camera, Frustum};
use crate::tiles::Aabb;

/// Mean Earth radius used for the curvature drop d²/2R (DESIGN.md "Earth curvature").
pub const EARTH_RADIUS_M: f64 = 6_371_000.0;

/// Extra vertical error from drawing the curvature drop linearly between vertices: over a cell
/// of diagonal `w` the chord of d²/2R departs from it by at most w²/8R.
pub fn curvature_interpolation_error(cell_diagonal_m: f64) -> f64 {
    cell_diagonal_m * cell_diagonal_m / (8.0 * EARTH_RADIUS_M)
}

/// Box of a tile in world space, curvature drop included: the drop is d²/2R for the horizontal
/// distance d from the eye, so the box bottom moves down by the farthest corner's drop (plus the
/// interpolation slack of the coarsest cell drawn) and the top by the nearest point's.
pub fn tile_aabb(
    lo: DVec2,
    hi: DVec2,
    min_h: f32,
    max_h: f32,
    eye: DVec3,
    curvature: bool,
    cell_diagonal_m: f64,
) -> Aabb {
    let (mut zlo, mut zhi) = (min_h as f64, max_h as f64);
    if curvature {
        let e = eye.truncate();
        let nearest = e.clamp(lo, hi);
        let far = DVec2::new(
            if (e.x - lo.x).abs() > (e.x - hi.x).abs() {
                lo.x
            } else {
                hi.x
            },
            if (e.y - lo.y).abs() > (e.y - hi.y).abs() {
                lo.y
            } else {
                hi.y
            },
        );
        // d² directly: its square root squared again is d² to rounding, two roots dearer.
        let d_min2 = (nearest - e).length_squared();
        let d_max2 = (far - e).length_squared();
        zhi -= d_min2 / (2.0 * EARTH_RADIUS_M);
        zlo -= d_max2 / (2.0 * EARTH_RADIUS_M) + curvature_interpolation_error(cell_diagonal_m);
    }
    Aabb {
        min: DVec3::new(lo.x, lo.y, zlo),
        max: DVec3::new(hi.x, hi.y, zhi),
    }
}

/// The eight corners of a box in view space, coordinate by coordinate (index as in
/// [`Aabb::corners`]): the corner pass then compares and divides two lanes at a time.
#[derive(Debug, Clone, Copy)]
pub(super) struct ViewCorners {
    pub x: [f64; 8],
    pub y: [f64; 8],
    pub z: [f64; 8],
}

/// The eight corners of `aabb` in view space (`m`: world → view), each bit for bit
/// `m.transform_point3(corner)`: the same products summed in the same order,
/// `w + (z·Z + (y·Y + x·X))`, with the six products shared between the corners instead of
/// formed eight times.
pub(super) fn view_corners(m: &DMat4, aabb: &Aabb) -> ViewCorners {
    let (a, b) = (aabb.min, aabb.max);
    let x = [m.x_axis.truncate() * a.x, m.x_axis.truncate() * b.x];
    let y = [m.y_axis.truncate() * a.y, m.y_axis.truncate() * b.y];
    let z = [m.z_axis.truncate() * a.z, m.z_axis.truncate() * b.z];
    let w = m.w_axis.truncate();
    let mut c = ViewCorners {
        x: [0.0; 8],
        y: [0.0; 8],
        z: [0.0; 8],
    };
    for i in 0..8 {
        let p = w + (z[i >> 2] + (y[(i >> 1) & 1] + x[i & 1]));
        (c.x[i], c.y[i], c.z[i]) = (p.x, p.y, p.z);
    }
    c
}

/// Smallest view depth of `aabb`'s corners (`m`: world → view), unclamped: bit for bit the
/// smallest `z` of [`view_corners`] — each product's smaller end summed in the same order, and
/// rounding is monotonic — without forming the corners.
pub(super) fn min_view_depth_of(m: &DMat4, aabb: &Aabb) -> f64 {
    let (a, b) = (aabb.min, aabb.max);
    let x = (m.x_axis.z * a.x).min(m.x_axis.z * b.x);
    let y = (m.y_axis.z * a.y).min(m.y_axis.z * b.y);
    let z = (m.z_axis.z * a.z).min(m.z_axis.z * b.z);
    m.w_axis.z + (z + (y + x))
}

/// Smallest view depth of a box (view depth is linear, so a corner attains it), clamped to the
/// near plane.
pub fn min_view_depth(camera: &Camera, aabb: &Aabb) -> f64 {
    let m = camera.world_to_view();
    min_depth_of(&aabb.corners().map(|c| m.transform_point3(c)), camera.near)
}

/// [`min_view_depth`] of corners already in view space.
pub(super) fn min_depth_of(corners: &[DVec3; 8], near: f64) -> f64 {
    corners
        .iter()
        .map(|c| c.z)
        .fold(f64::INFINITY, f64::min)
        .max(near)
}

/// [`crate::tiles::outside_frustum`] of corners already in view space.
pub(super) fn outside_of(corners: &[DVec3; 8], f: &Frustum, near: f64) -> bool {
    let all = |outside: &dyn Fn(&DVec3) -> bool| corners.iter().all(outside);
    all(&|p| p.z < near)
        || all(&|p| p.x > f.tan_right * p.z)
        || all(&|p| p.x < f.tan_left * p.z)
        || all(&|p| -p.y > f.tan_up * p.z)
        || all(&|p| -p.y < f.tan_down * p.z)
}

/// Whether no corner (view space) is outside any plane of the frustum — outside by
/// [`outside_of`]'s tests —: no part of the box can be culled. The reference evaluation's
/// (tests); the fast path's is `CornerPass::inside`, from the same comparisons as its cull.
#[cfg(test)]
pub(super) fn inside_of(corners: &[DVec3; 8], f: &Frustum, near: f64) -> bool {
    !corners.iter().any(|p| {
        p.z < near
            || p.x > f.tan_right * p.z
            || p.x < f.tan_left * p.z
            || -p.y > f.tan_up * p.z
            || -p.y < f.tan_down * p.z
    })
}

/// The screen factor of a *vertical* error over the part of a box inside the frustum — the `c`
/// of DESIGN.md's `ρ = ε·f·c / (z_min − ε)`, tightened for the direction terrain errors have.
///
/// A point p (view coordinates, a = x/z, b = y/z) displaced by ε' along the world vertical
/// (unit w in view space, |ε'| ≤ ε) moves on screen by exactly
/// `f·|ε'|·|(w_x − a·w_z, w_y − b·w_z)| / (z + ε'·w_z) ≤ f·ε·g / (z_min − ε)`
/// with `g = max |(w_x − a·w_z, w_y − b·w_z)|` over the (a, b) the box shows. Both squared
/// components are convex in one variable each, so their maxima over the box's (a, b) ranges —
/// the corners' ranges clamped to the frustum, a rectangle holding everything visible of the box
/// — are at range ends. `g ≤ sqrt(1 + a² + b²)` (the largest singular value of
/// [[1, 0, −a], [0, 1, −b]]), the direction-free obliquity, which looking level at 90° × 59°
/// overstates the vertical error's projection by up to 1.52×. A corner at or behind the eye
/// plane falls back to the whole frustum's ranges.
pub fn box_vertical_gain(camera: &Camera, aabb: &Aabb) -> f64 {
    let m = camera.world_to_view();
    let w = camera.world_to_view_rotation() * DVec3::Z;
    vertical_gain_of(
        &aabb.corners().map(|c| m.transform_point3(c)),
        &camera.frustum,
        w,
    )
}

/// [`box_vertical_gain`] of corners already in view space; `w` is the world vertical there.
pub(super) fn vertical_gain_of(corners: &[DVec3; 8], f: &Frustum, w: DVec3) -> f64 {
    let (mut a_lo, mut a_hi, mut b_lo, mut b_hi) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for v in corners {
        if v.z <= 1e-9 {
            return vertical_gain(w, [f.tan_left, f.tan_right], [-f.tan_up, -f.tan_down]);
        }
        let r = 1.0 / v.z;
        let (a, b) = (v.x * r, v.y * r);
        (a_lo, a_hi) = (a_lo.min(a), a_hi.max(a));
        (b_lo, b_hi) = (b_lo.min(b), b_hi.max(b));
    }
    // View y is down: b = y/z lies in [−tan_up, −tan_down].
    let a = [a_lo, a_hi].map(|a| a.clamp(f.tan_left, f.tan_right));
    let b = [b_lo, b_hi].map(|b| b.clamp(-f.tan_up, -f.tan_down));
    vertical_gain(w, a, b)
}

/// [`box_vertical_gain`] over the whole frustum (for boxes not culled against it).
pub fn frustum_vertical_gain(camera: &Camera) -> f64 {
    let f = camera.frustum;
    let w = camera.world_to_view_rotation() * DVec3::Z;
    vertical_gain(w, [f.tan_left, f.tan_right], [-f.tan_up, -f.tan_down])
}

/// The gain of a node on the ellipsoid (corners in view space): its error is ε along normals
/// that turn by up to `spread` from `up` (the centre's, in view space), plus an interpolation
/// slack in any direction. Writing each normal as up + δ with |δ| ≤ spread, the screen motion
/// of ε·n is at most ε·(g(up) + spread·c) with c = max sqrt(1 + a² + b²), the direction-free
/// factor; the slack s adds s·c. So the gain is `g(up) + c·slack` with slack = spread + s/ε.
/// (The reference of [`CornerPass::gain_parts`] and `evaluate_as`'s gain: tests only.)
#[cfg(test)]
pub(super) fn spread_gain_of(corners: &[DVec3; 8], f: &Frustum, up: DVec3, slack: f64) -> f64 {
    let g = vertical_gain_of(corners, f, up);
    if slack <= 0.0 {
        return g;
    }
    g + slack * obliquity_of(corners, f)
}

/// [`spread_gain_of`] over the whole frustum (boxes not culled against it).
pub(super) fn frustum_spread_gain(f: &Frustum, up: DVec3, slack: f64) -> f64 {
    vertical_gain(up, [f.tan_left, f.tan_right], [-f.tan_up, -f.tan_down])
        + slack.max(0.0) * f.max_obliquity()
}

/// Largest sqrt(1 + a² + b²) over the (a, b) a box shows, clamped to the frustum (the whole
/// frustum's when a corner is at or behind the eye plane). Convex: attained at range ends.
#[cfg(test)]
pub(super) fn obliquity_of(corners: &[DVec3; 8], f: &Frustum) -> f64 {
    let (mut a_max, mut b_max) = (0.0f64, 0.0f64);
    for v in corners {
        if v.z <= 1e-9 {
            return f.max_obliquity();
        }
        let r = 1.0 / v.z;
        let a = (v.x * r).clamp(f.tan_left, f.tan_right);
        let b = (v.y * r).clamp(-f.tan_up, -f.tan_down);
        (a_max, b_max) = (a_max.max(a.abs()), b_max.max(b.abs()));
    }
    (1.0 + a_max * a_max + b_max * b_max).sqrt()
}

/// The least vertical gain anywhere in the frustum: no box's gain ([`vertical_gain_of`], its
/// ranges clamped to the frustum or the whole frustum's) is below it. Each squared component
/// is least where its own variable comes nearest to making it vanish.
pub(super) fn frustum_gain_floor(f: &Frustum, w: DVec3) -> f64 {
    gain_floor_over(w, [f.tan_left, f.tan_right], [-f.tan_up, -f.tan_down])
}

/// The least vertical gain over the view ratios a ∈ `a`, b ∈ `b` (ranges within the frustum's):
/// no box whose clamped ranges lie within them has a smaller gain ([`vertical_gain`] is the
/// largest over a box's ranges, at least its value at any point of them).
pub(super) fn gain_floor_over(w: DVec3, a: [f64; 2], b: [f64; 2]) -> f64 {
    let least = |wc: f64, lo: f64, hi: f64| {
        let t = if w.z != 0.0 {
            (wc / w.z).clamp(lo, hi)
        } else {
            lo
        };
        (wc - t * w.z).powi(2)
    };
    (least(w.x, a[0], a[1]) + least(w.y, b[0], b[1])).sqrt()
}

/// The (a, b) ranges of view-space corners clamped to the frustum, the ranges every box within
/// theirs is clamped into; the frustum's own when a corner is at or behind the eye plane (the
/// gains then take the whole frustum's, as [`CornerPass::vertical_gain`] does).
pub(super) fn clamped_ranges(c: &ViewCorners, f: &Frustum) -> ([f64; 2], [f64; 2]) {
    let whole = ([f.tan_left, f.tan_right], [-f.tan_up, -f.tan_down]);
    if c.z.iter().any(|&z| z <= 1e-9) {
        return whole;
    }
    let (mut a, mut b) = (
        [f64::INFINITY, f64::NEG_INFINITY],
        [f64::INFINITY, f64::NEG_INFINITY],
    );
    for i in 0..8 {
        let r = 1.0 / c.z[i];
        let (ai, bi) = (c.x[i] * r, c.y[i] * r);
        (a[0], a[1]) = (a[0].min(ai), a[1].max(ai));
        (b[0], b[1]) = (b[0].min(bi), b[1].max(bi));
    }
    (
        a.map(|v| v.clamp(whole.0[0], whole.0[1])),
        b.map(|v| v.clamp(whole.1[0], whole.1[1])),
    )
}

fn vertical_gain(w: DVec3, a: [f64; 2], b: [f64; 2]) -> f64 {
    let gx = a.map(|a| (w.x - a * w.z).powi(2));
    let gy = b.map(|b| (w.y - b * w.z).powi(2));
    (gx[0].max(gx[1]) + gy[0].max(gy[1])).sqrt()
}

/// The projected-error bound in pixels of a vertical error `eps` anywhere in a box whose
/// smallest view depth is `z_min` (DESIGN.md: ρ = ε·f·c / (z_min − ε)).
pub fn projected_error_px(eps: f64, z_min: f64, focal_px: f64, obliquity: f64) -> f64 {
    if eps <= 0.0 {
        return 0.0;
    }
    let z = z_min - eps;
    if z <= 0.0 {
        f64::INFINITY
    } else {
        eps * focal_px * obliquity / z
    }
}

/// One pass over a box's view-space corners giving everything the bound needs of them: the
/// frustum cull ([`outside_of`]), the smallest depth ([`min_depth_of`]) and the (a, b) ranges
/// of [`vertical_gain_of`] and [`obliquity_of`] — the same comparisons and divisions in the
/// same order, so the same values bit for bit, with the corners read once instead of four times.
#[derive(Debug, Clone, Copy)]
pub(super) struct CornerPass {
    /// Every corner outside one frustum plane: the box is culled.
    pub outside: bool,
    /// Every corner inside every frustum plane: no part of the box can be culled.
    pub inside: bool,
    /// Smallest view depth of a corner, not clamped.
    pub z_min: f64,
    /// A corner at or behind the eye plane: the gains take the whole frustum's ranges.
    behind: bool,
    /// a = x/z and b = y/z ranges over the corners (when none is behind).
    a: [f64; 2],
    b: [f64; 2],
}

impl CornerPass {
    /// The pass. The (a, b) ranges — eight divisions — are formed only for a box inside the
    /// frustum with every corner in front of the eye: a culled box's gains are never read, and
    /// with a corner behind the gains take the whole frustum's ranges.
    pub(super) fn of(c: &ViewCorners, f: &Frustum, near: f64) -> Self {
        Self::cull_and_depth(c, f, near).with_ranges(c)
    }

    /// The pass's first half: the cull, the smallest depth and whether a corner is behind the
    /// eye, without the (a, b) ranges ([`Self::with_ranges`] forms them).
    pub(super) fn cull_and_depth(c: &ViewCorners, f: &Frustum, near: f64) -> Self {
        let mut z_min = f64::INFINITY;
        // Per plane: every corner outside it (the cull) and some corner outside it (a box
        // with none is inside), from one comparison per corner and plane.
        let [mut n, mut r, mut l, mut u, mut d] = [true; 5];
        let mut some_out = false;
        let mut behind = false;
        for i in 0..8 {
            let (x, y, z) = (c.x[i], c.y[i], c.z[i]);
            z_min = z_min.min(z);
            let out = [
                z < near,
                x > f.tan_right * z,
                x < f.tan_left * z,
                -y > f.tan_up * z,
                -y < f.tan_down * z,
            ];
            n &= out[0];
            r &= out[1];
            l &= out[2];
            u &= out[3];
            d &= out[4];
            some_out |= out[0] | out[1] | out[2] | out[3] | out[4];
            behind |= z <= 1e-9;
        }
        Self {
            outside: n || r || l || u || d,
            inside: !some_out,
            z_min,
            behind,
            a: [f64::INFINITY, f64::NEG_INFINITY],
            b: [f64::INFINITY, f64::NEG_INFINITY],
        }
    }

    /// The pass's second half: the (a, b) ranges of the same corners, for a box kept with
    /// every corner in front (else left empty, as [`Self::of`] says).
    pub(super) fn with_ranges(mut self, c: &ViewCorners) -> Self {
        if !self.outside && !self.behind {
            // One division per corner (a = x·(1/z), b = y·(1/z)), as the reference forms them.
            let r: [f64; 8] = std::array::from_fn(|i| 1.0 / c.z[i]);
            let a: [f64; 8] = std::array::from_fn(|i| c.x[i] * r[i]);
            let b: [f64; 8] = std::array::from_fn(|i| c.y[i] * r[i]);
            for i in 0..8 {
                (self.a[0], self.a[1]) = (self.a[0].min(a[i]), self.a[1].max(a[i]));
                (self.b[0], self.b[1]) = (self.b[0].min(b[i]), self.b[1].max(b[i]));
            }
        }
        self
    }

    /// [`vertical_gain_of`] of the corners; `w` is the world vertical in view space.
    pub(super) fn vertical_gain(&self, f: &Frustum, w: DVec3) -> f64 {
        if self.behind {
            return vertical_gain(w, [f.tan_left, f.tan_right], [-f.tan_up, -f.tan_down]);
        }
        let a = self.a.map(|a| a.clamp(f.tan_left, f.tan_right));
        let b = self.b.map(|b| b.clamp(-f.tan_up, -f.tan_down));
        vertical_gain(w, a, b)
    }

    /// The two parts of [`spread_gain_of`] of the corners: the vertical gain along `up` and
    /// the obliquity that multiplies the slack (`g` for no slack, `g + slack·c` else). The
    /// largest |a| over the corners, each clamped, is the larger of the clamped range ends'
    /// (clamping is monotonic): the same values.
    pub(super) fn gain_parts(&self, f: &Frustum, up: DVec3) -> (f64, f64) {
        (self.vertical_gain(f, up), self.obliquity(f))
    }

    /// Largest sqrt(1 + a² + b²) over the corners, each clamped to the frustum (the whole
    /// frustum's when a corner is at or behind the eye plane).
    fn obliquity(&self, f: &Frustum) -> f64 {
        if self.behind {
            return f.max_obliquity();
        }
        let a = self.a.map(|a| a.clamp(f.tan_left, f.tan_right).abs());
        let b = self.b.map(|b| b.clamp(-f.tan_up, -f.tan_down).abs());
        let (a_max, b_max) = (0f64.max(a[0]).max(a[1]), 0f64.max(b[0]).max(b[1]));
        (1.0 + a_max * a_max + b_max * b_max).sqrt()
    }
}
