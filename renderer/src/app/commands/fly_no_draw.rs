//! `aerie fly --no-draw`: the frame thread of a flight without drawing and without a GPU — tile
//! selection, the source's streaming (requests, gathers), the clipmap strips and the pool
//! decisions, exactly as a drawing frame plans them — paced to the flight's clock (`--pace`)
//! so the page workers have the time a real frame rate gives them. Reports the process's RSS
//! over time (from /proc/self/status), late tile-frames (streaming apart), the longest time the
//! frame thread spent gathering terrain samples in one frame, and the cache hit rate:
//! `frames.csv` (one row per frame) and `summary.json`.

use std::time::{Duration, Instant};

use crate::app::commands::flight_files::{
    csv_row, frames_csv_header, median_p99_max, write_csv_and_summary,
};
use crate::app::commands::render::stream_json;
use crate::app::failure::{bad_input, Failure};
use crate::app::flight_plan::FlightPlan;
use crate::app::out_path::WriteFailures;
use crate::app::prepare::Terrain;
use crate::app::progress::count_bar;
use crate::app::renderer_setup::Setup;
use crate::render::cpu_clock::thread_cpu_us;
use crate::render::frame::FrameStats;
use crate::render::plan::{plan_frame, select_frame, FramePlan, LateReason, PlanState, TileMeshes};
use crate::tools::percentile::percentile;
use aerie_terrain::camera::Camera;
use aerie_terrain::select::{Selection, MAX_REFINEMENT};

/// Staging offsets are aligned to at most this on the devices we run on (the plan's budget
/// arithmetic needs one; without a device the largest is taken).
const ALIGNMENT: u64 = 256;
/// RSS is sampled every this many frames (and at the first and last).
const RSS_EVERY: u32 = 30;

/// The process's resident set, bytes (VmRSS of /proc/self/status); 0 where unavailable.
pub fn rss_bytes() -> u64 {
    let Ok(s) = std::fs::read_to_string("/proc/self/status") else {
        return 0;
    };
    s.lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        .map_or(0, |kb| kb * 1024)
}

/// The refined tiles drawn late over a flight, by reason and by refinement: what runs out.
#[derive(Default)]
struct LateTally {
    budget: u64,
    no_slot: u64,
    stream: u64,
    by_refinement: [u64; MAX_REFINEMENT as usize],
}

impl LateTally {
    fn add(&mut self, plan: &FramePlan) {
        for l in &plan.late {
            *match l.reason {
                LateReason::Budget => &mut self.budget,
                LateReason::NoSlot => &mut self.no_slot,
                LateReason::Stream => &mut self.stream,
            } += 1;
            if let Some(n) = self.by_refinement.get_mut(l.key.refinement as usize - 1) {
                *n += 1;
            }
        }
    }

    fn json(&self) -> serde_json::Value {
        serde_json::json!({
            "budget": self.budget,
            "no_slot": self.no_slot,
            "stream": self.stream,
            "by_refinement": self.by_refinement,
        })
    }
}

/// What `fly --no-draw` was asked.
pub struct NoDrawFlight<'a> {
    pub dem: &'a std::path::Path,
    pub out: &'a std::path::Path,
    pub frames: u32,
    pub fps: f64,
    pub pace: f64,
}

