//! DEM loaders: turn elevation files (SRTM `.hgt`/`.hgt.zip`, GeoTIFF, 16-bit PNG, raw f32/u16,
//! NumPy `.npy`/`.npz`) into a [`Heightfield`] in metres, row 0 = south; [`stitch`] puts
//! adjacent SRTM tiles (a folder or a list) together into one grid.
//!
//! Every loader funnels through [`finish`] so the flip, the void fill and the sanity checks are
//! the same for all formats. Bad input is reported as a one-line [`DemError`] that names the
//! file (DESIGN.md "Conventions": bad data files stop start-up with a message naming the file,
//! the key or offset, and the reason) — never a panic.

mod geotiff;
mod hgt;
mod npy;
mod png16;
mod raw;
pub mod stitch;

use std::path::{Path, PathBuf};

use super::{GeoReference, Heightfield};

/// File name endings `load_dem` understands, for the "unknown extension" message.
const ACCEPTED_EXTENSIONS: &str =
    ".hgt, .hgt.zip, .zip, .tif, .tiff, .png, .f32, .r32, .raw, .u16, .r16, .npy, .npz";

/// Default grid spacing (metres) when a file carries none and no sidecar gives one.
pub(crate) const DEFAULT_SPACING_M: f64 = 30.0;

/// WGS84 semi-major axis, metres.
const WGS84_A: f64 = 6_378_137.0;
/// WGS84 flattening.
const WGS84_F: f64 = 1.0 / 298.257_223_563;

/// Why a DEM could not be loaded.
///
/// One variant per kind of failure so callers can react to e.g. a missing file differently;
/// `Display` is always a single line `"<path>: <reason>"` so a CLI can print it as is.
#[derive(Debug, thiserror::Error)]
pub enum DemError {
    /// The path does not exist.
    #[error("{path}: no such file")]
    NotFound { path: String },
    /// The path exists but cannot be read (permissions, a directory, I/O error).
    #[error("{path}: cannot read: {reason}")]
    Unreadable { path: String, reason: String },
    /// The file name ends in nothing `load_dem` knows.
    #[error(
        "{path}: unknown extension `{ext}` (accepted: {})",
        ACCEPTED_EXTENSIONS
    )]
    UnknownExtension { path: String, ext: String },
    /// The byte length or sample count does not match what the format or sidecar promises.
    #[error("{path}: {reason}")]
    Size { path: String, reason: String },
    /// The content is malformed or uses an unsupported variant of the format.
    #[error("{path}: {reason}")]
    Format { path: String, reason: String },
    /// A NaN or infinity where the format has no notion of nodata.
    #[error("{path}: non-finite sample {value} at (col {col}, row {row}) in file order, byte offset {offset}")]
    NonFinite {
        path: String,
        col: usize,
        row: usize,
        offset: u64,
        value: String,
    },
    /// A JSON sidecar is missing, malformed, has an unknown key or a value of the wrong type.
    /// `path` is the sidecar's own path unless the sidecar is missing.
    #[error("{path}: {reason}")]
    Sidecar { path: String, reason: String },
    /// Every sample is nodata, so there is nothing to interpolate from.
    #[error("{path}: all {count} samples are voids (nodata)")]
    AllVoid { path: String, count: usize },
}

impl DemError {
    /// The file the error is about (the DEM, or its sidecar for sidecar content errors).
    pub fn path(&self) -> &str {
        match self {
            DemError::NotFound { path }
            | DemError::Unreadable { path, .. }
            | DemError::UnknownExtension { path, .. }
            | DemError::Size { path, .. }
            | DemError::Format { path, .. }
            | DemError::NonFinite { path, .. }
            | DemError::Sidecar { path, .. }
            | DemError::AllVoid { path, .. } => path,
        }
    }
}

/// Path as shown in messages, kept on one line whatever the file is called.
pub(crate) fn show(path: &Path) -> String {
    one_line(&path.display().to_string())
}

/// Keeps foreign error texts (I/O, zip, PNG, JSON) on one line.
pub(crate) fn one_line(s: &str) -> String {
    s.replace("\r\n", "; ").replace(['\n', '\r'], "; ")
}

pub(crate) fn format_err(path: &Path, reason: impl Into<String>) -> DemError {
    DemError::Format {
        path: show(path),
        reason: one_line(&reason.into()),
    }
}

