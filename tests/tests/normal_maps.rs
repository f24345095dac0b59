//! Normal maps on lavapipe with the validation layer on: the normal the shader lights a level
//! tile with equals the CPU normal of the full-resolution samples (`render::normal_map`) at the
//! fragment, and a golden pair of a rough ridge country seen at a distance, normal maps on and
//! off, which differ where coarse levels are drawn and agree where level 0 is.

use std::sync::Arc;

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::render::frame::{Lighting, Look, RendererDesc};
use aerie::render::gathered::Gatherer;
use aerie::render::jobs::ImageUpload;
use aerie::render::normal_map::{decode_normal, normal_texels, NormalFootprint};
use aerie::render::plan::PlanState;
use aerie::terrain::source::{InMemoryTerrain, TerrainSource};
use aerie::terrain::source::{NotResident, SampleRect, SampleWant, SourceGrid};
use aerie_tests::ridges::*;
use aerie_tests::*;
use glam::DVec3;

const W: u32 = 256;
const H: u32 = 144;

fn camera(pos: [f64; 3], hpr_deg: [f64; 3], fov_deg: f64) -> Camera {
    Camera::new(
        DVec3::from_array(pos),
        Attitude::from_degrees(hpr_deg[0], hpr_deg[1], hpr_deg[2]),
        Frustum::symmetric(fov_deg.to_radians(), W, H),
    )
}

fn desc(look: Look, normal_maps: bool) -> RendererDesc {
    let mut d = test_desc(W, H);
    d.select.curvature = false;
    d.look = look;
    d.normal_maps = normal_maps;
    // A loose error bound: coarse levels drawn near enough to be seen in a small frame.
    d.select.tau_px = 8.0;
    d
}

/// The CPU normal texels of level `level` over the whole grid (what the renderer uploads, from
/// the in-memory source: the finest candidate is always resident).
struct CpuNormals {
    level: u32,
    side: usize,
    texels: Vec<[f32; 3]>,
}

impl CpuNormals {
    fn new(src: &InMemoryTerrain, level: u32) -> Self {
        let side = (N - 1) / (1 << level) + 1;
        let fp = NormalFootprint::candidates(level).next().unwrap();
        let size = [side as u32, side as u32];
        let rect = fp.rect([0, 0], size);
        let mut block = vec![0.0; rect.len()];
        src.gather(&rect, &mut block).unwrap();
        let mut t = Vec::new();
        normal_texels(&fp, &block, size, [SPACING, SPACING], &mut t);
        CpuNormals {
            level,
            side,
            texels: t.into_iter().map(decode_normal).collect(),
        }
    }

    /// The shader's arithmetic: x, y interpolated bilinearly at grid position `g` (level-0
    /// samples), z reconstructed, normalised.
    fn at(&self, g: [f64; 2]) -> [f64; 3] {
        let s = (1u64 << self.level) as f64;
        let u = [g[0] / s, g[1] / s];
        let i = [u[0].floor(), u[1].floor()];
        let f = [u[0] - i[0], u[1] - i[1]];
        let texel = |di: usize, dj: usize| {
            let c = (i[0] as usize + di).min(self.side - 1);
            let r = (i[1] as usize + dj).min(self.side - 1);
            self.texels[r * self.side + c]
        };
        let mut xy = [0.0f64; 2];
        for (dj, wy) in [(0, 1.0 - f[1]), (1, f[1])] {
            for (di, wx) in [(0, 1.0 - f[0]), (1, f[0])] {
                let t = texel(di, dj);
                for a in 0..2 {
                    xy[a] += wx * wy * f64::from(t[a]);
                }
            }
        }
        let z = (1.0 - xy[0] * xy[0] - xy[1] * xy[1]).max(0.0).sqrt();
        let len = (xy[0] * xy[0] + xy[1] * xy[1] + z * z).sqrt();
        [xy[0] / len, xy[1] / len, z / len]
    }
}

/// The world point a pixel's fragment lies at, from its reversed-Z depth.
fn fragment_world(cam: &Camera, x: u32, y: u32, depth: f32) -> DVec3 {
    let ray = cam.pixel_ray(x as f64 + 0.5, y as f64 + 0.5, W, H);
    let view_z = cam.near / f64::from(depth);
    let along = (cam.world_to_view_rotation() * ray).z;
    cam.position + ray * (view_z / along)
}

/// Largest difference in x or y between the shaded normal and the CPU normal.
const TOLERANCE: f64 = 0.03;

