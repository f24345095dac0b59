use aerie::terrain::clipmap::place_levels;
use aerie::terrain::select::{select_tiles, SelectParams, Selection};
use aerie_bench::{selection_size, thread_cpu_us, TargetScene};
fn main() {
    let size = selection_size();
    let scene = TargetScene::new(size, false);
    let cams = scene.flight_agl(600, 1280, 720, 300.0);
    for carry in [false, true, false, true] {
        let params = SelectParams {
            carry,
            ..SelectParams::default()
        };
        let mut sel = Selection::default();
        let mut times = vec![];
        let (mut carried, mut total, mut items) = (0u64, 0u64, 0usize);
        for cam in &cams {
            let placements = place_levels(&scene.clip, scene.viewer(cam));
            let t = thread_cpu_us();
            select_tiles(
                &scene.bake,
                &scene.clip,
                &placements,
                cam,
                (1280, 720),
                &params,
                &mut sel,
            );
            times.push(thread_cpu_us() - t);
            carried += sel.carry.stats.carried_nodes as u64;
            total += sel.items.len() as u64;
            items = sel.items.len();
        }
        times.sort_by(f64::total_cmp);
        eprintln!("carry {carry}: median {:.1} p99 {:.1} max {:.1}; carried {:.1} % of nodes; last items {items}",
            times[times.len() / 2], times[times.len() * 99 / 100], times[times.len()-1], 100.0 * carried as f64 / total as f64);
    }
}