pub(crate) fn size_err(path: &Path, reason: impl Into<String>) -> DemError {
    DemError::Size {
        path: show(path),
        reason: one_line(&reason.into()),
    }
}

pub(crate) fn io_err(path: &Path, e: &std::io::Error) -> DemError {
    if e.kind() == std::io::ErrorKind::NotFound {
        DemError::NotFound { path: show(path) }
    } else {
        DemError::Unreadable {
            path: show(path),
            reason: one_line(&e.to_string()),
        }
    }
}

/// Reads a whole file, mapping "missing" and "a directory" to their own messages.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, DemError> {
    let meta = std::fs::metadata(path).map_err(|e| io_err(path, &e))?;
    if meta.is_dir() {
        return Err(DemError::Unreadable {
            path: show(path),
            reason: "is a directory".into(),
        });
    }
    std::fs::read(path).map_err(|e| io_err(path, &e))
}

/// The formats `load_dem` dispatches to, decided from the file name alone.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Hgt,
    Zip,
    Tiff,
    Png,
    RawF32,
    RawU16,
    Npy,
    Npz,
}

fn kind_of(path: &Path) -> Result<Kind, DemError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let kind = if name.ends_with(".hgt") {
        Kind::Hgt
    } else if name.ends_with(".zip") {
        Kind::Zip
    } else if name.ends_with(".tif") || name.ends_with(".tiff") {
        Kind::Tiff
    } else if name.ends_with(".png") {
        Kind::Png
    } else if name.ends_with(".f32") || name.ends_with(".r32") || name.ends_with(".raw") {
        Kind::RawF32
    } else if name.ends_with(".u16") || name.ends_with(".r16") {
        Kind::RawU16
    } else if name.ends_with(".npy") {
        Kind::Npy
    } else if name.ends_with(".npz") {
        Kind::Npz
    } else {
        let ext = match name.rfind('.') {
            Some(i) if i > 0 => one_line(&name[i..]),
            _ => "(none)".to_string(),
        };
        return Err(DemError::UnknownExtension {
            path: show(path),
            ext,
        });
    };
    Ok(kind)
}

/// Loads a DEM file into a [`Heightfield`] (metres, row 0 = south, voids filled).
///
/// The format is chosen from the file name: `.hgt`, `.hgt.zip`/`.zip` (one `.hgt` inside),
/// `.tif`/`.tiff` (GeoTIFF, one sample per pixel), `.png` (16-bit grayscale, optional `<file>.json` sidecar), `.f32`/`.r32`/`.raw`/`.u16`/`.r16`
/// (raw samples, required `<file>.json` sidecar), `.npy`/`.npz` (optional sidecar).
pub fn load_dem(path: &Path) -> Result<Heightfield, DemError> {
    // Existence first: "no such file" is the most useful message for a mistyped path.
    let meta = std::fs::metadata(path).map_err(|e| io_err(path, &e))?;
    if meta.is_dir() {
        return Err(DemError::Unreadable {
            path: show(path),
            reason: "is a directory".into(),
        });
    }
    match kind_of(path)? {
        Kind::Hgt => hgt::load_hgt(path),
        Kind::Zip => hgt::load_hgt_zip(path),
        Kind::Tiff => geotiff::load_geotiff(path),
        Kind::Png => png16::load_png(path),
        Kind::RawF32 => raw::load_raw(path, raw::SampleFormat::F32Le),
        Kind::RawU16 => raw::load_raw(path, raw::SampleFormat::U16Le),
        Kind::Npy => npy::load_npy(path),
        Kind::Npz => npy::load_npz(path),
    }
}

// ---------------------------------------------------------------------------------------------
// Zip containers (.hgt.zip, .npz)
// ---------------------------------------------------------------------------------------------

pub(crate) type Zip<'a> = zip::ZipArchive<std::io::Cursor<&'a [u8]>>;

/// Opens an in-memory zip; a corrupt archive is an error naming the file.
pub(crate) fn open_zip<'a>(path: &Path, bytes: &'a [u8]) -> Result<Zip<'a>, DemError> {
    zip::ZipArchive::new(std::io::Cursor::new(bytes))
        .map_err(|e| format_err(path, format!("not a readable zip archive: {e}")))
}

/// Names of the archive's entries in index order.
pub(crate) fn zip_names(zip: &Zip<'_>) -> Vec<String> {
    (0..zip.len())
        .map(|i| zip.name_for_index(i).unwrap_or_default().to_string())
        .collect()
}

