//! The byte layout of a store: the header (fixed part + geo-reference and sources), the index
//! entries, and the page geometry both sides compute from the header. Pure: bytes in, values
//! out; every refusal names the byte offset and the field.

use crate::GeoReference;

/// First 8 bytes of every store.
pub const STORE_MAGIC: &[u8; 8] = b"AERIESTO";
/// The format version this code writes (version 1 had no bake section: opening it needed
/// every page; version 2 kept one ε per tile in it, version 3 each tile's quadrants' ε).
pub const STORE_VERSION: u32 = 4;
/// The oldest format this build reads: version 2 stores keep one ε per tile (their quadrants'
/// ε at the parent's resolution is taken as the parent's, a looser bound; re-import for the
/// measured one); version 3 stores keep the quadrants but not the blocks (a tile's ε at its
/// grandparent's resolution is taken as its parent's there).
pub const OLDEST_STORE_VERSION: u32 = 2;
/// File name extension of a store.
pub const STORE_EXTENSION: &str = "aerie";
/// Bytes of the fixed part of the header (its own CRC included).
pub const FIXED_HEADER: usize = 128;
/// Bytes of one index entry.
pub const INDEX_ENTRY: usize = 32;
/// Largest header accepted (geo-reference, spacing note and source list): a corrupt size field
/// must not make the reader allocate gigabytes.
pub const MAX_HEADER: usize = 1 << 20;
/// Default page side in tiles: at m = 17 a page is 129 × 129 samples (65 KiB as f32).
pub const DEFAULT_PAGE_TILES: u32 = 8;

/// How a page's samples are coded before compression (lossless either way).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coding {
    /// Every sample is an integer in i16 range (SRTM, int16 GeoTIFF): the residual of the
    /// gradient predictor (west + south − south-west, wrapping i16), zigzag, u16 LE.
    I16Gradient,
    /// Any f32: the bits XOR the west neighbour's (south for column 0), as 4 byte planes.
    F32Xor,
    /// Mostly integers (SRTM with filled voids): every sample rounded to i16 and coded as
    /// [`Coding::I16Gradient`], then u32 k and k exceptions (u32 sample index, increasing;
    /// u32 f32 bits) that restore the exact value of each sample that is not an exact i16.
    I16Exceptions,
}

impl Coding {
    pub fn code(self) -> u32 {
        match self {
            Coding::I16Gradient => 0,
            Coding::F32Xor => 1,
            Coding::I16Exceptions => 2,
        }
    }

    pub fn from_code(c: u32) -> Option<Self> {
        match c {
            0 => Some(Coding::I16Gradient),
            1 => Some(Coding::F32Xor),
            2 => Some(Coding::I16Exceptions),
            _ => None,
        }
    }

    /// Bytes per sample of the coded samples (the exceptions of `I16Exceptions` aside).
    pub fn bytes_per_sample(self) -> usize {
        match self {
            Coding::I16Gradient | Coding::I16Exceptions => 2,
            Coding::F32Xor => 4,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Coding::I16Gradient => "i16 gradient",
            Coding::F32Xor => "f32 xor",
            Coding::I16Exceptions => "i16 + exceptions",
        }
    }
}

/// What the header says. Sizes are those of [`crate::dataset::Dataset`] (padded) and of its
/// [`crate::bake::ErrorBake`].
#[derive(Debug, Clone, PartialEq)]
pub struct StoreHeader {
    pub version: u32,
    /// Bytes of the whole header (fixed part, variable part, its CRC) = the first page's offset.
    pub header_size: u32,
    /// Tile side in vertices, `m = 2^j + 1`.
    pub tile_size: u32,
    /// Page side in tiles (a power of two); pages at a level's east/north edge hold fewer.
    pub page_tiles: u32,
    pub levels: u32,
    pub width: u32,
    pub height: u32,
    pub valid_width: u32,
    pub valid_height: u32,
    pub page_count: u32,
    pub spacing_x: f64,
    pub spacing_y: f64,
    /// CRC-32 of the padded level-0 samples as f32 LE ([`crate::dataset::Dataset::checksum`]).
    pub source_checksum: u32,
    pub voids_filled: u64,
    /// First byte of the pages (= `header_size`).
    pub data_offset: u64,
    /// Bytes the pages' samples take as f32 (the compression ratio's numerator).
    pub raw_sample_bytes: u64,
    pub geo: Option<GeoReference>,
    pub spacing_note: String,
    /// The input files, one line each.
    pub sources: Vec<String>,
    /// Max ε over the terrain tiles of each level, metres (one per level).
    pub max_eps: Vec<f32>,
}

