//! The calling thread's CPU time: what the frame thread's own work cost, without the time
//! other threads took from it. On two shared cores lavapipe's rasteriser threads run while the
//! frame thread plans the next frame, and a wall clock there measures them as much as aerie.

/// CPU time the calling thread has used, in microseconds (`CLOCK_THREAD_CPUTIME_ID`); 0 where
/// the clock cannot be read (a difference of two readings is then 0, never negative).
pub fn thread_cpu_us() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // clock_gettime only writes `t`; an error leaves it zero and is reported as 0.
    // SAFETY: `t` is a valid, writable timespec that outlives the call, and the clock id exists.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    if rc != 0 {
        return 0.0;
    }
    t.tv_sec as f64 * 1e6 + t.tv_nsec as f64 * 1e-3
}

#[cfg(test)]
mod tests {
    use super::thread_cpu_us;

    /// The clock counts this thread's work and not a sleep (which uses no CPU).
    #[test]
    fn the_thread_clock_counts_work_not_sleep() {
        let t0 = thread_cpu_us();
        std::thread::sleep(std::time::Duration::from_millis(30));
        let slept = thread_cpu_us() - t0;
        let t1 = thread_cpu_us();
        let mut x = 0u64;
        let start = std::time::Instant::now();
        while start.elapsed() < std::time::Duration::from_millis(30) {
            x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
        }
        let worked = thread_cpu_us() - t1;
        assert!(t0 > 0.0, "the clock is read");
        assert!(slept < 10_000.0, "30 ms asleep counted {slept} µs");
        assert!(worked > 1_000.0, "30 ms of work counted {worked} µs");
    }
}
