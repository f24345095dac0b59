//! The imagery layer against its draper: every page of every level read back equal to the
//! draped window it was written from, level 0 equal to the in-memory drape, coarse levels
//! averaging fine imagery instead of aliasing it, the streamed store gathering a strip's
//! texels across pages; damaged layers and layers of other stores refused naming the field.

use std::path::PathBuf;
use std::time::Duration;

use super::tests::{baked, dataset, import, srtm_like};
use super::*;
use crate::drape::{
    drape_rgba, DrapeSize, GeoRaster, LevelDraper, RasterCrs, RasterRef, TerrainGrid,
};
use crate::source::{SampleRect, TerrainSource};
use crate::stream::{StreamParams, StreamedStore};

/// A geographic RGB raster over the test grid (47°N 11°E, 1/1200° a sample): `ppd` pixels per
/// sample, covering columns/rows [c0, c0 + n) of samples, colour `f(col, row)`.
fn raster(
    ppd: usize,
    c0: f64,
    r0: f64,
    n: usize,
    f: impl Fn(usize, usize) -> [u8; 3],
) -> GeoRaster {
    let d = 1.0 / 1200.0 / ppd as f64;
    let (w, h) = (n * ppd, n * ppd);
    let data = (0..h)
        .flat_map(|r| (0..w).map(move |c| (c, r)))
        .flat_map(|(c, r)| f(c, r))
        .collect();
    // Pixel centres: the first (north-west) at sample (c0, r0 + n) − half a pixel inwards.
    GeoRaster {
        path: "test.tif".into(),
        width: w,
        height: h,
        bands: 3,
        data,
        georef: RasterRef {
            crs: RasterCrs::Geographic,
            x0: 11.0 + (c0 - 0.5) / 1200.0 + d / 2.0,
            y0: 47.0 + (r0 + n as f64 - 0.5) / 1200.0 - d / 2.0,
            dx: d,
            dy: d,
        },
    }
}

fn smooth(c: usize, r: usize) -> [u8; 3] {
    [
        (c * 3 % 256) as u8,
        (r * 5 % 256) as u8,
        ((c + r) % 256) as u8,
    ]
}

struct Fixture {
    _dir: tempfile::TempDir,
    store_path: PathBuf,
    draper: LevelDraper,
    grid: TerrainGrid,
}

/// The test store (150 × 130 samples of 30 m × 20 m, pages of 2 tiles) in `dir`.
fn test_store(dir: &std::path::Path) -> (PathBuf, Store, TerrainGrid) {
    let ds = dataset(150, 130, srtm_like);
    let b = baked(&ds, 17);
    let (store_path, _) = import(dir, &ds, &b, 2);
    let store = Store::open(&store_path).unwrap();
    let grid = store_grid(&store).unwrap();
    (store_path, store, grid)
}

fn fixture(k: u32, rasters: &[GeoRaster]) -> Fixture {
    let dir = tempfile::tempdir().unwrap();
    let (store_path, store, grid) = test_store(dir.path());
    let draper = LevelDraper::new(&grid, rasters, k, store.header().levels).unwrap();
    let s = write_imagery_in(
        aerie_io::real(),
        &store,
        &draper,
        vec!["test.tif".into()],
        3,
        &|_, _| {},
    )
    .unwrap();
    assert_eq!(s.pages, store.header().page_count);
    assert!(s.covered_pages > 0 && s.covered_texels < s.texels, "{s:?}");
    Fixture {
        _dir: dir,
        store_path,
        draper,
        grid,
    }
}

fn open_layer(f: &Fixture) -> Result<ImageryLayer, StoreError> {
    let store = Store::open(&f.store_path).unwrap();
    ImageryLayer::open_in(
        aerie_io::real(),
        &imagery_path(&f.store_path),
        store.header(),
        store.layout(),
        &f.grid,
    )
}

