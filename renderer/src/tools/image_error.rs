//! Image-space error of a rendered frame, measured against the full-resolution terrain
//! (DESIGN.md "What within τ means when tested"; seed 003's depth-buffer idea).
//!
//! For every pixel of a frame's read-back depth (reversed-Z, `depth = near / view_z`, 0 = sky)
//! the drawn world point is reconstructed: `view_z = near / depth` along the pixel centre's view
//! direction. The full-resolution surface point *under* it — same (x, y), height of the true
//! piecewise-linear surface (full-resolution samples, the SW–NE diagonal of
//! [`quad_surface`], each vertex lowered by the curvature drop d²/2R exactly as the renderer
//! does, [`EARTH_RADIUS_M`]) — and the drawn point are both projected with the frame's camera;
//! the distance between the two in pixels is that pixel's error. Geographic data is drawn on the
//! WGS84 ellipsoid: there "under" is along the normal, the true point at its exact position. Silhouettes are covered by
//! it: where the drawn ridge is lower than the true one, the drawn crest pixels measure how far
//! the true crest is above them. A pixel that is sky in the frame but terrain in a reference
//! frame (the same camera drawn with `LodMode::Full`) is a *hole*; holes are counted, with the
//! distance along their column to the frame's nearest terrain pixel (an upper bound, in whole
//! pixels, of the silhouette's displacement there), but kept out of the error distribution: a
//! silhouette moved by 0.2 px flips whole pixels, and a crack shows up in the count.
//!
//! Lone pixels that disagree with all their neighbours are the rasteriser's doing (see
//! [`ImageError::confirmed`]): besides the raw distribution, each error capped by its largest
//! neighbour's is kept as the *confirmed* one.
//!
//! This runs on the CPU from the depth the renderer reads back (all cores, ~50 ms for 1280×720);
//! a GPU compute pass over the depth attachment would avoid the read-back and is future work.
//!
//! [`oracle_selection`] is a second, independent number: the brute-force error of the nodes a
//! selection draws, sample by sample against the node's own level surface (the CPU oracle of
//! `tests/tests/bound_oracle.rs`), on a subsample of the nodes and of their samples.

use glam::{DMat3, DVec2, DVec3};

use aerie_terrain::camera::Camera;
use aerie_terrain::dataset::Dataset;
use aerie_terrain::geodesy::GeoGrid;

pub use crate::tools::heatmap::heatmap_rgba;
use aerie_terrain::mesh::quad_surface;
use aerie_terrain::select::{DrawItem, EARTH_RADIUS_M};

/// Linear bins of 1/256 px up to this many pixels, then logarithmic bins.
const LINEAR_MAX_PX: f64 = 16.0;
const LINEAR_BINS_PER_PX: f64 = 256.0;
/// Logarithmic bins: each 1 % wider than the previous, up to 10⁶ px (the last bin takes more).
const LOG_RATIO: f64 = 1.01;
const LOG_BINS: usize = 1112;

/// Distribution of per-pixel errors: exact count, sum and maximum; quantiles to within a bin
/// (1/256 px below 16 px, 1 % above).
#[derive(Clone, PartialEq)]
pub struct ErrorHistogram {
    bins: Vec<u64>,
    count: u64,
    sum: f64,
    max: f64,
}

impl std::fmt::Debug for ErrorHistogram {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ErrorHistogram")
            .field("count", &self.count)
            .field("mean", &self.mean())
            .field("p50", &self.quantile(0.5))
            .field("p99", &self.quantile(0.99))
            .field("max", &self.max)
            .finish()
    }
}

impl Default for ErrorHistogram {
    fn default() -> Self {
        Self::new()
    }
}

impl ErrorHistogram {
    pub fn new() -> Self {
        let linear = (LINEAR_MAX_PX * LINEAR_BINS_PER_PX) as usize;
        Self {
            bins: vec![0; linear + LOG_BINS],
            count: 0,
            sum: 0.0,
            max: 0.0,
        }
    }

