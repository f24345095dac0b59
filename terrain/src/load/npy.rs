//! NumPy `.npy` (and `.npz`) grids: little-endian `<f4`, `<f8`, `<i2`, C order, 2-D.
//! NaN (and -32768 in `<i2`) is nodata and gets filled like SRTM voids.

use std::path::Path;

use super::archive::{open_zip, read_zip_entry, zip_names};
use super::error::{format_err, read_file, size_err, DemError};
use super::finish::{check_dims, finish};
use super::placement::Placement;
use super::sidecar::Sidecar;
use crate::Heightfield;

const KEYS: &[&str] = &["spacing_x", "spacing_y", "north_up"];
const MAGIC: &[u8] = b"\x93NUMPY";
/// Largest array accepted from inside an `.npz` (inflation guard).
const NPZ_ENTRY_MAX: u64 = 1 << 31;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Dtype {
    F4,
    F8,
    I2,
}

impl Dtype {
    fn size(self) -> usize {
        match self {
            Dtype::F4 => 4,
            Dtype::I2 => 2,
            Dtype::F8 => 8,
        }
    }
}

/// A parsed `.npy` blob: header facts plus where the data starts.
struct Npy<'a> {
    dtype: Dtype,
    shape: Vec<usize>,
    data_offset: usize,
    data: &'a [u8],
}

/// A Python literal, as far as `.npy` headers use them.
#[derive(Debug, PartialEq)]
enum Lit {
    Str(String),
    Bool(bool),
    Int(u64),
    Tuple(Vec<Lit>),
    Dict(Vec<(Lit, Lit)>),
    None,
}

/// Recursive-descent parser over the header text; depth-limited so hostile input cannot
/// overflow the stack.
struct LitParser<'a> {
    s: &'a [u8],
    pos: usize,
}

impl LitParser<'_> {
    fn skip_ws(&mut self) {
        while self.pos < self.s.len() && self.s[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
    }

    fn peek(&mut self) -> Option<u8> {
        self.skip_ws();
        self.s.get(self.pos).copied()
    }

    fn expect(&mut self, c: u8) -> Result<(), String> {
        if self.peek() == Some(c) {
            self.pos += 1;
            Ok(())
        } else {
            Err(format!(
                "expected '{}' at header byte {}",
                c as char, self.pos
            ))
        }
    }

    fn value(&mut self, depth: usize) -> Result<Lit, String> {
        if depth > 8 {
            return Err("header nests too deeply".into());
        }
        match self.peek() {
            Some(q @ (b'\'' | b'"')) => {
                self.pos += 1;
                let start = self.pos;
                while self.pos < self.s.len() && self.s[self.pos] != q {
                    self.pos += 1;
                }
                if self.pos >= self.s.len() {
                    return Err("unterminated string in header".into());
                }
                let text = String::from_utf8_lossy(&self.s[start..self.pos]).into_owned();
                self.pos += 1;
                Ok(Lit::Str(text))
            }
            Some(b'0'..=b'9') => {
                let mut v: u64 = 0;
                while let Some(&c) = self.s.get(self.pos).filter(|c| c.is_ascii_digit()) {
                    v = v
                        .checked_mul(10)
                        .and_then(|v| v.checked_add(u64::from(c - b'0')))
                        .ok_or("integer too large in header")?;
                    self.pos += 1;
                }
                // Python 2 era files may write `256L`.
                if self.s.get(self.pos) == Some(&b'L') {
                    self.pos += 1;
                }
                Ok(Lit::Int(v))
            }
            Some(open @ (b'(' | b'[')) => {
                let close = if open == b'(' { b')' } else { b']' };
                self.pos += 1;
                let mut items = Vec::new();
                loop {
                    if self.peek() == Some(close) {
                        self.pos += 1;
                        return Ok(Lit::Tuple(items));
                    }
                    items.push(self.value(depth + 1)?);
                    match self.peek() {
                        Some(b',') => self.pos += 1,
                        Some(c) if c == close => {}
                        _ => return Err(format!("bad tuple at header byte {}", self.pos)),
                    }
                }
            }
            Some(b'{') => {
                self.pos += 1;
                let mut items = Vec::new();
                loop {
                    if self.peek() == Some(b'}') {
                        self.pos += 1;
                        return Ok(Lit::Dict(items));
                    }
                    let k = self.value(depth + 1)?;
                    self.expect(b':')?;
                    let v = self.value(depth + 1)?;
                    items.push((k, v));
                    match self.peek() {
                        Some(b',') => self.pos += 1,
                        Some(b'}') => {}
                        _ => return Err(format!("bad dict at header byte {}", self.pos)),
                    }
                }
            }
            _ => {
                for (word, lit) in [
                    ("True", Lit::Bool(true)),
                    ("False", Lit::Bool(false)),
                    ("None", Lit::None),
                ] {
                    if self.s[self.pos..].starts_with(word.as_bytes()) {
                        self.pos += word.len();
                        return Ok(lit);
                    }
                }
                Err(format!("unexpected header text at byte {}", self.pos))
            }
        }
    }
}