/// One page of the index.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PageEntry {
    pub level: u32,
    pub px: u32,
    pub py: u32,
    pub coding: Coding,
    pub offset: u64,
    pub len: u32,
    /// CRC-32 of the page's stored (compressed) bytes.
    pub crc: u32,
}

/// Where each level's pages lie, from the header's sizes alone.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    /// Quads per level-0 tile side, `m − 1`.
    pub q: u32,
    pub page_tiles: u32,
    /// Per level: tiles per axis, pages per axis, index of its first page.
    pub levels: Vec<LevelLayout>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LevelLayout {
    pub tiles_x: u32,
    pub tiles_y: u32,
    pub pages_x: u32,
    pub pages_y: u32,
    pub first: u32,
}

/// The tiles and samples one page covers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PageRect {
    /// First tile (level-L tile coordinates) and tiles per axis.
    pub tx0: u32,
    pub ty0: u32,
    pub ntx: u32,
    pub nty: u32,
    /// Level-L samples per axis: `ntx·q + 1` (edges shared with the neighbour pages, so a
    /// page stands alone), starting at level-L sample `(tx0·q, ty0·q)`.
    pub cols: u32,
    pub rows: u32,
}

impl PageRect {
    pub fn tiles(&self) -> usize {
        (self.ntx * self.nty) as usize
    }

    pub fn samples(&self) -> usize {
        self.cols as usize * self.rows as usize
    }
}

impl Layout {
    /// The layout of a `width × height` grid with tiles of `q` quads, `levels` levels and
    /// pages of `page_tiles` tiles; `None` when the sizes do not tile (the header check says why).
    pub fn new(width: u32, height: u32, q: u32, levels: u32, page_tiles: u32) -> Option<Self> {
        if q < 2 || !q.is_power_of_two() || levels == 0 || levels > 31 {
            return None;
        }
        if page_tiles == 0 || !page_tiles.is_power_of_two() || width < 2 || height < 2 {
            return None;
        }
        let top = u64::from(q) << (levels - 1);
        if (u64::from(width) - 1) % top != 0 || (u64::from(height) - 1) % top != 0 {
            return None;
        }
        let mut first = 0u32;
        let mut out = Vec::with_capacity(levels as usize);
        for l in 0..levels {
            let t = u64::from(q) << l;
            let tiles_x = ((u64::from(width) - 1) / t) as u32;
            let tiles_y = ((u64::from(height) - 1) / t) as u32;
            let pages_x = tiles_x.div_ceil(page_tiles);
            let pages_y = tiles_y.div_ceil(page_tiles);
            out.push(LevelLayout {
                tiles_x,
                tiles_y,
                pages_x,
                pages_y,
                first,
            });
            first = first.checked_add(pages_x.checked_mul(pages_y)?)?;
        }
        Some(Layout {
            q,
            page_tiles,
            levels: out,
        })
    }

    pub fn page_count(&self) -> u32 {
        self.levels
            .last()
            .map(|l| l.first + l.pages_x * l.pages_y)
            .unwrap_or(0)
    }

    /// Index position of a page, or `None` outside the layout.
    pub fn position(&self, level: u32, px: u32, py: u32) -> Option<usize> {
        let l = self.levels.get(level as usize)?;
        (px < l.pages_x && py < l.pages_y).then(|| (l.first + py * l.pages_x + px) as usize)
    }

    /// The page at index position `i`: (level, px, py).
    pub fn page_at(&self, i: usize) -> Option<(u32, u32, u32)> {
        let i = u32::try_from(i).ok()?;
        self.levels.iter().enumerate().find_map(|(l, g)| {
            let k = i.checked_sub(g.first)?;
            (k < g.pages_x * g.pages_y).then_some((l as u32, k % g.pages_x, k / g.pages_x))
        })
    }

    /// Tiles and samples of a page (which must be in the layout).
    pub fn rect(&self, level: u32, px: u32, py: u32) -> PageRect {
        let g = self.levels[level as usize];
        let p = self.page_tiles;
        let (tx0, ty0) = (px * p, py * p);
        let ntx = p.min(g.tiles_x - tx0);
        let nty = p.min(g.tiles_y - ty0);
        PageRect {
            tx0,
            ty0,
            ntx,
            nty,
            cols: ntx * self.q + 1,
            rows: nty * self.q + 1,
        }
    }