    fn bin(e: f64) -> usize {
        let linear = (LINEAR_MAX_PX * LINEAR_BINS_PER_PX) as usize;
        if e < LINEAR_MAX_PX {
            ((e * LINEAR_BINS_PER_PX) as usize).min(linear - 1)
        } else {
            let k = ((e / LINEAR_MAX_PX).ln() / LOG_RATIO.ln()) as usize;
            linear + k.min(LOG_BINS - 1)
        }
    }

    /// Upper edge of bin `i`.
    fn upper(i: usize) -> f64 {
        let linear = (LINEAR_MAX_PX * LINEAR_BINS_PER_PX) as usize;
        if i < linear {
            (i + 1) as f64 / LINEAR_BINS_PER_PX
        } else {
            LINEAR_MAX_PX * LOG_RATIO.powi((i - linear + 1) as i32)
        }
    }

    /// Adds one error (pixels, ≥ 0; NaN counts as +∞ so it cannot hide).
    pub fn add(&mut self, e: f64) {
        let e = if e.is_nan() {
            f64::INFINITY
        } else {
            e.max(0.0)
        };
        self.bins[Self::bin(e)] += 1;
        self.count += 1;
        self.sum += e;
        self.max = self.max.max(e);
    }

    pub fn merge(&mut self, other: &Self) {
        for (a, b) in self.bins.iter_mut().zip(&other.bins) {
            *a += b;
        }
        self.count += other.count;
        self.sum += other.sum;
        self.max = self.max.max(other.max);
    }

    pub fn count(&self) -> u64 {
        self.count
    }

    /// Exact largest error (0 when empty).
    pub fn max(&self) -> f64 {
        self.max
    }

    /// Exact mean (0 when empty).
    pub fn mean(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            self.sum / self.count as f64
        }
    }

    /// The `p`-quantile (0 ≤ p ≤ 1), rounded up to its bin's upper edge and never above the
    /// exact maximum (0 when empty).
    pub fn quantile(&self, p: f64) -> f64 {
        if self.count == 0 {
            return 0.0;
        }
        let rank = ((p.clamp(0.0, 1.0) * self.count as f64).ceil() as u64).max(1);
        let mut seen = 0;
        for (i, &n) in self.bins.iter().enumerate() {
            seen += n;
            if seen >= rank {
                return Self::upper(i).min(self.max);
            }
        }
        self.max
    }
}

/// What [`measure`] found in one frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ImageError {
    /// Errors of the measured pixels (the frame's terrain pixels).
    pub hist: ErrorHistogram,
    /// τ the `over_tau` count was made against.
    pub tau_px: f64,
    /// Measured pixels above τ.
    pub over_tau: u64,
    /// Terrain pixels of the frame (depth > 0).
    pub terrain_px: u64,
    /// Sky in the frame, terrain in the reference (0 without a reference).
    pub holes_px: u64,
    /// Terrain in the frame, sky in the reference (measured like any terrain pixel).
    pub extra_px: u64,
    /// Terrain pixels whose point falls outside the dataset's real samples (not measured).
    pub off_dataset_px: u64,
    /// Terrain pixels whose surface point is behind the near plane (not measured).
    pub unprojectable_px: u64,
    /// Largest column distance (px) from a hole to the frame's nearest terrain pixel: an upper
    /// bound of how far the drawn silhouette is from the true one there.
    pub hole_max_px: f64,
    /// Pixel (x, y) of the largest error.
    pub max_at: Option<(u32, u32)>,
    /// The same pixels' errors, each capped by the largest error among its measured
    /// 8-neighbours: an error counts at the level a neighbour confirms. A lone pixel off by more
    /// than its neighbours is the rasteriser's, not the terrain's: the coverage of a sub-pixel
    /// triangle seen edge-on at the horizon is decided on snapped vertex positions, and its
    /// plane's depth then belongs to a point tens of metres outside it (`full` frames show
    /// such lone pixels of 1–4 px at 1280×720 while drawing the true surface). Terrain features
    /// narrower than a pixel (a lone needle far away) would be capped too: the CPU oracle of the
    /// selection checks every sample of the nodes it picks.
    pub confirmed: ErrorHistogram,
    /// Confirmed errors above τ.
    pub confirmed_over_tau: u64,
    /// Pixel (x, y) of the largest confirmed error.
    pub confirmed_max_at: Option<(u32, u32)>,
}