/// Parses the `.npy` header; `path` only for messages.
fn parse_npy<'a>(path: &Path, bytes: &'a [u8]) -> Result<Npy<'a>, DemError> {
    if bytes.len() < 10 || &bytes[..6] != MAGIC {
        return Err(format_err(
            path,
            "not a NumPy .npy file (magic \\x93NUMPY missing)",
        ));
    }
    let (major, minor) = (bytes[6], bytes[7]);
    let (header_len, start) = match major {
        1 => (
            usize::from(u16::from_le_bytes([bytes[8], bytes[9]])),
            10usize,
        ),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        2 | 3 => return Err(size_err(path, "truncated .npy header")),
        _ => {
            return Err(format_err(
                path,
                format!(
                ".npy format version {major}.{minor} is not supported (accepted: 1.0, 2.0, 3.0)"
            ),
            ))
        }
    };
    let end = start
        .checked_add(header_len)
        .filter(|&e| e <= bytes.len())
        .ok_or_else(|| {
            size_err(
                path,
                format!(
                    "truncated .npy header: {header_len} header bytes announced, {} present",
                    bytes.len().saturating_sub(start)
                ),
            )
        })?;
    let mut p = LitParser {
        s: &bytes[start..end],
        pos: 0,
    };
    let header = p
        .value(0)
        .map_err(|e| format_err(path, format!("malformed .npy header: {e}")))?;
    let Lit::Dict(items) = header else {
        return Err(format_err(path, "malformed .npy header: not a dict"));
    };
    let get = |key: &str| {
        items
            .iter()
            .find(|(k, _)| matches!(k, Lit::Str(s) if s == key))
            .map(|(_, v)| v)
    };
    let descr = match get("descr") {
        Some(Lit::Str(s)) => s.clone(),
        Some(_) => return Err(format_err(path, ".npy header: 'descr' is not a plain dtype string (structured arrays are not supported)")),
        None => return Err(format_err(path, ".npy header lacks 'descr'")),
    };
    let dtype = match descr.as_str() {
        "<f4" => Dtype::F4,
        "<f8" => Dtype::F8,
        "<i2" => Dtype::I2,
        other => {
            let hint = if other.starts_with('>') {
                " (big-endian; re-save as little-endian)"
            } else {
                ""
            };
            return Err(format_err(
                path,
                format!("unsupported dtype '{other}'{hint}; accepted: '<f4', '<f8', '<i2'"),
            ));
        }
    };
    match get("fortran_order") {
        Some(Lit::Bool(false)) => {}
        Some(Lit::Bool(true)) => {
            return Err(format_err(
                path,
                "Fortran-order array is not supported; save a C-order array (np.ascontiguousarray)",
            ))
        }
        _ => {
            return Err(format_err(
                path,
                ".npy header lacks a boolean 'fortran_order'",
            ))
        }
    }
    let shape = match get("shape") {
        Some(Lit::Tuple(dims)) => dims
            .iter()
            .map(|d| match d {
                Lit::Int(n) => usize::try_from(*n).ok(),
                _ => None,
            })
            .collect::<Option<Vec<usize>>>()
            .ok_or_else(|| format_err(path, ".npy header: 'shape' holds a non-integer"))?,
        _ => return Err(format_err(path, ".npy header lacks a 'shape' tuple")),
    };
    Ok(Npy {
        dtype,
        shape,
        data_offset: end,
        data: &bytes[end..],
    })
}

