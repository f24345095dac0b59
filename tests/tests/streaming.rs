//! The renderer drawing a tile store streamed page by page (issue 13 item 2), on lavapipe with
//! validation on: once the page cache is warm it draws exactly the image the in-memory renderer
//! draws from the same data; with every page read slowed down, frames keep coming while the
//! pages are on their way, the tiles drawn coarser meanwhile are counted late, and the image
//! it converges to is still the in-memory one (nothing stale was kept).

use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::render::frame::{FrameStats, RendererDesc, TerrainRenderer};
use aerie::terrain::bake::ErrorBake;
use aerie::terrain::dataset::Dataset;
use aerie::terrain::store::{write_store, ImportParams};
use aerie::terrain::stream::{StreamParams, StreamedStore};
use aerie::terrain::Heightfield;
use aerie_tests::{assert_validation_clean, prepare, test_desc};
use glam::DVec3;

const N: usize = 1025;
const W: u32 = 256;
const H: u32 = 144;

fn rough() -> Heightfield {
    Heightfield {
        width: N,
        height: N,
        spacing_x: 30.0,
        spacing_y: 30.0,
        heights: (0..N * N)
            .map(|k| {
                let (c, r) = ((k % N) as f32, (k / N) as f32);
                300.0 * (c * 0.011).sin() * (r * 0.013).cos()
                    + 40.0 * (c * 0.23).sin()
                    + 25.0 * (r * 0.31 + c * 0.07).cos()
                    + 0.4 * r
            })
            .collect(),
        geo: None,
        voids_filled: 0,
        spacing_note: String::new(),
    }
}

/// Low over the middle of the terrain looking north-east: every level and some refinement.
fn camera() -> Camera {
    Camera::new(
        DVec3::new(14_000.0, 13_000.0, 900.0),
        Attitude::from_degrees(40.0, -12.0, 0.0),
        Frustum::symmetric(90f64.to_radians(), W, H),
    )
}

fn import(ds: &Dataset, b: &ErrorBake, path: &Path) {
    let params = ImportParams {
        sources: vec![ds.source.clone()],
        page_tiles: 4,
        zstd_level: 1,
    };
    write_store(path, ds, b, &params, &|_, _| {}).expect("import");
}

/// The in-memory renderer's image of `camera`.
fn in_memory(desc: &RendererDesc, ds: Arc<Dataset>, b: Arc<ErrorBake>) -> Vec<u8> {
    let mut r = TerrainRenderer::new(desc).expect("renderer");
    r.load_terrain(ds, b, camera().position).expect("load");
    r.render(&camera()).expect("render");
    let rgba = r.colour_rgba();
    let counters = r.validation_counters();
    r.destroy();
    assert_validation_clean(&counters);
    rgba
}

/// Opens the store streamed (waiting only for the first frame's samples, as the commands do)
/// and renders `camera` until nothing is late for streaming; returns every frame's statistics
/// and the last image.
fn streamed(desc: &RendererDesc, path: &Path, fs: StreamParams) -> (Vec<FrameStats>, Vec<u8>) {
    let (store, bake) = StreamedStore::open(path, fs).expect("open store");
    let rects = desc.start_up_rects(aerie::terrain::source::TerrainSource::grid(&store));
    store
        .wait_resident(&rects, Duration::from_secs(60))
        .expect("coarsest level");
    let store = Arc::new(store);
    let mut r = TerrainRenderer::new(desc).expect("renderer");
    r.load_source(store.clone(), bake, camera().position)
        .expect("load");
    let mut frames = Vec::new();
    for _ in 0..2000 {
        let s = r.render(&camera()).expect("render");
        frames.push(s);
        if s.tiles_late_stream == 0 && s.cells_pending == 0 {
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let rgba = r.colour_rgba();
    let counters = r.validation_counters();
    r.destroy();
    assert_validation_clean(&counters);
    (frames, rgba)
}

fn params(cache_mb: u64, latency: Option<Duration>) -> StreamParams {
    let fs = match latency {
        Some(l) => aerie_io::FaultyFs::new(aerie_io::Faults {
            latency: Some(l),
            ..Default::default()
        })
        .shared(),
        None => aerie_io::real(),
    };
    StreamParams {
        cache_bytes: cache_mb << 20,
        workers: 2,
        fs,
    }
}

fn assert_same(a: &[u8], b: &[u8], what: &str) {
    assert_eq!(a.len(), b.len());
    let differing = a.chunks(4).zip(b.chunks(4)).filter(|(x, y)| x != y).count();
    assert_eq!(
        differing, 0,
        "{what}: {differing} pixels differ from the in-memory image"
    );
}

#[test]
fn streamed_and_in_memory_draw_identical_images_once_the_cache_is_warm() {
    let desc = test_desc(W, H);
    let (ds, b) = prepare(&desc, &rough());
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("rough.aerie");
    import(&ds, &b, &path);
    let want = in_memory(&desc, ds.clone(), b.clone());
    // A budget far below the data (5.6 MB decoded): level 0 is streamed on demand.
    let (frames, got) = streamed(&desc, &path, params(8, None));
    let last = frames.last().unwrap();
    assert_eq!(
        (last.tiles_late_stream, last.cells_pending),
        (0, 0),
        "never warmed up"
    );
    assert!(last.stream_loaded > 0 && last.stream_budget_bytes == 8 << 20);
    assert!(last.stream_resident_bytes <= last.stream_budget_bytes);
    assert_same(&want, &got, "warm streamed render");
}

#[test]
fn slow_page_reads_keep_frames_coming_count_late_tiles_and_converge_to_the_same_image() {
    let mut desc = test_desc(W, H);
    // With normal maps the start-up wait covers the coarsest level's normal footprints, which
    // on this small dataset are every level-0 page: nothing would be late to show.
    desc.normal_maps = false;
    let (ds, b) = prepare(&desc, &rough());
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("rough.aerie");
    import(&ds, &b, &path);
    let want = in_memory(&desc, ds.clone(), b.clone());
    let (frames, got) = streamed(&desc, &path, params(8, Some(Duration::from_millis(150))));
    // Each page takes at least 150 ms to read: the first frames are drawn without waiting,
    // coarser where level 0 has not arrived, and say so.
    let early = &frames[..3.min(frames.len())];
    assert!(
        frames.len() >= 3,
        "only {} frames before warm",
        frames.len()
    );
    for s in early {
        assert!(
            s.tiles_late_stream > 0 || s.cells_pending > 0,
            "frame {} had everything with slow reads: {s:?}",
            s.frame
        );
        assert!(s.tiles_late >= s.tiles_late_stream);
    }
    let last = frames.last().unwrap();
    assert_eq!(
        (last.tiles_late_stream, last.cells_pending),
        (0, 0),
        "never warmed up"
    );
    assert_same(&want, &got, "streamed render after slow reads");
}
