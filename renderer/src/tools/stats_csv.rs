//! `aerie run --stats <file.csv>`: one row per frame with the aircraft pose the renderer
//! actually used (every channel's camera derives from it), where it came from, and what the frame
//! cost. Rows are buffered in an atomic writer ([`aerie_io::AtomicFile`]): the file appears
//! under its name, complete, when the run ends (or the writer is dropped after another
//! failure); a failed write (a full disk) stops the run naming the file and leaves no cut CSV.
//!
//! Columns (empty when not applicable):
//!
//! | column | meaning |
//! |---|---|
//! | `frame` | display frame, 0-based |
//! | `wall_s` | seconds since the first frame began |
//! | `host_frame` | host frame number of the pose (CIGI IG Control frame, native frame field) |
//! | `sync_target` | `--sync-frames k`: the host frame wanted, newest − k |
//! | `sim_time_s` | sim time of the pose drawn (sent time + extrapolation) |
//! | `x_m,y_m,z_m` | aircraft reference point in the dataset's local frame |
//! | `lat_deg,lon_deg,alt_m` | the same point in WGS84 when the dataset is geo-referenced |
//! | `heading_deg,pitch_deg,roll_deg` | aircraft attitude |
//! | `pose_age_ms` | predicted display time − arrival of the pose's packet |
//! | `extrapolated` | 1 when the pose was carried forward from the received one |
//! | `stream` | `live`, `lost`, `waiting` (default view, no pose yet) or `builtin` (no input) |
//! | `triangles` | triangles drawn over all channels (empty when the frame drew none) |
//! | `frame_ms` | wall time of the frame (headless: its rendering; windows: since the last frame) |
//! | `tiles_late` | tiles drawn coarser than the bound asks over all channels (budget or streaming) |
//! | `tiles_late_stream` | the part of `tiles_late` whose samples were not resident yet |
//! | `terrain_data_us` | longest time a channel's frame spent gathering terrain samples |
//! | `terrain_hits,terrain_misses` | the source's resident / not resident answers so far |
//! | `terrain_resident_bytes,terrain_budget_bytes` | decoded pages in the page cache, its budget |
//!
//! Floating-point values are written with Rust's shortest round-trip formatting, so a reader
//! gets back exactly the f64 the renderer used.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use aerie_io::{AtomicFile, FileSystem};

use crate::sim::channel::AircraftPose;
use crate::sim::pose_input::{state_name, GeoMapping, PoseInfo};

pub const HEADER: &str = "frame,wall_s,host_frame,sync_target,sim_time_s,x_m,y_m,z_m,lat_deg,lon_deg,alt_m,heading_deg,pitch_deg,roll_deg,pose_age_ms,extrapolated,stream,triangles,frame_ms,tiles_late,tiles_late_stream,terrain_data_us,terrain_hits,terrain_misses,terrain_resident_bytes,terrain_budget_bytes";

/// What a drawn frame's terrain source did (empty columns for frames not drawn).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TerrainColumns {
    pub tiles_late: u64,
    pub tiles_late_stream: u64,
    pub terrain_data_us: f64,
    pub hits: u64,
    pub misses: u64,
    pub resident_bytes: u64,
    pub budget_bytes: u64,
}

impl TerrainColumns {
    /// Adds one channel's frame (late tiles summed, the longest gathering kept, the source's
    /// totals as of the last).
    pub fn add(&mut self, s: &crate::render::frame::FrameStats) {
        self.tiles_late += s.tiles_late as u64;
        self.tiles_late_stream += s.tiles_late_stream as u64;
        self.terrain_data_us = self.terrain_data_us.max(s.cpu_terrain_data_us);
        self.hits = s.stream_hits;
        self.misses = s.stream_misses;
        self.resident_bytes = s.stream_resident_bytes;
        self.budget_bytes = s.stream_budget_bytes;
    }
}

/// Where the frame's pose came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PoseOrigin {
    /// The simulator stream.
    Input(PoseInfo),
    /// Default view while no pose has arrived.
    Waiting,
    /// The built-in straight pass (no input configured).
    Builtin,
}

/// One frame's row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameRow {
    pub frame: u64,
    pub wall_s: f64,
    pub pose: AircraftPose,
    pub origin: PoseOrigin,
    pub triangles: Option<u64>,
    pub frame_ms: Option<f64>,
    pub terrain: Option<TerrainColumns>,
}

fn opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map(|v| v.to_string()).unwrap_or_default()
}

