//! A stitched review panorama of several display channels (issue 7 item 5): an
//! equirectangular canvas in aircraft-relative azimuth (clockwise from the nose) and elevation
//! (up from the body's forward-right plane), covering the union of the channel frusta. Each canvas
//! pixel is filled from the channel whose frustum contains its direction — nearest sample through
//! that channel's own f64 camera — pixels no channel sees are dark grey, and the borders between
//! two channels are marked by a one-pixel line.
//!
//! Everything here is plain CPU data: the projection (direction → channel, pixel) is a pure
//! function tested against [`crate::sim::channel::channel_camera`]; the lookup table is built once
//! per run (channels are fixed relative to the aircraft) and each frame is a gather.
//!
//! Directions are expressed for an aircraft at the rest attitude (heading 0, level): body
//! forward = +y (north), right = +x (east), up = +z. A channel's camera is its
//! [`channel_camera`](crate::sim::channel::channel_camera) for that pose, so the panorama is the same
//! whatever the aircraft's attitude (the channels move with it). Eye offsets move the eye, not
//! the view direction; at review scale (metres against kilometres) they are ignored.

use aerie_config::Channel;
use glam::{DVec2, DVec3};

use crate::sim::channel::channel_camera;
use aerie_terrain::camera::{Attitude, Camera};

/// Colour of canvas pixels no channel sees (sRGB bytes).
pub const NO_CHANNEL: [u8; 4] = [48, 48, 48, 255];
/// Colour of the line marking the border between two channels.
pub const BORDER: [u8; 4] = [255, 214, 0, 255];
/// Default cap on the canvas width (and height), pixels.
pub const MAX_CANVAS: u32 = 4096;
/// Tolerance, in pixels, for a direction on a frustum's edge to count as inside: the shared edge
/// of two channels projects to x = W in one and x = 0 in the other up to rounding.
const EDGE_TOLERANCE_PX: f64 = 1e-6;

/// One channel as the panorama sees it: its camera at the rest pose and its render size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PanoramaChannel {
    pub camera: Camera,
    pub size: (u32, u32),
}

impl PanoramaChannel {
    /// The channel's camera for an aircraft at the origin at the rest attitude (the same
    /// composition as [`channel_camera`] for any pose), rendered at `size`.
    pub fn new(ch: &Channel, size: (u32, u32)) -> Self {
        let rest = (DVec3::ZERO, Attitude::from_degrees(0.0, 0.0, 0.0));
        let mut camera = channel_camera(rest, ch, size.0 as f64 / size.1 as f64);
        camera.position = DVec3::ZERO;
        Self { camera, size }
    }

    /// Continuous pixel coordinates (origin top-left, edges at 0 and W/H, as
    /// [`Camera::project_px`]) of direction `dir`, or `None` when outside the frustum.
    pub fn pixel_of(&self, dir: DVec3) -> Option<DVec2> {
        let v = self.camera.world_to_view_rotation() * dir;
        if v.z <= 0.0 {
            return None;
        }
        let f = &self.camera.frustum;
        let (a, b) = (v.x / v.z, v.y / v.z);
        let (w, h) = (self.size.0 as f64, self.size.1 as f64);
        let p = DVec2::new(
            (a - f.tan_left) / (f.tan_right - f.tan_left) * w,
            (b + f.tan_up) / (f.tan_up - f.tan_down) * h,
        );
        let t = EDGE_TOLERANCE_PX;
        (p.x >= -t && p.x <= w + t && p.y >= -t && p.y <= h + t).then_some(p)
    }

    /// The pixel (column, row) holding continuous position `p`: nearest sample, the far edges
    /// belonging to the last column/row.
    pub fn pixel_index(&self, p: DVec2) -> (u32, u32) {
        let clamp = |v: f64, n: u32| (v.floor().max(0.0) as u32).min(n - 1);
        (clamp(p.x, self.size.0), clamp(p.y, self.size.1))
    }

    /// Pixels per radian on the view axis (the channel's finest angular resolution).
    fn pixels_per_radian(&self) -> f64 {
        let f = &self.camera.frustum;
        (self.size.0 as f64 / (f.tan_right - f.tan_left))
            .max(self.size.1 as f64 / (f.tan_up - f.tan_down))
    }