    /// Largest payload a page can have before compression: 16 (level, px, py, coding) + 12
    /// per tile (ε, min, max) + the coded samples (+ for `I16Exceptions`, 4 + 8 per
    /// exception, at most one per sample). The other codings have exactly this length.
    pub fn raw_len(&self, level: u32, px: u32, py: u32, coding: Coding) -> usize {
        let r = self.rect(level, px, py);
        let extra = match coding {
            Coding::I16Exceptions => 4 + 8 * r.samples(),
            _ => 0,
        };
        PAYLOAD_PREFIX + 12 * r.tiles() + coding.bytes_per_sample() * r.samples() + extra
    }
}

/// Bytes before a payload's tables: level, px, py, coding (u32 each).
pub const PAYLOAD_PREFIX: usize = 16;

// ---------------------------------------------------------------------------------------------
// Header bytes.

/// A little-endian writer.
#[derive(Default)]
pub(super) struct Put(pub(super) Vec<u8>);

impl Put {
    pub(super) fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub(super) fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub(super) fn f64(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn str(&mut self, s: &str) {
        self.u32(s.len() as u32);
        self.0.extend_from_slice(s.as_bytes());
    }
}

/// The header as bytes (`header_size` must already be [`header_len`] of it).
pub fn encode_header(h: &StoreHeader) -> Vec<u8> {
    let mut p = Put::default();
    p.0.extend_from_slice(STORE_MAGIC);
    for v in [
        h.version,
        h.header_size,
        h.tile_size,
        h.page_tiles,
        h.levels,
        h.width,
        h.height,
        h.valid_width,
        h.valid_height,
        h.page_count,
    ] {
        p.u32(v);
    }
    p.f64(h.spacing_x);
    p.f64(h.spacing_y);
    p.u32(h.source_checksum);
    p.u32(0); // flags
    p.u64(h.voids_filled);
    p.u64(h.data_offset);
    p.u64(h.raw_sample_bytes);
    p.0.resize(FIXED_HEADER - 4, 0);
    let crc = crc32fast::hash(&p.0);
    p.u32(crc);
    match &h.geo {
        None => p.u32(0),
        Some(GeoReference::Geographic {
            south_lat_deg,
            west_lon_deg,
            dlat_deg,
            dlon_deg,
        }) => {
            p.u32(1);
            for v in [*south_lat_deg, *west_lon_deg, *dlat_deg, *dlon_deg] {
                p.f64(v);
            }
        }
        Some(GeoReference::Projected {
            crs,
            easting,
            northing,
        }) => {
            p.u32(2);
            p.str(crs);
            p.f64(*easting);
            p.f64(*northing);
        }
    }
    p.str(&h.spacing_note);
    p.u32(h.sources.len() as u32);
    for s in &h.sources {
        p.str(s);
    }
    p.u32(h.max_eps.len() as u32);
    for e in &h.max_eps {
        p.0.extend_from_slice(&e.to_le_bytes());
    }
    let crc = crc32fast::hash(&p.0);
    p.u32(crc);
    p.0
}

/// Bytes [`encode_header`] makes of `h` (whatever its `header_size` says).
pub fn header_len(h: &StoreHeader) -> usize {
    encode_header(h).len()
}

/// Why header or index bytes are refused: the byte offset, the field, the reason.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldError {
    pub offset: u64,
    pub field: &'static str,
    pub reason: String,
}

pub(super) fn field_err(
    offset: usize,
    field: &'static str,
    reason: impl Into<String>,
) -> FieldError {
    FieldError {
        offset: offset as u64,
        field,
        reason: reason.into(),
    }
}

/// A little-endian reader over header bytes that names the offset of what it cannot read.
struct Get<'a> {
    b: &'a [u8],
    at: usize,
}

