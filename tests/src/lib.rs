//! Shared helpers for aerie's integration tests: paths to the data, a headless render that
//! fails on any validation message, and image comparison with a diff image on failure.

pub mod bins;
pub mod cigi_host;
pub mod drape_fixtures;
pub mod flat_oracle;
pub mod geo_oracle;
pub mod hills;
pub mod imports;
pub mod ridges;

pub use bins::{aerie_bin, aerie_send_bin, bin_dir};

use std::path::{Path, PathBuf};

use std::sync::Arc;

use aerie::camera::Camera;
use aerie::render::frame::{FrameStats, RendererDesc, TerrainRenderer};
use aerie::terrain::bake::{bake, BakeParams, ErrorBake};
use aerie::terrain::dataset::Dataset;
use aerie::terrain::Heightfield;

/// The repository root.
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The DEM committed in the repository for the demo and golden tests.
pub fn demo_dem() -> PathBuf {
    repo_root().join("assets/dem/N47E011.hgt.zip")
}

/// `../shared/data/dem` when present (it is not in a fresh clone): tests that need it skip.
pub fn shared_dem_dir() -> Option<PathBuf> {
    let p = repo_root().join("../shared/data/dem");
    p.is_dir().then_some(p)
}

/// Where tests write images for humans to look at (diffs, actual renders).
pub fn test_output_dir() -> PathBuf {
    let p = repo_root().join("target/test-output");
    std::fs::create_dir_all(&p).expect("create target/test-output");
    p
}

/// One rendered frame read back.
pub struct Rendered {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    pub depth: Vec<f32>,
    pub stats: FrameStats,
}

/// The renderer description every GPU test uses: validation on, lavapipe is fine.
pub fn test_desc(width: u32, height: u32) -> RendererDesc {
    RendererDesc {
        validation: true,
        width,
        height,
        ..Default::default()
    }
}

/// A heightfield padded into a dataset, with its error bake (tile size of `desc`).
pub fn prepare(desc: &RendererDesc, hf: &Heightfield) -> (Arc<Dataset>, Arc<ErrorBake>) {
    let ds = Dataset::from_heightfield(hf.clone(), "test".into());
    let params = BakeParams {
        tile_size: desc.tile_size,
        levels: 0,
    };
    let b = bake(&ds, params, &|_, _| {});
    (Arc::new(ds), Arc::new(b))
}

/// Renders each camera with a fresh renderer (validation on), tears everything down and
/// panics if the validation layer reported any error or warning — including leaks at teardown.
pub fn render_frames(desc: &RendererDesc, hf: &Heightfield, cameras: &[Camera]) -> Vec<Rendered> {
    let (ds, b) = prepare(desc, hf);
    render_dataset(desc, ds, b, cameras)
}

/// As [`render_frames`] for an already prepared dataset.
pub fn render_dataset(
    desc: &RendererDesc,
    ds: Arc<Dataset>,
    b: Arc<ErrorBake>,
    cameras: &[Camera],
) -> Vec<Rendered> {
    let mut r = TerrainRenderer::new(desc).expect("create renderer");
    r.load_terrain(ds, b, cameras[0].position)
        .expect("upload terrain");
    let mut out = Vec::new();
    for cam in cameras {
        let stats = r.render(cam).expect("render");
        out.push(Rendered {
            width: desc.width,
            height: desc.height,
            rgba: r.colour_rgba(),
            depth: r.depth(),
            stats,
        });
    }
    let counters = r.validation_counters();
    r.destroy();
    assert_validation_clean(&counters);
    out
}

/// Renders `cam` 1 + `again` times (the pools and level textures fill over the first frames)
/// and returns the last frame's statistics.
pub fn render_settled(r: &mut TerrainRenderer, cam: &Camera, again: u32) -> FrameStats {
    let mut stats = r.render(cam).expect("render");
    for _ in 0..again {
        stats = r.render(cam).expect("render");
    }
    stats
}

pub fn assert_validation_clean(c: &aerie::vk::ValidationCounters) {
    assert_eq!(
        (c.errors(), c.warnings()),
        (0, 0),
        "validation layer reported errors/warnings: {:#?}",
        c.messages()
    );
}

/// How two RGBA8 images differ.
#[derive(Debug, Clone, Copy)]
pub struct ImageDiff {
    /// Largest per-channel difference (0..=255).
    pub max: u8,
    /// Mean per-channel absolute difference.
    pub mean: f64,
    /// Fraction of pixels with any channel differing by more than the tolerance.
    pub fraction_over: f64,
}

pub fn diff_images(a: &[u8], b: &[u8], tolerance: u8) -> ImageDiff {
    assert_eq!(a.len(), b.len(), "image sizes differ");
    let mut max = 0u8;
    let mut sum = 0u64;
    let mut over = 0usize;
    for (pa, pb) in a.chunks(4).zip(b.chunks(4)) {
        let mut worst = 0u8;
        for c in 0..3 {
            let d = pa[c].abs_diff(pb[c]);
            worst = worst.max(d);
            sum += d as u64;
        }
        max = max.max(worst);
        if worst > tolerance {
            over += 1;
        }
    }
    let pixels = a.len() / 4;
    ImageDiff {
        max,
        mean: sum as f64 / (pixels * 3) as f64,
        fraction_over: over as f64 / pixels as f64,
    }
}

