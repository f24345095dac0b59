//! Shared set-up of aerie's criterion micro-benchmarks (`benches/`): generated datasets and
//! their bakes, and a flight of cameras over them. Run with `make bench` (or
//! `cargo bench -p aerie-bench`); `AERIE_BENCH_SIZE` overrides the selection dataset's side.
