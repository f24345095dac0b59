//! Registration against the f64 geodesy: generated ramps and checkerboards with known corner
//! coordinates land on the right terrain samples within 0.5 px.

use std::path::{Path, PathBuf};

use super::*;
use crate::geodesy::UtmZone;
use crate::GeoReference;

/// The terrain of these tests: 64 × 48 samples of 3" at 47°N 11°E (the Inn valley's latitude).
fn geo_grid() -> TerrainGrid {
    let (sx, sy) = crate::load::geographic_spacing_m(47.0, 1.0 / 1200.0, 1.0 / 1200.0);
    TerrainGrid::new(
        64,
        48,
        sx,
        sy,
        Some(&GeoReference::Geographic {
            south_lat_deg: 47.0,
            west_lon_deg: 11.0,
            dlat_deg: 1.0 / 1200.0,
            dlon_deg: 1.0 / 1200.0,
        }),
    )
    .unwrap()
}

fn write(
    dir: &Path,
    name: &str,
    w: u32,
    h: u32,
    bands: usize,
    data: &[u8],
    geo: Option<EncodeRef>,
) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, encode_geotiff(w, h, bands, data, geo).unwrap()).unwrap();
    p
}

/// A ramp raster: R = 2 · column, G = 2 · row (so a decoded position is good to 1/4 px).
fn ramp(w: u32, h: u32) -> Vec<u8> {
    let mut v = Vec::new();
    for r in 0..h {
        for c in 0..w {
            v.extend_from_slice(&[(2 * c) as u8, (2 * r) as u8, 100]);
        }
    }
    v
}

/// Draped RGBA at texel (tx, ty).
fn texel(size: &DrapeSize, t: &[u8], tx: usize, ty: usize) -> [u8; 4] {
    let i = (ty * size.width + tx) * 4;
    [t[i], t[i + 1], t[i + 2], t[i + 3]]
}

/// Every texel whose expected pixel (from `expect`, the f64 geodesy) is inside the ramp decodes
/// to within 0.5 px of it; returns the worst offset and the texels checked.
fn check_ramp(
    grid: &TerrainGrid,
    size: &DrapeSize,
    t: &[u8],
    (w, h): (u32, u32),
    expect: impl Fn(f64, f64) -> (f64, f64),
) -> (f64, usize) {
    let (mut worst, mut n) = (0.0f64, 0);
    for ty in 0..size.height {
        for tx in 0..size.width {
            let (gx, gy) = size.texel_centre(grid, tx, ty);
            let (px, py) = expect(gx, gy);
            let c = texel(size, t, tx, ty);
            let inside = px > 0.0 && py > 0.0 && px < f64::from(w) - 1.0 && py < f64::from(h) - 1.0;
            if !inside {
                // Beyond the raster's outer half pixel: transparent.
                if px < -0.51 || py < -0.51 || px > f64::from(w) - 0.49 || py > f64::from(h) - 0.49
                {
                    assert_eq!(
                        c[3], 0,
                        "texel ({tx}, {ty}) outside the raster at {px}, {py}"
                    );
                }
                continue;
            }
            assert_eq!(c[3], 255);
            let (dx, dy) = (f64::from(c[0]) / 2.0 - px, f64::from(c[1]) / 2.0 - py);
            worst = worst.max(dx.abs()).max(dy.abs());
            n += 1;
        }
    }
    assert!(worst <= 0.5, "registration off by {worst} px");
    (worst, n)
}

#[test]
fn geographic_ramp_lands_within_half_a_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let grid = geo_grid();
    // 1.5" pixels from a corner 10.3" west and 7.1" north of the grid's first sample.
    let d = 1.5 / 3600.0;
    let (west, north) = (11.0 - 10.3 / 3600.0, 47.0 + 47.0 / 1200.0 + 7.1 / 3600.0);
    let (w, h) = (100, 110);
    let p = write(
        dir.path(),
        "ramp.tif",
        w,
        h,
        3,
        &ramp(w, h),
        Some(EncodeRef {
            epsg: 4326,
            west,
            north,
            dx: d,
            dy: d,
        }),
    );
    let raster = read_raster(&p).unwrap();
    let size = DrapeSize::choose(&grid, &[&raster], 8192);
    assert_eq!(size.texels_per_sample, 2, "3\" samples, 1.5\" pixels");
    assert_eq!((size.width, size.height), (128, 96));
    let mut t = vec![0u8; size.texels() * 4];
    drape_rgba(&grid, &size, &raster, &mut t).unwrap();
    let (worst, n) = check_ramp(&grid, &size, &t, (w, h), |gx, gy| {
        let (lat, lon) = (47.0 + gy / 1200.0, 11.0 + gx / 1200.0);
        // PixelIsArea: the first pixel's centre is half a pixel in from the corner.
        ((lon - west) / d - 0.5, (north - lat) / d - 0.5)
    });
    assert!(n > 5000, "{n} texels checked");
    eprintln!("geographic ramp on a geographic grid: worst {worst:.3} px over {n} texels");
}