    /// Directions along the frustum's border (`n` per edge, corners included).
    fn border_directions(&self, n: u32) -> Vec<DVec3> {
        let (w, h) = (self.size.0, self.size.1);
        let (wf, hf) = (w as f64, h as f64);
        let mut out = Vec::with_capacity(4 * n as usize);
        for k in 0..=n {
            let s = k as f64 / n as f64;
            for (x, y) in [(s * wf, 0.0), (s * wf, hf), (0.0, s * hf), (wf, s * hf)] {
                out.push(self.camera.pixel_ray(x, y, w, h));
            }
        }
        out
    }
}

/// The unit direction at azimuth `az_deg` (clockwise from the nose) and elevation `el_deg`, in
/// the rest-pose frame (forward +y, right +x, up +z).
pub fn direction(az_deg: f64, el_deg: f64) -> DVec3 {
    let (az, el) = (az_deg.to_radians(), el_deg.to_radians());
    DVec3::new(az.sin() * el.cos(), az.cos() * el.cos(), el.sin())
}

/// Azimuth and elevation (degrees) of a rest-pose direction.
pub fn az_el(dir: DVec3) -> (f64, f64) {
    let d = dir.normalize();
    (
        d.x.atan2(d.y).to_degrees(),
        d.z.clamp(-1.0, 1.0).asin().to_degrees(),
    )
}

/// A canvas pixel's source: channel index and its pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Source {
    pub channel: u16,
    pub x: u32,
    pub y: u32,
}

/// Every channel whose frustum contains `dir`, with the continuous pixel position.
pub fn candidates(channels: &[PanoramaChannel], dir: DVec3) -> Vec<(usize, DVec2)> {
    channels
        .iter()
        .enumerate()
        .filter_map(|(i, c)| c.pixel_of(dir).map(|p| (i, p)))
        .collect()
}

/// The channel (and its pixel) that fills direction `dir`: where channels overlap, the one in
/// which the direction lies furthest from an edge (its most central view); on a shared edge the
/// first in config order. `None`: no channel sees it.
pub fn locate(channels: &[PanoramaChannel], dir: DVec3) -> Option<Source> {
    let mut best: Option<(f64, usize, DVec2)> = None;
    for (i, p) in candidates(channels, dir) {
        let (w, h) = (channels[i].size.0 as f64, channels[i].size.1 as f64);
        let margin = (p.x / w).min(1.0 - p.x / w).min(p.y / h).min(1.0 - p.y / h);
        if best.is_none_or(|(m, _, _)| margin > m) {
            best = Some((margin, i, p));
        }
    }
    best.map(|(_, i, p)| {
        let (x, y) = channels[i].pixel_index(p);
        Source {
            channel: i as u16,
            x,
            y,
        }
    })
}

/// The canvas: azimuth `az0..az0 + az_span` (may extend past ±180°), elevation `el0..el1`
/// (degrees), `width × height` pixels; column 0 is at `az0`, row 0 at `el1` (top).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Canvas {
    pub az0_deg: f64,
    pub az_span_deg: f64,
    pub el0_deg: f64,
    pub el1_deg: f64,
    pub width: u32,
    pub height: u32,
}

impl Canvas {
    /// The direction through the centre of canvas pixel (i, j).
    pub fn pixel_direction(&self, i: u32, j: u32) -> DVec3 {
        let az = self.az0_deg + (i as f64 + 0.5) / self.width as f64 * self.az_span_deg;
        let el =
            self.el1_deg - (j as f64 + 0.5) / self.height as f64 * (self.el1_deg - self.el0_deg);
        direction(az, el)
    }
}

/// Wraps an angle into [−180, 180).
fn wrap180(a: f64) -> f64 {
    (a + 180.0).rem_euclid(360.0) - 180.0
}

