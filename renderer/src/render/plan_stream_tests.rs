//! The frame plan over a source that withholds pages (no threads: pages arrive when the test
//! serves them). A CPU mirror of the level textures and pools receives exactly what the plan
//! stages, from the samples it gathered, and every texel each drawn node reads (normals'
//! neighbours included) is checked against the dataset: nothing stale is ever drawn.

use std::collections::HashSet;
use std::sync::{Arc, Mutex};

use glam::DVec3;

use aerie_terrain::bake::{bake, BakeParams, ErrorBake};
use aerie_terrain::camera::{Attitude, Camera, Frustum};
use aerie_terrain::clipmap::ClipmapDesc;
use aerie_terrain::dataset::Dataset;
use aerie_terrain::select::{SelectParams, Selection};
use aerie_terrain::source::{
    InMemoryTerrain, NotResident, SampleRect, SampleWant, SourceGrid, StreamStats, TerrainSource,
};
use aerie_terrain::Heightfield;

use super::*;
use crate::render::feed::{DRAWN_PRIORITY, PREFETCH_PRIORITY};
use crate::render::gathered::SampleCursor;
use crate::render::jobs::StagingBudget;
use crate::render::pool_atlas::{PoolAtlas, PoolLimits};

const N: usize = 513;
const Q: u32 = 16;
/// Level-L vertices per page side (two tiles).
const PAGE: i64 = 32;

type Page = (u32, i64, i64);

#[derive(Default)]
struct Withheld {
    /// Levels at or above this are wholly resident.
    resident_from: u32,
    /// Pages served since.
    served: HashSet<Page>,
    /// The last request, as the source got it.
    wants: Vec<SampleWant>,
    /// `gather` refuses this many more calls even when resident (an eviction between the
    /// plan's `is_resident` and its `gather`).
    fail_gathers: u32,
    hits: u64,
    misses: u64,
}

/// An in-memory source that holds only what the test says.
struct Withholding {
    inner: InMemoryTerrain,
    state: Mutex<Withheld>,
}

impl Withholding {
    fn new(ds: Arc<Dataset>, resident_from: u32) -> Self {
        Withholding {
            inner: InMemoryTerrain::new(ds),
            state: Mutex::new(Withheld {
                resident_from,
                ..Default::default()
            }),
        }
    }

    /// The pages of `rect` (level-L vertices of its clamped samples).
    fn pages(&self, rect: &SampleRect) -> Vec<Page> {
        let g = self.inner.grid();
        let clamp = |s: i64, max: u32| s.clamp(0, max as i64 - 1) >> rect.level;
        let step = rect.step() as i64;
        let span = |a: usize, max: u32| {
            let lo = clamp(rect.origin[a], max);
            let hi = clamp(rect.origin[a] + (rect.size[a] as i64 - 1) * step, max);
            (lo / PAGE, hi / PAGE)
        };
        let ((x0, x1), (y0, y1)) = (span(0, g.width), span(1, g.height));
        (y0..=y1)
            .flat_map(|y| (x0..=x1).map(move |x| (rect.level, x, y)))
            .collect()
    }

    fn missing(&self, rect: &SampleRect) -> Option<Page> {
        let s = self.state.lock().unwrap();
        self.pages(rect)
            .into_iter()
            .find(|p| p.0 < s.resident_from && !s.served.contains(p))
    }

    /// Serves the pages of the `n` most wanted rectangles of the last request.
    fn serve(&self, n: usize) -> usize {
        let mut wants = self.state.lock().unwrap().wants.clone();
        wants.sort_by(|a, b| b.priority.total_cmp(&a.priority));
        let pages: Vec<Page> = wants
            .iter()
            .take(n)
            .flat_map(|w| self.pages(&w.rect))
            .collect();
        let mut s = self.state.lock().unwrap();
        let before = s.served.len();
        s.served.extend(pages);
        s.served.len() - before
    }

    fn wants(&self) -> Vec<SampleWant> {
        self.state.lock().unwrap().wants.clone()
    }
}

impl TerrainSource for Withholding {
    fn grid(&self) -> &SourceGrid {
        self.inner.grid()
    }