impl Get<'_> {
    fn take(&mut self, n: usize, field: &'static str) -> Result<&[u8], FieldError> {
        if self.b.len() - self.at < n {
            return Err(field_err(
                self.at,
                field,
                format!("the header ends at byte {} inside this field", self.b.len()),
            ));
        }
        let s = &self.b[self.at..self.at + n];
        self.at += n;
        Ok(s)
    }
    fn u32(&mut self, field: &'static str) -> Result<u32, FieldError> {
        let s = self.take(4, field)?;
        Ok(u32::from_le_bytes(s.try_into().expect("4 bytes")))
    }
    fn u64(&mut self, field: &'static str) -> Result<u64, FieldError> {
        let s = self.take(8, field)?;
        Ok(u64::from_le_bytes(s.try_into().expect("8 bytes")))
    }
    fn f64(&mut self, field: &'static str) -> Result<f64, FieldError> {
        let s = self.take(8, field)?;
        Ok(f64::from_le_bytes(s.try_into().expect("8 bytes")))
    }
    fn str(&mut self, field: &'static str) -> Result<String, FieldError> {
        let at = self.at;
        let n = self.u32(field)? as usize;
        let s = self.take(n, field)?;
        String::from_utf8(s.to_vec()).map_err(|_| field_err(at, field, "not UTF-8"))
    }
}

/// The fixed part: magic, version, header size, its CRC. Returns the header size.
pub fn check_fixed(b: &[u8]) -> Result<u32, FieldError> {
    if b.len() < FIXED_HEADER {
        return Err(field_err(
            b.len(),
            "header",
            format!(
                "the file is {} bytes, shorter than the {FIXED_HEADER}-byte header",
                b.len()
            ),
        ));
    }
    if &b[..8] != STORE_MAGIC {
        return Err(field_err(
            0,
            "magic",
            format!(
                "{:02x?} is not an aerie store (expected \"AERIESTO\")",
                &b[..8]
            ),
        ));
    }
    let version = u32::from_le_bytes(b[8..12].try_into().expect("4"));
    if version > STORE_VERSION {
        return Err(field_err(
            8,
            "format version",
            format!("version {version} is newer than this aerie reads ({STORE_VERSION}); update aerie or re-import"),
        ));
    }
    if version == 0 {
        return Err(field_err(
            8,
            "format version",
            "version 0 is not a store version",
        ));
    }
    if version < OLDEST_STORE_VERSION {
        return Err(field_err(
            8,
            "format version",
            format!("version {version} is older than this aerie reads ({OLDEST_STORE_VERSION}..={STORE_VERSION}: the error bake in its own section, so a store opens without reading its pages); re-import it with `aerie import`"),
        ));
    }
    let want = u32::from_le_bytes(b[FIXED_HEADER - 4..FIXED_HEADER].try_into().expect("4"));
    let got = crc32fast::hash(&b[..FIXED_HEADER - 4]);
    if got != want {
        return Err(field_err(
            FIXED_HEADER - 4,
            "header CRC-32",
            format!("bytes 0..{} have CRC-32 {got:#010x}, the header says {want:#010x}: the header is corrupt", FIXED_HEADER - 4),
        ));
    }
    let size = u32::from_le_bytes(b[12..16].try_into().expect("4"));
    if (size as usize) < FIXED_HEADER + 20 || size as usize > MAX_HEADER {
        return Err(field_err(
            12,
            "header size",
            format!(
                "{size} bytes is outside {}..={MAX_HEADER}",
                FIXED_HEADER + 20
            ),
        ));
    }
    Ok(size)
}

