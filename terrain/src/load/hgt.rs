//! SRTM `.hgt` tiles (and zips holding one): big-endian i16, no header, north row first,
//! size known only from the file length, position only from the file name.

use std::path::Path;

use super::archive::{open_zip, read_zip_entry, zip_names};
use super::error::{format_err, read_file, size_err, DemError};
use super::finish::finish;
use super::placement::Placement;
use crate::Heightfield;

/// SRTM nodata marker.
const VOID: i16 = -32768;
/// (samples per side, arc-seconds) of the accepted tile sizes.
const TILE_SIDES: [(usize, u32); 2] = [(1201, 3), (3601, 1)];

fn accepted_lengths() -> String {
    TILE_SIDES
        .iter()
        .map(|&(n, s)| format!("{} bytes ({n}×{n}, SRTM{s})", n * n * 2))
        .collect::<Vec<_>>()
        .join(" or ")
}

/// South-west corner (lat, lon) in whole degrees from a name like `N47E011` or `s12w074.hgt`.
/// Anything after the 7 characters must start with '.', so `N47E011x.hgt` is not a tile.
pub(crate) fn parse_tile_name(name: &str) -> Option<(f64, f64)> {
    let b = name.as_bytes();
    if b.len() < 7 || (b.len() > 7 && b[7] != b'.') {
        return None;
    }
    let digits = |s: &[u8]| -> Option<u32> {
        s.iter().try_fold(0u32, |acc, &c| {
            c.is_ascii_digit().then(|| acc * 10 + u32::from(c - b'0'))
        })
    };
    let lat = digits(&b[1..3])?;
    let lon = digits(&b[4..7])?;
    let lat = match b[0].to_ascii_uppercase() {
        b'N' if lat <= 89 => f64::from(lat),
        b'S' if lat <= 90 => -f64::from(lat),
        _ => return None,
    };
    let lon = match b[3].to_ascii_uppercase() {
        b'E' if lon <= 179 => f64::from(lon),
        b'W' if lon <= 180 => -f64::from(lon),
        _ => return None,
    };
    Some((lat, lon))
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

pub(super) fn load_hgt(path: &Path) -> Result<Heightfield, DemError> {
    let tile = read_tile(path)?;
    tile.finish(path)
}

/// One SRTM tile decoded but not finished (no flip, no void fill): what stitching needs.
#[derive(Debug, Clone)]
pub(crate) struct HgtTile {
    /// South-west corner from the name, whole degrees.
    pub lat: f64,
    pub lon: f64,
    /// Samples per side (1201 or 3601).
    pub n: usize,
    /// Arc-seconds between samples (3 or 1).
    pub arcsec: u32,
    /// Row-major in file order (row 0 = north), NaN = void.
    pub samples: Vec<f32>,
}

impl HgtTile {
    /// Degrees between samples.
    pub(crate) fn step_deg(&self) -> f64 {
        1.0 / (3600 / self.arcsec) as f64
    }

    /// Flipped, checked and void-filled: the tile as a heightfield.
    pub(crate) fn finish(self, path: &Path) -> Result<Heightfield, DemError> {
        let d = self.step_deg();
        let place = Placement::geographic(self.lat, self.lon, d, d, self.n);
        finish(path, self.n, self.n, self.samples, true, place)
    }
}

/// Reads a `.hgt`, `.hgt.zip` or `.zip` tile without finishing it.
pub(crate) fn read_tile(path: &Path) -> Result<HgtTile, DemError> {
    let name = file_name(path).to_ascii_lowercase();
    if name.ends_with(".zip") {
        read_zip_tile(path)
    } else {
        let bytes = read_file(path)?;
        decode_tile(path, &file_name(path), &bytes)
    }
}

/// Decodes tile bytes; `path` is only used in messages, `tile_name` gives the position.
fn decode_tile(path: &Path, tile_name: &str, bytes: &[u8]) -> Result<HgtTile, DemError> {
    let Some(&(n, arcsec)) = TILE_SIDES.iter().find(|(n, _)| n * n * 2 == bytes.len()) else {
        return Err(size_err(
            path,
            format!(
                "{} bytes is not an SRTM tile size; accepted: {}",
                bytes.len(),
                accepted_lengths()
            ),
        ));
    };
    let (lat, lon) = parse_tile_name(tile_name).ok_or_else(|| {
        format_err(
            path,
            format!(
                "tile name `{tile_name}` does not give the south-west corner; expected e.g. N47E011.hgt or S12W074.hgt"
            ),
        )
    })?;
    let samples: Vec<f32> = bytes
        .chunks_exact(2)
        .map(|b| match i16::from_be_bytes([b[0], b[1]]) {
            VOID => f32::NAN,
            v => f32::from(v),
        })
        .collect();
    Ok(HgtTile {
        lat,
        lon,
        n,
        arcsec,
        samples,
    })
}

/// Puts the zip entry's name into a content error so the message says where inside the zip.
fn in_entry(e: DemError, entry: &str) -> DemError {
    match e {
        DemError::Size { path, reason } => DemError::Size {
            path,
            reason: format!("zip entry `{entry}`: {reason}"),
        },
        DemError::Format { path, reason } => DemError::Format {
            path,
            reason: format!("zip entry `{entry}`: {reason}"),
        },
        other => other,
    }
}

/// `.hgt.zip` or `.zip` with exactly one `.hgt` entry, unzipped in memory.
pub(super) fn load_hgt_zip(path: &Path) -> Result<Heightfield, DemError> {
    let tile = read_zip_tile(path)?;
    tile.finish(path)
}

fn read_zip_tile(path: &Path) -> Result<HgtTile, DemError> {
    let bytes = read_file(path)?;
    let mut zip = open_zip(path, &bytes)?;
    let names = zip_names(&zip);
    let hgts: Vec<usize> = names
        .iter()
        .enumerate()
        .filter(|(_, n)| n.to_ascii_lowercase().ends_with(".hgt"))
        .map(|(i, _)| i)
        .collect();
    let index = match hgts.as_slice() {
        [i] => *i,
        [] => {
            return Err(format_err(
                path,
                format!(
                    "zip holds no .hgt entry ({} entries: {})",
                    names.len(),
                    preview(&names)
                ),
            ))
        }
        many => {
            return Err(format_err(
                path,
                format!(
                    "zip holds {} .hgt entries, expected exactly one: {}",
                    many.len(),
                    preview(&hgts.iter().map(|&i| names[i].clone()).collect::<Vec<_>>())
                ),
            ))
        }
    };
    let max = TILE_SIDES.iter().map(|(n, _)| n * n * 2).max().unwrap_or(0) as u64;
    let entry = &names[index];
    let data = read_zip_entry(path, &mut zip, index, max)?;
    // The entry's base name gives the tile position; fall back to the zip's own name.
    let base = entry.rsplit(['/', '\\']).next().unwrap_or(entry);
    let tile_name = if parse_tile_name(base).is_some() {
        base.to_string()
    } else {
        file_name(path)
    };
    decode_tile(path, &tile_name, &data).map_err(|e| in_entry(e, entry))
}

fn preview(names: &[String]) -> String {
    if names.is_empty() {
        return "(empty)".into();
    }
    let mut s = names.iter().take(5).cloned().collect::<Vec<_>>().join(", ");
    if names.len() > 5 {
        s.push_str(", …");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load::load_dem;
    use crate::GeoReference;
    use std::io::Write as _;

    const N: usize = 1201;

    /// Height of file sample (file_row, col), file row 0 = north. Planar, so an interpolated
    /// void must land exactly on the plane.
    fn plane(file_row: usize, col: usize) -> i16 {
        (1000 + col as i32 - 2 * file_row as i32) as i16
    }

    const VOIDS: [(usize, usize); 4] = [(10, 20), (600, 600), (600, 601), (600, 602)];

    fn tile_bytes() -> Vec<u8> {
        let mut out = Vec::with_capacity(N * N * 2);
        for r in 0..N {
            for c in 0..N {
                let v = if VOIDS.contains(&(r, c)) {
                    VOID
                } else {
                    plane(r, c)
                };
                out.extend_from_slice(&v.to_be_bytes());
            }
        }
        out
    }

    /// Independent WGS84 radii (from a and b) for checking the loader's spacing.
    fn expected_spacing(lat_deg: f64, d_deg: f64) -> (f64, f64) {
        let a = 6_378_137.0_f64;
        let b = a * (1.0 - 1.0 / 298.257_223_563);
        let p = lat_deg.to_radians();
        let q = (a * a * p.cos().powi(2) + b * b * p.sin().powi(2)).sqrt();
        let m = (a * b).powi(2) / q.powi(3);
        let n = a * a / q;
        (d_deg.to_radians() * n * p.cos(), d_deg.to_radians() * m)
    }

    #[test]
    fn hgt_flip_voids_geo_and_spacing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("N47E011.hgt");
        std::fs::write(&p, tile_bytes()).unwrap();
        let hf = load_dem(&p).unwrap();
        assert_eq!((hf.width, hf.height), (N, N));
        // North row (file row 0) ends up last; south row (file row 1200) first.
        for c in [0, 5, 1200] {
            assert_eq!(hf.at(c, N - 1), f32::from(plane(0, c)));
            assert_eq!(hf.at(c, 0), f32::from(plane(N - 1, c)));
        }
        assert_eq!(hf.voids_filled, VOIDS.len());
        for &(r, c) in &VOIDS {
            let row = N - 1 - r;
            let v = hf.at(c, row);
            let neighbours = [
                hf.at(c - 1, row),
                hf.at(c + 3, row),
                hf.at(c, row - 1),
                hf.at(c, row + 1),
            ];
            let (lo, hi) = neighbours
                .iter()
                .fold((f32::MAX, f32::MIN), |(l, h), &x| (l.min(x), h.max(x)));
            assert!(
                lo < v && v < hi,
                "void ({c},{row}) = {v} not in ({lo},{hi})"
            );
            let want = f32::from(plane(r, c));
            assert!(
                (v - want).abs() < 0.01,
                "void ({c},{row}) = {v}, plane {want}"
            );
        }
        assert!(hf.heights.iter().all(|h| h.is_finite()));
        assert_eq!(
            hf.geo,
            Some(GeoReference::Geographic {
                south_lat_deg: 47.0,
                west_lon_deg: 11.0,
                dlat_deg: 1.0 / 1200.0,
                dlon_deg: 1.0 / 1200.0,
            })
        );
        let (ew, ns) = expected_spacing(47.5, 1.0 / 1200.0);
        assert!((hf.spacing_x - ew).abs() < 1e-6, "{} vs {ew}", hf.spacing_x);
        assert!((hf.spacing_y - ns).abs() < 1e-6, "{} vs {ns}", hf.spacing_y);
        assert!(hf.spacing_note.contains("47.500°N"), "{}", hf.spacing_note);
        assert!(hf.spacing_note.contains("3\""), "{}", hf.spacing_note);
        assert!(
            hf.spacing_note.contains(&format!("{ew:.2} m E-W")),
            "{}",
            hf.spacing_note
        );
    }

    #[test]
    fn southern_western_tile_name() {
        assert_eq!(parse_tile_name("S12W074.hgt"), Some((-12.0, -74.0)));
        assert_eq!(parse_tile_name("n40w074.hgt"), Some((40.0, -74.0)));
        assert_eq!(parse_tile_name("N47E011"), Some((47.0, 11.0)));
        assert_eq!(parse_tile_name("N47E011.SRTMGL1.hgt"), Some((47.0, 11.0)));
        for bad in [
            "tile.hgt",
            "N47E11.hgt",
            "N47E0111.hgt",
            "X47E011.hgt",
            "N91E011.hgt",
            "N47E181.hgt",
            "N4éE011.hgt",
            "",
        ] {
            assert_eq!(parse_tile_name(bad), None, "{bad}");
        }
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("S12W074.hgt");
        std::fs::write(&p, tile_bytes()).unwrap();
        let hf = load_dem(&p).unwrap();
        assert!(matches!(
            hf.geo,
            Some(GeoReference::Geographic { south_lat_deg, west_lon_deg, .. })
                if south_lat_deg == -12.0 && west_lon_deg == -74.0
        ));
        assert!(hf.spacing_note.contains("11.500°S"), "{}", hf.spacing_note);
    }

    #[test]
    fn unparsable_name_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("mytile.hgt");
        std::fs::write(&p, tile_bytes()).unwrap();
        let msg = load_dem(&p).unwrap_err().to_string();
        assert!(msg.starts_with(&p.display().to_string()), "{msg}");
        assert!(
            msg.contains("mytile.hgt") && msg.contains("N47E011"),
            "{msg}"
        );
    }

    #[test]
    fn wrong_length_names_found_and_accepted() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("N47E011.hgt");
        std::fs::write(&p, vec![0u8; 1000]).unwrap();
        let e = load_dem(&p).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, DemError::Size { .. }), "{e:?}");
        assert!(msg.starts_with(&format!("{}: ", p.display())), "{msg}");
        for part in ["1000 bytes", "2884802", "25934402"] {
            assert!(msg.contains(part), "{msg} lacks {part}");
        }
        // Off by one sample is also wrong.
        std::fs::write(&p, vec![0u8; N * N * 2 - 2]).unwrap();
        assert!(load_dem(&p)
            .unwrap_err()
            .to_string()
            .contains("2884800 bytes"));
    }

    #[test]
    fn all_void_tile_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("N00E000.hgt");
        let bytes: Vec<u8> = (0..N * N).flat_map(|_| VOID.to_be_bytes()).collect();
        std::fs::write(&p, bytes).unwrap();
        let e = load_dem(&p).unwrap_err();
        assert!(
            matches!(e, DemError::AllVoid { count, .. } if count == N * N),
            "{e:?}"
        );
    }

    #[test]
    fn srtm1_size_gives_one_arcsecond_grid() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("N60E010.hgt");
        let bytes: Vec<u8> = (0..3601 * 3601)
            .flat_map(|i: usize| ((i % 3601) as i16).to_be_bytes())
            .collect();
        std::fs::write(&p, bytes).unwrap();
        let hf = load_dem(&p).unwrap();
        assert_eq!((hf.width, hf.height), (3601, 3601));
        let (ew, ns) = expected_spacing(60.5, 1.0 / 3600.0);
        assert!((hf.spacing_x - ew).abs() < 1e-6 && (hf.spacing_y - ns).abs() < 1e-6);
        assert!(hf.spacing_note.contains("1\""), "{}", hf.spacing_note);
        assert_eq!(hf.at(7, 0), 7.0);
    }

    fn write_zip(path: &Path, entries: &[(&str, &[u8])]) {
        let f = std::fs::File::create(path).unwrap();
        let mut z = zip::ZipWriter::new(f);
        let opts = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Deflated);
        for (name, data) in entries {
            z.start_file(*name, opts).unwrap();
            z.write_all(data).unwrap();
        }
        z.finish().unwrap();
    }

    #[test]
    fn hgt_zip_matches_plain_hgt() {
        let dir = tempfile::tempdir().unwrap();
        let bytes = tile_bytes();
        let plain = dir.path().join("N47E011.hgt");
        std::fs::write(&plain, &bytes).unwrap();
        let zipped = dir.path().join("N47E011.hgt.zip");
        write_zip(&zipped, &[("N47E011.hgt", &bytes)]);
        let a = load_dem(&plain).unwrap();
        let b = load_dem(&zipped).unwrap();
        assert_eq!(a.heights, b.heights);
        assert_eq!(a.geo, b.geo);
        assert_eq!(b.voids_filled, VOIDS.len());

        // Plain .zip: the position comes from the entry, whatever the zip is called.
        let other = dir.path().join("download.zip");
        write_zip(
            &other,
            &[("readme.txt", b"hi"), ("tiles/S05W060.hgt", &bytes)],
        );
        let c = load_dem(&other).unwrap();
        assert!(
            matches!(c.geo, Some(GeoReference::Geographic { south_lat_deg, west_lon_deg, .. })
            if south_lat_deg == -5.0 && west_lon_deg == -60.0)
        );

        // Entry without a tile name: fall back to the zip's name.
        let fallback = dir.path().join("N10E020.hgt.zip");
        write_zip(&fallback, &[("data.hgt", &bytes)]);
        let d = load_dem(&fallback).unwrap();
        assert!(
            matches!(d.geo, Some(GeoReference::Geographic { south_lat_deg, west_lon_deg, .. })
            if south_lat_deg == 10.0 && west_lon_deg == 20.0)
        );
    }

    #[test]
    fn bad_zips_are_errors_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let corrupt = dir.path().join("N47E011.hgt.zip");
        std::fs::write(&corrupt, b"PK\x03\x04 definitely not a zip").unwrap();
        let msg = load_dem(&corrupt).unwrap_err().to_string();
        assert!(
            msg.starts_with(&format!("{}: ", corrupt.display())),
            "{msg}"
        );
        assert!(msg.contains("zip"), "{msg}");

        let none = dir.path().join("empty.zip");
        write_zip(&none, &[("a.txt", b"x")]);
        let msg = load_dem(&none).unwrap_err().to_string();
        assert!(
            msg.contains("no .hgt entry") && msg.contains("a.txt"),
            "{msg}"
        );

        let two = dir.path().join("two.zip");
        write_zip(&two, &[("N01E001.hgt", b"x"), ("N01E002.hgt", b"y")]);
        let msg = load_dem(&two).unwrap_err().to_string();
        assert!(msg.contains("2 .hgt entries"), "{msg}");

        let short = dir.path().join("N01E001.hgt.zip");
        write_zip(&short, &[("N01E001.hgt", &[0u8; 10])]);
        let msg = load_dem(&short).unwrap_err().to_string();
        assert!(
            msg.contains("`N01E001.hgt`") && msg.contains("10 bytes") && !msg.contains('\n'),
            "{msg}"
        );
    }
}
