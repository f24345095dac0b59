//! How fast the terrain queries answer: height of terrain (HOT) per 0.2 ms and 10 km lines of
//! sight per 1 ms, the host-query budgets of issue 12, on a DEM and on a generated grid.
//!
//! ```text
//! cargo run --release -p aerie-terrain --example query_timing -- [DEM] [--gen N] [--count N]
//! ```
//! `DEM` defaults to the embedded `assets/dem/N47E011.hgt.zip`; `--gen N` also times a
//! generated N² ridged grid (default 16385, 0 to skip; it needs ≈ 1.2 GB of memory); `--count`
//! is the number of queries per kind (default 20000). The bake is made in memory: nothing is
//! written next to the DEM.

use std::hint::black_box;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use aerie_terrain::bake::{bake, BakeParams};
use aerie_terrain::dataset::{load_dataset, Dataset};
use aerie_terrain::gen::{generate, DemKind, GenParams};
use aerie_terrain::query::{
    first_hit, height_of_terrain, InMemorySource, Lookup, Ray, SurfaceSource,
};
use glam::DVec3;

struct Args {
    dem: PathBuf,
    gen: usize,
    count: usize,
}

fn args() -> Result<Args, String> {
    let mut a = Args {
        dem: PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../assets/dem/N47E011.hgt.zip"),
        gen: 16385,
        count: 20_000,
    };
    let mut it = std::env::args().skip(1);
    while let Some(s) = it.next() {
        let mut num = |name: &str| -> Result<usize, String> {
            let v = it.next().ok_or(format!("{name} needs a number"))?;
            v.parse()
                .map_err(|_| format!("{name} {v:?} is not a number"))
        };
        match s.as_str() {
            "--gen" => a.gen = num("--gen")?,
            "--count" => a.count = num("--count")?.max(100),
            _ if s.starts_with("--") => return Err(format!("unknown option {s}")),
            _ => a.dem = PathBuf::from(s),
        }
    }
    Ok(a)
}

fn main() {
    let a = match args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("query_timing: {e}");
            std::process::exit(2);
        }
    };
    let ds = match load_dataset(&a.dem) {
        Ok(ds) => ds,
        Err(e) => {
            eprintln!("query_timing: {e}");
            std::process::exit(2);
        }
    };
    run(&a.dem.display().to_string(), ds, a.count);
    if a.gen > 0 {
        let t = Instant::now();
        let hf = generate(&GenParams {
            size: a.gen,
            spacing: 10.0,
            kind: DemKind::Ridged,
            seed: 2026,
        });
        println!(
            "generated {}² ridged in {:.1} s",
            a.gen,
            t.elapsed().as_secs_f64()
        );
        let name = format!("generated ridged {}², 10 m", a.gen);
        run(&name, Dataset::from_heightfield(hf, name.clone()), a.count);
    }
}

/// A small deterministic generator (xorshift64*).
struct Rng(u64);

impl Rng {
    fn unit(&mut self) -> f64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        (x.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

fn run(name: &str, ds: Dataset, count: usize) {
    println!("\n== {name}: {}", ds.summary());
    if let Ok(load) = std::fs::read_to_string("/proc/loadavg") {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        println!(
            "machine: {cores} cores, load average {}",
            load.split_whitespace()
                .take(3)
                .collect::<Vec<_>>()
                .join(" ")
        );
    }
    let t = Instant::now();
    let b = bake(&ds, BakeParams::default(), &|_, _| {});
    println!(
        "bake (m = 17, {} levels) in {:.2} s",
        b.levels.len(),
        t.elapsed().as_secs_f64()
    );
    let samples = ds.hf.heights.len();
    let t = Instant::now();
    let src = match InMemorySource::new(Arc::new(ds), Arc::new(b)) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("query_timing: {e}");
            std::process::exit(2);
        }
    };
    println!(
        "fine hierarchy: {} bytes ({:.3} byte/sample, {:.1} % of the f32 heights), built in {:.2} s",
        src.fine_bytes(),
        src.fine_bytes() as f64 / samples as f64,
        100.0 * src.fine_bytes() as f64 / (4 * samples) as f64,
        t.elapsed().as_secs_f64()
    );
    let (east, north) = src.grid().real_extent_m();
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let hot = |x: f64, y: f64| height_of_terrain(&src, x, y).ready().map(|g| g.height_m);