#[test]
fn utm_ramp_over_a_geographic_grid_lands_within_half_a_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let grid = geo_grid();
    let zone = UtmZone::of_epsg(32632).unwrap();
    // 20 m pixels from a corner 300 m west and 200 m north of the grid's north-west sample.
    let (e_nw, n_nw) = zone.easting_northing(47.0 + 47.0 / 1200.0, 11.0);
    let (west, north, d) = (e_nw - 300.0, n_nw + 200.0, 20.0);
    let (w, h) = (127, 127);
    let p = write(
        dir.path(),
        "utm.tif",
        w,
        h,
        3,
        &ramp(w, h),
        Some(EncodeRef {
            epsg: 32632,
            west,
            north,
            dx: d,
            dy: d,
        }),
    );
    let raster = read_raster(&p).unwrap();
    let size = DrapeSize::choose(&grid, &[&raster], 8192);
    // 3" is 63 m E-W and 93 m N-S here: 5 texels per sample for 20 m pixels.
    assert_eq!(size.texels_per_sample, 5);
    let mut t = vec![0u8; size.texels() * 4];
    drape_rgba(&grid, &size, &raster, &mut t).unwrap();
    let (worst, n) = check_ramp(&grid, &size, &t, (w, h), |gx, gy| {
        let (e, nn) = zone.easting_northing(47.0 + gy / 1200.0, 11.0 + gx / 1200.0);
        ((e - west) / d - 0.5, (north - nn) / d - 0.5)
    });
    assert!(n > 20_000, "{n} texels checked");
    eprintln!("UTM ramp on a geographic grid: worst {worst:.3} px over {n} texels");
}

#[test]
fn geographic_ramp_over_a_utm_grid_lands_within_half_a_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let zone = UtmZone::of_epsg(32632).unwrap();
    let (e0, n0) = (650_000.0, 5_210_000.0);
    let grid = TerrainGrid::new(
        40,
        30,
        50.0,
        50.0,
        Some(&GeoReference::Projected {
            crs: "EPSG:32632".into(),
            easting: e0,
            northing: n0,
        }),
    )
    .unwrap();
    let (lat_sw, lon_sw) = zone.lat_lon(e0, n0).unwrap();
    let d = 1.0 / 3600.0;
    let (west, north) = (lon_sw - 20.0 * d, lat_sw + 80.0 * d);
    let (w, h) = (120, 100);
    let p = write(
        dir.path(),
        "geo.tif",
        w,
        h,
        3,
        &ramp(w, h),
        Some(EncodeRef {
            epsg: 4326,
            west,
            north,
            dx: d,
            dy: d,
        }),
    );
    let raster = read_raster(&p).unwrap();
    let size = DrapeSize::choose(&grid, &[&raster], 8192);
    let mut t = vec![0u8; size.texels() * 4];
    drape_rgba(&grid, &size, &raster, &mut t).unwrap();
    let (worst, n) = check_ramp(&grid, &size, &t, (w, h), |gx, gy| {
        let (lat, lon) = zone.lat_lon(e0 + gx * 50.0, n0 + gy * 50.0).unwrap();
        ((lon - west) / d - 0.5, (north - lat) / d - 0.5)
    });
    assert!(n > 5000, "{n} texels checked");
    eprintln!("geographic ramp on a UTM grid: worst {worst:.3} px over {n} texels");
}