#[test]
fn every_page_reads_back_as_draped_and_level_0_is_the_in_memory_drape() {
    let r = raster(3, 20.0, 10.0, 90, smooth);
    let f = fixture(2, std::slice::from_ref(&r));
    let layer = open_layer(&f).unwrap();
    let store = Store::open(&f.store_path).unwrap();
    let layout = store.layout();
    // The whole level-0 raster, as the in-memory drape makes it at k = 2.
    let size = DrapeSize {
        width: f.grid.width * 2,
        height: f.grid.height * 2,
        texels_per_sample: 2,
    };
    let mut whole = vec![0u8; size.texels() * 4];
    drape_rgba(&f.grid, &size, &r, &mut whole).unwrap();
    let mut level0_seen = 0;
    for i in 0..layout.page_count() as usize {
        let (level, px, py) = layout.page_at(i).unwrap();
        let id = PageId { level, px, py };
        let page = layer.read_page(id).unwrap();
        let (origin, sz) = page_texels_of(layout, &f.grid, 2, id);
        assert_eq!((page.origin, page.size), (origin, sz), "{id}");
        let (want, _) = f.draper.window(level, origin[0], origin[1], sz[0], sz[1]);
        assert!(page.rgba == want, "{id}: texels differ from the draper's");
        if level == 0 {
            for y in 0..sz[1] {
                for x in 0..sz[0] {
                    let (gx, gy) = (origin[0] + x, origin[1] + y);
                    let a = &page.rgba[(y * sz[0] + x) * 4..][..4];
                    let b = &whole[(gy * size.width + gx) * 4..][..4];
                    assert_eq!(a, b, "level 0 texel ({gx}, {gy})");
                    level0_seen += 1;
                }
            }
        }
    }
    assert_eq!(
        level0_seen,
        size.texels(),
        "level 0's pages tile its raster"
    );
    assert_eq!(layer.texels_per_sample(), 2);
    assert_eq!(layer.header().sources, vec!["test.tif".to_string()]);
}

fn page_texels_of(
    layout: &Layout,
    grid: &TerrainGrid,
    k: u32,
    id: PageId,
) -> ([usize; 2], [usize; 2]) {
    super::imagery::page_texels(layout, grid, k, id)
}

#[test]
fn coarse_levels_average_fine_imagery_instead_of_aliasing_it() {
    // A one-pixel checkerboard, 4 pixels per sample: any level ≥ 1 texel spans many pixels.
    let r = raster(4, 0.0, 0.0, 150, |c, r| {
        if (c + r) % 2 == 0 {
            [255; 3]
        } else {
            [0; 3]
        }
    });
    let f = fixture(1, &[r]);
    let layer = open_layer(&f).unwrap();
    let store = Store::open(&f.store_path).unwrap();
    // Half the light in linear terms is sRGB 188; a point sample would give 0 or 255.
    let page = layer
        .read_page(PageId {
            level: 3,
            px: 0,
            py: 0,
        })
        .unwrap();
    let [w, h] = page.size;
    let inner: Vec<u8> = (1..h - 1)
        .flat_map(|y| (1..w - 1).map(move |x| (x, y)))
        .map(|(x, y)| page.rgba[(y * w + x) * 4])
        .collect();
    assert!(!inner.is_empty() && store.header().levels > 3);
    for v in inner {
        assert!(
            (170..=205).contains(&v),
            "level 3 texel {v}: aliased, not averaged"
        );
    }
}

#[test]
fn the_streamed_store_and_the_whole_store_gather_a_strip_of_texels_across_pages() {
    let r = raster(2, 5.0, 5.0, 120, smooth);
    let f = fixture(2, &[r]);
    let (s, _) = StreamedStore::open(&f.store_path, StreamParams::default()).unwrap();
    assert_eq!(s.imagery_texels_per_sample(), Some(2));
    // The store read whole (`--load-whole`) reads its imagery pages on the spot.
    let (ds, _) = load_store(&f.store_path).unwrap();
    let whole = crate::source::InMemoryTerrain::new(std::sync::Arc::new(ds))
        .with_imagery(open_layer(&f).unwrap());
    assert_eq!(whole.imagery_texels_per_sample(), Some(2));
    for (level, origin, size) in [
        (0u32, [3i64, 7], [140u32, 20]),
        (1, [10, 0], [30, 60]),
        (2, [-8, 4], [40, 40]),
    ] {
        let rect = SampleRect {
            level,
            origin: origin.map(|o| o << level),
            size,
        };
        s.wait_resident(&[rect], Duration::from_secs(20)).unwrap();
        let (w, h) = (size[0] as usize * 2, size[1] as usize * 2);
        let mut got = vec![7u8; w * h * 4];
        s.gather_imagery(&rect, &mut got).unwrap();
        let mut got_whole = vec![7u8; w * h * 4];
        whole.gather_imagery(&rect, &mut got_whole).unwrap();
        assert!(
            got_whole == got,
            "level {level}: the whole store gathers another strip"
        );
        // The oracle: the draper's window, clipped to the level's raster (transparent beyond).
        let (ew, eh) = f.draper.level_extent(level);
        let x0 = origin[0] * 2;
        let y0 = origin[1] * 2;
        let mut want = vec![0u8; w * h * 4];
        let (cx0, cy0) = (x0.max(0) as usize, y0.max(0) as usize);
        let cx1 = ((x0 + w as i64) as usize).min(ew);
        let cy1 = ((y0 + h as i64) as usize).min(eh);
        let (win, _) = f.draper.window(level, cx0, cy0, cx1 - cx0, cy1 - cy0);
        for y in cy0..cy1 {
            for x in cx0..cx1 {
                let src = ((y - cy0) * (cx1 - cx0) + (x - cx0)) * 4;
                let dst = ((y as i64 - y0) as usize * w + (x as i64 - x0) as usize) * 4;
                want[dst..dst + 4].copy_from_slice(&win[src..src + 4]);
            }
        }
        // Exact: the draper's lattice is anchored at the level raster, not at a window.
        let bad = got.iter().zip(&want).position(|(a, b)| a != b);
        assert!(
            bad.is_none(),
            "level {level} strip at {origin:?}: first difference at texel {:?} of {w}×{h}: {:?} vs {:?}",
            bad.map(|i| (i / 4 % w, i / 4 / w)),
            bad.map(|i| &got[i / 4 * 4..i / 4 * 4 + 4]),
            bad.map(|i| &want[i / 4 * 4..i / 4 * 4 + 4]),
        );
    }
}