/// Decompresses one entry, refusing to inflate more than `max_len` bytes (zip bombs).
pub(crate) fn read_zip_entry(
    path: &Path,
    zip: &mut Zip<'_>,
    index: usize,
    max_len: u64,
) -> Result<Vec<u8>, DemError> {
    use std::io::Read as _;
    let name = zip.name_for_index(index).unwrap_or_default().to_string();
    let entry_err = |e: &dyn std::fmt::Display| {
        format_err(path, format!("zip entry `{name}` cannot be read: {e}"))
    };
    let mut file = zip.by_index(index).map_err(|e| entry_err(&e))?;
    if file.size() > max_len {
        return Err(size_err(
            path,
            format!(
                "zip entry `{name}` is {} bytes, more than the {max_len} bytes accepted",
                file.size()
            ),
        ));
    }
    // The declared size is only a hint; do not trust it for a big up-front allocation.
    let mut out = Vec::with_capacity(file.size().min(1 << 26) as usize);
    (&mut file)
        .take(max_len + 1)
        .read_to_end(&mut out)
        .map_err(|e| entry_err(&e))?;
    if out.len() as u64 > max_len {
        return Err(size_err(
            path,
            format!("zip entry `{name}` inflates to more than the {max_len} bytes accepted"),
        ));
    }
    Ok(out)
}

// ---------------------------------------------------------------------------------------------
// Sidecar JSON
// ---------------------------------------------------------------------------------------------

/// `<file>.json` next to `<file>` (the whole name plus `.json`, e.g. `foo.png.json`).
pub(crate) fn sidecar_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".json");
    PathBuf::from(s)
}

/// A parsed sidecar whose keys have been checked against the loader's list.
pub(crate) struct Sidecar {
    path: PathBuf,
    map: serde_json::Map<String, serde_json::Value>,
}

impl Sidecar {
    /// Reads `<file>.json` when present. Unknown keys are rejected here so a typo
    /// (`"spacingx"`) is an error instead of a silently ignored setting.
    pub(crate) fn load(dem: &Path, allowed: &[&str]) -> Result<Option<Sidecar>, DemError> {
        let path = sidecar_path(dem);
        let bytes = match std::fs::read(&path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => {
                return Err(DemError::Sidecar {
                    path: show(&path),
                    reason: format!("cannot read sidecar: {}", one_line(&e.to_string())),
                })
            }
        };
        let value: serde_json::Value =
            serde_json::from_slice(&bytes).map_err(|e| DemError::Sidecar {
                path: show(&path),
                reason: format!("invalid JSON: {}", one_line(&e.to_string())),
            })?;
        let serde_json::Value::Object(map) = value else {
            return Err(DemError::Sidecar {
                path: show(&path),
                reason: format!("expected a JSON object, found {}", json_type(&value)),
            });
        };
        for key in map.keys() {
            if !allowed.contains(&key.as_str()) {
                return Err(DemError::Sidecar {
                    path: show(&path),
                    reason: format!(
                        "unknown key `{}` (accepted: {})",
                        one_line(key),
                        allowed.join(", ")
                    ),
                });
            }
        }
        Ok(Some(Sidecar { path, map }))
    }

    /// Like [`Sidecar::load`], for formats that cannot be read without one.
    pub(crate) fn require(dem: &Path, allowed: &[&str], needs: &str) -> Result<Sidecar, DemError> {
        Self::load(dem, allowed)?.ok_or_else(|| DemError::Sidecar {
            path: show(dem),
            reason: format!(
                "missing sidecar {} (a JSON object with {needs})",
                show(&sidecar_path(dem))
            ),
        })
    }

    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    pub(crate) fn err(&self, key: &str, reason: impl std::fmt::Display) -> DemError {
        DemError::Sidecar {
            path: show(&self.path),
            reason: one_line(&format!("key `{key}`: {reason}")),
        }
    }

    fn wrong_type(&self, key: &str, want: &str, v: &serde_json::Value) -> DemError {
        self.err(key, format!("expected {want}, found {}", json_type(v)))
    }

    /// A finite number.
    pub(crate) fn f64(&self, key: &str) -> Result<Option<f64>, DemError> {
        match self.map.get(key) {
            None => Ok(None),
            Some(v) => match v.as_f64() {
                Some(x) if x.is_finite() => Ok(Some(x)),
                _ => Err(self.wrong_type(key, "a finite number", v)),
            },
        }
    }

