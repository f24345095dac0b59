//! `aerie info <store>`: what a tile store holds — header, levels, pages, bytes, compression
//! ratio — from its header, index and bake section alone (no page is read), with the time
//! open and the bake section took (what a renderer's start-up reads); `--json` prints it as
//! JSON.
//! `--verify` also reads the bake section and every page (CRC-32, decompression, content, the
//! page's tables against the bake section) and reports the bad ones by reason and the read
//! throughput; a bad page or bake section makes the exit code 2. A store's imagery layer
//! (`<name>.aerie-imagery`) is described too, and verified page by page with `--verify`; a
//! layer that cannot be opened (damaged, another store's) is reported and exits 2.

use std::path::PathBuf;

use clap::Args;

use crate::app::failure::{bad_input, runtime, Failure};
use crate::app::progress::human_bytes;
use aerie_terrain::store::{
    open_imagery_beside, Coding, ImageryLayer, PageError, PageId, Store, StoreError,
};
use aerie_terrain::GeoReference;

/// What `info` says of a store whose bake section is older than this build writes: version
/// 2 has one ε per tile, version 3 the quadrants' ε but not the blocks'.
fn old_bake_section(version: u32) -> Option<&'static str> {
    match version {
        2 => Some(OLD_BAKE_SECTION),
        3 => Some(OLD_BAKE_SECTION_3),
        _ => None,
    }
}

/// What `info` says of a version-2 store, whose bake section has one ε per tile.
const OLD_BAKE_SECTION: &str = "format 2: one ε per tile, so a quadrant drawn at its parent's resolution is bounded by the parent's ε and a tile at its grandparent's by the grandparent's (it draws more than it needs); re-import the store with `aerie import` for the measured quadrant and block ε";
/// What `info` says of a version-3 store, whose bake section has the quadrants' ε only.
const OLD_BAKE_SECTION_3: &str = "format 3: ε over each tile's quadrants but not its 16 blocks, so a tile drawn at its grandparent's resolution is bounded by its parent's ε there (it draws more than it needs); re-import the store with `aerie import` for the measured block ε";

#[derive(Debug, Args)]
pub struct InfoArgs {
    /// The store (`<name>.aerie`).
    pub store: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Read and check every page (CRC-32, decompression, content) and time it.
    #[arg(long)]
    pub verify: bool,
}

/// What `--verify` found.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Verify {
    pub pages: u64,
    pub samples: u64,
    pub stored_bytes: u64,
    /// Bad pages by reason: unreadable, checksum, content.
    pub read_errors: u64,
    pub checksum_errors: u64,
    pub content_errors: u64,
    /// The first error of each reason, as its message.
    pub first_errors: Vec<String>,
    pub seconds: f64,
}

impl Verify {
    pub fn bad(&self) -> u64 {
        self.read_errors + self.checksum_errors + self.content_errors
    }
}

/// Reads the bake section and every page of `store` once, counting what fails by reason (a
/// bake section that cannot be read counts as one content error).
pub fn verify(store: &Store) -> Verify {
    let t = std::time::Instant::now();
    let mut v = Verify::default();
    let bake = match store.read_bake() {
        Ok(b) => Some(b),
        Err(e) => {
            v.content_errors += 1;
            v.first_errors.push(e.to_string());
            None
        }
    };
    for e in store.pages() {
        let id = PageId {
            level: e.level,
            px: e.px,
            py: e.py,
        };
        v.stored_bytes += u64::from(e.len);
        let checked = store.read_page(id).and_then(|p| match &bake {
            Some(b) => p
                .check_tables(b)
                .map(|_| p)
                .map_err(|reason| PageError::Content {
                    path: store.path().to_path_buf(),
                    page: id,
                    offset: e.offset,
                    end: e.offset + u64::from(e.len),
                    reason,
                }),
            None => Ok(p),
        });
        match checked {
            Ok(p) => {
                v.pages += 1;
                v.samples += p.samples.len() as u64;
            }
            Err(err) => count_error(&mut v, err),
        }
    }
    v.seconds = t.elapsed().as_secs_f64();
    v
}

/// Reads every page of the imagery layer once (CRC-32, decompression, size), counting what
/// fails by reason; `samples` counts texels.
pub fn verify_imagery(layer: &ImageryLayer) -> Verify {
    let t = std::time::Instant::now();
    let mut v = Verify {
        stored_bytes: layer.stored_bytes(),
        ..Verify::default()
    };
    for i in 0..layer.page_count() {
        let Some((level, px, py)) = layer.layout().page_at(i) else {
            continue;
        };
        match layer.read_page(PageId { level, px, py }) {
            Ok(p) => {
                v.pages += 1;
                v.samples += (p.size[0] * p.size[1]) as u64;
            }
            Err(err) => count_error(&mut v, err),
        }
    }
    v.seconds = t.elapsed().as_secs_f64();
    v
}