/// The union of circular azimuth intervals `(start, length)` (degrees) as one canvas range
/// `(start, span)`: everything except the largest uncovered gap. A full circle is
/// `(−180, 360)`.
pub fn azimuth_cover(intervals: &[(f64, f64)]) -> (f64, f64) {
    if intervals.is_empty() {
        return (-180.0, 360.0);
    }
    if intervals.iter().any(|&(_, len)| len >= 360.0) {
        return (-180.0, 360.0);
    }
    let mut iv: Vec<(f64, f64)> = intervals
        .iter()
        .map(|&(s, len)| {
            let s = wrap180(s);
            (s, s + len)
        })
        .collect();
    iv.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut merged: Vec<(f64, f64)> = Vec::new();
    for (s, e) in iv {
        match merged.last_mut() {
            Some(last) if s <= last.1 => last.1 = last.1.max(e),
            _ => merged.push((s, e)),
        }
    }
    // The last cluster may run past +180 into the first ones.
    while merged.len() > 1 {
        let first = merged[0];
        let last = merged.last_mut().expect("len > 1");
        if last.1 >= first.0 + 360.0 {
            last.1 = last.1.max(first.1 + 360.0);
            merged.remove(0);
        } else {
            break;
        }
    }
    let n = merged.len();
    if merged.iter().any(|&(s, e)| e - s >= 360.0) {
        return (-180.0, 360.0);
    }
    // The largest gap after cluster k; the canvas starts at the next cluster.
    let mut best = (f64::NEG_INFINITY, 0usize);
    for k in 0..n {
        let next_start = if k + 1 < n {
            merged[k + 1].0
        } else {
            merged[0].0 + 360.0
        };
        let gap = next_start - merged[k].1;
        if gap > best.0 {
            best = (gap, k);
        }
    }
    let start = merged[(best.1 + 1) % n].0;
    (start, 360.0 - best.0.max(0.0))
}

/// The canvas covering every channel's frustum, at the finest angular resolution among them
/// (pixels per degree on the view axis), the width capped at `max_width` and the height at
/// `max_width` too (the resolution scaled down uniformly).
pub fn canvas_for(channels: &[PanoramaChannel], max_width: u32) -> Canvas {
    const N: u32 = 64;
    let up = DVec3::Z;
    let mut intervals = Vec::new();
    let (mut el0, mut el1) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut ppd: f64 = 0.0;
    for c in channels {
        ppd = ppd.max(c.pixels_per_radian() * std::f64::consts::PI / 180.0);
        let border = c.border_directions(N);
        for d in &border {
            let (_, el) = az_el(*d);
            el0 = el0.min(el);
            el1 = el1.max(el);
        }
        // A frustum around a pole spans every azimuth; its extreme elevation is the pole.
        let zenith = c.pixel_of(up).is_some();
        let nadir = c.pixel_of(-up).is_some();
        if zenith {
            el1 = 90.0;
        }
        if nadir {
            el0 = -90.0;
        }
        if zenith || nadir {
            intervals.push((-180.0, 360.0));
            continue;
        }
        let (axis_az, _) = az_el(c.camera.attitude.body_to_world().x_axis);
        let (lo, hi) = border.iter().fold((0.0f64, 0.0f64), |(lo, hi), d| {
            let rel = wrap180(az_el(*d).0 - axis_az);
            (lo.min(rel), hi.max(rel))
        });
        intervals.push((axis_az + lo, hi - lo));
    }
    if channels.is_empty() {
        (el0, el1, ppd) = (-1.0, 1.0, 1.0);
    }
    let (az0, span) = azimuth_cover(&intervals);
    let el_span = (el1 - el0).max(1e-9);
    let cap = max_width.max(1) as f64;
    let scale = (cap / (span * ppd)).min(cap / (el_span * ppd)).min(1.0);
    let px = ppd * scale;
    Canvas {
        az0_deg: az0,
        az_span_deg: span,
        el0_deg: el0,
        el1_deg: el1,
        width: ((span * px).round() as u32).clamp(1, max_width.max(1)),
        height: ((el_span * px).round() as u32).clamp(1, max_width.max(1)),
    }
}

/// The lookup table of one canvas: per pixel its source (row-major) and whether it is on the
/// border between two channels.
#[derive(Debug, Clone)]
pub struct PanoramaMap {
    pub canvas: Canvas,
    pub sources: Vec<Option<Source>>,
    pub border: Vec<bool>,
}