impl ImageError {
    pub fn max_px(&self) -> f64 {
        self.hist.max()
    }

    pub fn p99_px(&self) -> f64 {
        self.hist.quantile(0.99)
    }

    pub fn mean_px(&self) -> f64 {
        self.hist.mean()
    }

    /// Fraction of the measured pixels above τ.
    pub fn fraction_over_tau(&self) -> f64 {
        if self.hist.count() == 0 {
            0.0
        } else {
            self.over_tau as f64 / self.hist.count() as f64
        }
    }

    /// Accumulates another frame (or part of one) measured against the same τ.
    /// Largest confirmed error (see [`ImageError::confirmed`]).
    pub fn confirmed_max_px(&self) -> f64 {
        self.confirmed.max()
    }

    pub fn merge(&mut self, o: &ImageError) {
        if o.hist.max() > self.hist.max() || self.max_at.is_none() {
            self.max_at = o.max_at.or(self.max_at);
        }
        if o.confirmed.max() > self.confirmed.max() || self.confirmed_max_at.is_none() {
            self.confirmed_max_at = o.confirmed_max_at.or(self.confirmed_max_at);
        }
        self.confirmed.merge(&o.confirmed);
        self.confirmed_over_tau += o.confirmed_over_tau;
        self.hole_max_px = self.hole_max_px.max(o.hole_max_px);
        self.hist.merge(&o.hist);
        self.over_tau += o.over_tau;
        self.terrain_px += o.terrain_px;
        self.holes_px += o.holes_px;
        self.extra_px += o.extra_px;
        self.off_dataset_px += o.off_dataset_px;
        self.unprojectable_px += o.unprojectable_px;
    }
}

/// How [`measure`] treats a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasureParams {
    /// Pixels above this are counted in [`ImageError::over_tau`].
    pub tau_px: f64,
    /// The frame was drawn with the curvature drop (`SelectParams::curvature`).
    pub curvature: bool,
    /// A hole's distance to the frame's terrain is searched this far along its column (a hole
    /// with no terrain pixel within it gets this value).
    pub hole_search_px: u32,
}

impl Default for MeasureParams {
    fn default() -> Self {
        Self {
            tau_px: 1.0,
            curvature: true,
            hole_search_px: 64,
        }
    }
}

/// The true full-resolution surface of a dataset as the renderer's `full` mode draws it:
/// piecewise linear over the samples with the SW–NE diagonal, each vertex lowered by the
/// curvature drop for the given eye — or, for geographic data, each sample at its exact place
/// on the WGS84 ellipsoid (`GeoGrid`), as the renderer draws those.
#[derive(Debug, Clone, Copy)]
pub struct TrueSurface<'a> {
    ds: &'a Dataset,
    eye: DVec3,
    curvature: bool,
    earth: Option<GeoGrid>,
}

impl<'a> TrueSurface<'a> {
    pub fn new(ds: &'a Dataset, eye: DVec3, curvature: bool) -> Self {
        let hf = &ds.hf;
        let earth = GeoGrid::of(hf.geo.as_ref(), hf.spacing_x, hf.spacing_y);
        Self {
            ds,
            eye,
            curvature: curvature && earth.is_none(),
            earth,
        }
    }

    /// World position of sample (col, row) as drawn at full resolution.
    pub fn sample_point(&self, col: usize, row: usize) -> DVec3 {
        let hf = &self.ds.hf;
        let g = DVec2::new(col as f64 * hf.spacing_x, row as f64 * hf.spacing_y);
        match &self.earth {
            Some(e) => e.world_of_grid(g, hf.at(col, row) as f64),
            None => g.extend(self.vertex(col, row)),
        }
    }

    /// The true surface point under the world point `p` (along the vertical, or the normal on
    /// the ellipsoid), None off the real samples.
    pub fn point_under(&self, p: DVec3) -> Option<DVec3> {
        match &self.earth {
            None => self.height_at(p.x, p.y).map(|h| DVec3::new(p.x, p.y, h)),
            Some(e) => {
                let g = e.grid_of_world(p);
                let h = self.height_at(g.x, g.y)?;
                Some(e.world_of_grid(g.truncate(), h))
            }
        }
    }