/// The registration test: a checkerboard of 4-pixel cells with known corners; every
/// terrain sample more than half a pixel inside a cell takes exactly that cell's colour.
#[test]
fn checkerboard_cells_land_on_the_right_samples() {
    let dir = tempfile::tempdir().unwrap();
    let grid = geo_grid();
    // 6" pixels (coarser than the grid: one texel per sample, at the sample).
    let d = 6.0 / 3600.0;
    let (west, north) = (11.0 - 4.4 / 3600.0, 47.0 + 47.0 / 1200.0 + 5.3 / 3600.0);
    let (w, h) = (36u32, 28u32);
    let cell = |c: u32, r: u32| -> [u8; 3] {
        if (c / 4 + r / 4).is_multiple_of(2) {
            [250, 240, 10]
        } else {
            [5, 20, 200]
        }
    };
    let mut data = Vec::new();
    for r in 0..h {
        for c in 0..w {
            data.extend_from_slice(&cell(c, r));
        }
    }
    let p = write(
        dir.path(),
        "board.tif",
        w,
        h,
        3,
        &data,
        Some(EncodeRef {
            epsg: 4326,
            west,
            north,
            dx: d,
            dy: d,
        }),
    );
    let raster = read_raster(&p).unwrap();
    let size = DrapeSize::choose(&grid, &[&raster], 8192);
    assert_eq!(size.texels_per_sample, 1);
    let mut t = vec![0u8; size.texels() * 4];
    drape_rgba(&grid, &size, &raster, &mut t).unwrap();
    let mut checked = 0;
    for row in 0..grid.height {
        for col in 0..grid.width {
            let (lat, lon) = (47.0 + row as f64 / 1200.0, 11.0 + col as f64 / 1200.0);
            // Position in cells of the raster's corner frame (pixel edges at integers).
            let (x, y) = ((lon - west) / d, (north - lat) / d);
            let border = |v: f64| (v - 4.0 * (v / 4.0).round()).abs();
            if x < 0.0
                || y < 0.0
                || x > f64::from(w)
                || y > f64::from(h)
                || border(x) <= 0.55
                || border(y) <= 0.55
            {
                continue;
            }
            let want = cell(x as u32, y as u32);
            let got = texel(&size, &t, col, row);
            assert_eq!(
                &got[..3],
                &want,
                "sample ({col}, {row}) at pixel ({x:.2}, {y:.2})"
            );
            checked += 1;
        }
    }
    assert!(checked > 500, "{checked} samples checked");
}

#[test]
fn later_rasters_go_on_top_by_their_alpha() {
    let dir = tempfile::tempdir().unwrap();
    let grid = geo_grid();
    let d = 3.0 / 3600.0;
    let all = EncodeRef {
        epsg: 4326,
        west: 11.0 - 0.5 * d,
        north: 47.0 + 47.5 * d,
        dx: d,
        dy: d,
    };
    let under = write(
        dir.path(),
        "under.tif",
        64,
        48,
        1,
        &[200u8; 64 * 48],
        Some(all),
    );
    // Half-transparent red over the western half only.
    let mut top = vec![0u8; 32 * 48 * 4];
    for px in top.chunks_exact_mut(4) {
        px.copy_from_slice(&[255, 0, 0, 128]);
    }
    let over = write(dir.path(), "over.tif", 32, 48, 4, &top, Some(all));
    let (a, b) = (read_raster(&under).unwrap(), read_raster(&over).unwrap());
    let size = DrapeSize::choose(&grid, &[&a, &b], 8192);
    let mut t = vec![0u8; size.texels() * 4];
    drape_rgba(&grid, &size, &a, &mut t).unwrap();
    drape_rgba(&grid, &size, &b, &mut t).unwrap();
    assert_eq!(texel(&size, &t, 60, 10), [200, 200, 200, 255]);
    let mixed = texel(&size, &t, 10, 10);
    assert_eq!(mixed[3], 255);
    assert!(
        (i32::from(mixed[0]) - 228).abs() <= 1 && (i32::from(mixed[1]) - 100).abs() <= 1,
        "{mixed:?}"
    );
}