fn count_error(v: &mut Verify, err: PageError) {
    let n = match err {
        PageError::Checksum { .. } => &mut v.checksum_errors,
        PageError::Content { .. } => &mut v.content_errors,
        PageError::Read { .. } | PageError::NoSuchPage { .. } => &mut v.read_errors,
    };
    if *n == 0 {
        v.first_errors.push(err.to_string());
    }
    *n += 1;
}

fn imagery_json(layer: &ImageryLayer, checked: Option<&Verify>) -> serde_json::Value {
    let h = layer.header();
    serde_json::json!({
        "layer": layer.path().display().to_string(),
        "texels_per_sample": h.texels_per_sample,
        "pages": layer.page_count(),
        "stored_bytes": layer.stored_bytes(),
        "texel_bytes": layer.texel_bytes(),
        "sources": h.sources,
        "verify": checked.map(verify_json),
    })
}

fn verify_json(v: &Verify) -> serde_json::Value {
    serde_json::json!({
        "pages_ok": v.pages,
        "read_errors": v.read_errors,
        "checksum_errors": v.checksum_errors,
        "content_errors": v.content_errors,
        "first_errors": v.first_errors,
        "seconds": v.seconds,
        "stored_mb_per_s": v.stored_bytes as f64 / v.seconds.max(1e-9) / 1e6,
        "samples_per_s": v.samples as f64 / v.seconds.max(1e-9),
    })
}

fn verdict(v: Option<&Verify>, imagery: Option<&Verify>) -> Result<(), Failure> {
    let say = |what: &str, v: &Verify| {
        format!(
            "{} bad {what} ({} unreadable, {} checksum, {} content); first: {}",
            v.bad(),
            v.read_errors,
            v.checksum_errors,
            v.content_errors,
            v.first_errors.join("; ")
        )
    };
    let bad: Vec<String> = [(v, "pages"), (imagery, "imagery pages")]
        .into_iter()
        .filter_map(|(v, what)| v.filter(|v| v.bad() > 0).map(|v| say(what, v)))
        .collect();
    if bad.is_empty() {
        Ok(())
    } else {
        Err(bad_input(bad.join("; ")))
    }
}

/// Per level, from the index: tiles, pages, stored bytes, pages coded as integers.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelInfo {
    pub level: u32,
    pub tiles: [u32; 2],
    pub pages: [u32; 2],
    pub bytes: u64,
    /// Pages coded as integers (exactly, or with exceptions).
    pub i16_pages: u32,
    pub max_eps: f32,
}

/// The per-level table of an opened store.
pub fn levels(store: &Store) -> Vec<LevelInfo> {
    let h = store.header();
    store
        .layout()
        .levels
        .iter()
        .enumerate()
        .map(|(l, g)| {
            let entries = store.pages().iter().filter(|e| e.level == l as u32);
            let (bytes, i16_pages) = entries.fold((0u64, 0u32), |(b, n), e| {
                (
                    b + u64::from(e.len),
                    n + u32::from(e.coding != Coding::F32Xor),
                )
            });
            LevelInfo {
                level: l as u32,
                tiles: [g.tiles_x, g.tiles_y],
                pages: [g.pages_x, g.pages_y],
                bytes,
                i16_pages,
                max_eps: h.max_eps[l],
            }
        })
        .collect()
}

fn geo_text(g: &Option<GeoReference>) -> String {
    match g {
        None => "none".into(),
        Some(GeoReference::Geographic {
            south_lat_deg,
            west_lon_deg,
            dlat_deg,
            dlon_deg,
        }) => format!(
            "geographic, south-west sample {south_lat_deg}°, {west_lon_deg}°, steps {:.3}″ × {:.3}″",
            dlat_deg * 3600.0,
            dlon_deg * 3600.0
        ),
        Some(GeoReference::Projected {
            crs,
            easting,
            northing,
        }) => format!("{crs}, south-west sample E {easting} N {northing}"),
    }
}