    fn is_resident(&self, rect: &SampleRect) -> bool {
        let yes = self.missing(rect).is_none();
        let mut s = self.state.lock().unwrap();
        if yes {
            s.hits += 1;
        } else {
            s.misses += 1;
        }
        yes
    }

    fn gather(&self, rect: &SampleRect, out: &mut [f32]) -> Result<(), NotResident> {
        let missing = self.missing(rect);
        let mut s = self.state.lock().unwrap();
        if missing.is_none() && s.fail_gathers > 0 {
            s.fail_gathers -= 1;
            return Err(NotResident {
                level: rect.level,
                px: 0,
                py: 0,
                failed: false,
            });
        }
        if let Some((level, px, py)) = missing {
            s.misses += 1;
            return Err(NotResident {
                level,
                px: px as u32,
                py: py as u32,
                failed: false,
            });
        }
        s.hits += 1;
        drop(s);
        self.inner.gather(rect, out)
    }

    fn request(&self, wants: &[SampleWant]) {
        self.state.lock().unwrap().wants = wants.to_vec();
    }

    fn stats(&self) -> StreamStats {
        let s = self.state.lock().unwrap();
        StreamStats {
            hits: s.hits,
            misses: s.misses,
            ..Default::default()
        }
    }
}

fn dataset() -> Arc<Dataset> {
    let hf = Heightfield {
        width: N,
        height: N,
        spacing_x: 10.0,
        spacing_y: 10.0,
        heights: (0..N * N)
            .map(|k| {
                let (c, r) = ((k % N) as f32, (k / N) as f32);
                40.0 * (c * 0.9).sin() + 35.0 * (r * 1.3).cos() + 0.2 * c
            })
            .collect(),
        geo: None,
        voids_filled: 0,
        spacing_note: String::new(),
    };
    Arc::new(Dataset::from_heightfield(hf, "stream test".into()))
}

fn clipmap() -> ClipmapDesc {
    ClipmapDesc {
        tile_quads: Q,
        patch_tiles: 8,
        margin_tiles: 2,
        width: N as u32,
        height: N as u32,
    }
}

/// What the GPU textures would hold: the level textures and the pools, NaN until written.
struct Mirror {
    side: usize,
    levels: Vec<Vec<f32>>,
    /// Per r = 1..: the pool's layout and its image's layers (each `width()`² texels).
    pools: Vec<(PoolAtlas, Vec<Vec<f32>>)>,
}

impl Mirror {
    fn new(st: &PlanState) -> Self {
        let side = st.clipmap.texture_side() as usize;
        Mirror {
            side,
            levels: vec![vec![f32::NAN; side * side]; st.clipmap.level_count() as usize],
            pools: st
                .pools
                .iter()
                .map(|p| {
                    let w = p.atlas.width() as usize;
                    (
                        p.atlas,
                        vec![vec![f32::NAN; w * w]; p.atlas.layers as usize],
                    )
                })
                .collect(),
        }
    }

    fn write(dst: &mut [f32], row: usize, job: &ImageUpload, src: &[f32]) {
        let (w, h) = (job.size[0] as usize, job.size[1] as usize);
        for j in 0..h {
            let at = (job.texel[1] as usize + j) * row + job.texel[0] as usize;
            dst[at..at + w].copy_from_slice(&src[j * w..(j + 1) * w]);
        }
    }

    /// Stages `plan` as the renderer does, from the samples the plan gathered.
    fn apply(&mut self, st: &PlanState, plan: &FramePlan) {
        let mut cursor = SampleCursor::new(st.feed.gatherer.samples());
        for job in plan.spilled_strips.iter().flatten().chain(&plan.strips) {
            let src = cursor.next(job).expect("samples for every strip");
            Self::write(&mut self.levels[job.layer as usize], self.side, job, src);
        }
        for p in &plan.pool_uploads {
            let src = cursor
                .next(&p.upload)
                .expect("samples for every pool upload");
            let (atlas, layers) = &mut self.pools[p.key.refinement as usize - 1];
            let w = atlas.width() as usize;
            Self::write(&mut layers[p.upload.layer as usize], w, &p.upload, src);
        }
        assert_eq!(cursor.left(), 0, "every gathered sample is staged");
    }