    /// Curvature drop at world (x, y) for this eye (0 when curvature is off).
    #[inline]
    pub fn drop_at(&self, x: f64, y: f64) -> f64 {
        if self.curvature {
            (DVec2::new(x, y) - self.eye.truncate()).length_squared() / (2.0 * EARTH_RADIUS_M)
        } else {
            0.0
        }
    }

    /// Height of vertex (col, row) as drawn (sample minus its curvature drop).
    #[inline]
    pub fn vertex(&self, col: usize, row: usize) -> f64 {
        let hf = &self.ds.hf;
        let (x, y) = (col as f64 * hf.spacing_x, row as f64 * hf.spacing_y);
        hf.at(col, row) as f64 - self.drop_at(x, y)
    }

    /// Surface height at world (x, y), or None outside the real samples (a tolerance of 1 mm
    /// keeps points on the last row or column in).
    pub fn height_at(&self, x: f64, y: f64) -> Option<f64> {
        let hf = &self.ds.hf;
        let (vw, vh) = (self.ds.valid_width, self.ds.valid_height);
        let u = x / hf.spacing_x;
        let v = y / hf.spacing_y;
        let (tol_u, tol_v) = (1e-3 / hf.spacing_x, 1e-3 / hf.spacing_y);
        let (max_u, max_v) = ((vw - 1) as f64, (vh - 1) as f64);
        if !(u >= -tol_u && v >= -tol_v && u <= max_u + tol_u && v <= max_v + tol_v) {
            return None;
        }
        let (u, v) = (u.clamp(0.0, max_u), v.clamp(0.0, max_v));
        let c = (u.floor() as usize).min(vw.saturating_sub(2));
        let r = (v.floor() as usize).min(vh.saturating_sub(2));
        let (c1, r1) = ((c + 1).min(hf.width - 1), (r + 1).min(hf.height - 1));
        Some(quad_surface(
            self.vertex(c, r),
            self.vertex(c1, r),
            self.vertex(c, r1),
            self.vertex(c1, r1),
            u - c as f64,
            v - r as f64,
        ))
    }
}

/// The camera's projection with its rotation precomputed ([`Camera::project_px`] recomputes
/// it per call); same arithmetic otherwise.
#[derive(Debug, Clone, Copy)]
struct Projector {
    eye: DVec3,
    rot: DMat3,
    near: f64,
    l: f64,
    r: f64,
    d: f64,
    u: f64,
    w: f64,
    h: f64,
}

impl Projector {
    fn new(camera: &Camera, w: u32, h: u32) -> Self {
        let f = camera.frustum;
        Self {
            eye: camera.position,
            rot: camera.world_to_view_rotation(),
            near: camera.near,
            l: f.tan_left,
            r: f.tan_right,
            d: f.tan_down,
            u: f.tan_up,
            w: w as f64,
            h: h as f64,
        }
    }

    #[inline]
    fn project(&self, p: DVec3) -> Option<DVec2> {
        let v = self.rot * (p - self.eye);
        if !(v.z >= self.near && v.z > 0.0) {
            return None;
        }
        let (a, b) = (v.x / v.z, v.y / v.z);
        let x_ndc = (2.0 * a - (self.r + self.l)) / (self.r - self.l);
        let y_ndc = (2.0 * b + (self.u + self.d)) / (self.u - self.d);
        Some(DVec2::new(
            0.5 * (x_ndc + 1.0) * self.w,
            0.5 * (y_ndc + 1.0) * self.h,
        ))
    }

    /// World point drawn at pixel centre (px + ½, py + ½) at view depth `z`.
    #[inline]
    fn unproject(&self, px: u32, py: u32, z: f64) -> DVec3 {
        let a = self.l + (px as f64 + 0.5) / self.w * (self.r - self.l);
        let b = (py as f64 + 0.5) / self.h * (self.u - self.d) - self.u;
        self.eye + self.rot.transpose() * DVec3::new(a * z, b * z, z)
    }
}