#[test]
fn class_codes_take_the_nearest_pixel_through_the_table() {
    let dir = tempfile::tempdir().unwrap();
    let grid = geo_grid();
    let d = 3.0 / 3600.0;
    // One pixel per sample; codes 10 in the west half, 80 in the east half, 99 unknown row.
    let mut codes = vec![0u8; 64 * 48];
    for (i, c) in codes.iter_mut().enumerate() {
        *c = if i / 64 == 0 {
            99
        } else if i % 64 < 32 {
            10
        } else {
            80
        };
    }
    let p = write(
        dir.path(),
        "lc.tif",
        64,
        48,
        1,
        &codes,
        Some(EncodeRef {
            epsg: 4326,
            west: 11.0 - 0.5 * d,
            north: 47.0 + 47.5 * d,
            dx: d,
            dy: d,
        }),
    );
    let raster = read_raster(&p).unwrap();
    let mut table = [CODE_NONE; 256];
    table[10] = 4;
    table[80] = 0;
    let size = DrapeSize::choose(&grid, &[&raster], 8192);
    let mut t = vec![CODE_NONE; size.texels()];
    let stats = drape_codes(&grid, &size, &raster, &table, &mut t).unwrap();
    assert_eq!(stats.covered, 64 * 48);
    assert_eq!(
        (stats.codes[10], stats.codes[80], stats.codes[99]),
        (32 * 47, 32 * 47, 64)
    );
    assert_eq!(t[5 * 64 + 3], 4);
    assert_eq!(t[5 * 64 + 40], 0);
    // File row 0 is the north: grid row 47, code 99 unknown → no class.
    assert_eq!(t[47 * 64 + 3], CODE_NONE);
    let mut rgb = vec![0u8; 64 * 48 * 4];
    drape_rgba(&grid, &size, &raster, &mut rgb).unwrap();
    let msg = drape_codes(
        &grid,
        &size,
        &read_raster(&write(
            dir.path(),
            "rgb.tif",
            2,
            2,
            3,
            &[0; 12],
            Some(EncodeRef {
                epsg: 4326,
                west: 11.0,
                north: 47.01,
                dx: d,
                dy: d,
            }),
        ))
        .unwrap(),
        &table,
        &mut t,
    )
    .unwrap_err()
    .to_string();
    assert!(msg.contains("rgb.tif") && msg.contains("one band"), "{msg}");
}

#[test]
fn size_follows_the_resolution_and_the_texture_limit() {
    let dir = tempfile::tempdir().unwrap();
    let grid = geo_grid();
    let d = 0.3 / 3600.0; // 10 texels per 3" sample
    let p = write(
        dir.path(),
        "fine.tif",
        4,
        4,
        1,
        &[1; 16],
        Some(EncodeRef {
            epsg: 4326,
            west: 11.0,
            north: 47.01,
            dx: d,
            dy: d,
        }),
    );
    let r = read_raster(&p).unwrap();
    assert_eq!(DrapeSize::choose(&grid, &[&r], 8192).texels_per_sample, 10);
    // 64 samples across: a 256-texel limit allows 4 per sample.
    let s = DrapeSize::choose(&grid, &[&r], 256);
    assert_eq!((s.texels_per_sample, s.width, s.height), (4, 256, 192));
    // A grid wider than the limit: the limit's texels, k = 0.
    let s = DrapeSize::choose(&grid, &[&r], 32);
    assert_eq!((s.texels_per_sample, s.width, s.height), (0, 32, 32));
    let (gx, gy) = s.texel_centre(&grid, 0, 31);
    assert!((gx - 0.5).abs() < 1e-12 && (gy - (31.5 * 1.5 - 0.5)).abs() < 1e-12);
    // A texel budget: the size that fits is kept; a smaller budget first lowers k (64×48
    // samples, k = 10 wanted), then goes coarser than the grid with the aspect kept.
    let want = DrapeSize::choose(&grid, &[&r], 8192);
    assert_eq!(want.within(&grid, want.texels()), want);
    let s = want.within(&grid, 64 * 48 * 9 - 1);
    assert_eq!((s.texels_per_sample, s.width, s.height), (2, 128, 96));
    for budget in [64 * 48 - 1, 1000, 1] {
        let s = want.within(&grid, budget);
        assert!(s.texels() <= budget.max(1), "{budget}: {s:?}");
        assert_eq!(s.texels_per_sample, 0, "{budget}: {s:?}");
        let aspect = s.width as f64 / s.height as f64;
        assert!(
            budget < 100 || (aspect - 64.0 / 48.0).abs() < 0.05,
            "{budget}: {s:?}"
        );
    }
    // Finer than 16 per sample is capped.
    let p = write(
        dir.path(),
        "finer.tif",
        4,
        4,
        1,
        &[1; 16],
        Some(EncodeRef {
            epsg: 4326,
            west: 11.0,
            north: 47.01,
            dx: d / 4.0,
            dy: d / 4.0,
        }),
    );
    let r = read_raster(&p).unwrap();
    assert_eq!(
        DrapeSize::choose(&grid, &[&r], 8192).texels_per_sample,
        MAX_TEXELS_PER_SAMPLE
    );
}