    /// Checks every texel the vertex shader reads for each drawn node against the dataset.
    fn check(&self, st: &PlanState, plan: &FramePlan, hf: &Heightfield, valid: [i64; 2]) {
        let truth = |x: i64, y: i64| {
            let (x, y) = (
                x.clamp(0, hf.width as i64 - 1),
                y.clamp(0, hf.height as i64 - 1),
            );
            hf.heights[y as usize * hf.width + x as usize]
        };
        let q = Q as i64;
        for (item, slot) in &plan.draw_list {
            let step = 1i64 << item.node_level;
            let origin = [
                item.node_tx as i64 * q * step,
                item.node_ty as i64 * q * step,
            ];
            let lim = [0, 1].map(|a| (valid[a] - 1 - origin[a] + step - 1) / step);
            let top = [0, 1].map(|a| lim[a].min(q) + 1);
            for j in -1..=top[1] {
                for i in -1..=top[0] {
                    let got = if item.refinement == 0 {
                        let l = item.level as usize;
                        let region = st.feed.caches[l].as_ref().unwrap();
                        let v = [(origin[0] >> item.level) + i, (origin[1] >> item.level) + j];
                        let side = self.side as i64;
                        let inside = (0..2)
                            .all(|a| v[a] >= region.origin[a] && v[a] < region.origin[a] + side);
                        if !inside {
                            continue; // read across the coarsest texture's wrap, as in memory
                        }
                        let t = v.map(|c| c.rem_euclid(side) as usize);
                        let want = truth(v[0] << item.level, v[1] << item.level);
                        (self.levels[l][t[1] * self.side + t[0]], want)
                    } else {
                        let (atlas, layers) = &self.pools[item.refinement as usize - 1];
                        let s = atlas.side as i64;
                        let (sx, sy, stride) = slot_placement(item, Q);
                        // Where the slot's samples should be read (clamped into the slot) …
                        let rel = [sx as i64 + i * stride as i64, sy as i64 + j * stride as i64];
                        let t = rel.map(|c| c.clamp(0, s - 1));
                        let fine = 1i64 << (item.level - item.refinement);
                        let tile = q << item.level;
                        let want = truth(
                            item.tx as i64 * tile + t[0] * fine,
                            item.ty as i64 * tile + t[1] * fine,
                        );
                        // … and where the shader reads them: the slot's layer, the texel it
                        // finds from the node's south-west texel in that layer.
                        let place = atlas.place(*slot);
                        let read = atlas.read_texel([place.x + sx, place.y + sy], rel);
                        let w = atlas.width() as usize;
                        (
                            layers[place.layer as usize][read[1] as usize * w + read[0] as usize],
                            want,
                        )
                    };
                    assert!(
                        got.0 == got.1,
                        "frame {}: {item:?} reads {} for {} at ({i}, {j})",
                        plan.stats.frame,
                        got.0,
                        got.1
                    );
                }
            }
        }
    }
}

fn camera(x: f64, y: f64, heading: f64) -> Camera {
    Camera::new(
        DVec3::new(x, y, 420.0),
        Attitude::from_degrees(heading, -25.0, 0.0),
        Frustum::symmetric(90f64.to_radians(), 320, 180),
    )
}

struct Fixture {
    ds: Arc<Dataset>,
    bake: Arc<ErrorBake>,
    /// The pools' image limits (None: common devices', one slot a layer here).
    pool_limits: Option<PoolLimits>,
}

impl Fixture {
    fn new() -> Self {
        let ds = dataset();
        let bake = Arc::new(bake(&ds, BakeParams::default(), &|_, _| {}));
        Fixture {
            ds,
            bake,
            pool_limits: None,
        }
    }

    fn state(&self, source: Arc<dyn TerrainSource>) -> PlanState {
        let mut st = PlanState::new(
            self.bake.clone(),
            source,
            clipmap(),
            &[64, 64, 32, 16, 8, 0],
        );
        if let Some(limits) = self.pool_limits {
            st.fit_pools(limits).expect("the pools fit");
        }
        st
    }
}

