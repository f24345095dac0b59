//! What a frame and a dataset upload did (DESIGN.md "Every stage reports what it did"), and the
//! CSV row every headless run writes per frame.

use aerie_terrain::select::{Selection, MAX_REFINEMENT};

/// Instance groups drawn: unrefined (r = 0) and r = 1..=MAX_REFINEMENT.
pub const RESOLUTIONS: usize = MAX_REFINEMENT as usize + 1;

/// What one frame did.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct FrameStats {
    pub frame: u64,
    pub finest_level: u32,
    pub tiles_considered: u32,
    pub tiles_culled: u32,
    /// Nodes in the frustum but hidden behind nearer terrain (horizon culling), not drawn.
    pub tiles_hidden: u32,
    /// Ring tiles drawn (considered − culled).
    pub tiles_drawn: u32,
    /// Drawn ring tiles per refinement r chosen by the bound (index r; 0 = unrefined).
    pub tiles_by_refinement: [u32; RESOLUTIONS],
    /// m×m instances drawn: one per unrefined tile, one per quadtree node of a refined tile.
    pub instances: u32,
    /// Tiles drawn coarser than the bound asked (or, outside the quadtree, not drawn) because
    /// their upload did not fit this frame or their samples were not resident yet.
    pub tiles_late: u32,
    /// The part of `tiles_late` due to streaming: samples not resident (a pool upload, or the
    /// level texture a finer tile is drawn from).
    pub tiles_late_stream: u32,
    /// Tiles whose bound could not be met within the refinement cap.
    pub tiles_unbounded: u32,
    pub triangles: u64,
    pub draw_calls: u32,
    pub bytes_clipmap: u64,
    pub bytes_refined: u64,
    /// Everything through the staging ring this frame (uniforms, instances, indirect included).
    pub bytes_uploaded: u64,
    /// Clipmap uploads that exceeded the frame's budget and were streamed in extra submissions.
    pub budget_spills: u32,
    pub pool_hits: u32,
    pub pool_misses: u32,
    pub prefetched: u32,
    /// Level-texture cells still waiting for their samples after this frame.
    pub cells_pending: u32,
    /// The source's totals after this frame (zero for a dataset in memory): `gather` and
    /// `is_resident` answers wholly resident or not, pages loaded and refused, decoded bytes
    /// resident now against the budget.
    pub stream_hits: u64,
    pub stream_misses: u64,
    pub stream_loaded: u64,
    pub stream_failed: u64,
    pub stream_resident_bytes: u64,
    pub stream_budget_bytes: u64,
    /// Time the frame thread spent gathering terrain samples from the source this frame.
    pub cpu_terrain_data_us: f64,
    /// A hash of the selection (nodes and refinements): equal for channels sharing one.
    #[serde(skip)]
    pub selection_digest: u64,
    pub cpu_select_us: f64,
    pub cpu_upload_us: f64,
    pub cpu_record_us: f64,
    pub gpu_upload_ms: f64,
    pub gpu_terrain_ms: f64,
    /// Normal maps: time the frame thread spent computing normal texels (`--normals cpu`;
    /// also in `cpu_terrain_data_us`), the bytes of normal texels staged (included in
    /// `bytes_clipmap`), and the GPU normal pass's milliseconds (`--normals gpu`).
    pub cpu_normals_us: f64,
    pub bytes_normals: u64,
    pub gpu_normals_ms: f64,
    /// Streamed imagery: cells copied this frame, and cells still wanted after it.
    pub imagery_cells: u32,
    pub imagery_cells_pending: u32,
    /// The frame thread's CPU time (its thread clock, `render/cpu_clock.rs`) over what
    /// `cpu_select_us` + `cpu_upload_us` + `cpu_record_us` span — selection, plan, staging,
    /// recording, submission — without waits (a frame's fence) and without the time other
    /// threads (a software rasteriser on shared cores) took from it: the whole CPU frame.
    pub cpu_thread_us: f64,
    /// Its part up to the end of the plan (selection and plan, what `fly --no-draw`
    /// measures); the rest is staging, recording and submission.
    pub cpu_thread_plan_us: f64,
}

impl FrameStats {
    pub const CSV_HEADER: &'static str = "frame,finest_level,tiles_considered,tiles_culled,tiles_drawn,refined_r0,refined_r1,refined_r2,refined_r3,refined_r4,refined_r5,refined_r6,instances,tiles_late,tiles_late_stream,tiles_unbounded,triangles,draw_calls,bytes_clipmap,bytes_refined,bytes_uploaded,budget_spills,pool_hits,pool_misses,prefetched,cells_pending,stream_hits,stream_misses,stream_loaded,stream_failed,stream_resident_bytes,stream_budget_bytes,cpu_terrain_data_us,cpu_select_us,cpu_upload_us,cpu_record_us,gpu_upload_ms,gpu_terrain_ms,tiles_hidden,cpu_normals_us,bytes_normals,gpu_normals_ms,imagery_cells,imagery_cells_pending,cpu_thread_us,cpu_thread_plan_us";

    /// Copies the source's running totals.
    pub fn set_stream(&mut self, s: &aerie_terrain::source::StreamStats) {
        self.stream_hits = s.hits;
        self.stream_misses = s.misses;
        self.stream_loaded = s.loaded;
        self.stream_failed = s.failed;
        self.stream_resident_bytes = s.resident_bytes;
        self.stream_budget_bytes = s.budget_bytes;
    }