/// The CSV line of `row` (with its newline).
pub fn format_row(row: &FrameRow, geo: Option<&GeoMapping>) -> String {
    let p = row.pose.position;
    let a = row.pose.attitude;
    let geodetic = geo.map(|g| g.world_to_geodetic(p));
    let info = match row.origin {
        PoseOrigin::Input(i) => Some(i),
        _ => None,
    };
    let stream = match row.origin {
        PoseOrigin::Input(i) => state_name(i.state),
        PoseOrigin::Waiting => "waiting",
        PoseOrigin::Builtin => "builtin",
    };
    format!(
        "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
        row.frame,
        row.wall_s,
        opt(info.map(|i| i.host_frame)),
        opt(info.and_then(|i| i.sync_target)),
        opt(info.map(|i| i.sim_time_s)),
        p.x,
        p.y,
        p.z,
        opt(geodetic.map(|g| g.0)),
        opt(geodetic.map(|g| g.1)),
        opt(geodetic.map(|g| g.2)),
        a.heading.to_degrees(),
        a.pitch.to_degrees(),
        a.roll.to_degrees(),
        opt(info.map(|i| i.age_s * 1e3)),
        opt(info.map(|i| u8::from(i.extrapolated))),
        stream,
        opt(row.triangles),
        opt(row.frame_ms),
        opt(row.terrain.map(|t| t.tiles_late)),
        opt(row.terrain.map(|t| t.tiles_late_stream)),
        opt(row.terrain.map(|t| t.terrain_data_us)),
        opt(row.terrain.map(|t| t.hits)),
        opt(row.terrain.map(|t| t.misses)),
        opt(row.terrain.map(|t| t.resident_bytes)),
        opt(row.terrain.map(|t| t.budget_bytes)),
    )
}

/// The open stats file.
pub struct StatsWriter {
    path: PathBuf,
    /// `None` once committed or after a failed write.
    out: Option<BufWriter<AtomicFile>>,
    geo: Option<GeoMapping>,
    rows: u64,
}

impl StatsWriter {
    /// Starts the file and writes the header; errors name the file.
    pub fn create(path: &Path, geo: Option<GeoMapping>) -> Result<Self, String> {
        Self::create_in(aerie_io::real(), path, geo)
    }

    /// [`StatsWriter::create`] on the given file system (tests inject faults through it).
    pub fn create_in(
        fs: Arc<dyn FileSystem>,
        path: &Path,
        geo: Option<GeoMapping>,
    ) -> Result<Self, String> {
        let file = AtomicFile::create_in(fs, path).map_err(|e| format!("--stats {e}"))?;
        let mut w = Self {
            path: path.to_path_buf(),
            out: Some(BufWriter::with_capacity(64 * 1024, file)),
            geo,
            rows: 0,
        };
        w.write_line(&format!("{HEADER}\n"))?;
        Ok(w)
    }

    fn closed(&self) -> String {
        format!(
            "--stats {}: the file was already written or failed",
            self.path.display()
        )
    }

    fn write_line(&mut self, line: &str) -> Result<(), String> {
        let Some(out) = self.out.as_mut() else {
            return Err(self.closed());
        };
        if let Err(e) = out.write_all(line.as_bytes()) {
            // Dropping the writer removes the temporary: no cut CSV is left.
            self.out = None;
            return Err(format!("--stats {e}"));
        }
        Ok(())
    }

    pub fn row(&mut self, row: &FrameRow) -> Result<(), String> {
        let line = format_row(row, self.geo.as_ref());
        self.write_line(&line)?;
        self.rows += 1;
        Ok(())
    }