/// Plans one frame (selection, budget) with a generous region; the mirror receives it.
fn frame(
    st: &mut PlanState,
    n: u64,
    cam: &Camera,
    select: &SelectParams,
    prefetch: f64,
) -> (Selection, FramePlan) {
    let mut inp = FrameInputs {
        frame: n,
        camera: cam,
        viewport: (320, 180),
        channels: &[],
        channels_generation: 0,
        select,
        prefetch_frames: prefetch,
        skirt_factor: 2.0,
        skirt_min_m: 1.0,
        skirts: SkirtRule::WhereResolutionsDiffer,
        overlay_bytes: None,
        tile_meshes: TileMeshes::indices(17).1,
        staging: StagingBudget::new(0, 64),
    };
    inp.staging = StagingBudget::new(64 << 20, 64);
    let mut sel = Selection::default();
    let strips = select_frame(st, &inp, &mut sel);
    let plan = plan_frame(st, &inp, &sel, strips).unwrap();
    (sel, plan)
}

fn select() -> SelectParams {
    SelectParams {
        tau_px: 0.5,
        ..SelectParams::default()
    }
}

#[test]
fn withheld_levels_are_drawn_coarser_late_and_never_stale_until_they_arrive() {
    withheld_levels_flight(Fixture::new());
}

/// The same flight with every pool packed several slots to a layer (at most 5 layers): each
/// slot's upload lands in its own cell and every node reads its own slot's samples.
#[test]
fn with_pools_packed_several_slots_to_a_layer_every_node_reads_its_own_slot() {
    let f = Fixture {
        pool_limits: Some(PoolLimits {
            max_layers: 5,
            max_side: 4096,
        }),
        ..Fixture::new()
    };
    let st = f.state(Arc::new(InMemoryTerrain::new(f.ds.clone())));
    let packed: Vec<u32> = st.pools.iter().map(|p| p.atlas.per_row).collect();
    assert_eq!(
        packed,
        [4, 4, 3, 2, 2, 1],
        "64, 64, 32, 16, 8 slots in 5 layers"
    );
    withheld_levels_flight(f);
}

fn withheld_levels_flight(f: Fixture) {
    let levels = clipmap().level_count();
    assert!(
        levels >= 3,
        "the fixture must have levels to descend ({levels})"
    );
    let coarsest = levels - 1;
    let src = Arc::new(Withholding::new(f.ds.clone(), coarsest));
    let mut st = f.state(src.clone());
    let mut mirror = Mirror::new(&st);
    let valid = [N as i64, N as i64];
    let strips = st.strips_around(camera(900.0, 900.0, 60.0).position);
    let first = FramePlan {
        strips,
        ..Default::default()
    };
    mirror.apply(&st, &first);
    assert!(
        st.feed.content.complete(coarsest),
        "the resident coarsest level fills at load"
    );
    assert!(
        st.feed.pending_cells() > 0,
        "the finer levels wait for their pages"
    );

    let mut late_frames = 0;
    let mut saw_request = false;
    // Fly north-east across level moves, a few requested pages arriving per frame.
    for n in 0..60u64 {
        let cam = camera(900.0 + 45.0 * n as f64, 900.0 + 30.0 * n as f64, 60.0);
        let (sel, plan) = frame(&mut st, n, &cam, &select(), 0.0);
        mirror.apply(&st, &plan);
        mirror.check(&st, &plan, &f.ds.hf, valid);
        if plan.stats.tiles_late_stream > 0 {
            late_frames += 1;
            assert!(plan.stats.tiles_late >= plan.stats.tiles_late_stream);
            let wants = src.wants();
            assert!(!wants.is_empty(), "frame {n}: late tiles are asked for");
            saw_request = true;
            // What the draw needs outranks what it does not.
            assert!(
                wants.iter().any(|w| w.priority >= DRAWN_PRIORITY),
                "{wants:?}"
            );
            assert!(sel.stream_late + plan.stats.tiles_late_stream > 0);
        }
        src.serve(if n < 30 { 3 } else { 1000 });
    }
    assert!(
        late_frames > 0 && saw_request,
        "withheld pages must make tiles late"
    );

    // Everything served: the plan converges to what the in-memory source draws.
    let cam = camera(900.0 + 45.0 * 60.0, 900.0 + 30.0 * 60.0, 60.0);
    for n in 60..64 {
        let (_, plan) = frame(&mut st, n, &cam, &select(), 0.0);
        mirror.apply(&st, &plan);
        mirror.check(&st, &plan, &f.ds.hf, valid);
        src.serve(1000);
    }
    let (sel, plan) = frame(&mut st, 64, &cam, &select(), 0.0);
    mirror.apply(&st, &plan);
    mirror.check(&st, &plan, &f.ds.hf, valid);
    assert_eq!((plan.stats.tiles_late, plan.stats.cells_pending), (0, 0));
    let mut mem = f.state(Arc::new(InMemoryTerrain::new(f.ds.clone())));
    mem.strips_around(cam.position);
    let (want, _) = frame(&mut mem, 0, &cam, &select(), 0.0);
    assert_eq!(
        sel.items, want.items,
        "warm, the streamed selection is the in-memory one"
    );
}

