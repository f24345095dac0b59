//! A store's imagery streamed in windows around the eye (issue 17: imagery paged in like the
//! heights), on lavapipe with the validation layer on. The layer is written at 4 texels per
//! sample so that level 0 (516² texels) exceeds a 1.4 MB `--drape-mb`: level 2 is then held
//! whole and levels 0–1 stream in windows of 320² texels. The oracle is level 0 held whole
//! (the default budget): from 1,000 m above the ground a pixel is 0.6 level-0 texels, so the
//! shader draws the level-0 window, which must give that image — and again after the eye
//! moves by a cell, the window rewriting only what it uncovered. Level 2 alone (streaming
//! off) draws visibly another image, so the comparison can fail.

use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::render::frame::{Look, RendererDesc, TerrainRenderer};
use aerie::terrain::drape::{read_raster, LevelDraper};
use aerie::terrain::source::{InMemoryTerrain, TerrainSource};
use aerie::terrain::store::{
    load_store, open_imagery_beside, store_grid, write_imagery_in, write_store, ImportParams, Store,
};
use aerie::terrain::stream::{StreamParams, StreamedStore};
use aerie_tests::drape_fixtures::*;
use aerie_tests::*;
use glam::DVec3;

const W: u32 = 256;
const H: u32 = 144;
/// Bytes that hold level 2 whole (129², 88.7 KB with mips) beside two 320² windows
/// (819 KB), but not level 0 whole (516², 1.42 MB).
const BUDGET: u64 = 1_400_000;

/// Looking straight down from 1,000 m above the terrain (at 500 m), over level-0 texel
/// `4·x / 30` per axis: eye texels 288 and 352 are where a 320-texel window is centred
/// (origin 128 or 192, whole cells).
fn camera(x: f64, y: f64) -> Camera {
    Camera::new(
        DVec3::new(x, y, 1500.0),
        Attitude::from_degrees(0.0, -90.0, 0.0),
        Frustum::symmetric(60f64.to_radians(), W, H),
    )
}

fn desc(budget: u64, stream: bool) -> RendererDesc {
    let mut d = test_desc(W, H);
    d.look = Look::Classes;
    d.drape_budget_bytes = budget;
    d.drape_stream_imagery = stream;
    d
}

/// The UTM terrain as a store in `dir` with the checkerboard as its imagery layer at 4
/// texels per sample.
fn store_with_imagery(dir: &Path) -> std::path::PathBuf {
    let (ds, b) = prepare(&desc(BUDGET, true), &utm_terrain(&[]));
    let path = dir.join("utm.aerie");
    let ip = ImportParams {
        sources: vec!["utm".into()],
        page_tiles: 2,
        zstd_level: 1,
    };
    write_store(&path, &ds, &b, &ip, &|_, _| {}).expect("import");
    let (tif, _) = checkerboard(dir);
    let raster = read_raster(&tif).unwrap();
    let store = Store::open(&path).unwrap();
    let grid = store_grid(&store).unwrap();
    let draper = LevelDraper::new(&grid, &[raster], 4, store.header().levels).unwrap();
    write_imagery_in(
        aerie_io::real(),
        &store,
        &draper,
        vec!["board.tif".into()],
        1,
        &|_, _| {},
    )
    .unwrap();
    path
}

/// How the store is served.
#[derive(Clone, Copy, Debug)]
enum Serve {
    Streamed,
    Whole,
}

fn source(
    path: &Path,
    serve: Serve,
) -> (Arc<dyn TerrainSource>, Arc<aerie::terrain::bake::ErrorBake>) {
    match serve {
        Serve::Streamed => {
            let (s, bake) = StreamedStore::open(path, StreamParams::default()).expect("open");
            let rects = desc(BUDGET, true).start_up_rects(s.grid());
            s.wait_resident(&rects, Duration::from_secs(60))
                .expect("coarsest level");
            (Arc::new(s), bake)
        }
        Serve::Whole => {
            let (ds, bake) = load_store(path).expect("load whole");
            let store = Store::open(path).unwrap();
            let layer = open_imagery_beside(&aerie_io::real(), path, &store)
                .unwrap()
                .expect("layer");
            let s = InMemoryTerrain::new(Arc::new(ds)).with_imagery(layer);
            (Arc::new(s), Arc::new(bake))
        }
    }
}