/// Measures one frame (see the module documentation). `depth` is the frame's read-back depth
/// (`width × height`, rows top to bottom), `reference` the same camera's depth drawn with
/// `LodMode::Full` (for holes), `heat` receives each pixel's error (NaN for sky and unmeasured
/// pixels, −1 for holes). Runs on all cores.
pub fn measure(
    ds: &Dataset,
    camera: &Camera,
    size: (u32, u32),
    depth: &[f32],
    reference: Option<&[f32]>,
    params: &MeasureParams,
    heat: Option<&mut [f32]>,
) -> ImageError {
    let (w, h) = size;
    let n = w as usize * h as usize;
    assert_eq!(depth.len(), n, "depth buffer is not {w}×{h}");
    if let Some(r) = reference {
        assert_eq!(r.len(), n, "reference depth is not {w}×{h}");
    }
    let mut own = Vec::new();
    let heat: &mut [f32] = match heat {
        Some(s) => {
            assert_eq!(s.len(), n, "heat buffer is not {w}×{h}");
            s
        }
        None => {
            own.resize(n, 0.0);
            &mut own
        }
    };
    let threads = std::thread::available_parallelism()
        .map(|t| t.get())
        .unwrap_or(1)
        .clamp(1, 32);
    let rows_per = (h as usize).div_ceil(threads).max(1);
    let proj = Projector::new(camera, w, h);
    let surface = TrueSurface::new(ds, camera.position, params.curvature);
    let mut parts: Vec<ImageError> = Vec::new();
    std::thread::scope(|s| {
        let mut handles = Vec::new();
        let mut heat_rest: &mut [f32] = &mut *heat;
        for start in (0..h as usize).step_by(rows_per) {
            let rows = rows_per.min(h as usize - start);
            let (heat_rows, rest) = std::mem::take(&mut heat_rest).split_at_mut(rows * w as usize);
            heat_rest = rest;
            let (proj, surface) = (&proj, &surface);
            handles.push(s.spawn(move || {
                measure_rows(
                    proj,
                    surface,
                    (w, h),
                    start..start + rows,
                    depth,
                    reference,
                    params,
                    heat_rows,
                )
            }));
        }
        for handle in handles {
            parts.push(handle.join().expect("image error thread"));
        }
    });
    let mut total = ImageError {
        tau_px: params.tau_px,
        ..Default::default()
    };
    for p in &parts {
        total.merge(p);
    }
    confirm(heat, w, h, params.tau_px, &mut total);
    total
}

