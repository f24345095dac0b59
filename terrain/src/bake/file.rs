//! The on-disk bake: writing, reading and checking a file, and whether an existing one is stale.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use aerie_io::FileSystem;

use crate::dataset::Dataset;

use super::error::{show, BakeError};
use super::exact::bake;
use super::format::{
    file_layout, section_size, values_per_tile, BAKE_EXTENSION, BAKE_MAGIC, BAKE_VERSION,
    HEADER_SIZE,
};
use super::table::{BakeParams, ErrorBake, MeasuredBake, MeasuredEps};

/// Where the bake of a dataset lives: `<name>.aerie-bake` next to the file (the full file
/// name is kept: `N47E011.hgt.zip` → `N47E011.hgt.zip.aerie-bake`); for a folder of tiles,
/// next to the folder: `srtm/` → `srtm.aerie-bake` (so the folder holds only tiles).
pub fn bake_path_for(dataset_path: &Path) -> PathBuf {
    let p = if dataset_path.file_name().is_none() {
        std::fs::canonicalize(dataset_path).unwrap_or_else(|_| dataset_path.to_path_buf())
    } else {
        dataset_path.to_path_buf()
    };
    let mut name = p.file_name().map(|n| n.to_owned()).unwrap_or_default();
    name.push(".");
    name.push(BAKE_EXTENSION);
    p.with_file_name(name)
}