    /// A finite number > 0 (spacings).
    pub(crate) fn positive(&self, key: &str) -> Result<Option<f64>, DemError> {
        match self.f64(key)? {
            Some(x) if x <= 0.0 => Err(self.err(key, format!("must be > 0, found {x}"))),
            other => Ok(other),
        }
    }

    pub(crate) fn bool(&self, key: &str) -> Result<Option<bool>, DemError> {
        match self.map.get(key) {
            None => Ok(None),
            Some(serde_json::Value::Bool(b)) => Ok(Some(*b)),
            Some(v) => Err(self.wrong_type(key, "true or false", v)),
        }
    }

    /// A non-negative integer that fits in `usize`.
    pub(crate) fn usize(&self, key: &str) -> Result<Option<usize>, DemError> {
        match self.map.get(key) {
            None => Ok(None),
            Some(v) => match v.as_u64().and_then(|x| usize::try_from(x).ok()) {
                Some(x) => Ok(Some(x)),
                None => Err(self.wrong_type(key, "a non-negative integer", v)),
            },
        }
    }

    pub(crate) fn str(&self, key: &str) -> Result<Option<&str>, DemError> {
        match self.map.get(key) {
            None => Ok(None),
            Some(serde_json::Value::String(s)) => Ok(Some(s)),
            Some(v) => Err(self.wrong_type(key, "a string", v)),
        }
    }
}

fn json_type(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::Null => "null".into(),
        serde_json::Value::Bool(b) => format!("boolean {b}"),
        serde_json::Value::Number(n) => format!("number {n}"),
        serde_json::Value::String(_) => "a string".into(),
        serde_json::Value::Array(_) => "an array".into(),
        serde_json::Value::Object(_) => "an object".into(),
    }
}

/// Spacing for grids without a geo-reference: sidecar values or the 30 m default, plus the
/// sentence for `spacing_note`.
pub(crate) fn metric_spacing(sidecar: Option<&Sidecar>) -> Result<(f64, f64, String), DemError> {
    let sx = match sidecar {
        Some(s) => s.positive("spacing_x")?,
        None => None,
    };
    let sy = match sidecar {
        Some(s) => s.positive("spacing_y")?,
        None => None,
    };
    let note = match (sidecar, sx, sy) {
        (Some(s), Some(x), Some(y)) => format!(
            "from sidecar {}: {x} m E-W, {y} m N-S",
            show(s.path())
        ),
        (Some(s), x, y) if x.is_some() || y.is_some() => format!(
            "from sidecar {} with the {DEFAULT_SPACING_M} m default for the missing one: {} m E-W, {} m N-S",
            show(s.path()),
            x.unwrap_or(DEFAULT_SPACING_M),
            y.unwrap_or(DEFAULT_SPACING_M)
        ),
        _ => format!(
            "default {DEFAULT_SPACING_M} m grid (no spacing in the file or a sidecar): {DEFAULT_SPACING_M} m E-W, {DEFAULT_SPACING_M} m N-S"
        ),
    };
    Ok((
        sx.unwrap_or(DEFAULT_SPACING_M),
        sy.unwrap_or(DEFAULT_SPACING_M),
        note,
    ))
}

// ---------------------------------------------------------------------------------------------
// Geographic grids
// ---------------------------------------------------------------------------------------------

/// Ground spacing in metres `(east_west, north_south)` of a lat/lon grid with steps
/// `dlat_deg` × `dlon_deg`, on the WGS84 local tangent plane at `lat_deg`.
///
/// Uses the meridian radius M(φ) for N–S and the prime-vertical radius N(φ)·cos φ for E–W, so a
/// 3" SRTM tile at 47.5°N comes out at about 62.8 m × 92.6 m instead of a square grid.
pub fn geographic_spacing_m(lat_deg: f64, dlat_deg: f64, dlon_deg: f64) -> (f64, f64) {
    let e2 = WGS84_F * (2.0 - WGS84_F);
    let phi = lat_deg.to_radians();
    let s2 = phi.sin() * phi.sin();
    let w = (1.0 - e2 * s2).sqrt();
    let m = WGS84_A * (1.0 - e2) / (w * w * w);
    let n = WGS84_A / w;
    (
        dlon_deg.to_radians() * n * phi.cos(),
        dlat_deg.to_radians() * m,
    )
}