#[test]
fn bad_rasters_are_refused_naming_the_file_and_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let grid = geo_grid();
    let d = 3.0 / 3600.0;
    let here = EncodeRef {
        epsg: 4326,
        west: 11.0,
        north: 47.03,
        dx: d,
        dy: d,
    };
    let expect = |p: &Path, why: &str| {
        let e = read_raster(p).and_then(|r| {
            let size = DrapeSize::choose(&grid, &[&r], 8192);
            drape_rgba(&grid, &size, &r, &mut vec![0; size.texels() * 4]).map(|_| ())
        });
        let msg = e.unwrap_err().to_string();
        assert!(
            msg.starts_with(&p.display().to_string()) && msg.contains(why),
            "{msg}"
        );
        assert!(!msg.contains('\n'));
    };
    // 16-bit samples.
    let p = dir.path().join("u16.tif");
    {
        let f = std::fs::File::create(&p).unwrap();
        let mut enc = tiff::encoder::TiffEncoder::new(f).unwrap();
        enc.write_image::<tiff::encoder::colortype::Gray16>(2, 2, &[1, 2, 3, 4])
            .unwrap();
    }
    expect(&p, "not 8-bit");
    expect(
        &write(dir.path(), "plain.tif", 2, 2, 3, &[0; 12], None),
        "missing geo-reference",
    );
    expect(
        &write(
            dir.path(),
            "lv95.tif",
            2,
            2,
            3,
            &[0; 12],
            Some(EncodeRef {
                epsg: 2056,
                west: 2.6e6,
                north: 1.2e6,
                dx: 10.0,
                dy: 10.0,
            }),
        ),
        "EPSG:2056",
    );
    expect(
        &write(
            dir.path(),
            "nad27.tif",
            2,
            2,
            3,
            &[0; 12],
            Some(EncodeRef { epsg: 4267, ..here }),
        ),
        "EPSG:4267",
    );
    expect(
        &write(
            dir.path(),
            "far.tif",
            2,
            2,
            3,
            &[0; 12],
            Some(EncodeRef {
                west: 100.0,
                ..here
            }),
        ),
        "no overlap with the terrain",
    );
    let p = dir.path().join("junk.tif");
    std::fs::write(&p, b"II*\0junk").unwrap();
    expect(&p, "TIFF");
    expect(&dir.path().join("missing.tif"), "");
    assert!(TerrainGrid::new(2, 2, 1.0, 1.0, None)
        .unwrap_err()
        .contains("no geo-reference"));
    // A raster in a non-UTM CRS drapes a terrain in that very CRS.
    let flat = TerrainGrid::new(
        4,
        4,
        10.0,
        10.0,
        Some(&GeoReference::Projected {
            crs: "EPSG:2056".into(),
            easting: 2.6e6,
            northing: 1.2e6,
        }),
    )
    .unwrap();
    let p = write(
        dir.path(),
        "lv95b.tif",
        4,
        4,
        1,
        &[7; 16],
        Some(EncodeRef {
            epsg: 2056,
            west: 2.6e6 - 5.0,
            north: 1.2e6 + 35.0,
            dx: 10.0,
            dy: 10.0,
        }),
    );
    let r = read_raster(&p).unwrap();
    let size = DrapeSize::choose(&flat, &[&r], 8192);
    let mut t = vec![0; size.texels() * 4];
    assert_eq!(drape_rgba(&flat, &size, &r, &mut t).unwrap().covered, 16);
    assert!(t.chunks_exact(4).all(|p| p == [7, 7, 7, 255]));
}
