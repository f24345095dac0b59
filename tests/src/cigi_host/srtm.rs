//! An SRTM tile read here, independently of aerie's loader: the raw big-endian i16 samples of
//! the `.hgt` (n × n, row 0 the northern edge, −32768 a void), and the bilinear surface through
//! them. The drawn (and queried) surface is the two triangles of each quad instead; over one
//! quad with corners sw, se, nw, ne the two differ by `|sw − se − nw + ne| · y(1 − x)` (or
//! `x(1 − y)` on the other triangle), at most a quarter of the quad's twist — the bound
//! [`Bilinear::twist_bound_m`] that answers must agree within.

use std::io::Read;
use std::path::Path;

/// One SRTM tile's samples and where they are.
#[derive(Debug, Clone)]
pub struct Srtm {
    /// Samples per side (1201 for 3″, 3601 for 1″).
    pub n: usize,
    pub south_lat: f64,
    pub west_lon: f64,
    /// Row 0 is the north edge, as in the file.
    samples: Vec<i16>,
}

/// The bilinear height at a point and how far the triangles may be from it there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bilinear {
    pub height_m: f64,
    /// A quarter of the quad's twist `|sw − se − nw + ne|`.
    pub twist_bound_m: f64,
}

/// Void marker of SRTM.
const VOID: i16 = -32768;

impl Srtm {
    /// Reads a `.hgt` or a `.hgt.zip` holding one, named like `N47E011` (its south-west corner).
    pub fn read(path: &Path) -> Result<Self, String> {
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .ok_or_else(|| format!("{}: no file name", path.display()))?;
        let bytes = if name.ends_with(".zip") {
            let file = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
            let mut zip =
                zip::ZipArchive::new(file).map_err(|e| format!("{}: {e}", path.display()))?;
            let index = (0..zip.len())
                .find(|&i| {
                    zip.by_index(i)
                        .map(|f| f.name().to_ascii_lowercase().ends_with(".hgt"))
                        .unwrap_or(false)
                })
                .ok_or_else(|| format!("{}: no .hgt inside", path.display()))?;
            let mut f = zip
                .by_index(index)
                .map_err(|e| format!("{}: {e}", path.display()))?;
            let mut b = Vec::new();
            f.read_to_end(&mut b)
                .map_err(|e| format!("{}: {e}", path.display()))?;
            b
        } else {
            std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?
        };
        let n = (bytes.len() as f64 / 2.0).sqrt().round() as usize;
        if n < 2 || n * n * 2 != bytes.len() {
            return Err(format!(
                "{}: {} bytes is not n² big-endian i16 samples",
                path.display(),
                bytes.len()
            ));
        }
        let (south_lat, west_lon) = corner(name)
            .ok_or_else(|| format!("{}: name does not start like N47E011", path.display()))?;
        let samples = bytes
            .chunks_exact(2)
            .map(|c| i16::from_be_bytes([c[0], c[1]]))
            .collect();
        Ok(Self {
            n,
            south_lat,
            west_lon,
            samples,
        })
    }

    /// The sample `col` east and `row` north of the south-west corner; `None` for a void.
    pub fn sample(&self, col: usize, row: usize) -> Option<f64> {
        let v = self.samples[(self.n - 1 - row) * self.n + col];
        (v != VOID).then_some(v as f64)
    }

    /// The bilinear surface at (lat, lon); `None` outside the tile or when a corner is a void.
    pub fn bilinear(&self, lat: f64, lon: f64) -> Option<Bilinear> {
        let steps = (self.n - 1) as f64;
        let u = (lon - self.west_lon) * steps;
        let v = (lat - self.south_lat) * steps;
        if !(0.0..=steps).contains(&u) || !(0.0..=steps).contains(&v) {
            return None;
        }
        let c = (u.floor() as usize).min(self.n - 2);
        let r = (v.floor() as usize).min(self.n - 2);
        let (x, y) = (u - c as f64, v - r as f64);
        let sw = self.sample(c, r)?;
        let se = self.sample(c + 1, r)?;
        let nw = self.sample(c, r + 1)?;
        let ne = self.sample(c + 1, r + 1)?;
        Some(Bilinear {
            height_m: sw * (1.0 - x) * (1.0 - y)
                + se * x * (1.0 - y)
                + nw * (1.0 - x) * y
                + ne * x * y,
            twist_bound_m: (sw - se - nw + ne).abs() / 4.0,
        })
    }
}

/// South-west corner from a name like `N47E011…` or `s12w077…`.
fn corner(name: &str) -> Option<(f64, f64)> {
    let b = name.as_bytes();
    if b.len() < 7 {
        return None;
    }
    let lat: f64 = name.get(1..3)?.parse().ok()?;
    let lon: f64 = name.get(4..7)?.parse().ok()?;
    let lat = match b[0].to_ascii_uppercase() {
        b'N' => lat,
        b'S' => -lat,
        _ => return None,
    };
    let lon = match b[3].to_ascii_uppercase() {
        b'E' => lon,
        b'W' => -lon,
        _ => return None,
    };
    Some((lat, lon))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corners_from_names() {
        assert_eq!(corner("N47E011.hgt.zip"), Some((47.0, 11.0)));
        assert_eq!(corner("s12W077.hgt"), Some((-12.0, -77.0)));
        assert_eq!(corner("X47E011.hgt"), None);
        assert_eq!(corner("N4"), None);
    }

    #[test]
    fn bilinear_is_exact_at_samples_and_bounded_by_the_twist() {
        // 3 × 3 samples, row 0 north: a saddle in the south-west quad.
        let s = Srtm {
            n: 3,
            south_lat: 47.0,
            west_lon: 11.0,
            samples: vec![5, 5, 5, 100, 0, 5, 0, 100, 5],
        };
        assert_eq!(s.sample(0, 0), Some(0.0));
        assert_eq!(s.sample(1, 0), Some(100.0));
        assert_eq!(s.sample(0, 1), Some(100.0));
        assert_eq!(s.sample(1, 1), Some(0.0));
        let mid = s.bilinear(47.25, 11.25).unwrap();
        assert_eq!(mid.height_m, 50.0);
        assert_eq!(mid.twist_bound_m, 50.0);
        // On a corner the bilinear surface is the sample.
        assert_eq!(s.bilinear(47.5, 11.5).unwrap().height_m, 0.0);
        assert_eq!(s.bilinear(47.0, 11.0).unwrap().height_m, 0.0);
        assert!(s.bilinear(46.9, 11.0).is_none());
        let voided = Srtm {
            samples: vec![5, 5, 5, VOID, 0, 5, 0, 100, 5],
            ..s
        };
        assert!(voided.bilinear(47.25, 11.25).is_none());
    }
}
