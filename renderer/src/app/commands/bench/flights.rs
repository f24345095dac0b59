//! The suite's flights over a dataset, as timed waypoints (one per frame, so the waypoint
//! file is the flight exactly): high cruise, terrain following, an approach, a manoeuvre.
//! Pure: a dataset and a spec in, waypoints text out.

use glam::DVec2;

use aerie_terrain::dataset::Dataset;

/// What a flight does (the suite's `[[flight]]` `kind` and its keys).
#[derive(Debug, Clone, PartialEq)]
pub enum FlightKind {
    /// Straight and level at `agl` above the dataset's highest sample.
    Cruise { pitch_deg: f64, agl_m: f64 },
    /// Straight, `agl` above the ground under the aircraft at every frame.
    Follow { pitch_deg: f64, agl_m: f64 },
    /// A straight descent on a `glide_deg` slope ending `to_agl` above the flattest ground
    /// the path can reach (camera pitched down the slope); never below `to_agl` above the
    /// ground under it.
    Approach { glide_deg: f64, to_agl_m: f64 },
    /// Straight, `agl` above the highest sample, the camera pitching between `pitch_deg`
    /// (one full cycle) and rolling ±`roll_deg` (two cycles).
    Manoeuvre {
        agl_m: f64,
        pitch_deg: [f64; 2],
        roll_deg: f64,
    },
}

/// One flight of a suite.
#[derive(Debug, Clone, PartialEq)]
pub struct FlightSpec {
    pub name: String,
    pub heading_deg: f64,
    /// Ground speed, m/s (a path longer than the dataset is shortened to fit).
    pub speed: f64,
    pub kind: FlightKind,
}

/// The valid extent of `ds` in metres.
fn extent(ds: &Dataset) -> DVec2 {
    DVec2::new(
        (ds.valid_width - 1) as f64 * ds.hf.spacing_x,
        (ds.valid_height - 1) as f64 * ds.hf.spacing_y,
    )
}

/// Whether `p` lies in the valid extent.
fn inside(ds: &Dataset, p: DVec2) -> bool {
    let e = extent(ds);
    p.x >= 0.0 && p.y >= 0.0 && p.x <= e.x && p.y <= e.y
}

/// The spread (max − min) of the heights over a square of half-side `r` around `p`, and their
/// mean, from 9×9 samples.
fn roughness(ds: &Dataset, p: DVec2, r: f64) -> (f64, f64) {
    let (mut lo, mut hi, mut sum) = (f64::INFINITY, f64::NEG_INFINITY, 0.0);
    for j in 0..9 {
        for i in 0..9 {
            let q = p + DVec2::new(i as f64 - 4.0, j as f64 - 4.0) * (r / 4.0);
            let h = ds.hf.height_at_m(q.x, q.y);
            (lo, hi, sum) = (lo.min(h), hi.max(h), sum + h);
        }
    }
    (hi - lo, sum / 81.0)
}

/// The end of an approach of length `len` on heading `dir`: among a 24×24 grid of candidates
/// whose start `end − dir·len` is inside the dataset, the one with the flattest ground around
/// it (over 1/20 of the extent), land preferred (mean height above 0.5 m: SRTM's sea is 0);
/// ties to the centre. None when no candidate fits.
pub fn flattest_end(ds: &Dataset, dir: DVec2, len: f64) -> Option<DVec2> {
    let e = extent(ds);
    let r = e.min_element() / 40.0;
    let mut best: Option<(bool, f64, f64, DVec2)> = None;
    for j in 0..24 {
        for i in 0..24 {
            let p = DVec2::new(
                e.x * (0.1 + 0.8 * i as f64 / 23.0),
                e.y * (0.1 + 0.8 * j as f64 / 23.0),
            );
            if !inside(ds, p - dir * len) {
                continue;
            }
            let (spread, mean) = roughness(ds, p, r);
            let sea = mean <= 0.5;
            let centre = (p - e / 2.0).length();
            let key = (sea, spread, centre, p);
            let better = match &best {
                None => true,
                Some(b) => (key.0, key.1, key.2) < (b.0, b.1, b.2),
            };
            if better {
                best = Some(key);
            }
        }
    }
    best.map(|b| b.3)
}