/// A difference image: black where equal, the absolute difference ×8 elsewhere.
pub fn diff_image(a: &[u8], b: &[u8]) -> Vec<u8> {
    a.chunks(4)
        .zip(b.chunks(4))
        .flat_map(|(pa, pb)| {
            let d = |c: usize| pa[c].abs_diff(pb[c]).saturating_mul(8);
            [d(0), d(1), d(2), 255]
        })
        .collect()
}

/// Tolerance of the golden-image tests: per-channel differences up to `tolerance` are noise
/// (lavapipe on another CPU may round differently); at most `max_fraction_over` of the pixels may
/// exceed it and the mean difference must stay below `max_mean`.
#[derive(Debug, Clone, Copy)]
pub struct GoldenTolerance {
    pub tolerance: u8,
    pub max_fraction_over: f64,
    pub max_mean: f64,
}

pub const GOLDEN_TOLERANCE: GoldenTolerance = GoldenTolerance {
    tolerance: 16,
    max_fraction_over: 0.005,
    max_mean: 1.5,
};

/// Compares with the committed golden PNG. `AERIE_UPDATE_GOLDEN=1` rewrites it instead. On
/// failure the actual image and the diff image are written to `target/test-output/`.
pub fn check_golden(name: &str, img: &Rendered, tol: GoldenTolerance) {
    let golden_path = repo_root().join("tests/golden").join(format!("{name}.png"));
    let out = test_output_dir();
    let actual_path = out.join(format!("{name}.actual.png"));
    aerie::tools::output::write_png(&actual_path, img.width, img.height, &img.rgba).unwrap();
    if std::env::var_os("AERIE_UPDATE_GOLDEN").is_some() {
        std::fs::create_dir_all(golden_path.parent().unwrap()).unwrap();
        aerie::tools::output::write_png(&golden_path, img.width, img.height, &img.rgba).unwrap();
        eprintln!("updated golden {}", golden_path.display());
        return;
    }
    let golden = image::open(&golden_path)
        .unwrap_or_else(|e| panic!("golden {} unreadable: {e}", golden_path.display()))
        .to_rgba8();
    assert_eq!(
        (golden.width(), golden.height()),
        (img.width, img.height),
        "golden size"
    );
    let d = diff_images(&img.rgba, golden.as_raw(), tol.tolerance);
    if d.fraction_over > tol.max_fraction_over || d.mean > tol.max_mean {
        let diff_path = out.join(format!("{name}.diff.png"));
        aerie::tools::output::write_png(
            &diff_path,
            img.width,
            img.height,
            &diff_image(&img.rgba, golden.as_raw()),
        )
        .unwrap();
        panic!(
            "{name}: differs from golden {} ({d:?}, allowed {tol:?}); actual {}, diff {}",
            golden_path.display(),
            actual_path.display(),
            diff_path.display()
        );
    }
}

/// A flat heightfield at `h` metres with optional raised rectangles (col0, row0, col1, row1, h).
pub fn synthetic(
    width: usize,
    height: usize,
    spacing: f64,
    h: f32,
    blocks: &[(usize, usize, usize, usize, f32)],
) -> Heightfield {
    let mut heights = vec![h; width * height];
    for &(c0, r0, c1, r1, bh) in blocks {
        for r in r0..=r1 {
            for c in c0..=c1 {
                heights[r * width + c] = bh;
            }
        }
    }
    Heightfield {
        width,
        height,
        spacing_x: spacing,
        spacing_y: spacing,
        heights,
        geo: None,
        voids_filled: 0,
        spacing_note: "synthetic".into(),
    }
}

/// Renders each (camera, light) of `shots` with one renderer on `ds`; validation must stay clean
/// through teardown.
pub fn render_lit(
    desc: &RendererDesc,
    ds: &Arc<Dataset>,
    b: &Arc<ErrorBake>,
    shots: &[(Camera, aerie::render::frame::Lighting)],
) -> Vec<Rendered> {
    let mut r = TerrainRenderer::new(desc).expect("create renderer");
    r.load_terrain(Arc::clone(ds), Arc::clone(b), shots[0].0.position)
        .expect("upload terrain");
    let mut out = Vec::new();
    for (cam, light) in shots {
        r.set_lighting(*light);
        let stats = r.render(cam).expect("render");
        out.push(Rendered {
            width: desc.width,
            height: desc.height,
            rgba: r.colour_rgba(),
            depth: r.depth(),
            stats,
        });
    }
    let counters = r.validation_counters();
    r.destroy();
    assert_validation_clean(&counters);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diff_counts_pixels_over_tolerance() {
        let a = vec![10u8, 10, 10, 255, 0, 0, 0, 255];
        let b = vec![10u8, 30, 10, 255, 0, 0, 5, 255];
        let d = diff_images(&a, &b, 5);
        assert_eq!(d.max, 20);
        assert_eq!(d.fraction_over, 0.5);
        assert!((d.mean - 25.0 / 6.0).abs() < 1e-12);
    }
}