fn put_u32(b: &mut [u8], at: usize, v: u32) {
    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

fn put_u64(b: &mut [u8], at: usize, v: u64) {
    b[at..at + 8].copy_from_slice(&v.to_le_bytes());
}

fn put_f32s(b: &mut [u8], at: usize, v: &[f32]) {
    for (d, x) in b[at..at + 4 * v.len()].chunks_exact_mut(4).zip(v) {
        d.copy_from_slice(&x.to_le_bytes());
    }
}

/// Serialises a bake into `buf` (exactly `b.file_size()` bytes, zeroed).
fn encode(b: &ErrorBake, buf: &mut [u8]) {
    let layout = file_layout(b.width, b.height, b.params.tile_size, b.levels.len() as u32);
    assert_eq!(buf.len() as u64, layout.total);
    buf[0..8].copy_from_slice(&BAKE_MAGIC);
    put_u32(buf, 8, BAKE_VERSION);
    put_u32(buf, 12, HEADER_SIZE as u32);
    put_u32(buf, 16, b.params.tile_size);
    put_u32(buf, 20, b.levels.len() as u32);
    put_u32(buf, 24, b.width);
    put_u32(buf, 28, b.height);
    put_u32(buf, 32, b.valid_width);
    put_u32(buf, 36, b.valid_height);
    put_u64(buf, 40, b.spacing_x.to_bits());
    put_u64(buf, 48, b.spacing_y.to_bits());
    put_u32(buf, 56, b.source_checksum);
    put_u32(buf, 60, 0);
    put_u64(buf, 64, layout.total);
    let hcrc = crc32fast::hash(&buf[..92]);
    put_u32(buf, 92, hcrc);
    for (t, s) in b.levels.iter().zip(&layout.sections) {
        let n = t.len();
        assert_eq!((t.tiles_x, t.tiles_y), (s.tiles_x, s.tiles_y));
        let o = s.offset;
        put_u32(buf, o, t.level);
        put_u32(buf, o + 4, t.tiles_x);
        put_u32(buf, o + 8, t.tiles_y);
        if t.level == 0 {
            put_f32s(buf, o + 16, &t.min);
            put_f32s(buf, o + 16 + 4 * n, &t.max);
        } else {
            // ε of this level's surface over level 0's tiles (level 1: the quadrants) or level
            // L−2's (the blocks).
            let parts = match t.level {
                1 => &b.levels[0].coarse_eps,
                l => &b.levels[l as usize - 2].fine_eps,
            };
            assert_eq!(parts.len(), values_per_tile(t.level) * n);
            put_f32s(buf, o + 16, parts);
        }
    }
    let end = buf.len() - 4;
    let crc = crc32fast::hash(&buf[..end]);
    put_u32(buf, end, crc);
}

/// Writes the bake to `path` with plain checked writes through a temporary file in the same
/// folder, synced and renamed over `path` when complete: a full disk or a crash never leaves
/// a half-written bake under the real name, nor a temporary (no memory map, so no `SIGBUS`).
/// Overwrites `path` — callers decide whether that is allowed ([`load_or_bake`] does).
pub fn write_bake(path: &Path, b: &ErrorBake) -> Result<(), BakeError> {
    write_bake_in(aerie_io::real(), path, b)
}

/// [`write_bake`] on the given file system (tests inject faults through it).
pub fn write_bake_in(fs: Arc<dyn FileSystem>, path: &Path, b: &ErrorBake) -> Result<(), BakeError> {
    // The bake is small next to its dataset (under 2 % of the f32 samples), so it is encoded
    // on the heap and written in one checked pass.
    let mut buf = vec![0u8; b.file_size() as usize];
    encode(b, &mut buf);
    aerie_io::write_atomic_in(fs, path, &buf).map_err(|e| BakeError::Write {
        path: show(path),
        reason: match e.step {
            "write" => e.source.to_string(),
            step => format!("{step} failed: {}", e.source),
        }
        .replace(['\n', '\r'], " "),
    })
}

fn get_u32(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}

fn get_u64(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
}

fn get_f32s(b: &[u8], at: usize, n: usize) -> Vec<f32> {
    b[at..at + 4 * n]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// Decodes a bake file's bytes, checking structure only (not the dataset).
fn decode(path: &Path, bytes: &[u8]) -> Result<ErrorBake, BakeError> {
    let p = show(path);
    let len = bytes.len() as u64;
    let truncated = |offset: u64, reason: String| BakeError::Truncated {
        path: p.clone(),
        offset,
        reason,
    };
    let corrupt = |field: &str, offset: u64, reason: String| BakeError::Corrupt {
        path: p.clone(),
        field: field.to_string(),
        offset,
        reason,
    };
    let head = &bytes[..bytes.len().min(8)];
    if head != &BAKE_MAGIC[..head.len()] || bytes.is_empty() {
        let found = if bytes.is_empty() {
            "empty".to_string()
        } else {
            format!("{:?}", String::from_utf8_lossy(head))
        };
        return Err(BakeError::BadMagic { path: p, found });
    }
    if len < 12 {
        return Err(truncated(
            len,
            format!("the file is {len} bytes and ends before the format version (bytes 8..12)"),
        ));
    }
    let version = get_u32(bytes, 8);
    if version != BAKE_VERSION {
        return Err(BakeError::Version {
            path: p,
            found: version,
        });
    }
    if len < HEADER_SIZE as u64 {
        return Err(truncated(
            len,
            format!("the file is {len} bytes and ends inside the {HEADER_SIZE}-byte header"),
        ));
    }
    let hcrc = crc32fast::hash(&bytes[..92]);
    if get_u32(bytes, 92) != hcrc {
        return Err(corrupt(
            "header CRC-32",
            92,
            format!(
                "stored {:#010x}, header bytes 0..92 give {hcrc:#010x}",
                get_u32(bytes, 92)
            ),
        ));
    }
    if get_u32(bytes, 12) as usize != HEADER_SIZE {
        return Err(corrupt(
            "header size",
            12,
            format!("{} (expected {HEADER_SIZE})", get_u32(bytes, 12)),
        ));
    }
    let m = get_u32(bytes, 16);
    let levels = get_u32(bytes, 20);
    let (width, height) = (get_u32(bytes, 24), get_u32(bytes, 28));
    let (vw, vh) = (get_u32(bytes, 32), get_u32(bytes, 36));
    let params = BakeParams {
        tile_size: m,
        levels,
    };
    params
        .log2_quads()
        .map_err(|e| corrupt("tile size", 16, e.to_string()))?;
    for (name, off, v) in [("width", 24, width), ("height", 28, height)] {
        if v < 2 || !(v - 1).is_power_of_two() {
            return Err(corrupt(name, off, format!("{v} is not 2^K + 1")));
        }
    }
    if vw == 0 || vw > width || vh == 0 || vh > height {
        return Err(corrupt(
            "valid size",
            32,
            format!("{vw}×{vh} real samples in a {width}×{height} grid"),
        ));
    }
    let kmin = (width - 1)
        .trailing_zeros()
        .min((height - 1).trailing_zeros());
    let j = (m - 1).trailing_zeros();
    if levels == 0 || kmin < j || levels > kmin - j + 1 {
        return Err(corrupt(
            "levels",
            20,
            format!("{levels} levels do not fit a {width}×{height} grid with {m}×{m} tiles"),
        ));
    }
    let sx = f64::from_bits(get_u64(bytes, 40));
    let sy = f64::from_bits(get_u64(bytes, 48));
    let layout = file_layout(width, height, m, levels);
    let promised = get_u64(bytes, 64);
    if promised != layout.total {
        return Err(corrupt(
            "file size",
            64,
            format!("{promised}, but the parameters give {} bytes", layout.total),
        ));
    }
    if len < layout.total {
        // Say which part the file ends in.
        let mut part = "the trailing CRC-32".to_string();
        for (l, s) in layout.sections.iter().enumerate() {
            let n = s.tiles_x as u64 * s.tiles_y as u64;
            let o = s.offset as u64;
            let parts: &[(u64, &str)] = if l == 0 {
                &[
                    (o, "section header"),
                    (o + 16, "min array"),
                    (o + 16 + 4 * n, "max array"),
                ]
            } else if l == 1 {
                &[(o, "section header"), (o + 16, "quadrant ε array")]
            } else {
                &[(o, "section header"), (o + 16, "block ε array")]
            };
            let end = o + section_size(l as u32, n as usize) as u64;
            if len < end {
                let (start, what) = parts
                    .iter()
                    .rev()
                    .find(|(start, _)| len >= *start)
                    .copied()
                    .unwrap_or(parts[0]);
                part = format!("level {l} {what} (starts at byte offset {start})");
                break;
            }
        }
        return Err(truncated(
            len,
            format!(
                "the file is {len} bytes, the header promises {}; it ends inside {part}",
                layout.total
            ),
        ));
    }
    if len > layout.total {
        return Err(corrupt(
            "file size",
            64,
            format!(
                "the file is {len} bytes, {} more than the {} the header promises",
                len - layout.total,
                layout.total
            ),
        ));
    }
    let end = bytes.len() - 4;
    let crc = crc32fast::hash(&bytes[..end]);
    if get_u32(bytes, end) != crc {
        return Err(corrupt(
            "file CRC-32",
            end as u64,
            format!(
                "stored {:#010x}, bytes 0..{end} give {crc:#010x} (the file was changed after it was written)",
                get_u32(bytes, end)
            ),
        ));
    }
    let mut eps = Vec::with_capacity(levels as usize);
    let (mut min0, mut max0) = (Vec::new(), Vec::new());
    for (l, s) in layout.sections.iter().enumerate() {
        let o = s.offset;
        let n = s.tiles_x as usize * s.tiles_y as usize;
        let (lv, tx, ty) = (
            get_u32(bytes, o),
            get_u32(bytes, o + 4),
            get_u32(bytes, o + 8),
        );
        if (lv, tx, ty) != (l as u32, s.tiles_x, s.tiles_y) {
            return Err(corrupt(
                "level section header",
                o as u64,
                format!(
                    "level {lv} with {tx}×{ty} tiles, expected level {l} with {}×{} tiles",
                    s.tiles_x, s.tiles_y
                ),
            ));
        }
        if l == 0 {
            min0 = get_f32s(bytes, o + 16, n);
            max0 = get_f32s(bytes, o + 16 + 4 * n, n);
            eps.push(Vec::new());
        } else {
            let parts = get_f32s(bytes, o + 16, values_per_tile(l as u32) * n);
            if let Some(k) = parts.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
                let (field, of) = if l == 1 {
                    ("quadrant ε", 0)
                } else {
                    ("block ε", l - 2)
                };
                let tx = layout.sections[of].tiles_x as usize;
                return Err(corrupt(
                    field,
                    (o + 16 + 4 * k) as u64,
                    format!(
                        "level {l} over level {of}'s tile ({}, {}) (index {k}): {} is not a finite number ≥ 0",
                        k % tx,
                        k / tx,
                        parts[k]
                    ),
                ));
            }
            eps.push(parts);
        }
    }
    Ok(ErrorBake::from_measured(MeasuredBake {
        params,
        width,
        height,
        valid_width: vw,
        valid_height: vh,
        spacing_x: sx,
        spacing_y: sy,
        source_checksum: get_u32(bytes, 56),
        min0,
        max0,
        eps: MeasuredEps::Blocks(eps),
    }))
}

/// Reads a bake file made for `ds`: checks the magic, version, sizes and CRCs, then that it
/// belongs to `ds` (grid size, real size, spacing, sample checksum). Errors name the file,
/// the field or byte offset and the reason, and say to re-run `aerie bake`.
pub fn read_bake(path: &Path, ds: &Dataset) -> Result<ErrorBake, BakeError> {
    let b = read_bake_file(path)?;
    check_belongs(path, &b, ds)?;
    Ok(b)
}

/// Reads and checks a bake file on its own, without a dataset to compare it with.
pub fn read_bake_file(path: &Path) -> Result<ErrorBake, BakeError> {
    let bytes = std::fs::read(path).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            BakeError::NotFound { path: show(path) }
        } else {
            BakeError::Io {
                path: show(path),
                reason: e.to_string(),
            }
        }
    })?;
    decode(path, &bytes)
}

