//! Nearest-rank percentiles of sorted samples, the one definition every summary uses
//! (`render`/`fly` summaries, `run` frame times, channel flights).

/// The sample at rank `round((n − 1)·p)` of `sorted` (ascending), `p` in [0, 1]; 0 when empty.
pub fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let k = ((sorted.len() - 1) as f64 * p.clamp(0.0, 1.0)).round() as usize;
    sorted[k]
}

#[cfg(test)]
mod tests {
    use super::percentile;

    #[test]
    fn nearest_rank_of_sorted_samples() {
        let v: Vec<f64> = (0..=100).map(f64::from).collect();
        assert_eq!(percentile(&v, 0.0), 0.0);
        assert_eq!(percentile(&v, 0.5), 50.0);
        assert_eq!(percentile(&v, 0.99), 99.0);
        assert_eq!(percentile(&v, 1.0), 100.0);
        assert_eq!(percentile(&[1.0, 2.0], 0.5), 2.0, "rank 0.5 rounds up");
        assert_eq!(percentile(&[], 0.5), 0.0);
        assert_eq!(percentile(&[3.0], 2.0), 3.0, "p is clamped to [0, 1]");
    }
}