    // HOT at random points, timed in batches of 100 (one frame's worth at the target).
    let pts: Vec<(f64, f64)> = (0..count)
        .map(|_| (rng.range(0.0, east), rng.range(0.0, north)))
        .collect();
    let mut batches = Vec::new();
    let mut sink = 0.0;
    for chunk in pts.chunks(100) {
        let t = Instant::now();
        for &(x, y) in chunk {
            sink += hot(x, y).unwrap_or(0.0);
        }
        batches.push(t.elapsed().as_secs_f64() / chunk.len() as f64);
    }
    black_box(sink);
    report("HOT", &batches, 0.2e-3);

    // 10 km lines of sight, three kinds.
    let margin = 10_000.0;
    if east < 2.0 * margin || north < 2.0 * margin {
        println!("(the data is under 20 km across: lines of sight shortened to fit)");
    }
    let len = 10_000f64.min(0.45 * east.min(north));
    let eye = |rng: &mut Rng| -> (f64, f64, f64) {
        let (x, y) = (rng.range(0.0, east), rng.range(0.0, north));
        (x, y, hot(x, y).unwrap_or(0.0))
    };
    let mut kinds: Vec<(&str, Vec<Ray>)> = vec![
        (
            "LOS ground to ground (eye 2–300 m, target 0–30 m AGL)",
            Vec::new(),
        ),
        ("LOS level at 100–1000 m AGL", Vec::new()),
        ("LOS looking down 1–10° from 300–3000 m AGL", Vec::new()),
    ];
    while kinds[0].1.len() < count {
        let (x, y, h) = eye(&mut rng);
        let az = rng.range(0.0, std::f64::consts::TAU);
        let (tx, ty) = (x + len * az.cos(), y + len * az.sin());
        if !(0.0..=east).contains(&tx) || !(0.0..=north).contains(&ty) {
            continue;
        }
        let from = DVec3::new(x, y, h + rng.range(2.0, 300.0));
        let to = DVec3::new(tx, ty, hot(tx, ty).unwrap_or(0.0) + rng.range(0.0, 30.0));
        kinds[0].1.push(Ray::segment(from, to).expect("finite"));
    }
    for (k, (_, rays)) in kinds.iter_mut().enumerate().skip(1) {
        for _ in 0..count {
            let (x, y, h) = eye(&mut rng);
            let az = rng.range(0.0, std::f64::consts::TAU);
            let (agl, el) = if k == 1 {
                (rng.range(100.0, 1000.0), 0.0f64)
            } else {
                (rng.range(300.0, 3000.0), -rng.range(1.0, 10.0).to_radians())
            };
            let d = DVec3::new(az.cos() * el.cos(), az.sin() * el.cos(), el.sin());
            rays.push(Ray::new(DVec3::new(x, y, h + agl), d, 0.0, len).expect("finite"));
        }
    }
    for (label, rays) in &kinds {
        let mut batches = Vec::new();
        let mut each = Vec::with_capacity(rays.len());
        let (mut hits, mut clear) = (0usize, 0usize);
        for chunk in rays.chunks(100) {
            let t = Instant::now();
            for r in chunk {
                let q = Instant::now();
                match first_hit(&src, r) {
                    Lookup::Ready(Some(h)) => {
                        hits += 1;
                        black_box(h);
                    }
                    Lookup::Ready(None) => clear += 1,
                    other => {
                        black_box(other);
                    }
                }
                each.push(q.elapsed().as_secs_f64());
            }
            batches.push(t.elapsed().as_secs_f64() / chunk.len() as f64);
        }
        report(label, &batches, 1e-3);
        each.sort_by(f64::total_cmp);
        println!(
            "    {:.0} m: {hits} hit, {clear} clear; per query median {:.2} µs, p99 {:.2} µs, max {:.2} µs",
            len,
            each[each.len() / 2] * 1e6,
            each[each.len() * 99 / 100] * 1e6,
            each[each.len() - 1] * 1e6
        );
    }
}

/// One line: time per query and how many fit the budget, from the median batch of 100 (the
/// steady rate), the mean, and the slowest batch (which, on a shared machine, is mostly the
/// scheduler taking the core away).
fn report(label: &str, per_query_by_batch: &[f64], budget_s: f64) {
    let mut b = per_query_by_batch.to_vec();
    b.sort_by(f64::total_cmp);
    let median = b[b.len() / 2];
    let mean = b.iter().sum::<f64>() / b.len() as f64;
    let worst = b[b.len() - 1];
    let fit = |t: f64| budget_s / t;
    println!(
        "{label}: {:.0} per {} ms ({:.3} µs per query, median batch of 100); mean {:.3} µs → {:.0}; slowest batch {:.0}",
        fit(median),
        budget_s * 1e3,
        median * 1e6,
        mean * 1e6,
        fit(mean),
        fit(worst),
    );
}