fn check_belongs(path: &Path, b: &ErrorBake, ds: &Dataset) -> Result<(), BakeError> {
    let stale = |reason: String| BakeError::Stale {
        path: show(path),
        reason,
    };
    if (b.width as usize, b.height as usize) != (ds.hf.width, ds.hf.height)
        || (b.valid_width as usize, b.valid_height as usize) != (ds.valid_width, ds.valid_height)
    {
        return Err(stale(format!(
            "made for a {}×{} grid ({}×{} real samples), the dataset is {}×{} ({}×{} real)",
            b.width,
            b.height,
            b.valid_width,
            b.valid_height,
            ds.hf.width,
            ds.hf.height,
            ds.valid_width,
            ds.valid_height
        )));
    }
    if b.spacing_x != ds.hf.spacing_x || b.spacing_y != ds.hf.spacing_y {
        return Err(stale(format!(
            "made for {} m × {} m spacing, the dataset has {} m × {} m",
            b.spacing_x, b.spacing_y, ds.hf.spacing_x, ds.hf.spacing_y
        )));
    }
    let sum = ds.checksum();
    if sum != b.source_checksum {
        return Err(stale(format!(
            "source checksum {:#010x} (byte offset 56) differs from the dataset's {sum:#010x}: the samples changed since the bake",
            b.source_checksum
        )));
    }
    Ok(())
}

