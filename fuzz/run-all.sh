#!/usr/bin/env bash
# Runs every fuzz target of both cargo-fuzz projects for FUZZ_RUNS inputs each on the stable
# toolchain (RUSTC_BOOTSTRAP=1 lets cargo-fuzz pass its -Z flags), then minimises each corpus
# in place (`cargo fuzz cmin`) so the checked-in corpora stay small; `cargo test` replays them.
#
#   FUZZ_RUNS=10000000 FUZZ_TARGETS="native cigi" FUZZ_SANITIZER=address fuzz/run-all.sh
#
# FUZZ_SANITIZER defaults to none: the parsers are safe Rust, and without ASan libFuzzer runs
# several times as many inputs per second. A crash stops the script (exit 1) with the input
# saved under <project>/artifacts/<target>/. Logs (with libFuzzer's final cov:/ft: figures) go
# to FUZZ_LOG_DIR.
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${FUZZ_RUNS:-10000000}
SAN=${FUZZ_SANITIZER:-none}
LOGS=${FUZZ_LOG_DIR:-target/fuzz-logs}
export RUSTC_BOOTSTRAP=1
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked
mkdir -p "$LOGS"
LOGS=$(cd "$LOGS" && pwd)
# project folder : targets, fastest first
PROJECTS=(
  "sim-bridge/fuzz:native xplane fgfs cigi shm recording auto"
  "fuzz:config bake store dem"
)
for entry in "${PROJECTS[@]}"; do
  dir=${entry%%:*}
  for t in ${entry#*:}; do
    if [ -n "${FUZZ_TARGETS:-}" ] && [[ " $FUZZ_TARGETS " != *" $t "* ]]; then continue; fi
    echo "== $dir $t: $RUNS runs"
    mkdir -p "$dir/corpus/$t"
    start=$(date +%s)
    (cd "$dir" && cargo fuzz run -s "$SAN" "$t" "corpus/$t" -- \
        -runs="$RUNS" -print_final_stats=1 -max_len=4096 >"$LOGS/$t.log" 2>&1) || {
      tail -40 "$LOGS/$t.log"; echo "fuzz: $t failed (log $LOGS/$t.log)"; exit 1; }
    end=$(date +%s)
    # cmin drops inputs whose coverage others repeat; the named seeds and regression inputs
    # stay (the replay tests rely on them).
    keep=$(mktemp -d)
    find "$dir/corpus/$t" -maxdepth 1 -type f \( -name 'seed_*' -o -name 'regression_*' \) \
        -exec cp {} "$keep/" \;
    (cd "$dir" && cargo fuzz cmin -s "$SAN" "$t" "corpus/$t" -- -max_len=4096 \
        >"$LOGS/$t.cmin.log" 2>&1)
    cp "$keep"/* "$dir/corpus/$t/" 2>/dev/null || true
    rm -rf "$keep"
    files=$(find "$dir/corpus/$t" -type f | wc -l)
    bytes=$(du -sb "$dir/corpus/$t" | cut -f1)
    last=$(grep -E '^#[0-9]+' "$LOGS/$t.log" | tail -1 || true)
    echo "$t: $((end - start)) s; corpus $files files, $bytes bytes; last: $last"
    grep -E 'stat::number_of_executed_units|Done [0-9]+ runs' "$LOGS/$t.log" || true
  done
done
