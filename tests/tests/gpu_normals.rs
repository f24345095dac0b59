//! `--normals gpu` on lavapipe with the validation layer on: the normal texels the compute pass
//! writes (read back from the normal texture) equal its CPU twin
//! (`normal_map::level_normal_texel`) over every level's whole cache region after strips
//! moved in (first fill, moves, pieces split at the toroidal wrap), within one snorm step; at
//! level 0 they equal the CPU path's texels; on coarse levels their angle to the CPU path's
//! full-resolution normals is measured and recorded (`gpu_normals_angles.csv`).

use std::sync::Arc;

use aerie::camera::{Attitude, Camera, Frustum};
use aerie::render::frame::{Look, NormalSource, RendererDesc, TerrainRenderer};
use aerie::render::normal_map::{
    decode_normal, level_normal_texel, level_spacing, LevelRegion, NormalTexel,
};
use aerie::terrain::clipmap::CacheRegion;
use aerie::terrain::dataset::Dataset;
use aerie::terrain::source::{InMemoryTerrain, SampleRect, TerrainSource};
use aerie_tests::ridges::*;
use aerie_tests::*;
use glam::DVec3;

const W: u32 = 256;
const H: u32 = 144;

fn desc(source: NormalSource) -> RendererDesc {
    let mut d = test_desc(W, H);
    d.select.curvature = false;
    d.look = Look::Plain;
    d.normal_maps = true;
    d.normal_source = source;
    d.select.tau_px = 4.0;
    d
}

/// A flight that moves every level (strips, toroidal wraps), ending where the levels settle.
fn cameras() -> Vec<Camera> {
    [
        (9_000.0, 9_000.0),
        (9_700.0, 9_350.0),
        (14_000.0, 12_500.0),
        (14_000.0, 12_500.0),
        (14_000.0, 12_500.0),
    ]
    .iter()
    .map(|&(x, y)| {
        Camera::new(
            DVec3::new(x, y, 1_500.0),
            Attitude::from_degrees(30.0, -30.0, 0.0),
            Frustum::symmetric(60f64.to_radians(), W, H),
        )
    })
    .collect()
}

/// What the normal texture holds after the flight, per level, and where each level's region is.
struct Texels {
    layers: Vec<Vec<NormalTexel>>,
    regions: Vec<Option<CacheRegion>>,
    side: u32,
}

fn fly(
    source: NormalSource,
    ds: &Arc<Dataset>,
    b: &Arc<aerie::terrain::bake::ErrorBake>,
) -> Texels {
    let d = desc(source);
    let cams = cameras();
    let mut r = TerrainRenderer::new(&d).expect("create renderer");
    r.load_terrain(Arc::clone(ds), Arc::clone(b), cams[0].position)
        .expect("upload terrain");
    let mut gpu_ms = Vec::new();
    for cam in &cams {
        let s = r.render(cam).expect("render");
        gpu_ms.push(s.gpu_normals_ms);
        if source == NormalSource::Gpu {
            assert_eq!((s.bytes_normals, s.cpu_normals_us), (0, 0.0), "{s:?}");
        }
    }
    eprintln!("{source:?}: GPU normal pass ms per frame {gpu_ms:?}");
    assert_eq!(r.pending_cells(), 0, "every level filled");
    let (regions, side) = r.level_regions();
    let layers = (0..regions.len() as u32)
        .map(|l| r.read_normal_layer(l).expect("read back"))
        .collect();
    let counters = r.validation_counters();
    r.destroy();
    assert_validation_clean(&counters);
    Texels {
        layers,
        regions,
        side,
    }
}

/// The level-L sample texel `t` of a level whose region starts at `origin` holds.
fn sample_at(t: [u32; 2], origin: [i64; 2], side: u32) -> [i64; 2] {
    [0, 1].map(|a| origin[a] + (t[a] as i64 - origin[a]).rem_euclid(side as i64))
}

/// Level `level`'s heights over its region and one sample around it, as the uploader writes
/// them (from the source).
fn region_heights(
    src: &InMemoryTerrain,
    level: u32,
    region: &CacheRegion,
) -> impl Fn([i64; 2]) -> f32 {
    let rect = SampleRect {
        level,
        origin: region.origin.map(|o| (o - 1) << level),
        size: [region.side + 2; 2],
    };
    let mut block = vec![0.0f32; rect.len()];
    src.gather(&rect, &mut block).expect("resident");
    let (origin, side) = (region.origin.map(|o| o - 1), region.side as i64 + 2);
    move |s: [i64; 2]| {
        let (c, r) = (s[0] - origin[0], s[1] - origin[1]);
        assert!(
            (0..side).contains(&c) && (0..side).contains(&r),
            "{s:?} outside"
        );
        block[(r * side + c) as usize]
    }
}