/// What is at a bake path, judged against the dataset and the parameters asked for.
#[derive(Debug)]
pub enum Existing {
    /// Nothing there: bake and write.
    Missing,
    /// A valid bake of this dataset with these parameters.
    UpToDate(Box<ErrorBake>),
    /// An aerie bake that may be replaced, and why it must be (stale, other parameters,
    /// truncated, corrupt, older version, or `--force`).
    Replace(String),
}

/// Decides what to do about the file at `bake_path` (levels 0 in `params` = as many as fit).
/// A file that is not a bake, or a bake of a newer format version, is an error
/// ([`BakeError::Refused`]) unless `force`; `force` also replaces an up-to-date bake.
pub fn check_existing(
    ds: &Dataset,
    bake_path: &Path,
    params: BakeParams,
    force: bool,
) -> Result<Existing, BakeError> {
    let levels = params.resolve_levels(ds)?;
    match read_bake(bake_path, ds) {
        Ok(b) => {
            if force {
                Ok(Existing::Replace(format!(
                    "{}: valid, re-baked because of --force",
                    show(bake_path)
                )))
            } else if b.params.tile_size == params.tile_size && b.params.levels == levels {
                Ok(Existing::UpToDate(Box::new(b)))
            } else {
                Ok(Existing::Replace(format!(
                    "{}: made with m = {} and {} levels, m = {} and {} levels asked",
                    show(bake_path),
                    b.params.tile_size,
                    b.params.levels,
                    params.tile_size,
                    levels
                )))
            }
        }
        Err(BakeError::NotFound { .. }) => Ok(Existing::Missing),
        Err(e @ (BakeError::BadMagic { .. } | BakeError::Version { .. })) => {
            let newer = matches!(e, BakeError::Version { found, .. } if found > BAKE_VERSION);
            let not_bake = matches!(e, BakeError::BadMagic { .. });
            if (newer || not_bake) && !force {
                let what = if not_bake {
                    "exists and is not an aerie bake file"
                } else {
                    "is a bake of a newer format version than this build writes"
                };
                return Err(BakeError::Refused {
                    path: show(bake_path),
                    reason: format!(
                        "{what}; not overwriting it (use --force to replace it, or --out to write elsewhere)"
                    ),
                });
            }
            Ok(Existing::Replace(e.to_string()))
        }
        Err(
            e @ (BakeError::Truncated { .. } | BakeError::Corrupt { .. } | BakeError::Stale { .. }),
        ) => Ok(Existing::Replace(e.to_string())),
        Err(e) => Err(e),
    }
}

/// What [`load_or_bake`] did.
#[derive(Debug, Clone, PartialEq)]
pub enum BakeOutcome {
    /// A valid bake with the same checksum and parameters was already there.
    UpToDate,
    /// There was no file; a new bake was written.
    Baked,
    /// An existing bake was replaced, for the reason given.
    Replaced(String),
}

/// Reads the bake at `bake_path` when it is a valid bake of `ds` with `params`, else bakes
/// and writes it, following [`check_existing`]: never overwrites a file that is not a bake
/// (or a newer version's) unless `force`, and says in the outcome why a bake was replaced.
pub fn load_or_bake(
    ds: &Dataset,
    bake_path: &Path,
    params: BakeParams,
    force: bool,
    progress: &dyn Fn(u64, u64),
) -> Result<(ErrorBake, BakeOutcome), BakeError> {
    let outcome = match check_existing(ds, bake_path, params, force)? {
        Existing::UpToDate(b) => return Ok((*b, BakeOutcome::UpToDate)),
        Existing::Missing => BakeOutcome::Baked,
        Existing::Replace(why) => BakeOutcome::Replaced(why),
    };
    let b = bake(ds, params, progress);
    write_bake(bake_path, &b)?;
    Ok((b, outcome))
}