/// One waypoint per frame time `k / fps`, k = 0..frames (inclusive of the last), as the
/// `t_s,x_m,y_m,z_m,heading_deg,pitch_deg,roll_deg` text `Waypoints::parse` reads.
pub fn waypoints_csv(ds: &Dataset, spec: &FlightSpec, frames: u32, fps: f64) -> String {
    let duration = frames as f64 / fps;
    let h = spec.heading_deg.to_radians();
    let dir = DVec2::new(h.sin(), h.cos());
    let e = extent(ds);
    let top = ds.hf.min_max().1 as f64;
    let ground = |p: DVec2| ds.hf.height_at_m(p.x, p.y);
    // The path: centred on the dataset, shortened to fit inside it.
    let mut len = (spec.speed * duration).min(e.min_element() * 0.9);
    let mut start = e / 2.0 - dir * len / 2.0;
    if let FlightKind::Approach { .. } = spec.kind {
        len = (spec.speed * duration).min(e.min_element() * 0.7);
        let end = flattest_end(ds, dir, len).unwrap_or(e / 2.0 + dir * len / 2.0);
        start = end - dir * len;
    }
    let mut text = format!(
        "# {}: t_s,x_m,y_m,z_m,heading_deg,pitch_deg,roll_deg\n",
        spec.name
    );
    for k in 0..=frames {
        let t = k as f64 / fps;
        let s = if duration > 0.0 { t / duration } else { 0.0 };
        let p = start + dir * len * s;
        let (z, pitch, roll) = match spec.kind {
            FlightKind::Cruise { pitch_deg, agl_m } => (top + agl_m, pitch_deg, 0.0),
            FlightKind::Follow { pitch_deg, agl_m } => (ground(p) + agl_m, pitch_deg, 0.0),
            FlightKind::Approach {
                glide_deg,
                to_agl_m,
            } => {
                let end = start + dir * len;
                let to_go = len * (1.0 - s);
                let on_slope = ground(end) + to_agl_m + to_go * glide_deg.to_radians().tan();
                (on_slope.max(ground(p) + to_agl_m), -glide_deg, 0.0)
            }
            FlightKind::Manoeuvre {
                agl_m,
                pitch_deg: [lo, hi],
                roll_deg,
            } => {
                let tau = std::f64::consts::TAU;
                let pitch = (lo + hi) / 2.0 + (hi - lo) / 2.0 * (tau * s).sin();
                (top + agl_m, pitch, roll_deg * (2.0 * tau * s).sin())
            }
        };
        text.push_str(&format!(
            "{t:.6},{:.3},{:.3},{z:.3},{:.6},{pitch:.6},{roll:.6}\n",
            p.x,
            p.y,
            spec.heading_deg.rem_euclid(360.0)
        ));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::flight::Waypoints;
    use aerie_terrain::Heightfield;

    /// 201² at 10 m: a ramp rising east (x) with bumps, flat in the north-west quarter.
    fn ds() -> Dataset {
        let n = 201;
        let heights = (0..n * n)
            .map(|k| {
                let (c, r) = ((k % n) as f32, (k / n) as f32);
                if c < 100.0 && r > 100.0 {
                    300.0
                } else {
                    300.0 + c * 2.0 + (c * 0.7).sin() * 30.0 + (r * 0.9).cos() * 25.0
                }
            })
            .collect();
        let hf = Heightfield {
            width: n,
            height: n,
            spacing_x: 10.0,
            spacing_y: 10.0,
            heights,
            geo: None,
            voids_filled: 0,
            spacing_note: String::new(),
        };
        Dataset::from_heightfield(hf, "t".into())
    }

    fn spec(kind: FlightKind) -> FlightSpec {
        FlightSpec {
            name: "f".into(),
            heading_deg: 90.0,
            speed: 50.0,
            kind,
        }
    }

    fn poses(d: &Dataset, s: &FlightSpec) -> Vec<(glam::DVec3, aerie_terrain::camera::Attitude)> {
        let w = Waypoints::parse(&waypoints_csv(d, s, 20, 10.0), "f.csv").unwrap();
        (0..=20).map(|k| w.pose_at(k as f64 / 10.0)).collect()
    }

    #[test]
    fn follow_keeps_its_height_above_the_ground_and_cruise_its_altitude() {
        let d = ds();
        let top = d.hf.min_max().1 as f64;
        for (p, a) in poses(
            &d,
            &spec(FlightKind::Follow {
                pitch_deg: -5.0,
                agl_m: 150.0,
            }),
        ) {
            let agl = p.z - d.hf.height_at_m(p.x, p.y);
            assert!((agl - 150.0).abs() < 1e-2, "{agl}");
            assert!((a.pitch.to_degrees() + 5.0).abs() < 1e-6);
        }
        let cruise = poses(
            &d,
            &spec(FlightKind::Cruise {
                pitch_deg: -10.0,
                agl_m: 2000.0,
            }),
        );
        assert!(cruise
            .iter()
            .all(|(p, _)| (p.z - top - 2000.0).abs() < 1e-2));
        // 50 m/s for 2 s, eastward.
        let dx = cruise[20].0.x - cruise[0].0.x;
        assert!((dx - 100.0).abs() < 1e-2 && (cruise[20].0.y - cruise[0].0.y).abs() < 1e-2);
    }

    #[test]
    fn approach_descends_at_its_slope_to_its_height_over_flat_ground() {
        let d = ds();
        let s = spec(FlightKind::Approach {
            glide_deg: 3.0,
            to_agl_m: 50.0,
        });
        let p = poses(&d, &s);
        let end = p[20].0;
        // Ends over the flat quarter, 50 m above it.
        assert!(end.x < 1000.0 && end.y > 1000.0, "{end:?}");
        assert!((end.z - 350.0).abs() < 1e-2, "{}", end.z);
        let slope = (p[0].0.z - end.z) / (end.x - p[0].0.x);
        assert!((slope - 3f64.to_radians().tan()).abs() < 1e-4, "{slope}");
        assert!((p[5].1.pitch.to_degrees() + 3.0).abs() < 1e-6);
    }

    #[test]
    fn manoeuvre_spans_its_pitch_and_rolls() {
        let d = ds();
        let s = spec(FlightKind::Manoeuvre {
            agl_m: 500.0,
            pitch_deg: [-60.0, 30.0],
            roll_deg: 90.0,
        });
        let w = Waypoints::parse(&waypoints_csv(&d, &s, 400, 100.0), "m.csv").unwrap();
        let att: Vec<_> = (0..=400).map(|k| w.pose_at(k as f64 / 100.0).1).collect();
        let pitch: Vec<f64> = att.iter().map(|a| a.pitch.to_degrees()).collect();
        let roll: Vec<f64> = att.iter().map(|a| a.roll.to_degrees()).collect();
        let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
        assert!((max(&pitch) - 30.0).abs() < 0.1 && (min(&pitch) + 60.0).abs() < 0.1);
        assert!((max(&roll) - 90.0).abs() < 0.1 && (min(&roll) + 90.0).abs() < 0.1);
    }
}