#[test]
fn the_shaded_normal_is_the_cpu_normal_of_the_full_resolution_samples() {
    let hf = ridges();
    // Straight down at τ = 1 px (fine levels near the eye), and at τ = 8 px straight down and
    // oblique across the dataset (coarse levels near the middle of the frame).
    let runs = [
        (
            1.0,
            vec![camera(
                [15_000.0, 15_000.0, 3_000.0],
                [0.0, -90.0, 0.0],
                50.0,
            )],
        ),
        (
            8.0,
            vec![
                camera([15_000.0, 15_000.0, 3_000.0], [0.0, -90.0, 0.0], 50.0),
                camera([2_000.0, 2_000.0, 2_500.0], [45.0, -10.0, 0.0], 60.0),
            ],
        ),
    ];
    let mut shots = Vec::new();
    let mut frames = Vec::new();
    let mut src = None;
    for (tau, cams) in runs {
        let mut d = desc(Look::Normals, true);
        d.select.tau_px = tau;
        let (ds, b) = prepare(&d, &hf);
        src.get_or_insert_with(|| InMemoryTerrain::new(Arc::clone(&ds)));
        let lit: Vec<_> = cams.iter().map(|c| (*c, Lighting::default())).collect();
        frames.extend(render_lit(&d, &ds, &b, &lit));
        shots.extend(cams);
    }
    let src = src.unwrap();
    let mut cpu: Vec<Option<CpuNormals>> = (0..16).map(|_| None).collect();
    let (mut checked, mut over, mut worst, mut sum) = ([0u32; 16], 0u32, 0.0f64, 0.0f64);
    for (k, (cam, f)) in shots.iter().zip(&frames).enumerate() {
        let path = test_output_dir().join(format!("normal_maps_view{k}.png"));
        aerie::tools::output::write_png(&path, f.width, f.height, &f.rgba).unwrap();
        for y in 0..H {
            for x in 0..W {
                let i = (y * W + x) as usize;
                let depth = f.depth[i];
                let px = &f.rgba[i * 4..i * 4 + 3];
                // Blue: (L + 1)·16 from the level-L normal map; 0 per vertex, sky elsewhere.
                let code = px[2] as i32;
                let k = (code + 8) / 16;
                if depth <= 0.0 || k < 1 || (code - 16 * k).abs() > 3 {
                    continue;
                }
                let level = (k - 1) as u32;
                let p = fragment_world(cam, x, y, depth);
                let g = [p.x / SPACING, p.y / SPACING];
                if !(g[0] >= 0.0 && g[1] >= 0.0 && g[0] < (N - 1) as f64 && g[1] < (N - 1) as f64) {
                    continue;
                }
                // At the texels: the fragment within a quarter texel of a texel centre.
                let s = (1u64 << level) as f64;
                let near_centre = g.iter().all(|v| {
                    let u = v / s;
                    (u - u.round()).abs() < 0.25
                });
                if !near_centre {
                    continue;
                }
                let n = cpu[level as usize].get_or_insert_with(|| CpuNormals::new(&src, level));
                let want = n.at(g);
                let got = [0, 1].map(|a| f64::from(px[a]) / 255.0 * 2.0 - 1.0);
                let err = (got[0] - want[0]).abs().max((got[1] - want[1]).abs());
                checked[level as usize] += 1;
                worst = worst.max(err);
                sum += err;
                if err > TOLERANCE {
                    over += 1;
                }
            }
        }
    }
    let total: u32 = checked.iter().sum();
    let coarse: u32 = checked[2..].iter().sum();
    eprintln!(
        "checked per level {checked:?}, over {TOLERANCE}: {over}, worst {worst:.4}, mean {:.4}",
        sum / total.max(1) as f64
    );
    assert!(total > 2000, "too few pixels at texel centres: {checked:?}");
    assert!(
        checked[0] + checked[1] > 100,
        "levels 0, 1 barely drawn: {checked:?}"
    );
    assert!(coarse > 200, "coarse levels barely drawn: {checked:?}");
    // Skirts and silhouettes may put a few fragments where no texel is (under 0.5 %).
    assert!(
        (over as f64) < 0.005 * total as f64,
        "{over} of {total} pixels differ from the CPU normal by more than {TOLERANCE} (worst {worst})"
    );
}