/// Spacing and note for a geographic grid whose south-west sample is at `south_lat_deg` and
/// which has `height` rows.
pub(crate) fn geographic_spacing_with_note(
    south_lat_deg: f64,
    dlat_deg: f64,
    dlon_deg: f64,
    height: usize,
) -> (f64, f64, String) {
    let centre = south_lat_deg + dlat_deg * (height.saturating_sub(1)) as f64 / 2.0;
    let (sx, sy) = geographic_spacing_m(centre, dlat_deg, dlon_deg);
    let hemi = if centre < 0.0 { 'S' } else { 'N' };
    let step = if (dlat_deg - dlon_deg).abs() <= 1e-12 * dlat_deg.abs().max(1e-300) {
        arcsec(dlat_deg)
    } else {
        format!("{}×{}", arcsec(dlat_deg), arcsec(dlon_deg))
    };
    let note = format!(
        "geographic {step} grid, local tangent plane at {:.3}°{hemi}: {sx:.2} m E-W, {sy:.2} m N-S",
        centre.abs()
    );
    (sx, sy, note)
}

/// `3"` for 1/1200°, `1.5"` etc.
fn arcsec(deg: f64) -> String {
    let s = deg * 3600.0;
    if (s - s.round()).abs() < 1e-6 {
        format!("{}\"", s.round())
    } else {
        format!("{s:.3}\"")
    }
}

// ---------------------------------------------------------------------------------------------
// Common finishing: flip, void fill, checks
// ---------------------------------------------------------------------------------------------

/// What a format loader hands over: samples in file row order, NaN = void.
pub(crate) struct Grid {
    pub width: usize,
    pub height: usize,
    /// Row-major in file order; NaN marks a void to fill.
    pub samples: Vec<f32>,
    /// True when file row 0 is the northern edge (flip to make row 0 south).
    pub north_up: bool,
    pub spacing_x: f64,
    pub spacing_y: f64,
    pub geo: Option<GeoReference>,
    pub spacing_note: String,
}

/// Rejects degenerate sizes with a message naming the problem (zero or below 2×2).
pub(crate) fn check_dims(path: &Path, width: usize, height: usize) -> Result<(), DemError> {
    if width == 0 || height == 0 {
        return Err(size_err(
            path,
            format!("zero-size grid ({width}×{height} samples)"),
        ));
    }
    if width < 2 || height < 2 {
        return Err(size_err(
            path,
            format!("grid {width}×{height} is smaller than the 2×2 minimum"),
        ));
    }
    Ok(())
}

/// Flips to row 0 = south, fills voids, and checks the result is usable.
pub(crate) fn finish(path: &Path, mut g: Grid) -> Result<Heightfield, DemError> {
    check_dims(path, g.width, g.height)?;
    if g.width.checked_mul(g.height) != Some(g.samples.len()) {
        return Err(size_err(
            path,
            format!(
                "{} samples for a {}×{} grid",
                g.samples.len(),
                g.width,
                g.height
            ),
        ));
    }
    if !(g.spacing_x.is_finite()
        && g.spacing_x > 0.0
        && g.spacing_y.is_finite()
        && g.spacing_y > 0.0)
    {
        return Err(format_err(
            path,
            format!("invalid grid spacing {} m × {} m", g.spacing_x, g.spacing_y),
        ));
    }
    if let Some(i) = g.samples.iter().position(|v| v.is_infinite()) {
        return Err(format_err(
            path,
            format!(
                "height out of range ({}) at (col {}, row {}) in file order after scale/offset",
                g.samples[i],
                i % g.width,
                i / g.width
            ),
        ));
    }
    if g.north_up {
        flip_rows(&mut g.samples, g.width);
    }
    let voids = g.samples.iter().filter(|v| v.is_nan()).count();
    if voids == g.samples.len() {
        return Err(DemError::AllVoid {
            path: show(path),
            count: voids,
        });
    }
    if voids > 0 {
        fill_voids(&mut g.samples, g.width, g.height, g.spacing_x, g.spacing_y);
    }
    Ok(Heightfield {
        width: g.width,
        height: g.height,
        spacing_x: g.spacing_x,
        spacing_y: g.spacing_y,
        heights: g.samples,
        geo: g.geo,
        voids_filled: voids,
        spacing_note: g.spacing_note,
    })
}