/// Every texel of every level's region is its sample's [`level_normal_texel`] over the region
/// (one-sided at the region's edges), except that an edge sample the region moved onto keeps
/// the central difference it was computed with while its outer neighbour was resident (it is
/// recomputed only when a neighbour's heights arrive): there either is right.
#[test]
fn gpu_normal_texels_are_their_cpu_twin_over_every_level_region() {
    let hf = ridges();
    let (ds, b) = prepare(&desc(NormalSource::Gpu), &hf);
    let src = InMemoryTerrain::new(Arc::clone(&ds));
    let got = fly(NormalSource::Gpu, &ds, &b);
    let mut checked = 0usize;
    for (level, region) in got.regions.iter().enumerate() {
        let region = region.as_ref().expect("placed");
        let level = level as u32;
        let h = region_heights(&src, level, region);
        let lr = LevelRegion::of_cache(region.origin, got.side);
        let wider = LevelRegion {
            lo: lr.lo.map(|v| v - 1),
            hi: lr.hi.map(|v| v + 1),
        };
        let sp = level_spacing([SPACING, SPACING], level);
        let (mut over, mut worst, mut kept) = (0usize, 0i32, 0usize);
        for ty in 0..got.side {
            for tx in 0..got.side {
                let s = sample_at([tx, ty], region.origin, got.side);
                let have = got.layers[level as usize][(ty * got.side + tx) as usize];
                let steps = |want: NormalTexel| {
                    (0..2)
                        .map(|a| (i32::from(have[a]) - i32::from(want[a])).abs())
                        .max()
                        .unwrap()
                };
                let want = level_normal_texel(&h, s, &lr, sp);
                let mut d = steps(want);
                let edge = (0..2).any(|a| s[a] == lr.lo[a] || s[a] == lr.hi[a]);
                if edge && d > 1 {
                    d = steps(level_normal_texel(&h, s, &wider, sp));
                    kept += (d <= 1) as usize;
                }
                worst = worst.max(d);
                if d > 1 {
                    over += 1;
                    if over < 5 {
                        eprintln!("level {level} texel ({tx}, {ty}) sample {s:?}: {have:?} vs twin {want:?}");
                    }
                }
                checked += 1;
            }
        }
        assert_eq!(
            over, 0,
            "level {level}: {over} texels over one snorm step (worst {worst})"
        );
        eprintln!("level {level}: {kept} edge texels kept their central difference");
    }
    eprintln!("{checked} texels equal their CPU twin within one snorm step");
    assert!(checked > 100_000, "{checked}");
}

/// Angle in degrees between the normals two texels stand for.
fn angle_deg(a: NormalTexel, b: NormalTexel) -> f64 {
    let (u, v) = (decode_normal(a), decode_normal(b));
    let dot: f64 = (0..3).map(|i| f64::from(u[i]) * f64::from(v[i])).sum();
    dot.clamp(-1.0, 1.0).acos().to_degrees()
}

fn pct(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

#[test]
fn gpu_normals_equal_the_cpu_ones_at_level0_and_their_coarse_angle_is_recorded() {
    let hf = ridges();
    let (ds, b) = prepare(&desc(NormalSource::Gpu), &hf);
    let gpu = fly(NormalSource::Gpu, &ds, &b);
    let cpu = fly(NormalSource::Cpu, &ds, &b);
    assert_eq!(
        gpu.regions, cpu.regions,
        "the same flight places the levels alike"
    );
    let mut csv = String::from("level,texels,median_deg,p99_deg,max_deg\n");
    let mut all = Vec::new();
    let mut coarse = Vec::new();
    for (level, region) in gpu.regions.iter().enumerate() {
        let region = region.as_ref().expect("placed");
        let lr = LevelRegion::of_cache(region.origin, gpu.side);
        let mut angles = Vec::new();
        let mut level0_over = 0;
        for ty in 0..gpu.side {
            for tx in 0..gpu.side {
                let s = sample_at([tx, ty], region.origin, gpu.side);
                // Inside the region (its edge samples take one-sided differences on the GPU) and
                // inside the dataset's samples (beyond them both read clamped heights).
                let edge = (0..2).any(|a| s[a] == lr.lo[a] || s[a] == lr.hi[a]);
                let outside = (0..2).any(|a| s[a] < 0 || (s[a] << level) >= N as i64 - 1);
                if edge || outside {
                    continue;
                }
                let k = (ty * gpu.side + tx) as usize;
                let (g, c) = (gpu.layers[level][k], cpu.layers[level][k]);
                if level == 0 {
                    let d = (0..2)
                        .map(|a| (i32::from(g[a]) - i32::from(c[a])).abs())
                        .max();
                    if d.unwrap() > 2 {
                        level0_over += 1;
                    }
                }
                angles.push(angle_deg(g, c));
            }
        }
        assert!(
            angles.len() > 1000,
            "level {level}: {} texels",
            angles.len()
        );
        if level == 0 {
            assert_eq!(level0_over, 0, "level 0 texels over two snorm steps apart");
        }
        angles.sort_by(f64::total_cmp);
        let (m, p99, max) = (
            pct(&angles, 0.5),
            pct(&angles, 0.99),
            *angles.last().unwrap(),
        );
        eprintln!(
            "level {level}: {} texels, GPU vs full-resolution CPU normals {m:.2}° median, {p99:.2}° p99, {max:.2}° max",
            angles.len()
        );
        csv.push_str(&format!(
            "{level},{},{m:.3},{p99:.3},{max:.3}\n",
            angles.len()
        ));
        if level >= 1 {
            coarse.extend_from_slice(&angles);
        }
        all.extend(angles);
    }
    coarse.sort_by(f64::total_cmp);
    let (m, p99, max) = (
        pct(&coarse, 0.5),
        pct(&coarse, 0.99),
        *coarse.last().unwrap(),
    );
    eprintln!(
        "levels ≥ 1: {} texels, {m:.2}° median, {p99:.2}° p99, {max:.2}° max",
        coarse.len()
    );
    csv.push_str(&format!("1+,{},{m:.3},{p99:.3},{max:.3}\n", coarse.len()));
    let path = test_output_dir().join("gpu_normals_angles.csv");
    aerie_io::write_atomic(&path, csv.as_bytes()).unwrap();
    // Level 0: the same formula (within quantisation); coarse levels lose the gullies.
    assert!(m > 1.0, "coarse levels barely differ: {m}°");
}
