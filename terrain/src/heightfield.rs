//! The heightfield model: N×M samples in metres on a regular grid in the local ENU frame.

/// Where a heightfield sits on the Earth, when its source says so.
#[derive(Debug, Clone, PartialEq)]
pub enum GeoReference {
    /// A latitude/longitude grid (e.g. SRTM). Corner of sample (col 0, row 0), i.e. the
    /// south-west sample, and the arc spacing between samples, in degrees.
    Geographic {
        south_lat_deg: f64,
        west_lon_deg: f64,
        dlat_deg: f64,
        dlon_deg: f64,
    },
    /// A projected grid (e.g. UTM): CRS name (e.g. "EPSG:32611") and the easting/northing of
    /// the south-west sample, metres.
    Projected {
        crs: String,
        easting: f64,
        northing: f64,
    },
}

/// A regular grid of heights.
///
/// Convention (DESIGN.md "Conventions"): x east, y north, z up, metres. Sample (col, row) sits at
/// `x = col * spacing_x`, `y = row * spacing_y` relative to the south-west sample; **row 0 is the
/// southern edge** (loaders flip north-up files).
#[derive(Debug, Clone)]
pub struct Heightfield {
    /// Samples per row (east-west count).
    pub width: usize,
    /// Number of rows (north-south count).
    pub height: usize,
    /// Metres between adjacent columns (east-west).
    pub spacing_x: f64,
    /// Metres between adjacent rows (north-south).
    pub spacing_y: f64,
    /// Heights in metres, row-major, `heights[row * width + col]`, row 0 = south. Never NaN.
    pub heights: Vec<f32>,
    /// Geo-reference, when the source carries one.
    pub geo: Option<GeoReference>,
    /// Number of void samples that the loader filled by interpolation.
    pub voids_filled: usize,
    /// One human-readable sentence saying how the spacing was obtained
    /// (e.g. "geographic 3\" grid on a local tangent plane at 47.50°N: 62.7 m E-W, 92.6 m N-S").
    pub spacing_note: String,
}

impl Heightfield {
    /// Height at (col, row); panics when out of range.
    #[inline]
    pub fn at(&self, col: usize, row: usize) -> f32 {
        self.heights[row * self.width + col]
    }

    /// Height at (col, row) with both clamped into the grid.
    #[inline]
    pub fn at_clamped(&self, col: i64, row: i64) -> f32 {
        let c = col.clamp(0, self.width as i64 - 1) as usize;
        let r = row.clamp(0, self.height as i64 - 1) as usize;
        self.heights[r * self.width + c]
    }

    /// Smallest and largest height.
    pub fn min_max(&self) -> (f32, f32) {
        self.heights
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &h| {
                (lo.min(h), hi.max(h))
            })
    }

    /// Extent in metres (east-west, north-south) from the first to the last sample.
    pub fn extent_m(&self) -> (f64, f64) {
        (
            (self.width - 1) as f64 * self.spacing_x,
            (self.height - 1) as f64 * self.spacing_y,
        )
    }

    /// Bilinear height at a world position (x, y) in metres, clamped to the grid.
    pub fn height_at_m(&self, x: f64, y: f64) -> f64 {
        let fx = (x / self.spacing_x).clamp(0.0, (self.width - 1) as f64);
        let fy = (y / self.spacing_y).clamp(0.0, (self.height - 1) as f64);
        let (c0, r0) = (fx.floor() as i64, fy.floor() as i64);
        let (tx, ty) = (fx - c0 as f64, fy - r0 as f64);
        let h = |c: i64, r: i64| self.at_clamped(c, r) as f64;
        let a = h(c0, r0) * (1.0 - tx) + h(c0 + 1, r0) * tx;
        let b = h(c0, r0 + 1) * (1.0 - tx) + h(c0 + 1, r0 + 1) * tx;
        a * (1.0 - ty) + b * ty
    }
}