/// Reverses the row order in place.
pub(crate) fn flip_rows(samples: &mut [f32], width: usize) {
    if width == 0 {
        return;
    }
    let height = samples.len() / width;
    for r in 0..height / 2 {
        let (top, bottom) = samples.split_at_mut((height - 1 - r) * width);
        top[r * width..(r + 1) * width].swap_with_slice(&mut bottom[..width]);
    }
}

/// Fills NaN samples in place.
///
/// For each void, the nearest valid sample in each of the four axis directions (±x, ±y) is
/// found and the void gets their inverse-distance weighted mean (distance in metres, weight
/// 1/d) — along a single line this is exact linear interpolation across the gap. A void whose
/// row and column are entirely void gets nothing in the first pass; a second pass then uses
/// the values filled in the first. Every fill is a convex combination of valid samples, so it
/// lies within their min/max. O(samples) per pass, memory O(voids + width).
pub(crate) fn fill_voids(samples: &mut [f32], width: usize, height: usize, sx: f64, sy: f64) {
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for &v in samples.iter().filter(|v| !v.is_nan()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return; // all void: the caller reports it
    }
    let mut voids: Vec<usize> = (0..samples.len())
        .filter(|&i| samples[i].is_nan())
        .collect();
    let mut row_start = vec![0usize; height + 1];
    let mut last_row = vec![usize::MAX; width];
    let mut last_val = vec![0f32; width];
    while !voids.is_empty() {
        // Accumulated (Σw, Σw·v) per void, in the same row-major order as `voids`.
        let mut acc = vec![(0f64, 0f64); voids.len()];
        // row_start[r]..row_start[r+1] are the voids in row r.
        let mut k = 0;
        for (r, start) in row_start.iter_mut().enumerate() {
            while k < voids.len() && voids[k] / width < r {
                k += 1;
            }
            *start = k;
        }
        // Horizontal: nearest valid to the west and to the east.
        for r in 0..height {
            let (a, b) = (row_start[r], row_start[r + 1]);
            if a == b {
                continue;
            }
            let row = &samples[r * width..(r + 1) * width];
            let mut k = a;
            let mut last: Option<(usize, f32)> = None;
            for (c, &v) in row.iter().enumerate() {
                if v.is_nan() {
                    if let Some((lc, lv)) = last {
                        add(&mut acc[k], (c - lc) as f64 * sx, lv);
                    }
                    k += 1;
                } else {
                    last = Some((c, v));
                }
            }
            let mut k = b;
            last = None;
            for (c, &v) in row.iter().enumerate().rev() {
                if v.is_nan() {
                    k -= 1;
                    if let Some((lc, lv)) = last {
                        add(&mut acc[k], (lc - c) as f64 * sx, lv);
                    }
                } else {
                    last = Some((c, v));
                }
            }
        }
        // Vertical: nearest valid below (south-to-north sweep) and above (north-to-south).
        for pass in 0..2 {
            last_row.fill(usize::MAX);
            for i in 0..height {
                let r = if pass == 0 { i } else { height - 1 - i };
                let row = &samples[r * width..(r + 1) * width];
                let mut k = row_start[r];
                for (c, &v) in row.iter().enumerate() {
                    if v.is_nan() {
                        if last_row[c] != usize::MAX {
                            add(
                                &mut acc[k],
                                last_row[c].abs_diff(r) as f64 * sy,
                                last_val[c],
                            );
                        }
                        k += 1;
                    } else {
                        last_row[c] = r;
                        last_val[c] = v;
                    }
                }
            }
        }
        let mut remaining = Vec::new();
        for (&i, &(w, wv)) in voids.iter().zip(&acc) {
            if w > 0.0 {
                samples[i] = ((wv / w) as f32).clamp(lo, hi);
            } else {
                remaining.push(i);
            }
        }
        if remaining.len() == voids.len() {
            // Cannot happen with at least one valid sample; never loop forever regardless.
            for &i in &remaining {
                samples[i] = lo;
            }
            break;
        }
        voids = remaining;
    }
}

#[inline]
fn add(acc: &mut (f64, f64), dist: f64, v: f32) {
    let w = 1.0 / dist;
    acc.0 += w;
    acc.1 += w * v as f64;
}

#[cfg(test)]
mod tests;