impl Npy<'_> {
    /// Element count, checking the data length matches it exactly.
    fn checked_len(&self, path: &Path) -> Result<usize, DemError> {
        let n = self
            .shape
            .iter()
            .try_fold(1usize, |a, &d| a.checked_mul(d))
            .ok_or_else(|| size_err(path, format!("shape {:?} is too large", self.shape)))?;
        let expected = n.checked_mul(self.dtype.size());
        if expected != Some(self.data.len()) {
            let exp = expected.unwrap_or(usize::MAX);
            let found = self.data.len();
            let how = if found < exp {
                format!("truncated by {} bytes", exp - found)
            } else {
                format!("too long by {} bytes", found - exp)
            };
            return Err(size_err(
                path,
                format!(
                    "expected {exp} data bytes for shape {:?}, found {found} ({how})",
                    self.shape
                ),
            ));
        }
        Ok(n)
    }

    fn value(&self, i: usize) -> f64 {
        let b = &self.data[i * self.dtype.size()..];
        match self.dtype {
            Dtype::F4 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Dtype::F8 => f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
            Dtype::I2 => match i16::from_le_bytes([b[0], b[1]]) {
                i16::MIN => f64::NAN,
                v => f64::from(v),
            },
        }
    }

    /// All values as f64 (for small coordinate arrays in `.npz`).
    fn values(&self, path: &Path) -> Result<Vec<f64>, DemError> {
        let n = self.checked_len(path)?;
        Ok((0..n).map(|i| self.value(i)).collect())
    }

    /// The 2-D elevation grid as (width, height, samples), NaN = void.
    fn grid(&self, path: &Path) -> Result<(usize, usize, Vec<f32>), DemError> {
        let [rows, cols] = self.shape[..] else {
            return Err(format_err(
                path,
                format!(
                    "expected a 2-D array (rows, cols), found shape {:?}",
                    self.shape
                ),
            ));
        };
        check_dims(path, cols, rows)?;
        let n = self.checked_len(path)?;
        let mut out = Vec::with_capacity(n);
        for i in 0..n {
            let v = self.value(i);
            if v.is_infinite() || (v.is_finite() && v.abs() > f64::from(f32::MAX)) {
                return Err(super::raw::non_finite_at(
                    path,
                    v,
                    i,
                    cols,
                    self.dtype.size(),
                    self.data_offset,
                ));
            }
            out.push(v as f32);
        }
        Ok((cols, rows, out))
    }
}

pub(super) fn load_npy(path: &Path) -> Result<Heightfield, DemError> {
    let bytes = read_file(path)?;
    let sidecar = Sidecar::load(path, KEYS)?;
    let npy = parse_npy(path, &bytes)?;
    let (width, height, samples) = npy.grid(path)?;
    let north_up = match &sidecar {
        Some(s) => s.bool("north_up")?.unwrap_or(true),
        None => true,
    };
    let place = Placement::metric(sidecar.as_ref())?;
    finish(path, width, height, samples, north_up, place)
}