fn layer_bytes(f: &Fixture) -> Vec<u8> {
    std::fs::read(imagery_path(&f.store_path)).unwrap()
}

fn refused(f: &Fixture, bytes: &[u8]) -> String {
    std::fs::write(imagery_path(&f.store_path), bytes).unwrap();
    open_layer(f).unwrap_err().to_string()
}

#[test]
fn damaged_layers_are_refused_naming_the_field() {
    let f = fixture(1, &[raster(1, 0.0, 0.0, 100, smooth)]);
    let good = layer_bytes(&f);
    let mut b = good.clone();
    b[3] ^= 1;
    assert!(refused(&f, &b).contains("magic"));
    let mut b = good.clone();
    b[8] = 9;
    assert!(refused(&f, &b).contains("version"));
    let mut b = good.clone();
    b[33] ^= 1;
    let e = refused(&f, &b);
    assert!(e.contains("header CRC") && e.contains("60"), "{e}");
    let e = refused(&f, &good[..good.len() - 5]);
    assert!(e.contains("trailer"), "{e}");
    // A flipped index byte: the index checksum names it.
    let t = good.len() - 32;
    let index_at = u64::from_le_bytes(good[t + 8..t + 16].try_into().unwrap()) as usize;
    let mut b = good.clone();
    b[index_at + 1] ^= 0x40;
    assert!(refused(&f, &b).contains("index"));
    // Every single-byte flip is refused or named by its page, never a panic, never other data.
    std::fs::write(imagery_path(&f.store_path), &good).unwrap();
    let intact = open_layer(&f).unwrap();
    let store = Store::open(&f.store_path).unwrap();
    let pages: Vec<PageId> = (0..store.layout().page_count() as usize)
        .map(|i| {
            let (level, px, py) = store.layout().page_at(i).unwrap();
            PageId { level, px, py }
        })
        .collect();
    let want: Vec<ImageryPage> = pages
        .iter()
        .map(|&p| intact.read_page(p).unwrap())
        .collect();
    for at in (0..good.len()).step_by(good.len() / 97 + 1) {
        let mut b = good.clone();
        b[at] ^= 0x10;
        std::fs::write(imagery_path(&f.store_path), &b).unwrap();
        let Ok(layer) = open_layer(&f) else { continue };
        let mut named = 0;
        for (p, w) in pages.iter().zip(&want) {
            match layer.read_page(*p) {
                Ok(got) => assert_eq!(&got, w, "flip at byte {at} changed {p}"),
                Err(e) => {
                    assert!(e.to_string().contains(&p.to_string()), "{e}");
                    named += 1;
                }
            }
        }
        assert_eq!(
            named, 1,
            "a flip at byte {at} inside the pages fails one page"
        );
    }
}

#[test]
fn a_layer_of_another_store_is_refused_naming_the_field() {
    let f = fixture(1, &[raster(1, 0.0, 0.0, 100, smooth)]);
    let layer = layer_bytes(&f);
    // Another store of the same size over other heights: the checksum differs.
    let dir = tempfile::tempdir().unwrap();
    let other = dataset(150, 130, |c, r| srtm_like(c, r) + 1.0);
    let (p, _) = import(dir.path(), &other, &baked(&other, 17), 2);
    std::fs::write(imagery_path(&p), &layer).unwrap();
    let store = Store::open(&p).unwrap();
    let e = ImageryLayer::open_in(
        aerie_io::real(),
        &imagery_path(&p),
        store.header(),
        store.layout(),
        &f.grid,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("store checksum") && e.contains("byte 48"), "{e}");
    // The streamed store refuses it too, instead of drawing another store's imagery.
    let e = StreamedStore::open(&p, StreamParams::default())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("store checksum"), "{e}");
}