/// A distant ridge country lit from the north-west, normal maps on and off (plain look).
#[test]
fn golden_pair_distant_ridges_lit_with_full_resolution_detail() {
    let hf = ridges();
    let cam = camera([3_000.0, 3_000.0, 1_300.0], [45.0, -12.0, 0.0], 60.0);
    // A low sun from the west in clear air: slopes show.
    let (az, el) = (270f64.to_radians(), 20f64.to_radians());
    let sun = [el.cos() * az.sin(), el.cos() * az.cos(), el.sin()];
    let shot = [(cam, Lighting::from_host(Some(sun), Some(150_000.0)))];
    let render = |look, on| {
        let mut d = desc(look, on);
        // Level 0 near the eye, coarse levels within the frame.
        d.select.tau_px = 3.0;
        // Every node on its own mesh: the check below compares level 0's normal map with level
        // 0's per-vertex normals, which a quadrant drawn on its parent's mesh does not have
        // (there the maps-off frame shows the coarser mesh's normals; mean difference 2.5).
        d.select.parent_quadrants = false;
        let (ds, b) = prepare(&d, &hf);
        render_lit(&d, &ds, &b, &shot).remove(0)
    };
    let on = render(Look::Plain, true);
    let off = render(Look::Plain, false);
    let levels = render(Look::Normals, true);
    check_golden("normal_maps_on", &on, GOLDEN_TOLERANCE);
    check_golden("normal_maps_off", &off, GOLDEN_TOLERANCE);
    // Per pixel: where level 0's normal map is drawn the two agree; where a coarse level's is,
    // they differ (the level's own normals lose the detail).
    let (mut fine, mut coarse) = ((0u64, 0u64), (0u64, 0u64));
    let mut per_level = [(0u64, 0u64); 16];
    for i in 0..(W * H) as usize {
        if levels.depth[i] <= 0.0 {
            continue;
        }
        let code = levels.rgba[i * 4 + 2] as i32;
        let diff: u64 = (0..3)
            .map(|c| on.rgba[i * 4 + c].abs_diff(off.rgba[i * 4 + c]) as u64)
            .sum();
        let l = ((code + 8) / 16) as usize;
        per_level[l.min(15)] = (per_level[l.min(15)].0 + diff, per_level[l.min(15)].1 + 1);
        match (code + 8) / 16 {
            1 => fine = (fine.0 + diff, fine.1 + 1),
            l if l >= 3 => coarse = (coarse.0 + diff, coarse.1 + 1),
            _ => {}
        }
    }
    eprintln!("per level code (diff sum, pixels): {per_level:?}");
    let path = test_output_dir().join("normal_maps_levels.png");
    aerie::tools::output::write_png(&path, W, H, &levels.rgba).unwrap();
    assert!(
        fine.1 > 500 && coarse.1 > 500,
        "fine {fine:?}, coarse {coarse:?}"
    );
    let (fine_mean, coarse_mean) = (
        fine.0 as f64 / fine.1 as f64,
        coarse.0 as f64 / coarse.1 as f64,
    );
    eprintln!("mean RGB difference on/off: level 0 {fine_mean:.2}, levels ≥ 2 {coarse_mean:.2}");
    assert!(fine_mean < 1.0, "level 0 changed: {fine_mean}");
    assert!(
        coarse_mean > 1.5 && coarse_mean > 4.0 * fine_mean,
        "coarse levels barely changed: {coarse_mean} vs level 0 {fine_mean}"
    );
}

/// Every normal texel the plan uploads with the level strips — first fill, moves, pieces split
/// at the toroidal wrap — is the CPU normal of its own level-L sample, registered to the level
/// texture's texel (sample / 2^L mod side).
#[test]
fn uploaded_normal_texels_are_their_samples_normals_across_the_toroidal_wrap() {
    let hf = ridges();
    let d = desc(Look::Plain, true);
    let (ds, b) = prepare(&d, &hf);
    let src = Arc::new(InMemoryTerrain::new(Arc::clone(&ds)));
    let clipmap = d.clipmap(src.grid());
    let side = clipmap.texture_side();
    let mut st = PlanState::new(b, src.clone(), clipmap, &[0; 6]);
    st.feed.gatherer.set_normal_maps(Some([SPACING, SPACING]));
    let mut wraps = 0;
    let mut texels = 0usize;
    for (x, y) in [(9_000.0, 9_000.0), (9_700.0, 9_350.0), (14_000.0, 12_500.0)] {
        let strips = st.strips_around(DVec3::new(x, y, 1_500.0));
        let normals = st.feed.gatherer.normals();
        let mut at = 0;
        for job in &strips {
            let step = job.step as i64;
            for a in 0..2 {
                let texel = (job.origin_sample[a] / step).rem_euclid(side as i64);
                assert_eq!(texel, job.texel[a] as i64, "{job:?} axis {a}");
                // The piece after a wrap starts at texel 0 and another of its rows ends at
                // the texture's side.
                if job.texel[a] == 0
                    && strips.iter().any(|o| {
                        o.layer == job.layer
                            && o.texel[a] + o.size[a] == side
                            && o.origin_sample[1 - a] == job.origin_sample[1 - a]
                    })
                {
                    wraps += 1;
                }
            }
            let fp = NormalFootprint::candidates(job.layer).next().unwrap();
            for j in 0..job.size[1] as i64 {
                for i in 0..job.size[0] as i64 {
                    let origin = [
                        job.origin_sample[0] + i * step,
                        job.origin_sample[1] + j * step,
                    ];
                    let rect = fp.rect(origin, [1, 1]);
                    let mut block = vec![0.0; rect.len()];
                    src.gather(&rect, &mut block).unwrap();
                    let mut want = Vec::new();
                    normal_texels(&fp, &block, [1, 1], [SPACING, SPACING], &mut want);
                    assert_eq!(normals[at], want[0], "{job:?} texel ({i}, {j})");
                    at += 1;
                }
            }
        }
        assert_eq!(at, normals.len(), "one normal texel per uploaded height");
        texels += at;
    }
    assert!(wraps > 0, "no strip crossed the toroidal wrap");
    assert!(texels > 10_000, "{texels} texels checked");
}