/// What one view drew and what the imagery stream did for it.
struct View {
    rgba: Vec<u8>,
    cells_copied: u64,
    pending: u32,
}

/// Renders `cameras` in turn, each until nothing is pending (heights or imagery).
fn render(d: &RendererDesc, path: &Path, serve: Serve, cameras: &[Camera]) -> (Vec<View>, u32) {
    let (src, bake) = source(path, serve);
    let mut r = TerrainRenderer::new(d).expect("renderer");
    r.load_source(src, bake, cameras[0].position).expect("load");
    let mut views = Vec::new();
    for cam in cameras {
        let mut s = r.render(cam).expect("render");
        for _ in 0..2000 {
            if s.tiles_late_stream == 0 && s.cells_pending == 0 && s.imagery_cells_pending == 0 {
                break;
            }
            std::thread::sleep(Duration::from_millis(5));
            s = r.render(cam).expect("render");
        }
        let stream = r.imagery_stream().unwrap();
        views.push(View {
            rgba: r.colour_rgba(),
            cells_copied: stream.totals.cells,
            pending: s.imagery_cells_pending,
        });
    }
    let base = r
        .draped()
        .0
        .and_then(|d| d.layer_level.as_ref().map(|l| l.level))
        .expect("the layer is draped");
    let counters = r.validation_counters();
    r.destroy();
    assert_validation_clean(&counters);
    (views, base)
}

/// Worst channel difference, and pixels whose worst channel differs by more than 24.
fn compare(a: &[u8], b: &[u8]) -> (u8, usize) {
    let worst = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap();
    let off = a
        .chunks(4)
        .zip(b.chunks(4))
        .filter(|(p, q)| (0..3).any(|i| p[i].abs_diff(q[i]) > 24))
        .count();
    (worst, off)
}

#[test]
fn streamed_windows_draw_what_level_0_held_whole_draws_and_follow_the_eye() {
    let dir = tempfile::tempdir().unwrap();
    let path = store_with_imagery(dir.path());
    // Eye texels 288 → 352 per axis: the level-0 window moves by one cell (64 texels).
    let at = |t: f64| (t + 0.5) / 4.0 * 30.0;
    let cameras = [camera(at(288.0), at(288.0)), camera(at(352.0), at(288.0))];

    let (oracle, base) = render(&desc(64 << 20, true), &path, Serve::Streamed, &cameras);
    assert_eq!(base, 0, "the default budget holds level 0 whole");
    assert_eq!(oracle[1].cells_copied, 0, "nothing streamed beside level 0");

    for serve in [Serve::Streamed, Serve::Whole] {
        let (views, base) = render(&desc(BUDGET, true), &path, serve, &cameras);
        assert_eq!(base, 2, "{serve:?}: level 2 whole under {BUDGET} bytes");
        // Levels 0 and 1, 5 × 5 cells of 64 each, filled; then the level-0 column uncovered
        // by the move (level 1's window, half as fine, moves by half a cell: not at all, or
        // one column).
        let first = views[0].cells_copied;
        assert_eq!(first, 2 * 25, "{serve:?}: both windows filled once");
        let moved = views[1].cells_copied - first;
        assert!(
            moved == 5 || moved == 10,
            "{serve:?}: {moved} cells after a one-cell move"
        );
        for (i, (v, o)) in views.iter().zip(&oracle).enumerate() {
            assert_eq!(v.pending, 0, "{serve:?} view {i}: cells still pending");
            let (worst, off) = compare(&v.rgba, &o.rgba);
            eprintln!("{serve:?} view {i}: worst channel difference {worst} from level 0 whole, {off} pixels over 24");
            assert!(
                worst <= 2,
                "{serve:?} view {i}: worst channel difference {worst}"
            );
        }
    }

    // Level 2 alone (streaming off, the budget's whole level): another image.
    let (coarse, base) = render(&desc(100_000, false), &path, Serve::Streamed, &cameras[..1]);
    assert_eq!(base, 2);
    let (worst, off) = compare(&coarse[0].rgba, &oracle[0].rgba);
    eprintln!("level 2 alone: worst channel difference {worst}, {off} pixels over 24");
    assert!(
        off > 500,
        "level 2 alone differs from level 0 in only {off} pixels"
    );
}