/// Flies `flight` over `terrain` planning every frame as the renderer would, drawing nothing.
pub fn fly_no_draw(
    a: &NoDrawFlight,
    s: &Setup,
    terrain: &Terrain,
    flight: &FlightPlan,
) -> Result<(), Failure> {
    if !(a.pace.is_finite() && a.pace >= 0.0) {
        return Err(bad_input(format!(
            "--pace: {} must be ≥ 0 (1 = the flight's own clock, 0 = as fast as possible)",
            a.pace
        )));
    }
    let desc = &s.desc;
    let clipmap = desc.clipmap(terrain.grid());
    clipmap
        .validate()
        .map_err(|e| bad_input(format!("{}: clipmap: {e}", a.dem.display())))?;
    let rss_start = rss_bytes();
    let mut st = PlanState::new(
        terrain.bake.clone(),
        terrain.source.clone(),
        clipmap,
        &desc.pool_capacity,
    );
    st.warm_start = desc.warm_start;
    let start_up = Instant::now();
    st.strips_around(flight.pose_at(0.0).0);
    let first_fill_s = start_up.elapsed().as_secs_f64();
    let indices = TileMeshes::indices(desc.tile_size).1;
    let (width, height) = (s.view.width, s.view.height);
    let mut sel = Selection::default();
    let mut csv = frames_csv_header();
    let mut rss = vec![(0.0, rss_start)];
    let mut cpu_us = Vec::with_capacity(a.frames as usize);
    let mut thread_us = Vec::with_capacity(a.frames as usize);
    let (mut late, mut late_stream, mut drawn) = (0u64, 0u64, 0u64);
    let (mut data_us, mut late_frames) = (0f64, 0u32);
    let mut last = FrameStats::default();
    let mut reasons = LateTally::default();
    // Strip pieces left for a later frame by the data cap, and the frames that left some.
    let (mut deferred, mut deferred_frames) = (0u64, 0u32);
    let bar = count_bar(a.frames as u64, "frames", "flying (no draw)");
    let clock = Instant::now();
    for f in 0..a.frames {
        let t = f as f64 / a.fps;
        if a.pace > 0.0 {
            // The frame's own time on the flight's clock (a real IG waits for its vsync).
            let due = Duration::from_secs_f64(t / a.pace);
            if let Some(wait) = due.checked_sub(clock.elapsed()) {
                std::thread::sleep(wait);
            }
        }
        let (pos, att) = flight.pose_at(t);
        let camera = Camera::new(pos, att, s.view.frustum);
        let inputs = desc.solo_frame_inputs(f as u64, &camera, (width, height), indices, ALIGNMENT);
        let t0 = Instant::now();
        let cpu0 = thread_cpu_us();
        let strips = select_frame(&mut st, &inputs, &mut sel);
        let t1 = Instant::now();
        let plan = plan_frame(&mut st, &inputs, &sel, strips)
            .map_err(|e| crate::app::failure::runtime(format!("frame {f}: {e}")))?;
        // No staging or recording here: the whole thread time is the plan's part.
        let thread = thread_cpu_us() - cpu0;
        let stats = FrameStats {
            cpu_select_us: (t1 - t0).as_secs_f64() * 1e6,
            cpu_upload_us: t1.elapsed().as_secs_f64() * 1e6,
            cpu_thread_us: thread,
            cpu_thread_plan_us: thread,
            ..plan.stats
        };
        cpu_us.push(t0.elapsed().as_secs_f64() * 1e6);
        thread_us.push(stats.cpu_thread_us);
        late += stats.tiles_late as u64;
        late_stream += stats.tiles_late_stream as u64;
        late_frames += (stats.tiles_late > 0) as u32;
        drawn += stats.tiles_drawn as u64;
        reasons.add(&plan);
        deferred += u64::from(st.feed.deferred);
        deferred_frames += (st.feed.deferred > 0) as u32;
        data_us = data_us.max(stats.cpu_terrain_data_us);
        csv.push_str(&csv_row(&stats, t, pos, att));
        last = stats;
        if f % RSS_EVERY == 0 || f + 1 == a.frames {
            rss.push((t, rss_bytes()));
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let wall_s = clock.elapsed().as_secs_f64();
    cpu_us.sort_by(f64::total_cmp);
    thread_us.sort_by(f64::total_cmp);
    let mb = |b: u64| b as f64 / (1 << 20) as f64;
    let rss_max = rss.iter().map(|r| r.1).max().unwrap_or(0);
    let rss_end = rss.last().map_or(0, |r| r.1);
    let hits = last.stream_hits;
    let lookups = hits + last.stream_misses;
    let hit_rate = if lookups > 0 {
        hits as f64 / lookups as f64
    } else {
        1.0
    };
    let late_pct = 100.0 * late as f64 / drawn.max(1) as f64;
    let distance_km = {
        let (p0, _) = flight.pose_at(0.0);
        let (p1, _) = flight.pose_at((a.frames.max(1) - 1) as f64 / a.fps);
        (p1 - p0).truncate().length() / 1e3
    };
    let summary = serde_json::json!({
        "dem": a.dem.display().to_string(),
        "mode": "no-draw",
        "frames": a.frames,
        "fps": a.fps,
        "pace": a.pace,
        "wall_s": wall_s,
        "distance_km": distance_km,
        "size": [width, height],
        "lod": desc.select.mode,
        "tau_px": desc.select.tau_px,
        "streamed": terrain.streamed.is_some(),
        "prepare_s": terrain.prepare_s,
        "first_fill_s": first_fill_s,
        "rss_mb": {
            "start": mb(rss_start),
            "max": mb(rss_max),
            "end": mb(rss_end),
            "series": rss.iter().map(|(t, b)| [*t, mb(*b)]).collect::<Vec<_>>(),
        },
        "tiles_drawn": drawn,
        "tiles_late": late,
        "tiles_late_stream": late_stream,
        "late_percent": late_pct,
        "late_frames": late_frames,
        "late_refined": reasons.json(),
        "data_cap_samples": st.feed.data_cap_samples,
        "strip_pieces_deferred": deferred,
        "frames_deferring": deferred_frames,
        "max_terrain_data_us": data_us,
        "frame_cpu_us": median_p99_max(&cpu_us),
        "frame_thread_cpu_us": median_p99_max(&thread_us),
        "cache_hit_rate": hit_rate,
        "stream": stream_json(&last),
        "cells_pending_at_end": last.cells_pending,
    });
    let mut failures = WriteFailures::default();
    let done = write_csv_and_summary(a.out, &csv, summary, &mut failures);
    println!(
        "{} frames, {:.1} km (no draw, pace {}) in {:.1} s: RSS {:.0}/{:.0}/{:.0} MiB (start/max/end); late {} of {} tile-frames ({:.3} %, {} streaming); longest terrain-data time {:.0} µs; frame CPU p99 {:.0} µs ({:.0} µs of the thread's clock); cache hit rate {:.4}",
        a.frames,
        distance_km,
        a.pace,
        wall_s,
        mb(rss_start),
        mb(rss_max),
        mb(rss_end),
        late,
        drawn,
        late_pct,
        late_stream,
        data_us,
        percentile(&cpu_us, 0.99),
        percentile(&thread_us, 0.99),
        hit_rate,
    );
    done
}
