# Two commands: `make demo` renders a scripted flight over the embedded Inn valley DEM,
# `make test` passes every check. Both install missing system packages first (Debian).
SHELL := /bin/bash
DEMO_OUT ?= out/demo
DEM ?= assets/dem/N47E011.hgt.zip
# Where cargo puts the binaries: CARGO_TARGET_DIR when set (shared build folders), else target/.
TARGET_DIR := $(or $(CARGO_TARGET_DIR),target)
AERIE := $(TARGET_DIR)/debug/aerie
AERIE_RELEASE := $(TARGET_DIR)/release/aerie

.PHONY: setup demo test lint fmt bench bench-run ccl

setup:
	@scripts/setup-debian.sh

# Every command creates the folders it writes into (out/ does not exist in a fresh clone).
demo: setup
	cargo build -p aerie
	$(AERIE) render --dem $(DEM) \
	    --camera 30500,12000,4500,0,-15,0 --size 1280x720 --out $(DEMO_OUT)-still.png
	$(AERIE) render --dem $(DEM) --look plain \
	    --camera 30500,12000,4500,0,-15,0 --size 1280x720 --out $(DEMO_OUT)-plain.png
	$(AERIE) render --dem $(DEM) --sun 290,4 \
	    --camera 30500,12000,4500,300,-5,0 --size 1280x720 --out $(DEMO_OUT)-sunset.png
	$(AERIE) render --dem $(DEM) --debug-tiles \
	    --camera 30500,12000,4500,0,-15,0 --size 1280x720 --out $(DEMO_OUT)-tiles.png
	$(AERIE) fly --dem $(DEM) \
	    --frames 24 --every 4 --size 640x360 --out $(DEMO_OUT) --overwrite
	@echo "demo: $(DEMO_OUT)-still.png (the full look), $(DEMO_OUT)-plain.png (the plain look), $(DEMO_OUT)-sunset.png, $(DEMO_OUT)-tiles.png, $(DEMO_OUT)/frame_*.png, $(DEMO_OUT)/frames.csv, $(DEMO_OUT)/summary.json"

# `make test` is CI's second command (after `make demo`): formatting, then every test. Clippy is
# `make lint` (a second full compilation would double the CI time on 2 cores); run it before
# committing.
lint:
	cargo fmt --all -- --check
	cargo clippy --workspace --all-targets -- -D warnings

# The CIGI Class Library (../shared/tools/cigi-ccl, or AERIE_CIGI_CCL) and the test host written
# with it (tests/cigi-host/), for this machine and as a big-endian s390x host run under qemu:
# built once per source hash into target/cigi-ccl/ (about 3 minutes on 2 cores, then a second).
# tests/tests/cigi_host.rs builds it on demand too; `make test` builds it first so the time
# shows here and not inside a test.
ccl: setup
	tests/cigi-host/build.sh native >/dev/null
	tests/cigi-host/build.sh s390x >/dev/null

# aerie-bench (criterion) is left out: compiling criterion is not worth CI's 2-core budget.
test: setup ccl
	cargo fmt --all -- --check
	cargo test --workspace --exclude aerie-bench

fmt:
	cargo fmt --all

# criterion micro-benchmarks (tile selection on a generated 16385² dataset — AERIE_BENCH_SIZE
# overrides —, bake throughput, staging-ring cursor, gather); reports in target/criterion/.
bench: setup
	cargo bench -p aerie-bench

# Time against image-space error, every LOD mode on the same frames (README "Benchmark").
BENCH_OUT ?= out/bench
bench-run: setup
	cargo build --release -p aerie
	$(AERIE_RELEASE) bench --dem $(DEM) --out $(BENCH_OUT) --overwrite \
	    --size 1280x720 --frames 60 --modes bounded,clipmap,distance,full --tau 0.5,1,2,5

# Every fuzz target (sim-bridge/fuzz: the pose decoders; fuzz/: DEM, bake and config parsers)
# for FUZZ_RUNS inputs each on the stable toolchain (RUSTC_BOOTSTRAP=1; cargo-fuzz is installed
# when missing), then each corpus minimised in place; commit the corpora, `cargo test` replays
# them. FUZZ_TARGETS="native dem" runs some; FUZZ_SANITIZER=address adds ASan (slower).
FUZZ_RUNS ?= 10000000
FUZZ_SANITIZER ?= none
.PHONY: fuzz
fuzz:
	FUZZ_RUNS=$(FUZZ_RUNS) FUZZ_SANITIZER=$(FUZZ_SANITIZER) FUZZ_TARGETS="$(FUZZ_TARGETS)" \
	    RUSTC_BOOTSTRAP=1 fuzz/run-all.sh