#[test]
fn a_stores_texels_per_sample_follow_the_finest_raster_as_a_power_of_two() {
    let dir = tempfile::tempdir().unwrap();
    let (_, store, grid) = test_store(dir.path());
    // The grid's samples are 30 m × 20 m; a raster of p pixels per 1/1200° has pixels of
    // 63.2/p m × 92.6/p m at 47°N: 0.475·p of them per sample E-W, the finer axis.
    for (p, k) in [(1, 1), (4, 2), (8, 4), (16, 4)] {
        let r = raster(p, 0.0, 0.0, 10, smooth);
        assert_eq!(
            crate::drape::store_texels_per_sample(&grid, &[r]),
            k,
            "{p} pixels per 1/1200°"
        );
    }
    // A raster far off the terrain covers nothing at the coarsest level; one on it does.
    let levels = store.header().levels;
    let off = raster(2, 5000.0, 5000.0, 20, smooth);
    let on = raster(2, 40.0, 40.0, 20, smooth);
    let d = LevelDraper::new(&grid, &[off], 2, levels).unwrap();
    assert_eq!(d.coarse_coverage(levels), 0);
    let d = LevelDraper::new(&grid, &[on], 2, levels).unwrap();
    assert!(d.coarse_coverage(levels) > 0);
}

#[test]
fn a_whole_level_reads_back_as_its_draped_raster_and_the_budget_picks_the_level() {
    let r = raster(2, 10.0, 10.0, 100, smooth);
    let f = fixture(2, std::slice::from_ref(&r));
    let layer = open_layer(&f).unwrap();
    let levels = layer.layout().levels.len() as u32;
    for level in [0, 1, levels - 1] {
        let ticks = std::cell::Cell::new(0);
        let (got, failed) = read_level(&layer, level, &|_, _| ticks.set(ticks.get() + 1));
        assert!(failed.is_empty(), "{failed:?}");
        let (w, h) = f.draper.level_extent(level);
        assert_eq!((got.width, got.height, got.level), (w, h, level));
        let (want, _) = f.draper.window(level, 0, 0, w, h);
        assert!(
            got.rgba == want,
            "level {level} differs from its draped raster"
        );
        let g = layer.layout().levels[level as usize];
        assert_eq!(ticks.get(), g.pages_x * g.pages_y, "progress per page");
        assert_eq!(got.samples_per_texel(), f64::from(1u32 << level) / 2.0);
    }
    // Level 0 is 300 × 260 texels: 416,000 bytes with its mips.
    let bytes = |l: u32| {
        let (w, h) = f.draper.level_extent(l);
        (w * h) as u64 * 16 / 3
    };
    assert_eq!(choose_level(&layer, bytes(0), 300), Some(0));
    assert_eq!(choose_level(&layer, bytes(0) - 1, 300), Some(1));
    assert_eq!(choose_level(&layer, bytes(0), 299), Some(1));
    assert_eq!(choose_level(&layer, 0, 300), None);
    // A damaged page is named and left transparent; the rest of its level reads as draped.
    let mut b = layer_bytes(&f);
    let at = layer.header().header_size as usize + 10;
    b[at] ^= 0x5a;
    std::fs::write(imagery_path(&f.store_path), &b).unwrap();
    let layer = open_layer(&f).unwrap();
    let (got, failed) = read_level(&layer, 0, &|_, _| {});
    assert_eq!(failed.len(), 1, "{failed:?}");
    let e = failed[0].to_string();
    assert!(e.contains("aerie-imagery") && e.contains("level 0"), "{e}");
    let (w, h) = f.draper.level_extent(0);
    let (want, _) = f.draper.window(0, 0, 0, w, h);
    let differing = got
        .rgba
        .chunks(4)
        .zip(want.chunks(4))
        .filter(|(a, b)| a != b)
        .count();
    assert!(got.rgba.chunks(4).filter(|p| p[3] == 0).count() >= differing);
    assert!(
        differing > 0,
        "the damaged page's texels are not the draper's"
    );
    let first = layout_first_page_texels(&layer);
    assert!(
        differing <= first,
        "{differing} texels differ, the page holds {first}"
    );
}

/// Texels of the first non-empty page of level 0 (the one right after the header).
fn layout_first_page_texels(layer: &ImageryLayer) -> usize {
    let g = layer.layout().levels[0];
    (0..g.pages_y)
        .flat_map(|py| (0..g.pages_x).map(move |px| (px, py)))
        .map(|(px, py)| {
            let (_, [w, h]) =
                page_texels_of(layer.layout(), layer.grid(), 2, PageId { level: 0, px, py });
            w * h
        })
        .find(|&n| n > 0)
        .unwrap()
}
