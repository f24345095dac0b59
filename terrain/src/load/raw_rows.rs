//! A raw grid (`.f32`/`.r32`/`.raw`/`.u16`/`.r16` with its `<file>.json` sidecar) read a row at
//! a time with positioned reads, padded as [`crate::dataset::Dataset`] pads it: the streamed
//! import's source, so a grid larger than memory never has to be held whole.
//!
//! Row `r` here is the padded dataset's row `r` (row 0 = south): the file's rows (flipped when
//! the sidecar says `north_up`), then the last real row repeated; each row extended east by
//! its last real sample. Every sample passes the same checks as the whole-file loader (finite,
//! within ±[`MAX_HEIGHT_M`](super::finish::MAX_HEIGHT_M)), with the same messages: a bad sample
//! is an error naming its byte offset or file column and row, found when its row is read.

use std::path::{Path, PathBuf};

use aerie_io::InFile;

use super::error::{io_err, size_err, DemError};
use super::finish::{check_heights, check_spacing};
use super::raw::{decode, raw_grid, RawGrid, SampleFormat};
use crate::dataset::padded_side;
use crate::GeoReference;

/// A raw grid open for reading rows.
pub struct RawRows {
    path: PathBuf,
    file: Box<dyn InFile>,
    grid: RawGrid,
    padded: (usize, usize),
}

impl RawRows {
    /// Opens `path` when it is a raw grid by its extension (`Ok(None)` otherwise): its sidecar
    /// is read and checked, and the file's length against it; no sample is read.
    pub fn open(path: &Path) -> Result<Option<Self>, DemError> {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        let default = if [".f32", ".r32", ".raw"].iter().any(|e| name.ends_with(e)) {
            SampleFormat::F32Le
        } else if [".u16", ".r16"].iter().any(|e| name.ends_with(e)) {
            SampleFormat::U16Le
        } else {
            return Ok(None);
        };
        let grid = raw_grid(path, default)?;
        let p = &grid.place;
        check_spacing(path, p.spacing_x, p.spacing_y, &p.spacing_note)?;
        let file = aerie_io::real().open(path).map_err(|e| io_err(path, &e))?;
        let padded = (padded_side(grid.width), padded_side(grid.height));
        Ok(Some(Self {
            path: path.to_path_buf(),
            file,
            grid,
            padded,
        }))
    }

    /// Real samples per row and real rows.
    pub fn valid_size(&self) -> (usize, usize) {
        (self.grid.width, self.grid.height)
    }

    /// Samples per padded row and padded rows (2^K + 1 each).
    pub fn padded_size(&self) -> (usize, usize) {
        self.padded
    }

    /// Metres between columns and between rows.
    pub fn spacing(&self) -> (f64, f64) {
        (self.grid.place.spacing_x, self.grid.place.spacing_y)
    }

    pub fn geo(&self) -> Option<&GeoReference> {
        self.grid.place.geo.as_ref()
    }

    /// How the spacing was obtained (the loader's sentence).
    pub fn spacing_note(&self) -> &str {
        &self.grid.place.spacing_note
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Padded row `r` into `out` (`padded_size().0` samples).
    pub fn read_row(&self, r: usize, out: &mut [f32]) -> Result<(), DemError> {
        let (w, h) = (self.grid.width, self.grid.height);
        assert!(
            r < self.padded.1 && out.len() == self.padded.0,
            "row {r} out of the grid"
        );
        let real = r.min(h - 1);
        let file_row = if self.grid.north_up {
            h - 1 - real
        } else {
            real
        };
        let item = self.grid.format.bytes();
        let offset = (file_row * w * item) as u64;
        let mut bytes = vec![0u8; w * item];
        self.file.read_exact_at(&mut bytes, offset).map_err(|e| {
            size_err(
                &self.path,
                format!(
                    "reading row {file_row} ({} bytes at byte offset {offset}) failed: {e}",
                    bytes.len()
                ),
            )
        })?;
        let mut row = Vec::with_capacity(w);
        let g = &self.grid;
        decode(
            &self.path,
            &bytes,
            g.format,
            w,
            g.scale,
            g.offset,
            file_row * w,
            &mut row,
        )?;
        check_heights(&self.path, &row, w, file_row)?;
        out[..w].copy_from_slice(&row);
        let edge = row[w - 1];
        out[w..].fill(edge);
        Ok(())
    }
}