    pub fn csv_row(&self) -> String {
        let r = &self.tiles_by_refinement;
        format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.1},{:.1},{:.1},{:.1},{:.3},{:.3},{},{:.1},{},{:.4},{},{},{:.1},{:.1}",
            self.frame,
            self.finest_level,
            self.tiles_considered,
            self.tiles_culled,
            self.tiles_drawn,
            r[0],
            r[1],
            r[2],
            r[3],
            r[4],
            r[5],
            r[6],
            self.instances,
            self.tiles_late,
            self.tiles_late_stream,
            self.tiles_unbounded,
            self.triangles,
            self.draw_calls,
            self.bytes_clipmap,
            self.bytes_refined,
            self.bytes_uploaded,
            self.budget_spills,
            self.pool_hits,
            self.pool_misses,
            self.prefetched,
            self.cells_pending,
            self.stream_hits,
            self.stream_misses,
            self.stream_loaded,
            self.stream_failed,
            self.stream_resident_bytes,
            self.stream_budget_bytes,
            self.cpu_terrain_data_us,
            self.cpu_select_us,
            self.cpu_upload_us,
            self.cpu_record_us,
            self.gpu_upload_ms,
            self.gpu_terrain_ms,
            self.tiles_hidden,
            self.cpu_normals_us,
            self.bytes_normals,
            self.gpu_normals_ms,
            self.imagery_cells,
            self.imagery_cells_pending,
            self.cpu_thread_us,
            self.cpu_thread_plan_us
        )
    }
}

/// What loading a dataset onto the GPU did.
#[derive(Debug, Clone, Copy, Default)]
pub struct UploadStats {
    pub bytes: u64,
    /// Submissions the upload was split into (by the per-frame staging budget).
    pub submissions: u32,
    pub levels: u32,
}

/// A frame's statistics as far as its selection tells them.
pub fn selection_stats(frame: u64, sel: &Selection) -> FrameStats {
    let mut stats = FrameStats {
        frame,
        selection_digest: selection_digest(sel),
        finest_level: sel.finest_level,
        tiles_unbounded: sel.unbounded,
        tiles_hidden: sel.hidden,
        tiles_late: sel.stream_late,
        tiles_late_stream: sel.stream_late,
        ..Default::default()
    };
    for l in &sel.levels {
        stats.tiles_considered += l.considered;
        stats.tiles_culled += l.culled;
        stats.tiles_drawn += l.drawn;
        for (sum, n) in stats.tiles_by_refinement.iter_mut().zip(l.refined) {
            *sum += n;
        }
    }
    stats
}

/// A digest of every selected node, in order: channels drawn from one shared selection report
/// the same; `bench` replays compare it. Each node's values are mixed on their own (the CPU
/// overlaps the nodes) and then folded in order with one multiply: FNV-1a over every value, one
/// dependent multiply after another, was 12 µs of a 1,400-node frame.
pub fn selection_digest(sel: &Selection) -> u64 {
    let mix = |mut x: u64| {
        // splitmix64's finaliser.
        x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        x ^ (x >> 31)
    };
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for i in &sel.items {
        let place = i.tx as u64 | (i.ty as u64) << 32;
        let node = i.node_tx as u64 | (i.node_ty as u64) << 32;
        let levels = i.level as u64 | (i.refinement as u64) << 21 | (i.node_level as u64) << 42;
        let x = mix(place)
            ^ mix(node ^ 0x9e37_79b9_7f4a_7c15).rotate_left(21)
            ^ mix(levels).rotate_left(42);
        h = (h ^ x).wrapping_mul(0x0100_0000_01b3).rotate_left(29);
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_row_has_one_field_per_header_column_in_order() {
        let s = FrameStats {
            frame: 7,
            tiles_by_refinement: [1, 2, 3, 4, 5, 6, 8],
            gpu_terrain_ms: 1.5,
            ..Default::default()
        };
        let header: Vec<&str> = FrameStats::CSV_HEADER.split(',').collect();
        let row = s.csv_row();
        let fields: Vec<&str> = row.split(',').collect();
        assert_eq!(header.len(), fields.len());
        let at = |name: &str| fields[header.iter().position(|h| *h == name).unwrap()];
        assert_eq!(at("frame"), "7");
        assert_eq!(at("refined_r0"), "1");
        assert_eq!(at("refined_r6"), "8");
        assert_eq!(at("gpu_terrain_ms"), "1.500");
        let s = FrameStats {
            tiles_late_stream: 3,
            stream_budget_bytes: 1 << 30,
            cpu_terrain_data_us: 12.25,
            ..Default::default()
        };
        let row = s.csv_row();
        let fields: Vec<&str> = row.split(',').collect();
        let at = |name: &str| fields[header.iter().position(|h| *h == name).unwrap()];
        assert_eq!(at("tiles_late_stream"), "3");
        assert_eq!(at("stream_budget_bytes"), "1073741824");
        assert_eq!(at("cpu_terrain_data_us"), "12.2");
        let s = FrameStats {
            cpu_normals_us: 3.25,
            bytes_normals: 512,
            gpu_normals_ms: 0.0625,
            cpu_thread_us: 431.25,
            cpu_thread_plan_us: 250.5,
            ..Default::default()
        };
        let row = s.csv_row();
        let fields: Vec<&str> = row.split(',').collect();
        let at = |name: &str| fields[header.iter().position(|h| *h == name).unwrap()];
        assert_eq!(at("cpu_normals_us"), "3.2");
        assert_eq!(at("bytes_normals"), "512");
        assert_eq!(at("gpu_normals_ms"), "0.0625");
        assert_eq!(at("cpu_thread_us"), "431.2");
        assert_eq!(at("cpu_thread_plan_us"), "250.5");
    }
}
