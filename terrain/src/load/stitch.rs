//! Stitching adjacent SRTM tiles (`.hgt`, `.hgt.zip`) into one grid.
//!
//! Neighbouring SRTM tiles share one row or column (samples lie on the integer-degree lines).
//! The mosaic keeps each shared sample once: an R × C block of n×n tiles becomes
//! `(n−1)·R + 1` rows × `(n−1)·C + 1` columns, north row first in file order, exactly as the
//! reference in `shared/data/dem/SOURCES.md` ("How to stitch the SRTM3 tiles"): on a seam the
//! southern / eastern tile's sample is kept, unless it is a void and the other is not. Voids are
//! filled once, over the whole mosaic, and counted. The tiles must have one resolution and form
//! a full rectangle; a gap, a duplicate or a mixed resolution is an error naming the tiles.
//! The mosaic's spacing uses the local tangent plane at its centre latitude.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::error::{format_err, io_err, show, DemError};
use super::finish::finish;
use super::hgt::{read_tile, HgtTile};
use super::placement::Placement;
use crate::Heightfield;

/// What stitching did, for the load summary.
#[derive(Debug, Clone, PartialEq)]
pub struct StitchInfo {
    /// Tile rows (latitudes) and columns (longitudes).
    pub tile_rows: usize,
    pub tile_cols: usize,
    /// South-west tile corner, whole degrees.
    pub south_lat: i32,
    pub west_lon: i32,
    /// Arc-seconds between samples (3 or 1).
    pub arcsec: u32,
    /// Shared seam samples on which two valid tile values differed (the kept one is the
    /// southern/eastern tile's); 0 for clean SRTM.
    pub seam_mismatches: usize,
}

impl StitchInfo {
    /// "2×3 SRTM3 tiles N36..N37 W005..W003".
    pub fn describe(&self) -> String {
        let lat = |v: i32| {
            if v < 0 {
                format!("S{:02}", -v)
            } else {
                format!("N{v:02}")
            }
        };
        let lon = |v: i32| {
            if v < 0 {
                format!("W{:03}", -v)
            } else {
                format!("E{v:03}")
            }
        };
        format!(
            "{}×{} SRTM{} tiles {}..{} {}..{}, {} seam mismatches",
            self.tile_rows,
            self.tile_cols,
            self.arcsec,
            lat(self.south_lat),
            lat(self.south_lat + self.tile_rows as i32 - 1),
            lon(self.west_lon),
            lon(self.west_lon + self.tile_cols as i32 - 1),
            self.seam_mismatches
        )
    }
}

/// True for names this module stitches: `*.hgt`, `*.hgt.zip`, `*.zip`.
fn is_tile_file(p: &Path) -> bool {
    let name = p
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    name.ends_with(".hgt") || name.ends_with(".hgt.zip")
}

/// The `.hgt` / `.hgt.zip` files of a folder, sorted by name; other files are ignored.
pub fn tile_files(dir: &Path) -> Result<Vec<PathBuf>, DemError> {
    let rd = std::fs::read_dir(dir).map_err(|e| io_err(dir, &e))?;
    let mut out = Vec::new();
    for entry in rd {
        let entry = entry.map_err(|e| io_err(dir, &e))?;
        let p = entry.path();
        if p.is_file() && is_tile_file(&p) {
            out.push(p);
        }
    }
    out.sort();
    if out.is_empty() {
        return Err(format_err(
            dir,
            "folder holds no SRTM tiles (*.hgt, *.hgt.zip) to stitch",
        ));
    }
    Ok(out)
}

/// Stitches every `.hgt`/`.hgt.zip` tile of a folder.
pub fn stitch_folder(dir: &Path) -> Result<(Heightfield, StitchInfo), DemError> {
    let files = tile_files(dir)?;
    stitch_at(dir, &files)
}

/// Stitches a list of tiles; errors about the whole set name the first file.
pub fn stitch_tiles(paths: &[PathBuf]) -> Result<(Heightfield, StitchInfo), DemError> {
    let Some(first) = paths.first() else {
        return Err(DemError::Format {
            path: "(no files)".into(),
            reason: "no SRTM tiles given to stitch".into(),
        });
    };
    stitch_at(first, paths)
}

fn tile_label(lat: i32, lon: i32) -> String {
    format!(
        "{}{:02}{}{:03}",
        if lat < 0 { 'S' } else { 'N' },
        lat.abs(),
        if lon < 0 { 'W' } else { 'E' },
        lon.abs()
    )
}