    pub fn rows(&self) -> u64 {
        self.rows
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Writes the buffered rows, syncs the file and puts it in place under its name. Rows
    /// after this are refused.
    pub fn flush(&mut self) -> Result<(), String> {
        let out = self.out.take().ok_or_else(|| self.closed())?;
        let file = out
            .into_inner()
            .map_err(|e| format!("--stats {}", e.error()))?;
        file.commit().map_err(|e| format!("--stats {e}"))
    }
}

impl Drop for StatsWriter {
    /// The run stopped for another reason: the rows so far are whole lines, so they are kept
    /// (and if writing them fails, nothing is left).
    fn drop(&mut self) {
        if self.out.is_some() {
            if let Err(e) = self.flush() {
                tracing::error!("{e}");
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use aerie_sim_bridge::StreamState;
    use aerie_terrain::camera::Attitude;
    use glam::DVec3;

    #[test]
    fn rows_round_trip_exactly_and_fill_every_column() {
        let pose = AircraftPose {
            position: DVec3::new(1234.5678901234, -0.1, 2999.999999),
            attitude: Attitude::from_degrees(359.9, -12.5, 3.25),
        };
        let geo = GeoMapping {
            south_lat_deg: 47.0,
            west_lon_deg: 11.0,
            dlat_deg: 1.0 / 1200.0,
            dlon_deg: 1.0 / 1200.0,
            spacing_x: 62.79,
            spacing_y: 92.65,
            projected: None,
        };
        let row = FrameRow {
            frame: 7,
            wall_s: 0.125,
            pose,
            origin: PoseOrigin::Input(PoseInfo {
                host_frame: 42,
                sync_target: Some(41),
                sim_time_s: 0.7,
                age_s: 0.0123,
                extrapolated: true,
                state: StreamState::Live,
            }),
            triangles: Some(5000),
            frame_ms: Some(16.5),
            terrain: Some(TerrainColumns {
                tiles_late: 3,
                tiles_late_stream: 2,
                terrain_data_us: 41.5,
                budget_bytes: 1 << 30,
                ..Default::default()
            }),
        };
        let line = format_row(&row, Some(&geo));
        let cols: Vec<&str> = line.trim_end().split(',').collect();
        let names: Vec<&str> = HEADER.split(',').collect();
        assert_eq!(cols.len(), names.len());
        let col = |n: &str| cols[names.iter().position(|h| *h == n).unwrap()];
        assert_eq!(col("host_frame"), "42");
        assert_eq!(col("sync_target"), "41");
        assert_eq!(col("x_m").parse::<f64>().unwrap(), pose.position.x);
        assert_eq!(col("z_m").parse::<f64>().unwrap(), pose.position.z);
        let lat: f64 = col("lat_deg").parse().unwrap();
        // The world frame is ENU at the grid's south-west sample, on the ellipsoid.
        let want = aerie_terrain::geodesy::LocalTangentPlane::new(
            aerie_terrain::geodesy::Geodetic::new(47.0, 11.0, 0.0),
        )
        .enu_to_geodetic(pose.position);
        assert!((lat - want.lat_deg).abs() < 1e-12, "{lat} vs {want:?}");
        assert!(lat < 47.0 && lat > 46.999_99, "{lat}");
        assert!((col("heading_deg").parse::<f64>().unwrap() - 359.9).abs() < 1e-9);
        assert_eq!(col("extrapolated"), "1");
        assert_eq!(col("stream"), "live");
        assert_eq!(col("triangles"), "5000");
        assert_eq!(col("tiles_late_stream"), "2");
        assert_eq!(col("terrain_data_us"), "41.5");
        assert_eq!(col("terrain_budget_bytes"), "1073741824");
        // Without input or geo-reference those columns are empty.
        let builtin = FrameRow {
            origin: PoseOrigin::Builtin,
            triangles: None,
            terrain: None,
            ..row
        };
        let line = format_row(&builtin, None);
        let cols: Vec<&str> = line.trim_end().split(',').collect();
        assert_eq!(cols.len(), names.len());
        assert_eq!(cols[2], "");
        assert_eq!(cols[8], "");
        assert_eq!(cols[16], "builtin");
    }

    fn row_n(frame: u64) -> FrameRow {
        FrameRow {
            frame,
            wall_s: frame as f64 / 60.0,
            pose: AircraftPose {
                position: DVec3::new(1.0, 2.0, 3.0),
                attitude: Attitude::from_degrees(10.0, 0.0, 0.0),
            },
            origin: PoseOrigin::Builtin,
            triangles: Some(1000),
            frame_ms: Some(16.0),
            terrain: None,
        }
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    /// Writes `n` rows and finishes; the first error.
    fn write_rows(w: &mut StatsWriter, n: u64) -> Result<(), String> {
        for f in 0..n {
            w.row(&row_n(f))?;
        }
        w.flush()
    }

    #[test]
    fn a_full_disk_stops_with_the_file_named_and_leaves_no_cut_csv() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("stats.csv");
        let fs = aerie_io::FaultyFs::new(aerie_io::Faults::full_after(20_000));
        let mut w = StatsWriter::create_in(fs.shared(), &p, None).unwrap();
        let err = write_rows(&mut w, 5000).unwrap_err();
        assert!(
            err.contains("--stats") && err.contains("stats.csv"),
            "{err}"
        );
        assert!(err.contains("No space left on device"), "{err}");
        // Later rows are refused, not silently dropped.
        assert!(w.row(&row_n(0)).is_err());
        drop(w);
        assert!(names(dir.path()).is_empty(), "{:?}", names(dir.path()));
    }

    #[test]
    fn rows_are_complete_when_finished_or_dropped_after_another_failure() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("stats.csv");
        let mut w = StatsWriter::create(&p, None).unwrap();
        // Nothing appears under the name until the run ends.
        w.row(&row_n(0)).unwrap();
        assert!(!p.exists());
        write_rows(&mut w, 3).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(std::fs::read_to_string(&p).unwrap().lines().count(), 5);
        // A run that stops early (dropped without `flush`) keeps its whole rows.
        let q = dir.path().join("early.csv");
        let mut w = StatsWriter::create(&q, None).unwrap();
        for f in 0..10 {
            w.row(&row_n(f)).unwrap();
        }
        drop(w);
        let text = std::fs::read_to_string(&q).unwrap();
        assert_eq!(text.lines().count(), 11);
        assert!(text.ends_with('\n'));
        assert_eq!(names(dir.path()), ["early.csv", "stats.csv"]);
    }

    #[test]
    fn a_real_full_tmpfs_leaves_no_cut_csv() {
        let disk = match aerie_io::tmpfs::SmallTmpfs::mount(16 * 1024) {
            Ok(d) => d,
            Err(why) => {
                eprintln!("skipped (no small tmpfs: {why}); the injected ENOSPC test covers it");
                return;
            }
        };
        let p = disk.path().join("stats.csv");
        let mut w = StatsWriter::create(&p, None).unwrap();
        let err = write_rows(&mut w, 5000).unwrap_err();
        assert!(
            err.contains("stats.csv") && err.contains("No space left"),
            "{err}"
        );
        drop(w);
        assert!(disk.entries().is_empty(), "{:?}", disk.entries());
    }
}