impl PanoramaMap {
    pub fn new(channels: &[PanoramaChannel], canvas: Canvas) -> Self {
        let (w, h) = (canvas.width, canvas.height);
        let mut sources = Vec::with_capacity(w as usize * h as usize);
        for j in 0..h {
            for i in 0..w {
                sources.push(locate(channels, canvas.pixel_direction(i, j)));
            }
        }
        // A pixel whose right or lower neighbour comes from another channel is on a border
        // (one-pixel line on the left/top side); edges against "no channel" need no line.
        let ch = |k: usize| sources[k].map(|s| s.channel);
        let mut border = vec![false; sources.len()];
        for j in 0..h as usize {
            for i in 0..w as usize {
                let k = j * w as usize + i;
                let Some(c) = ch(k) else { continue };
                let differs = |n: usize| ch(n).is_some_and(|o| o != c);
                border[k] = (i + 1 < w as usize && differs(k + 1))
                    || (j + 1 < h as usize && differs(k + w as usize));
            }
        }
        Self {
            canvas,
            sources,
            border,
        }
    }

    /// Canvas pixels filled by each channel.
    pub fn coverage(&self, channels: usize) -> Vec<u64> {
        let mut n = vec![0u64; channels];
        for s in self.sources.iter().flatten() {
            n[s.channel as usize] += 1;
        }
        n
    }