#[test]
fn a_pool_upload_whose_samples_are_not_resident_is_late_and_asked_for_by_its_error() {
    let f = Fixture::new();
    // Level 0 withheld: its texture never fills, and a refined tile reading level-0 samples
    // (L − r = 0) cannot be uploaded; everything coarser is resident.
    let src = Arc::new(Withholding::new(f.ds.clone(), 1));
    let mut st = f.state(src.clone());
    let cam = camera(1300.0, 1300.0, 45.0);
    let mut mirror = Mirror::new(&st);
    let strips = st.strips_around(cam.position);
    mirror.apply(
        &st,
        &FramePlan {
            strips,
            ..Default::default()
        },
    );
    let (_, plan) = frame(&mut st, 0, &cam, &select(), 0.0);
    mirror.apply(&st, &plan);
    mirror.check(&st, &plan, &f.ds.hf, [N as i64; 2]);
    assert!(
        plan.stats.tiles_late_stream > 0,
        "refined tiles over level 0 must be late"
    );
    let wants = src.wants();
    let mut asked = 0;
    for l in &plan.late {
        assert!(l.drawn_refinement < l.key.refinement, "{l:?}");
        let atlas = st.pools[l.key.refinement as usize - 1].atlas;
        let rect = atlas.upload(Q, &l.key, 0).sample_rect();
        if rect.level == 0 {
            let w = wants
                .iter()
                .find(|w| w.rect == rect)
                .expect("a late tile is asked for");
            assert!(w.priority >= DRAWN_PRIORITY, "{w:?}");
            asked += 1;
        }
    }
    assert!(asked > 0);
    // No level-0 texel is drawn: nothing there is resident.
    assert!(plan.draw_list.iter().all(|(d, _)| d.node_level > 0));
}

#[test]
fn a_gather_refused_after_is_resident_said_yes_leaves_the_strip_pending_and_nothing_stale() {
    let f = Fixture::new();
    let src = Arc::new(Withholding::new(f.ds.clone(), 0));
    let mut st = f.state(src.clone());
    let mut mirror = Mirror::new(&st);
    let cam = camera(1500.0, 1500.0, 0.0);
    let strips = st.strips_around(cam.position);
    mirror.apply(
        &st,
        &FramePlan {
            strips,
            ..Default::default()
        },
    );
    assert_eq!(st.feed.pending_cells(), 0);
    // Move far enough to expose strips, with the source "evicting" between the check and the
    // copy of the first few.
    src.state.lock().unwrap().fail_gathers = 3;
    let far = camera(1500.0 + 700.0, 1500.0, 0.0);
    let (_, plan) = frame(&mut st, 1, &far, &select(), 0.0);
    mirror.apply(&st, &plan);
    mirror.check(&st, &plan, &f.ds.hf, [N as i64; 2]);
    // The refused ones were retried cell by cell or stay pending for the next frame.
    let (_, next) = frame(&mut st, 2, &far, &select(), 0.0);
    mirror.apply(&st, &next);
    mirror.check(&st, &next, &f.ds.hf, [N as i64; 2]);
    assert_eq!(
        st.feed.pending_cells(),
        0,
        "resident strips arrive by the next frame"
    );
    assert_eq!(next.stats.tiles_late, 0);
}