pub fn run(a: InfoArgs) -> Result<(), Failure> {
    let to_failure = |e: StoreError| match e {
        StoreError::Io { .. } => runtime(e),
        _ => bad_input(e),
    };
    let t = std::time::Instant::now();
    let store = Store::open(&a.store).map_err(to_failure)?;
    let open_ms = t.elapsed().as_secs_f64() * 1e3;
    let t = std::time::Instant::now();
    // A bad bake section is reported after the summary (exit 2), as a bad page is.
    let bake_err = store
        .read_bake()
        .and_then(|b| store.check_consistency(&b))
        .err();
    let bake_ms = t.elapsed().as_secs_f64() * 1e3;
    let h = store.header();
    let lv = levels(&store);
    let page_bytes: u64 = store.pages().iter().map(|e| u64::from(e.len)).sum();
    let ratio = h.raw_sample_bytes as f64 / page_bytes.max(1) as f64;
    let checked = a.verify.then(|| verify(&store));
    // The imagery layer beside the store: described, verified with the pages; one that cannot
    // be opened is reported after the summary (exit 2).
    let (layer, layer_err) = match open_imagery_beside(&aerie_io::real(), &a.store, &store) {
        Ok(l) => (l, None),
        Err(e) => (None, Some(e)),
    };
    let layer_checked = layer.as_ref().filter(|_| a.verify).map(verify_imagery);
    let finish = |bake_err: Option<StoreError>| match bake_err.or(layer_err) {
        Some(e) => Err(to_failure(e)),
        None => verdict(checked.as_ref(), layer_checked.as_ref()),
    };
    if a.json {
        let v = serde_json::json!({
            "store": a.store.display().to_string(),
            "format_version": h.version,
            "quadrant_eps": h.version >= 3,
            "block_eps": h.version >= 4,
            "width": h.width,
            "height": h.height,
            "valid_width": h.valid_width,
            "valid_height": h.valid_height,
            "spacing_m": [h.spacing_x, h.spacing_y],
            "spacing_note": h.spacing_note,
            "geo": geo_text(&h.geo),
            "tile_size": h.tile_size,
            "page_tiles": h.page_tiles,
            "levels": h.levels,
            "pages": h.page_count,
            "file_bytes": store.file_len(),
            "page_bytes": page_bytes,
            "raw_sample_bytes": h.raw_sample_bytes,
            "compression_ratio": ratio,
            "source_checksum": format!("{:#010x}", h.source_checksum),
            "voids_filled": h.voids_filled,
            "sources": h.sources,
            "open_bytes": store.open_bytes(),
            "open_ms": open_ms,
            "bake_bytes": store.bake_bytes(),
            "bake_ms": bake_ms,
            "per_level": lv.iter().map(|l| serde_json::json!({
                "level": l.level,
                "tiles": l.tiles,
                "pages": l.pages,
                "bytes": l.bytes,
                "i16_pages": l.i16_pages,
                "max_eps_m": l.max_eps,
            })).collect::<Vec<_>>(),
            "verify": checked.as_ref().map(verify_json),
            "imagery": layer.as_ref().map(|l| imagery_json(l, layer_checked.as_ref())),
        });
        println!("{v:#}");
        return finish(bake_err);
    }
    println!(
        "{}: aerie tile store, format version {}",
        a.store.display(),
        h.version
    );
    if let Some(why) = old_bake_section(h.version) {
        println!("  {why}");
    }
    println!(
        "  grid {}×{} samples ({}×{} real), spacing {} m × {} m ({})",
        h.width, h.height, h.valid_width, h.valid_height, h.spacing_x, h.spacing_y, h.spacing_note
    );
    println!("  geo-reference: {}", geo_text(&h.geo));
    println!(
        "  tiles of {} vertices, pages of {}×{} tiles, {} levels, {} pages",
        h.tile_size, h.page_tiles, h.page_tiles, h.levels, h.page_count
    );
    println!(
        "  {} ({} of samples as f32, ratio {ratio:.2}); source checksum {:#010x}, {} voids filled",
        human_bytes(store.file_len()),
        human_bytes(h.raw_sample_bytes),
        h.source_checksum,
        h.voids_filled,
    );
    println!(
        "  open: {} read in {open_ms:.1} ms; bake section: {} read and decoded in {bake_ms:.1} ms",
        human_bytes(store.open_bytes()),
        human_bytes(store.bake_bytes())
    );
    let n = h.sources.len();
    match h.sources.as_slice() {
        [] => {}
        [one] => println!("  source: {one}"),
        [first, .., last] => println!("  sources: {n} files, {first} … {last}"),
    }
    println!("  level  tiles        pages      bytes      i16 pages  max ε (m)");
    for l in &lv {
        println!(
            "  {:>5}  {:>5}×{:<5}  {:>4}×{:<4}  {:>9}  {:>9}  {}",
            l.level,
            l.tiles[0],
            l.tiles[1],
            l.pages[0],
            l.pages[1],
            human_bytes(l.bytes),
            l.i16_pages,
            l.max_eps
        );
    }
    if let Some(v) = &checked {
        println!(
            "  verified {} of {} pages in {:.3} s: {:.0} MB/s stored, {:.1} M samples/s decoded; {} unreadable, {} checksum, {} content errors",
            v.pages,
            h.page_count,
            v.seconds,
            v.stored_bytes as f64 / v.seconds.max(1e-9) / 1e6,
            v.samples as f64 / v.seconds.max(1e-9) / 1e6,
            v.read_errors,
            v.checksum_errors,
            v.content_errors
        );
    }
    if let Some(l) = &layer {
        println!(
            "  imagery layer {}: {} texels per sample, {} pages, {} stored ({} of texels); from {}",
            l.path().display(),
            l.texels_per_sample(),
            l.page_count(),
            human_bytes(l.stored_bytes()),
            human_bytes(l.texel_bytes()),
            l.header().sources.join(", ")
        );
    }
    if let Some(v) = &layer_checked {
        println!(
            "  verified {} of {} imagery pages in {:.3} s; {} unreadable, {} checksum, {} content errors",
            v.pages,
            layer.as_ref().map_or(0, ImageryLayer::page_count),
            v.seconds,
            v.read_errors,
            v.checksum_errors,
            v.content_errors
        );
    }
    finish(bake_err)
}