/// `whole` names the set in messages about the set (a folder, or the first file).
fn stitch_at(whole: &Path, paths: &[PathBuf]) -> Result<(Heightfield, StitchInfo), DemError> {
    // Read and decode all tiles (2.9 MB each for SRTM3), two at a time.
    let mut tiles: Vec<Option<Result<HgtTile, DemError>>> =
        (0..paths.len()).map(|_| None).collect();
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
        .min(paths.len().max(1));
    let next = std::sync::atomic::AtomicUsize::new(0);
    let results = std::sync::Mutex::new(&mut tiles);
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                if i >= paths.len() {
                    break;
                }
                let t = read_tile(&paths[i]);
                results.lock().unwrap_or_else(|e| e.into_inner())[i] = Some(t);
            });
        }
    });
    let mut by_pos: BTreeMap<(i32, i32), (usize, HgtTile)> = BTreeMap::new();
    let mut first: Option<(usize, u32, usize)> = None; // (n, arcsec, index)
    for (i, t) in tiles.into_iter().enumerate() {
        let tile = t.expect("every tile was read")?;
        match first {
            None => first = Some((tile.n, tile.arcsec, i)),
            Some((n, arcsec, j)) if n != tile.n => {
                return Err(format_err(
                    &paths[i],
                    format!(
                        "mixed resolutions: this tile is SRTM{} ({}×{}) but {} is SRTM{arcsec} ({n}×{n}); stitch tiles of one resolution",
                        tile.arcsec,
                        tile.n,
                        tile.n,
                        show(&paths[j])
                    ),
                ))
            }
            _ => {}
        }
        let pos = (tile.lat as i32, tile.lon as i32);
        if let Some((j, _)) = by_pos.get(&pos) {
            return Err(format_err(
                &paths[i],
                format!(
                    "tile {} is given twice (also {})",
                    tile_label(pos.0, pos.1),
                    show(&paths[*j])
                ),
            ));
        }
        by_pos.insert(pos, (i, tile));
    }
    let (n, arcsec, _) = first.expect("at least one tile");
    let lat_min = by_pos.keys().map(|k| k.0).min().unwrap_or(0);
    let lat_max = by_pos.keys().map(|k| k.0).max().unwrap_or(0);
    let lon_min = by_pos.keys().map(|k| k.1).min().unwrap_or(0);
    let lon_max = by_pos.keys().map(|k| k.1).max().unwrap_or(0);
    let (rows, cols) = (
        (lat_max - lat_min + 1) as usize,
        (lon_max - lon_min + 1) as usize,
    );
    let missing: Vec<String> = (lat_min..=lat_max)
        .rev()
        .flat_map(|la| (lon_min..=lon_max).map(move |lo| (la, lo)))
        .filter(|p| !by_pos.contains_key(p))
        .map(|(la, lo)| tile_label(la, lo))
        .collect();
    if !missing.is_empty() {
        let mut list = missing
            .iter()
            .take(8)
            .cloned()
            .collect::<Vec<_>>()
            .join(", ");
        if missing.len() > 8 {
            list.push_str(", …");
        }
        return Err(format_err(
            whole,
            format!(
                "the {} tiles do not form a full rectangle {}..{}: {} missing ({list})",
                by_pos.len(),
                tile_label(lat_min, lon_min),
                tile_label(lat_max, lon_max),
                missing.len()
            ),
        ));
    }
    let step = n - 1;
    let (height, width) = (step * rows + 1, step * cols + 1);
    let mut samples = vec![f32::NAN; width * height];
    let mut mismatches = 0usize;
    // North to south, west to east: later (southern/eastern) tiles overwrite shared seams.
    for la in (lat_min..=lat_max).rev() {
        for lo in lon_min..=lon_max {
            let (_, tile) = &by_pos[&(la, lo)];
            let r0 = (lat_max - la) as usize * step;
            let c0 = (lo - lon_min) as usize * step;
            for r in 0..n {
                let dst = &mut samples[(r0 + r) * width + c0..(r0 + r) * width + c0 + n];
                let src = &tile.samples[r * n..(r + 1) * n];
                let seam_row = r == 0 && la != lat_max;
                for (c, (d, &v)) in dst.iter_mut().zip(src).enumerate() {
                    let seam = seam_row || (c == 0 && lo != lon_min);
                    if seam {
                        if v.is_nan() {
                            continue;
                        }
                        if !d.is_nan() && *d != v {
                            mismatches += 1;
                        }
                    }
                    *d = v;
                }
            }
        }
    }
    let info = StitchInfo {
        tile_rows: rows,
        tile_cols: cols,
        south_lat: lat_min,
        west_lon: lon_min,
        arcsec,
        seam_mismatches: mismatches,
    };
    // The SW tile's geo-reference and spacing, re-centred on the whole mosaic.
    let (_, sw) = &by_pos[&(lat_min, lon_min)];
    let d = 1.0 / (3600 / arcsec) as f64;
    let place = Placement::geographic(sw.lat, sw.lon, d, d, height);
    drop(by_pos);
    let hf = finish(whole, width, height, samples, true, place)?;
    Ok((hf, info))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1201² tile whose sample (file_row, col) is `f(global north row, global col)`.
    fn write_tile(dir: &Path, name: &str, r0: usize, c0: usize, f: &dyn Fn(usize, usize) -> i16) {
        let mut bytes = Vec::with_capacity(1201 * 1201 * 2);
        for r in 0..1201 {
            for c in 0..1201 {
                bytes.extend_from_slice(&f(r0 + r, c0 + c).to_be_bytes());
            }
        }
        std::fs::write(dir.join(name), bytes).unwrap();
    }

    fn value(r: usize, c: usize) -> i16 {
        ((r * 7 + c * 3) % 3000) as i16
    }

    #[test]
    fn two_by_two_keeps_each_seam_once() {
        let dir = tempfile::tempdir().unwrap();
        // North row of tiles is lat 11, west column lon 20.
        write_tile(dir.path(), "N11E020.hgt", 0, 0, &value);
        write_tile(dir.path(), "N11E021.hgt", 0, 1200, &value);
        write_tile(dir.path(), "N10E020.hgt", 1200, 0, &value);
        write_tile(dir.path(), "N10E021.hgt", 1200, 1200, &value);
        std::fs::write(dir.path().join("README.txt"), "not a tile").unwrap();
        let (hf, info) = stitch_folder(dir.path()).unwrap();
        assert_eq!((hf.width, hf.height), (2401, 2401));
        assert_eq!(info.seam_mismatches, 0);
        assert_eq!((info.tile_rows, info.tile_cols), (2, 2));
        for (r, c) in [(0, 0), (1200, 1200), (2400, 2400), (17, 2000), (1199, 1201)] {
            // Heightfield row 0 = south = global north row 2400.
            assert_eq!(hf.at(c, 2400 - r), f32::from(value(r, c)), "({r},{c})");
        }
        assert!(hf.spacing_note.contains("11.000°N"), "{}", hf.spacing_note);
        assert!(matches!(
            hf.geo,
            Some(crate::GeoReference::Geographic { south_lat_deg, west_lon_deg, .. })
                if south_lat_deg == 10.0 && west_lon_deg == 20.0
        ));
    }

    #[test]
    fn gap_duplicate_and_mixed_resolution_are_errors() {
        let dir = tempfile::tempdir().unwrap();
        write_tile(dir.path(), "N11E020.hgt", 0, 0, &value);
        write_tile(dir.path(), "N10E021.hgt", 1200, 1200, &value);
        let msg = stitch_folder(dir.path()).unwrap_err().to_string();
        assert!(
            msg.contains("full rectangle") && msg.contains("N10E020") && msg.contains("N11E021"),
            "{msg}"
        );
        let a = dir.path().join("N11E020.hgt");
        let msg = stitch_tiles(&[a.clone(), a.clone()])
            .unwrap_err()
            .to_string();
        assert!(msg.contains("given twice"), "{msg}");
        let big = dir.path().join("N12E020.hgt");
        std::fs::write(&big, vec![0u8; 3601 * 3601 * 2]).unwrap();
        let msg = stitch_tiles(&[a, big]).unwrap_err().to_string();
        assert!(msg.contains("mixed resolutions"), "{msg}");
        let empty = tempfile::tempdir().unwrap();
        let msg = stitch_folder(empty.path()).unwrap_err().to_string();
        assert!(msg.contains("no SRTM tiles"), "{msg}");
    }

    #[test]
    fn void_on_a_seam_takes_the_other_tiles_value() {
        let dir = tempfile::tempdir().unwrap();
        write_tile(dir.path(), "N10E020.hgt", 0, 0, &value);
        // East tile: its first column (the seam) is void at file row 5.
        write_tile(dir.path(), "N10E021.hgt", 0, 1200, &|r, c| {
            if r == 5 && c == 1200 {
                -32768
            } else {
                value(r, c)
            }
        });
        let (hf, info) = stitch_folder(dir.path()).unwrap();
        assert_eq!(hf.voids_filled, 0);
        assert_eq!(info.seam_mismatches, 0);
        assert_eq!(hf.at(1200, 1200 - 5), f32::from(value(5, 1200)));
    }
}
