//! Scripted flights for headless runs: a straight-and-level pass over a dataset. Pure CPU.

use glam::{DVec2, DVec3};

use aerie_sim_bridge::script::WaypointFrame;
use aerie_terrain::camera::Attitude;
use aerie_terrain::dataset::Dataset;
use aerie_terrain::source::SourceGrid;

use crate::sim::geo_mapping::GeoMapping;
#[cfg(test)]
use aerie_terrain::Heightfield;

/// A straight, level pass at constant speed: position = start + t·speed·(sin ψ, cos ψ).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StraightPass {
    pub start: DVec2,
    pub altitude: f64,
    pub speed: f64,
    pub attitude: Attitude,
}

impl StraightPass {
    /// A pass through the centre of `hf` on `heading_deg`, at `agl` metres above the highest
    /// sample, camera pitched `pitch_deg`, lasting `duration_s` at `speed` m/s and centred on
    /// the dataset's middle (clamped so the pass starts inside the dataset).
    pub fn over(
        ds: &Dataset,
        heading_deg: f64,
        pitch_deg: f64,
        speed: f64,
        agl: f64,
        duration_s: f64,
    ) -> Self {
        let hf = &ds.hf;
        let (_, top) = hf.min_max();
        let extent = [
            (ds.valid_width - 1) as f64 * hf.spacing_x,
            (ds.valid_height - 1) as f64 * hf.spacing_y,
        ];
        Self::over_extent(
            extent,
            top as f64,
            heading_deg,
            pitch_deg,
            speed,
            agl,
            duration_s,
        )
    }

    /// [`Self::over`] a terrain of `extent` metres (east, north) whose highest sample is `top`
    /// metres — a source whose samples are not all in memory (a streamed store).
    pub fn over_extent(
        extent: [f64; 2],
        top: f64,
        heading_deg: f64,
        pitch_deg: f64,
        speed: f64,
        agl: f64,
        duration_s: f64,
    ) -> Self {
        let [ex, ey] = extent;
        let centre = DVec2::new(ex / 2.0, ey / 2.0);
        let h = heading_deg.to_radians();
        let dir = DVec2::new(h.sin(), h.cos());
        let half = (speed * duration_s / 2.0).min(ex.min(ey) / 2.0);
        Self {
            start: centre - dir * half,
            altitude: top + agl,
            speed,
            attitude: Attitude::from_degrees(heading_deg, pitch_deg, 0.0),
        }
    }

    pub fn pose_at(&self, t: f64) -> (DVec3, Attitude) {
        let h = self.attitude.heading;
        let p = self.start + DVec2::new(h.sin(), h.cos()) * self.speed * t;
        (DVec3::new(p.x, p.y, self.altitude), self.attitude)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pass_moves_along_its_heading_at_its_speed() {
        let hf = Heightfield {
            width: 101,
            height: 101,
            spacing_x: 10.0,
            spacing_y: 10.0,
            heights: vec![100.0; 101 * 101],
            geo: None,
            voids_filled: 0,
            spacing_note: String::new(),
        };
        let ds = Dataset::from_heightfield(hf, "test".into());
        let pass = StraightPass::over(&ds, 90.0, -10.0, 50.0, 300.0, 10.0);
        let (p0, a) = pass.pose_at(0.0);
        let (p1, _) = pass.pose_at(2.0);
        assert!((p1.x - p0.x - 100.0).abs() < 1e-9 && (p1.y - p0.y).abs() < 1e-9);
        assert_eq!(p0.z, 400.0);
        assert_eq!((p0.x, p0.y), (250.0, 500.0)); // centred: 250 m before the middle
        assert!((a.pitch + 10f64.to_radians()).abs() < 1e-12);
    }
}

/// A scripted flight from timed waypoints, linearly interpolated (heading along the shorter
/// arc). File format: one waypoint per line, `t_s,x_m,y_m,z_m,heading_deg,pitch_deg,roll_deg`;
/// blank lines and `#` comments are ignored; times strictly increase. A file headed `geo`
/// holds `t_s,lat_deg,lon_deg,alt_m,heading_deg,pitch_deg,roll_deg` instead, placed on a
/// geo-referenced dataset by [`Waypoints::placed_on`] exactly as a host's geodetic poses are
/// ([`GeoMapping`]). A thin wrapper over `aerie_sim_bridge::script::Waypoints`, so
/// `aerie fly --path` and `aerie-send --path` fly exactly the same path.
#[derive(Debug, Clone, PartialEq)]
pub struct Waypoints {
    inner: aerie_sim_bridge::script::Waypoints,
    /// A geo file's placement on its dataset (`None`: local metres, or not yet placed).
    mapping: Option<GeoMapping>,
}

impl Waypoints {
    /// Parses the text of a waypoint file; errors name `source:line` and the reason.
    pub fn parse(text: &str, source: &str) -> Result<Self, String> {
        aerie_sim_bridge::script::Waypoints::parse(text, source).map(|inner| Self {
            inner,
            mapping: None,
        })
    }