    /// The panorama image (RGBA8, rows top to bottom) from each channel's RGBA8 image (rows top
    /// to bottom, of the channel's size), with or without border lines.
    pub fn compose(&self, images: &[&[u8]], sizes: &[(u32, u32)], borders: bool) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.sources.len() * 4);
        for (k, s) in self.sources.iter().enumerate() {
            let px = match s {
                None => NO_CHANNEL,
                Some(_) if borders && self.border[k] => BORDER,
                Some(s) => {
                    let w = sizes[s.channel as usize].0;
                    let o = (s.y as usize * w as usize + s.x as usize) * 4;
                    let img = images[s.channel as usize];
                    [img[o], img[o + 1], img[o + 2], img[o + 3]]
                }
            };
            out.extend_from_slice(&px);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use aerie_config::{ChannelFrustum, ViewOffset};

    fn wall3(w: u32, h: u32) -> Vec<(Channel, PanoramaChannel)> {
        ["left", "centre", "right"]
            .iter()
            .zip([-60.0, 0.0, 60.0])
            .map(|(name, heading)| {
                let ch = Channel {
                    view: ViewOffset {
                        heading_deg: heading,
                        ..Default::default()
                    },
                    ..Channel::window(name, w, h, 60.0, 1.0)
                };
                let p = PanoramaChannel::new(&ch, (w, h));
                (ch, p)
            })
            .collect()
    }

    #[test]
    fn shared_edge_of_wall3_maps_to_last_column_of_left_and_first_of_centre() {
        let (w, h) = (1920, 1080);
        let chans: Vec<PanoramaChannel> = wall3(w, h).into_iter().map(|c| c.1).collect();
        // The direction of the left channel's right edge, from channel_camera itself, at an
        // arbitrary aircraft attitude expressed back in the rest frame.
        let (chl, _) = &wall3(w, h)[0];
        let att = Attitude::from_degrees(47.0, 8.0, 12.0);
        let cam = channel_camera((DVec3::ZERO, att), chl, w as f64 / h as f64);
        for row in [0.5, 300.5, 539.5, 1079.5] {
            let world = cam.pixel_ray(w as f64, row, w, h);
            let rest = att.body_to_world().transpose() * world;
            // body (forward, right, down) → rest frame (right = x, forward = y, up = z)
            let dir = DVec3::new(rest.y, rest.x, -rest.z);
            let c = candidates(&chans, dir);
            assert_eq!(c.len(), 2, "row {row}: {c:?}");
            let (l, ce) = (c[0], c[1]);
            assert_eq!((l.0, ce.0), (0, 1));
            assert_eq!(chans[0].pixel_index(l.1), (w - 1, row as u32));
            assert_eq!(chans[1].pixel_index(ce.1), (0, row as u32));
            // The chosen source is on one side of the seam, at the same row.
            let s = locate(&chans, dir).unwrap();
            assert!(
                (s.channel, s.x) == (0, w - 1) || (s.channel, s.x) == (1, 0),
                "{s:?}"
            );
            assert_eq!(s.y, row as u32);
        }
    }

    #[test]
    fn projection_matches_channel_camera_project_px() {
        // An asymmetric, pitched, rolled channel: pixel_of agrees with the f64 camera's own
        // projection for an arbitrary aircraft pose (directions relative to the aircraft).
        let ch = Channel {
            view: ViewOffset {
                heading_deg: 25.0,
                pitch_deg: -30.0,
                roll_deg: 5.0,
            },
            frustum: ChannelFrustum::Asymmetric {
                left_deg: -20.0,
                right_deg: 30.0,
                down_deg: -15.0,
                up_deg: 10.0,
            },
            ..Channel::window("chin", 1280, 1024, 60.0, 1.0)
        };
        let (w, h) = (1280, 1024);
        let pc = PanoramaChannel::new(&ch, (w, h));
        let att = Attitude::from_degrees(-130.0, 12.0, -20.0);
        let eye = DVec3::new(1e5, 2e5, 3000.0);
        let cam = channel_camera((eye, att), &ch, w as f64 / h as f64);
        let mut inside = 0;
        for k in 0..400 {
            let az = -60.0 + (k % 20) as f64 * 6.0;
            let el = -60.0 + (k / 20) as f64 * 4.0;
            let d = direction(az, el);
            let body = DVec3::new(d.y, d.x, -d.z);
            let world = eye + att.body_to_world() * body * 1e4;
            let expect = cam
                .project_px(world, w, h)
                .map(|(p, _)| p)
                .filter(|p| p.x >= 0.0 && p.x <= w as f64 && p.y >= 0.0 && p.y <= h as f64);
            let got = pc.pixel_of(d);
            match (expect, got) {
                (Some(e), Some(g)) => {
                    inside += 1;
                    assert!((e - g).length() < 1e-6, "az {az} el {el}: {e} vs {g}");
                }
                (None, None) => {}
                _ => panic!("az {az} el {el}: {expect:?} vs {got:?}"),
            }
        }
        assert!(inside > 20, "{inside}");
    }

    #[test]
    fn azimuth_cover_takes_the_complement_of_the_largest_gap() {
        assert_eq!(
            azimuth_cover(&[(-90.0, 60.0), (-30.0, 60.0), (30.0, 60.0)]),
            (-90.0, 180.0)
        );
        // Across ±180: a rear channel (160°..220°) and a front one; the largest gap is 30°..160°,
        // so the canvas runs from 160° through the tail to +30°.
        let (s, span) = azimuth_cover(&[(160.0, 60.0), (-30.0, 60.0)]);
        assert_eq!((s, span), (160.0, 230.0));
        let (s, span) = azimuth_cover(&[(170.0, 40.0)]);
        assert_eq!((s, span), (170.0, 40.0));
        assert_eq!(azimuth_cover(&[(0.0, 360.0)]), (-180.0, 360.0));
        // Overlapping intervals that close the circle.
        assert_eq!(
            azimuth_cover(&[(-180.0, 130.0), (-60.0, 130.0), (60.0, 130.0)]),
            (-180.0, 360.0)
        );
    }

    #[test]
    fn wall3_canvas_spans_180_degrees_at_the_channels_resolution() {
        let chans: Vec<PanoramaChannel> = wall3(160, 90).into_iter().map(|c| c.1).collect();
        let c = canvas_for(&chans, MAX_CANVAS);
        assert!((c.az0_deg + 90.0).abs() < 1e-9, "{c:?}");
        assert!((c.az_span_deg - 180.0).abs() < 1e-9, "{c:?}");
        // Vertical half-angle at the centre of the top edge: atan(tan 30° · 90/160).
        let v = (30f64.to_radians().tan() * 90.0 / 160.0)
            .atan()
            .to_degrees();
        assert!(
            (c.el1_deg - v).abs() < 1e-6 && (c.el0_deg + v).abs() < 1e-6,
            "{c:?}"
        );
        // 160 px over tan 30° · 2 on the axis.
        let ppd = 160.0 / (2.0 * 30f64.to_radians().tan()) * std::f64::consts::PI / 180.0;
        assert_eq!(c.width, (180.0 * ppd).round() as u32);
        // Full-size presets are capped.
        let big: Vec<PanoramaChannel> = wall3(1920, 1080).into_iter().map(|c| c.1).collect();
        let c = canvas_for(&big, MAX_CANVAS);
        assert_eq!(c.width, MAX_CANVAS);
        assert!(c.height < MAX_CANVAS);
    }

    #[test]
    fn map_fills_each_pixel_from_its_channel_and_marks_seams() {
        let (w, h) = (64, 36);
        let chans: Vec<PanoramaChannel> = wall3(w, h).into_iter().map(|c| c.1).collect();
        let canvas = canvas_for(&chans, MAX_CANVAS);
        let map = PanoramaMap::new(&chans, canvas);
        let cov = map.coverage(3);
        assert!(cov.iter().all(|&n| n > 0), "{cov:?}");
        // Images whose pixels encode (channel, x, y).
        let imgs: Vec<Vec<u8>> = (0..3u8)
            .map(|c| {
                (0..h)
                    .flat_map(|y| (0..w).flat_map(move |x| [c, x as u8, y as u8, 255]))
                    .collect()
            })
            .collect();
        let refs: Vec<&[u8]> = imgs.iter().map(|v| v.as_slice()).collect();
        let out = map.compose(&refs, &[(w, h); 3], false);
        let mid = canvas.height / 2;
        let mut seams = 0;
        for (k, s) in map.sources.iter().enumerate() {
            let px = &out[k * 4..k * 4 + 4];
            match s {
                Some(s) => assert_eq!(px, [s.channel as u8, s.x as u8, s.y as u8, 255]),
                None => assert_eq!(px, NO_CHANNEL),
            }
        }
        // The middle row: left then centre then right, no uncovered pixel in between.
        let row: Vec<Option<u16>> = (0..canvas.width)
            .map(|i| map.sources[(mid * canvas.width + i) as usize].map(|s| s.channel))
            .collect();
        assert!(row.iter().all(|c| c.is_some()), "{row:?}");
        for p in row.windows(2) {
            if p[0] != p[1] {
                seams += 1;
                assert_eq!(p[1].unwrap(), p[0].unwrap() + 1);
            }
        }
        assert_eq!(seams, 2);
        let with = map.compose(&refs, &[(w, h); 3], true);
        let marked = map.border.iter().filter(|&&b| b).count();
        assert!(marked >= 2 * canvas.height as usize / 2, "{marked}");
        for (k, &b) in map.border.iter().enumerate() {
            if b {
                assert_eq!(&with[k * 4..k * 4 + 4], BORDER);
            } else {
                assert_eq!(&with[k * 4..k * 4 + 4], &out[k * 4..k * 4 + 4]);
            }
        }
    }

    #[test]
    fn uncovered_directions_are_dark_grey() {
        // One 60° channel looking right: the canvas is just that channel; a second one at 180°
        // leaves gaps that stay grey.
        let a = Channel {
            view: ViewOffset {
                heading_deg: 90.0,
                ..Default::default()
            },
            ..Channel::window("a", 32, 32, 60.0, 1.0)
        };
        let b = Channel {
            view: ViewOffset {
                heading_deg: 180.0,
                pitch_deg: 20.0,
                ..Default::default()
            },
            ..Channel::window("b", 32, 32, 40.0, 1.0)
        };
        let chans = [
            PanoramaChannel::new(&a, (32, 32)),
            PanoramaChannel::new(&b, (32, 32)),
        ];
        let canvas = canvas_for(&chans, 512);
        assert!((canvas.az0_deg - 60.0).abs() < 1e-9, "{canvas:?}");
        let map = PanoramaMap::new(&chans, canvas);
        let none = map.sources.iter().filter(|s| s.is_none()).count();
        assert!(none > 0);
        let img = vec![200u8; 32 * 32 * 4];
        let out = map.compose(&[&img, &img], &[(32, 32); 2], true);
        for (k, s) in map.sources.iter().enumerate() {
            if s.is_none() {
                assert_eq!(&out[k * 4..k * 4 + 4], NO_CHANNEL);
            }
        }
    }
}