/// `.npz`: the `elevation` or `topo` array, else the first 2-D one. Orientation and a
/// geographic spacing come from `latitude`/`longitude` axes or `xmin..ymax`/`dx`/`dy` scalars
/// when present (matplotlib's sample files use both styles, with opposite row orders); a
/// sidecar overrides them.
pub(super) fn load_npz(path: &Path) -> Result<Heightfield, DemError> {
    let bytes = read_file(path)?;
    let sidecar = Sidecar::load(path, KEYS)?;
    let mut zip = open_zip(path, &bytes)?;
    let names = zip_names(&zip);
    let mut entries: Vec<(String, Vec<u8>)> = Vec::new();
    for (i, name) in names.iter().enumerate() {
        if let Some(stem) = name.strip_suffix(".npy") {
            entries.push((
                stem.to_string(),
                read_zip_entry(path, &mut zip, i, NPZ_ENTRY_MAX)?,
            ));
        }
    }
    let in_entry = |name: &str, e: DemError| match e {
        DemError::Format { path, reason } => DemError::Format {
            path,
            reason: format!("array `{name}`: {reason}"),
        },
        DemError::Size { path, reason } => DemError::Size {
            path,
            reason: format!("array `{name}`: {reason}"),
        },
        other => other,
    };
    let by_name = |want: &str| entries.iter().position(|(n, _)| n == want);
    let chosen = match by_name("elevation").or_else(|| by_name("topo")) {
        Some(i) => i,
        None => entries
            .iter()
            .position(|(_, b)| parse_npy(path, b).is_ok_and(|a| a.shape.len() == 2))
            .ok_or_else(|| {
                format_err(
                    path,
                    format!(
                        "no 2-D array in the .npz (arrays: {})",
                        entries
                            .iter()
                            .map(|(n, _)| n.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
            })?,
    };
    let (name, data) = &entries[chosen];
    let npy = parse_npy(path, data).map_err(|e| in_entry(name, e))?;
    let (width, height, samples) = npy.grid(path).map_err(|e| in_entry(name, e))?;

    // Optional coordinate arrays; anything odd about them just means "no geo-reference".
    let aux = |want: &str| -> Option<Vec<f64>> {
        let i = by_name(want)?;
        let a = parse_npy(path, &entries[i].1).ok()?;
        a.values(path)
            .ok()
            .filter(|v| v.iter().all(|x| x.is_finite()))
    };
    let scalar = |want: &str| aux(want).filter(|v| v.len() == 1).map(|v| v[0]);
    // (north_up, south_lat, west_lon, dlat, dlon)
    let mut geo_guess: Option<(bool, f64, f64, f64, f64)> = None;
    if let (Some(lat), Some(lon)) = (aux("latitude"), aux("longitude")) {
        if lat.len() == height && lon.len() == width && lon[width - 1] > lon[0] {
            let north_up = lat[0] > lat[height - 1];
            let dlat = (lat[height - 1] - lat[0]).abs() / (height - 1) as f64;
            let dlon = (lon[width - 1] - lon[0]) / (width - 1) as f64;
            let west = if lon[0] > 180.0 {
                lon[0] - 360.0
            } else {
                lon[0]
            };
            let south = lat[0].min(lat[height - 1]);
            geo_guess = Some((north_up, south, west, dlat, dlon));
        }
    } else if let (Some(xmin), Some(xmax), Some(ymin), Some(ymax)) = (
        scalar("xmin"),
        scalar("xmax"),
        scalar("ymin"),
        scalar("ymax"),
    ) {
        // matplotlib draws row 0 at `ymin` (linspace(ymin, ymax, rows)), whatever its sign.
        let dlat = scalar("dy").unwrap_or((ymax - ymin).abs() / (height - 1) as f64);
        let dlon = scalar("dx").unwrap_or((xmax - xmin).abs() / (width - 1) as f64);
        if ymin != ymax && xmax > xmin {
            geo_guess = Some((ymin > ymax, ymin.min(ymax), xmin, dlat.abs(), dlon.abs()));
        }
    }
    let geo_guess = geo_guess.filter(|&(_, s, w, dlat, dlon)| {
        dlat > 0.0 && dlon > 0.0 && s.abs() <= 90.0 && w.abs() <= 360.0
    });
    let sc = sidecar.as_ref();
    let north_up = sc
        .map(|s| s.bool("north_up"))
        .transpose()?
        .flatten()
        .or(geo_guess.map(|g| g.0))
        .unwrap_or(true);
    let has_spacing = match sc {
        Some(s) => s.spacing("spacing_x")?.is_some() || s.spacing("spacing_y")?.is_some(),
        None => false,
    };
    let place = match geo_guess {
        Some((_, south, west, dlat, dlon)) if !has_spacing => {
            Placement::geographic(south, west, dlat, dlon, height)
        }
        _ => Placement::metric(sc)?,
    };
    finish(path, width, height, samples, north_up, place)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::load::load_dem;
    use crate::load::sidecar::sidecar_path;
    use crate::GeoReference;
    use std::io::Write as _;

    /// A version-1.0 `.npy` with the header padded to 64 bytes as NumPy does.
    pub(crate) fn npy_bytes(descr: &str, fortran: bool, shape: &[usize], data: &[u8]) -> Vec<u8> {
        let dims = match shape {
            [n] => format!("({n},)"),
            _ => format!(
                "({})",
                shape
                    .iter()
                    .map(|d| d.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        let fo = if fortran { "True" } else { "False" };
        let mut header =
            format!("{{'descr': '{descr}', 'fortran_order': {fo}, 'shape': {dims}, }}");
        while (10 + header.len() + 1) % 64 != 0 {
            header.push(' ');
        }
        header.push('\n');
        let mut out = MAGIC.to_vec();
        out.extend_from_slice(&[1, 0]);
        out.extend_from_slice(&(header.len() as u16).to_le_bytes());
        out.extend_from_slice(header.as_bytes());
        out.extend_from_slice(data);
        out
    }

    fn f4(vals: &[f32]) -> Vec<u8> {
        vals.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    #[test]
    fn npy_round_trip_with_nan_voids() {
        let dir = tempfile::tempdir().unwrap();
        let n = f32::NAN;
        // 4 wide × 3 rows, file row 0 = north.
        let vals = [
            10., 20., 30., 40., //
            11., n, n, 41., //
            12., 22., 32., 42.,
        ];
        let p = dir.path().join("dem.npy");
        std::fs::write(&p, npy_bytes("<f4", false, &[3, 4], &f4(&vals))).unwrap();
        let hf = load_dem(&p).unwrap();
        assert_eq!((hf.width, hf.height), (4, 3));
        assert_eq!(hf.voids_filled, 2);
        assert_eq!(hf.spacing_x, 30.0);
        // Flipped: file row 2 is heightfield row 0.
        assert_eq!(&hf.heights[..4], &[12., 22., 32., 42.]);
        assert_eq!(&hf.heights[8..], &[10., 20., 30., 40.]);
        let (a, b) = (hf.at(1, 1), hf.at(2, 1));
        assert!(a > 11.0 && a < 41.0 && b > a && b < 41.0, "{a} {b}");
        // (1,1): W 11 at 1, E 41 at 2, N 20 at 1, S 22 at 1 → (11+20.5+20+22)/3.5
        assert!((a - (11.0 + 20.5 + 20.0 + 22.0) / 3.5).abs() < 1e-4, "{a}");
        assert!(hf.heights.iter().all(|h| h.is_finite()));

        // Sidecar spacing and orientation.
        std::fs::write(
            sidecar_path(&p),
            r#"{"spacing_x": 2, "spacing_y": 3, "north_up": false}"#,
        )
        .unwrap();
        let hf = load_dem(&p).unwrap();
        assert_eq!((hf.spacing_x, hf.spacing_y), (2.0, 3.0));
        assert_eq!(&hf.heights[..4], &[10., 20., 30., 40.]);
    }

    #[test]
    fn npy_other_dtypes_and_version2() {
        let dir = tempfile::tempdir().unwrap();
        let i2: Vec<u8> = [1i16, -5, i16::MIN, 300]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let p = dir.path().join("i.npy");
        std::fs::write(&p, npy_bytes("<i2", false, &[2, 2], &i2)).unwrap();
        let hf = load_dem(&p).unwrap();
        assert_eq!(hf.voids_filled, 1);
        assert_eq!((hf.at(0, 1), hf.at(1, 1), hf.at(1, 0)), (1.0, -5.0, 300.0));

        let f8: Vec<u8> = [1.5f64, 2.5, 3.5, 4.5]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let mut v2 = npy_bytes("<f8", false, &[2, 2], &f8);
        // Rewrite as a version 2.0 header (u32 length).
        let hl = u16::from_le_bytes([v2[8], v2[9]]) as u32;
        v2.splice(6..10, [2u8, 0].into_iter().chain(hl.to_le_bytes()));
        let p = dir.path().join("v2.npy");
        std::fs::write(&p, v2).unwrap();
        assert_eq!(load_dem(&p).unwrap().heights, [3.5, 4.5, 1.5, 2.5]);
    }

    #[test]
    fn npy_rejections() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.npy");
        let check = |bytes: Vec<u8>, want: &[&str]| {
            std::fs::write(&p, bytes).unwrap();
            let msg = load_dem(&p).unwrap_err().to_string();
            assert!(msg.starts_with(&format!("{}: ", p.display())), "{msg}");
            assert!(!msg.contains('\n'), "{msg}");
            for w in want {
                assert!(msg.contains(w), "{msg} lacks {w}");
            }
        };
        let d = f4(&[1.0; 4]);
        check(npy_bytes("<f4", true, &[2, 2], &d), &["Fortran"]);
        check(npy_bytes(">f4", false, &[2, 2], &d), &[">f4", "big-endian"]);
        check(npy_bytes("<u1", false, &[2, 2], &d), &["'<u1'", "'<f4'"]);
        check(npy_bytes("<f4", false, &[4], &d), &["2-D", "[4]"]);
        check(npy_bytes("<f4", false, &[1, 4], &d), &["2×2"]);
        check(npy_bytes("<f4", false, &[0, 4], &[]), &["zero-size"]);
        check(
            npy_bytes("<f4", false, &[2, 2], &d[..12]),
            &["expected 16", "found 12", "truncated"],
        );
        check(
            npy_bytes("<f4", false, &[2, 2], &f4(&[f32::NAN; 4])),
            &["all 4 samples are voids"],
        );
        let hdr = npy_bytes("<f4", false, &[2, 2], &[]).len();
        check(
            npy_bytes("<f4", false, &[2, 2], &f4(&[1.0, 2.0, f32::INFINITY, 3.0])),
            &["inf", "(col 0, row 1)", &format!("byte offset {}", hdr + 8)],
        );
        check(b"\x93NUMPY\x01\x00\xff\xff{".to_vec(), &["truncated"]);
        check(b"not numpy at all".to_vec(), &["NumPy"]);
    }

    fn write_npz(path: &Path, entries: &[(&str, Vec<u8>)]) {
        let mut z = zip::ZipWriter::new(std::fs::File::create(path).unwrap());
        let opts = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Deflated);
        for (name, data) in entries {
            z.start_file(*name, opts).unwrap();
            z.write_all(data).unwrap();
        }
        z.finish().unwrap();
    }

    #[test]
    fn npz_picks_elevation_and_reads_axes() {
        let dir = tempfile::tempdir().unwrap();
        let grid = f4(&[1., 2., 3., 4., 5., 6.]); // 2 rows × 3 cols
        let f8 = |v: &[f64]| -> Vec<u8> { v.iter().flat_map(|x| x.to_le_bytes()).collect() };
        // Latitude ascending → row 0 is south, no flip.
        let p = dir.path().join("t.npz");
        write_npz(
            &p,
            &[
                (
                    "longitude.npy",
                    npy_bytes("<f8", false, &[3], &f8(&[234.0, 234.5, 235.0])),
                ),
                ("topo.npy", npy_bytes("<f4", false, &[2, 3], &grid)),
                (
                    "latitude.npy",
                    npy_bytes("<f8", false, &[2], &f8(&[48.0, 48.5])),
                ),
            ],
        );
        let hf = load_dem(&p).unwrap();
        assert_eq!(hf.heights, [1., 2., 3., 4., 5., 6.]);
        assert_eq!(
            hf.geo,
            Some(GeoReference::Geographic {
                south_lat_deg: 48.0,
                west_lon_deg: -126.0,
                dlat_deg: 0.5,
                dlon_deg: 0.5
            })
        );
        assert!(hf.spacing_x < hf.spacing_y);

        // No axes: first 2-D array, default north-up flip and 30 m.
        let p = dir.path().join("plain.npz");
        write_npz(
            &p,
            &[
                ("dx.npy", npy_bytes("<f8", false, &[], &f8(&[1.0]))),
                ("z.npy", npy_bytes("<f4", false, &[2, 3], &grid)),
            ],
        );
        let hf = load_dem(&p).unwrap();
        assert_eq!(hf.heights, [4., 5., 6., 1., 2., 3.]);
        assert_eq!(hf.spacing_x, 30.0);

        let p = dir.path().join("none.npz");
        write_npz(&p, &[("dx.npy", npy_bytes("<f8", false, &[], &f8(&[1.0])))]);
        assert!(load_dem(&p)
            .unwrap_err()
            .to_string()
            .contains("no 2-D array"));
    }
}