/// Fills the `confirmed` distribution: each measured pixel's error capped by the largest error
/// among its measured 8-neighbours (a pixel without measured neighbours keeps its own).
fn confirm(heat: &[f32], w: u32, h: u32, tau_px: f64, out: &mut ImageError) {
    let (w, h) = (w as i64, h as i64);
    let measured = |x: i64, y: i64| -> Option<f32> {
        if x < 0 || y < 0 || x >= w || y >= h {
            return None;
        }
        let e = heat[(y * w + x) as usize];
        (e >= 0.0).then_some(e)
    };
    for y in 0..h {
        for x in 0..w {
            let Some(e) = measured(x, y) else { continue };
            let mut best: Option<f32> = None;
            for (dx, dy) in [
                (-1, -1),
                (0, -1),
                (1, -1),
                (-1, 0),
                (1, 0),
                (-1, 1),
                (0, 1),
                (1, 1),
            ] {
                if let Some(n) = measured(x + dx, y + dy) {
                    best = Some(best.map_or(n, |b| b.max(n)));
                }
            }
            let c = best.map_or(e, |b| e.min(b)) as f64;
            if c > out.confirmed.max() || out.confirmed_max_at.is_none() {
                out.confirmed_max_at = Some((x as u32, y as u32));
            }
            out.confirmed.add(c);
            out.confirmed_over_tau += (c > tau_px) as u64;
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn measure_rows(
    proj: &Projector,
    surface: &TrueSurface,
    (w, h): (u32, u32),
    rows: std::ops::Range<usize>,
    depth: &[f32],
    reference: Option<&[f32]>,
    params: &MeasureParams,
    heat: &mut [f32],
) -> ImageError {
    let mut out = ImageError {
        tau_px: params.tau_px,
        ..Default::default()
    };
    let row0 = rows.start;
    for py in rows {
        for px in 0..w {
            let i = py * w as usize + px as usize;
            let d = depth[i];
            let ref_terrain = reference.map(|r| r[i] > 0.0);
            let mut e = f64::NAN;
            if d > 0.0 {
                out.terrain_px += 1;
                if ref_terrain == Some(false) {
                    out.extra_px += 1;
                }
                let z = proj.near / d as f64;
                let p = proj.unproject(px, py as u32, z);
                match surface.point_under(p) {
                    None => out.off_dataset_px += 1,
                    Some(q) => match (proj.project(p), proj.project(q)) {
                        (Some(a), Some(b)) => e = (a - b).length(),
                        _ => out.unprojectable_px += 1,
                    },
                }
            } else if ref_terrain == Some(true) {
                out.holes_px += 1;
                let k = hole_distance(depth, w, h, px, py, params.hole_search_px);
                out.hole_max_px = out.hole_max_px.max(k);
                if !heat.is_empty() {
                    heat[(py - row0) * w as usize + px as usize] = -1.0;
                }
                continue;
            }
            if !e.is_nan() {
                if e > out.hist.max() || out.max_at.is_none() {
                    out.max_at = Some((px, py as u32));
                }
                out.hist.add(e);
                out.over_tau += (e > params.tau_px) as u64;
            }
            if !heat.is_empty() {
                heat[(py - row0) * w as usize + px as usize] = e as f32;
            }
        }
    }
    out
}

/// Distance in pixels along column `px` from (px, py) to the nearest terrain pixel of the frame,
/// capped at `limit`.
fn hole_distance(depth: &[f32], w: u32, h: u32, px: u32, py: usize, limit: u32) -> f64 {
    for k in 1..=limit as usize {
        let up = py.checked_sub(k);
        let down = (py + k < h as usize).then_some(py + k);
        for y in [up, down].into_iter().flatten() {
            if depth[y * w as usize + px as usize] > 0.0 {
                return k as f64;
            }
        }
    }
    limit as f64
}

/// Brute-force error (px) of one drawn node, DESIGN.md's definition: for full-resolution
/// samples p of the level-`level` tile (tx, ty) (tiles of `tile_quads` quads), the distance on
/// screen between the true point (x, y, h(p) − drop) and the point of the level-`drawn` surface
/// drawn there — the node's own level, its parent's for a quadrant drawn at the parent's
/// resolution, its grandparent's for a sixteenth — (its vertices dropped, interpolated over the
/// SW–NE diagonal); samples where either projects inside the viewport count. Samples are taken
/// every `stride` (1 = all; larger strides vary the offset inside each cell so that every
/// position in a cell is visited across the tile).
#[allow(clippy::too_many_arguments)]
pub fn node_error_px(
    ds: &Dataset,
    camera: &Camera,
    size: (u32, u32),
    tile_quads: u32,
    (level, tx, ty): (u32, u32, u32),
    drawn: u32,
    curvature: bool,
    stride: usize,
) -> f64 {
    let hf = &ds.hf;
    let side = (tile_quads as usize) << level;
    let step = 1usize << drawn.max(level);
    let (c0, r0) = (tx as usize * side, ty as usize * side);
    let surf = TrueSurface::new(ds, camera.position, curvature);
    let proj = Projector::new(camera, size.0, size.1);
    let vertex = |c: usize, r: usize| surf.sample_point(c.min(hf.width - 1), r.min(hf.height - 1));
    let on_screen = |p: DVec2| p.x >= 0.0 && p.x <= proj.w && p.y >= 0.0 && p.y <= proj.h;
    let stride = stride.max(1);
    let positions = |start: usize, limit: usize| -> Vec<usize> {
        let mut v: Vec<usize> = (0..)
            .map(|k: usize| start + k * stride + (k * 7 + 3) % stride)
            .take_while(|&p| p <= start + side)
            .filter(|&p| p < limit)
            .collect();
        if stride > 1 && start + side < limit {
            v.push(start + side);
        }
        v
    };
    let cols = positions(c0, ds.valid_width);
    let rows = positions(r0, ds.valid_height);
    let mut worst: f64 = 0.0;
    for &row in &rows {
        for &c in &cols {
            let truth = surf.sample_point(c, row);
            let (ci, ri) = (
                ((c - c0) / step).min(side / step - 1),
                ((row - r0) / step).min(side / step - 1),
            );
            let (vc, vr) = (c0 + ci * step, r0 + ri * step);
            let u = (c - vc) as f64 / step as f64;
            let v = (row - vr) as f64 / step as f64;
            let corners = [
                (vc, vr),
                (vc + step, vr),
                (vc, vr + step),
                (vc + step, vr + step),
            ]
            .map(|(c, r)| vertex(c, r));
            let axis = |k: usize| {
                let [sw, se, nw, ne] = corners.map(|p| p[k]);
                quad_surface(sw, se, nw, ne, u, v)
            };
            // Flat: the vertical through the sample; on the ellipsoid the GPU's interpolation
            // of the vertices' exact positions.
            let drawn = match surf.earth {
                None => DVec3::new(truth.x, truth.y, axis(2)),
                Some(_) => DVec3::new(axis(0), axis(1), axis(2)),
            };
            let a = proj.project(truth);
            let b = proj.project(drawn);
            if let (Some(pa), Some(pb)) = (a, b) {
                if on_screen(pa) || on_screen(pb) {
                    worst = worst.max((pa - pb).length());
                }
            }
        }
    }
    worst
}

/// What [`oracle_selection`] found.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct OracleResult {
    /// Largest brute-force error among the nodes checked, px.
    pub max_px: f64,
    /// Nodes checked.
    pub nodes: u32,
    /// Largest projected-error bound ρ of the whole selection, px (∞ for nodes the eye is
    /// inside of).
    pub max_bound_px: f64,
}

/// The brute-force error of a selection's drawn nodes: the `nodes / 2` with the largest bound ρ
/// and as many more drawn at random (deterministic in `seed`), each on at most ~129² samples
/// (a node of level ℓ > 3 is sampled every 2^(ℓ−3)-th sample with varying offsets — the exact,
/// all-sample oracle is the `bound_oracle` test).
#[allow(clippy::too_many_arguments)]
pub fn oracle_selection(
    ds: &Dataset,
    camera: &Camera,
    size: (u32, u32),
    tile_quads: u32,
    items: &[DrawItem],
    curvature: bool,
    nodes: usize,
    seed: u64,
) -> OracleResult {
    let max_bound_px = items.iter().map(|i| i.rho_px as f64).fold(0.0, f64::max);
    if items.is_empty() || nodes == 0 {
        return OracleResult {
            max_bound_px,
            ..Default::default()
        };
    }
    let mut order: Vec<usize> = (0..items.len()).collect();
    order.sort_by(|&a, &b| items[b].rho_px.total_cmp(&items[a].rho_px));
    let mut pick: Vec<usize> = order.iter().take(nodes.div_ceil(2)).copied().collect();
    let mut state = seed ^ 0x9e37_79b9_7f4a_7c15;
    let mut tries = 0;
    while pick.len() < nodes.min(items.len()) && tries < 8 * nodes {
        tries += 1;
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        let k = ((z ^ (z >> 31)) % items.len() as u64) as usize;
        if !pick.contains(&k) {
            pick.push(k);
        }
    }
    let per_side = (tile_quads as usize) << 3;
    let results: Vec<f64> = std::thread::scope(|s| {
        let handles: Vec<_> = pick
            .iter()
            .map(|&k| {
                let it = items[k];
                s.spawn(move || {
                    let side = (tile_quads as usize) << it.node_level;
                    let stride = side.div_ceil(per_side).max(1);
                    node_error_px(
                        ds,
                        camera,
                        size,
                        tile_quads,
                        (it.node_level, it.node_tx, it.node_ty),
                        // A quadrant or sixteenth is drawn at a coarser level's resolution.
                        it.node_level + it.morph.levels_up(),
                        curvature,
                        stride,
                    )
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("oracle thread"))
            .collect()
    });
    OracleResult {
        max_px: results.iter().copied().fold(0.0, f64::max),
        nodes: pick.len() as u32,
        max_bound_px,
    }
}

#[cfg(test)]
#[path = "image_error_tests.rs"]
mod tests;