#[test]
fn prefetch_asks_for_what_lies_ahead_below_anything_drawn() {
    let f = Fixture::new();
    let coarsest = clipmap().level_count() - 1;
    let run = |prefetch: f64| {
        let src = Arc::new(Withholding::new(f.ds.clone(), coarsest));
        let mut st = f.state(src.clone());
        st.strips_around(camera(900.0, 900.0, 90.0).position);
        frame(&mut st, 0, &camera(900.0, 900.0, 90.0), &select(), prefetch);
        frame(&mut st, 1, &camera(960.0, 900.0, 90.0), &select(), prefetch);
        src.wants()
    };
    let (with, without) = (run(30.0), run(0.0));
    let extra: Vec<_> = with
        .iter()
        .filter(|w| !without.iter().any(|o| o.rect == w.rect))
        .collect();
    assert!(!extra.is_empty(), "moving east asks for what lies ahead");
    for w in &extra {
        assert!(
            w.priority <= PREFETCH_PRIORITY,
            "a prefetch outranks a draw: {w:?}"
        );
        assert!(
            w.rect.origin[0] as f64 * 10.0 > 960.0,
            "ahead is east of the eye: {w:?}"
        );
    }
    assert!(
        with.iter().any(|w| w.priority >= DRAWN_PRIORITY),
        "the frame's own needs too"
    );
}

#[test]
fn without_the_quadtree_a_ring_tile_not_ready_is_not_drawn_and_counts_late() {
    let f = Fixture::new();
    let coarsest = clipmap().level_count() - 1;
    let src = Arc::new(Withholding::new(f.ds.clone(), coarsest));
    let mut st = f.state(src.clone());
    let cam = camera(1500.0, 1500.0, 30.0);
    let mut mirror = Mirror::new(&st);
    let strips = st.strips_around(cam.position);
    mirror.apply(
        &st,
        &FramePlan {
            strips,
            ..Default::default()
        },
    );
    let plain = SelectParams {
        coarsen: false,
        ..select()
    };
    let (sel, plan) = frame(&mut st, 0, &cam, &plain, 0.0);
    mirror.apply(&st, &plan);
    mirror.check(&st, &plan, &f.ds.hf, [N as i64; 2]);
    assert!(sel.stream_late > 0);
    assert!(plan.stats.tiles_late >= sel.stream_late);
}

#[test]
fn the_data_cap_bounds_each_frames_gathered_samples_and_what_waits_comes_later() {
    let f = Fixture::new();
    let mut st = f.state(Arc::new(InMemoryTerrain::new(f.ds.clone())));
    let mut mirror = Mirror::new(&st);
    let valid = [N as i64, N as i64];
    let start = FramePlan {
        strips: st.strips_around(camera(900.0, 900.0, 60.0).position),
        ..Default::default()
    };
    mirror.apply(&st, &start);
    assert_eq!(st.feed.pending_cells(), 0, "start-up is not capped");
    // Four level cells a frame: a jump across the dataset exposes far more.
    let cap = 4 * (Q * Q) as usize;
    st.feed.data_cap_samples = cap;
    let cam = camera(5200.0, 4100.0, 60.0);
    let mut deferred_frames = 0;
    for n in 0..400u64 {
        let (_, plan) = frame(&mut st, n, &cam, &select(), 0.0);
        mirror.apply(&st, &plan);
        // Whatever waits, nothing drawn is stale.
        mirror.check(&st, &plan, &f.ds.hf, valid);
        let largest = plan
            .strips
            .iter()
            .chain(plan.pool_uploads.iter().map(|p| &p.upload))
            .map(|u| u.size[0] as usize * u.size[1] as usize)
            .max()
            .unwrap_or(0);
        let gathered = st.feed.gatherer.samples().len();
        assert!(
            gathered <= cap.max(largest),
            "frame {n}: {gathered} samples gathered, cap {cap}"
        );
        deferred_frames += (st.feed.deferred > 0) as u32;
        if st.feed.pending_cells() == 0 && st.feed.deferred == 0 && plan.stats.tiles_late == 0 {
            break;
        }
    }
    assert!(deferred_frames > 1, "the jump must take several frames");
    assert_eq!(st.feed.pending_cells(), 0, "everything arrives");
    // Caught up, the capped plan draws what the uncapped one draws.
    let (sel, _) = frame(&mut st, 400, &cam, &select(), 0.0);
    let mut free = f.state(Arc::new(InMemoryTerrain::new(f.ds.clone())));
    free.strips_around(cam.position);
    let (want, _) = frame(&mut free, 0, &cam, &select(), 0.0);
    assert_eq!(sel.items, want.items);
}