    /// Whether the file holds geodetic waypoints (headed `geo`).
    pub fn is_geo(&self) -> bool {
        self.inner.frame() == WaypointFrame::Geodetic
    }

    /// The waypoints on the dataset of `grid`: a geo file placed on the ellipsoid through the
    /// grid's geo-reference (`Err` names why it has none); a local file unchanged.
    pub fn placed_on(self, grid: &SourceGrid) -> Result<Self, String> {
        if !self.is_geo() {
            return Ok(self);
        }
        let mapping = GeoMapping::of_source(grid).map_err(|e| {
            format!("geo waypoints (lat, lon, alt) need a geo-referenced dataset: {e}")
        })?;
        Ok(Self {
            mapping: Some(mapping),
            ..self
        })
    }

    /// Time of the last waypoint, seconds.
    pub fn duration(&self) -> f64 {
        self.inner.duration()
    }

    /// Pose at time `t` in the dataset's world frame, held before the first and after the
    /// last waypoint. Geodetic waypoints: the exact point on the ellipsoid, the attitude in
    /// the north-east-down frame at that point.
    ///
    /// # Panics
    /// For a geo file not yet [`placed_on`](Self::placed_on) its dataset (a programming error:
    /// every flight places its waypoints when it is planned).
    pub fn pose_at(&self, t: f64) -> (DVec3, Attitude) {
        let s = self.inner.sample(t);
        let [h, p, r] = s.attitude_deg;
        let attitude = Attitude::from_degrees(h, p, r);
        if !self.is_geo() {
            return (DVec3::from_array(s.position), attitude);
        }
        let m = self
            .mapping
            .as_ref()
            .expect("geo waypoints are placed on their dataset before they are flown");
        let [lat, lon, alt] = s.position;
        (m.to_world(lat, lon, alt), m.attitude_at(lat, lon, attitude))
    }
}

#[cfg(test)]
mod waypoint_tests {
    use super::*;

    #[test]
    fn interpolates_and_wraps_heading_through_north() {
        let w = Waypoints::parse(
            "# t,x,y,z,h,p,r\n0,0,0,100,350,0,0\n\n10,1000,0,200,10,-10,20 # turn\n",
            "f.csv",
        )
        .unwrap();
        let (p, a) = w.pose_at(5.0);
        assert!((p - DVec3::new(500.0, 0.0, 150.0)).length() < 1e-9);
        assert!(
            (a.heading.to_degrees() - 0.0).abs() < 1e-9
                || (a.heading.to_degrees() - 360.0).abs() < 1e-9
        );
        assert!(
            (a.pitch.to_degrees() + 5.0).abs() < 1e-9 && (a.roll.to_degrees() - 10.0).abs() < 1e-9
        );
        assert_eq!(w.pose_at(-1.0).0, DVec3::new(0.0, 0.0, 100.0));
        assert_eq!(w.pose_at(99.0).0, DVec3::new(1000.0, 0.0, 200.0));
        assert_eq!(w.duration(), 10.0);
    }

    #[test]
    fn errors_name_the_line_and_reason() {
        let e = Waypoints::parse("0,0,0,0,0,0,0\n1,2,3\n", "p.csv").unwrap_err();
        assert!(e.starts_with("p.csv:2:") && e.contains("expected 7"), "{e}");
        let e = Waypoints::parse("0,0,0,0,0,0,0\n0,0,0,0,0,0,0\n", "p.csv").unwrap_err();
        assert!(
            e.contains("p.csv:2:") && e.contains("does not increase"),
            "{e}"
        );
        let e = Waypoints::parse("0,0,nan,0,0,0,0\n", "p.csv").unwrap_err();
        assert!(e.contains("y_m"), "{e}");
        assert!(Waypoints::parse("# nothing\n", "p.csv")
            .unwrap_err()
            .contains("no waypoints"));
    }
}