/// The whole header (`b` holds exactly `header_size` bytes, the fixed part already checked).
pub fn decode_header(b: &[u8]) -> Result<StoreHeader, FieldError> {
    let n = b.len();
    let want = u32::from_le_bytes(b[n - 4..].try_into().expect("4"));
    let got = crc32fast::hash(&b[..n - 4]);
    if got != want {
        return Err(field_err(
            n - 4,
            "header CRC-32",
            format!("bytes 0..{} have CRC-32 {got:#010x}, the header says {want:#010x}: the header is corrupt", n - 4),
        ));
    }
    let body = &b[..n - 4];
    let mut g = Get { b: body, at: 8 };
    let version = g.u32("format version")?;
    let header_size = g.u32("header size")?;
    let tile_size = g.u32("tile size")?;
    let page_tiles = g.u32("page tiles")?;
    let levels = g.u32("levels")?;
    let width = g.u32("width")?;
    let height = g.u32("height")?;
    let valid_width = g.u32("valid width")?;
    let valid_height = g.u32("valid height")?;
    let page_count = g.u32("page count")?;
    let spacing_x = g.f64("spacing x")?;
    let spacing_y = g.f64("spacing y")?;
    let source_checksum = g.u32("source checksum")?;
    let _flags = g.u32("flags")?;
    let voids_filled = g.u64("voids filled")?;
    let data_offset = g.u64("data offset")?;
    let raw_sample_bytes = g.u64("raw sample bytes")?;
    if data_offset != u64::from(header_size) {
        return Err(field_err(
            80,
            "data offset",
            format!("{data_offset} is not the header size {header_size}"),
        ));
    }
    g.at = FIXED_HEADER;
    let at = g.at;
    let geo = match g.u32("geo-reference kind")? {
        0 => None,
        1 => Some(GeoReference::Geographic {
            south_lat_deg: g.f64("geo south latitude")?,
            west_lon_deg: g.f64("geo west longitude")?,
            dlat_deg: g.f64("geo latitude step")?,
            dlon_deg: g.f64("geo longitude step")?,
        }),
        2 => Some(GeoReference::Projected {
            crs: g.str("geo CRS")?,
            easting: g.f64("geo easting")?,
            northing: g.f64("geo northing")?,
        }),
        k => {
            return Err(field_err(
                at,
                "geo-reference kind",
                format!("{k} is not 0 (none), 1 (geographic) or 2 (projected)"),
            ))
        }
    };
    let spacing_note = g.str("spacing note")?;
    let at = g.at;
    let count = g.u32("source count")? as usize;
    if count > body.len() / 4 {
        return Err(field_err(
            at,
            "source count",
            format!("{count} sources cannot fit a {n}-byte header"),
        ));
    }
    let mut sources = Vec::with_capacity(count);
    for _ in 0..count {
        sources.push(g.str("source")?);
    }
    let at = g.at;
    let n_eps = g.u32("max ε count")?;
    if n_eps != levels {
        return Err(field_err(
            at,
            "max ε count",
            format!("{n_eps} values for {levels} levels"),
        ));
    }
    let mut max_eps = Vec::with_capacity(n_eps as usize);
    for _ in 0..n_eps {
        max_eps.push(f32::from_bits(g.u32("max ε")?));
    }
    if g.at != body.len() {
        return Err(field_err(
            g.at,
            "header size",
            format!(
                "the header's fields end at byte {}, its size says {}",
                g.at,
                body.len() + 4
            ),
        ));
    }
    Ok(StoreHeader {
        version,
        header_size,
        tile_size,
        page_tiles,
        levels,
        width,
        height,
        valid_width,
        valid_height,
        page_count,
        spacing_x,
        spacing_y,
        source_checksum,
        voids_filled,
        data_offset,
        raw_sample_bytes,
        geo,
        spacing_note,
        sources,
        max_eps,
    })
}

/// The layout the header's sizes make, or which field disagrees with it.
pub fn check_layout(h: &StoreHeader) -> Result<Layout, FieldError> {
    let q = h.tile_size.wrapping_sub(1);
    if !(3..=257).contains(&h.tile_size) || !q.is_power_of_two() {
        return Err(field_err(
            16,
            "tile size",
            format!("{} is not 2^j + 1 in 3..=257", h.tile_size),
        ));
    }
    if h.page_tiles == 0 || !h.page_tiles.is_power_of_two() || h.page_tiles > 1024 {
        return Err(field_err(
            20,
            "page tiles",
            format!("{} is not a power of two ≤ 1024", h.page_tiles),
        ));
    }
    if !(h.spacing_x.is_finite()
        && h.spacing_x > 0.0
        && h.spacing_y.is_finite()
        && h.spacing_y > 0.0)
    {
        return Err(field_err(
            48,
            "spacing",
            format!(
                "{} × {} m is not positive and finite",
                h.spacing_x, h.spacing_y
            ),
        ));
    }
    if h.valid_width < 2
        || h.valid_width > h.width
        || h.valid_height < 2
        || h.valid_height > h.height
    {
        return Err(field_err(
            36,
            "valid size",
            format!(
                "{}×{} real samples do not fit the {}×{} grid",
                h.valid_width, h.valid_height, h.width, h.height
            ),
        ));
    }
    let layout = Layout::new(h.width, h.height, q, h.levels, h.page_tiles).ok_or_else(|| {
        field_err(
            24,
            "levels",
            format!(
                "{} levels of {}-vertex tiles do not tile a {}×{} grid",
                h.levels, h.tile_size, h.width, h.height
            ),
        )
    })?;
    if layout.page_count() != h.page_count {
        return Err(field_err(
            44,
            "page count",
            format!(
                "{} pages, but the grid and levels make {}",
                h.page_count,
                layout.page_count()
            ),
        ));
    }
    Ok(layout)
}