/// A streamed store's view from far away: levels below `finest` are not resident.
struct Coarse {
    inner: InMemoryTerrain,
    finest: u32,
}

impl TerrainSource for Coarse {
    fn grid(&self) -> &SourceGrid {
        self.inner.grid()
    }
    fn is_resident(&self, rect: &SampleRect) -> bool {
        rect.level >= self.finest
    }
    fn gather(&self, rect: &SampleRect, out: &mut [f32]) -> Result<(), NotResident> {
        if rect.level < self.finest {
            return Err(NotResident {
                level: rect.level,
                px: 0,
                py: 0,
                failed: false,
            });
        }
        self.inner.gather(rect, out)
    }
    fn request(&self, _wants: &[SampleWant]) {}
}

/// A level strip is admitted only with its normal texels, computed from level max(0, L − 3);
/// where the source lacks that level, the texels are refused (the strip's heights dropped with
/// them by the feed) and the rectangle is kept to be asked for.
#[test]
fn normal_texels_need_their_level_or_the_strip_stays_pending() {
    let hf = ridges();
    let d = desc(Look::Plain, true);
    let (ds, _) = prepare(&d, &hf);
    let level = 4;
    let job = ImageUpload {
        layer: level,
        texel: [0, 0],
        size: [9, 7],
        origin_sample: [160, 320],
        step: 1 << level,
    };
    let fp = NormalFootprint::of_level(level);
    assert_eq!(fp.source, 1);
    for finest in 0..=level {
        let src = Arc::new(Coarse {
            inner: InMemoryTerrain::new(Arc::clone(&ds)),
            finest,
        });
        let mut g = Gatherer::new(src.clone());
        g.set_normal_maps(Some([SPACING, SPACING]));
        let got = g.gather_normals(&job);
        let rect = fp.rect(job.origin_sample, job.size);
        if finest > fp.source {
            assert!(got.is_err(), "level {} is not resident", fp.source);
            assert!(g.normals().is_empty());
            assert_eq!(
                g.take_normal_misses(),
                vec![rect],
                "the lacking rectangle is kept"
            );
            continue;
        }
        got.unwrap();
        let mut block = vec![0.0; rect.len()];
        src.inner.gather(&rect, &mut block).unwrap();
        let mut want = Vec::new();
        normal_texels(&fp, &block, job.size, [SPACING, SPACING], &mut want);
        assert_eq!(g.normals(), &want[..], "finest resident level {finest}");
    }
    // Through the feed: levels 0 and 1 missing. Every level here (0..=3) reads level 0 for its
    // normal texels, so every strip stays pending, no height is kept, and level 0 is asked for.
    let src = Arc::new(Coarse {
        inner: InMemoryTerrain::new(Arc::clone(&ds)),
        finest: 2,
    });
    let (_, b) = prepare(&d, &hf);
    let clipmap = d.clipmap(src.grid());
    let mut st = PlanState::new(b, src, clipmap, &[0; 6]);
    st.feed.gatherer.set_normal_maps(Some([SPACING, SPACING]));
    let strips = st.strips_around(DVec3::new(15_000.0, 15_000.0, 1_500.0));
    assert!(
        strips.is_empty(),
        "admitted without normal texels: {strips:?}"
    );
    assert!(
        st.feed.gatherer.samples().is_empty(),
        "heights kept for refused strips"
    );
    assert!(st.feed.pending_cells() > 0, "the levels are pending");
    // The footprints' level was asked for with the cells.
    let wants = st.feed.gatherer.wants();
    assert!(
        wants.iter().any(|w| w.rect.level == 0),
        "level 0 not asked for"
    );
}
