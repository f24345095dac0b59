#!/usr/bin/env bash
# The whole CPU frame of each flight, on the frame thread's own clock (FrameStats cpu_thread_us):
# selection + plan from `fly --no-draw` (RUNS fresh runs, each frame's least: the runs do the
# same work, so the least is that work with less of the machine's noise), staging + recording +
# submission from DRAWN_RUNS drawn `fly` runs (each frame's least likewise; on lavapipe, whose
# rasteriser shares the cores, an upper bound), summed frame by frame over the same poses. The first SKIP frames (start-up: empty
# caches, the first uploads) are left out of the percentiles and reported apart.
#
#   scripts/cpu-frame.sh AERIE FLIGHTS OUT NAME=DEM [NAME=DEM ...]
#
# AERIE: the aerie binary (a release build); FLIGHTS: a folder of waypoint files
# NAME-<flight>.csv (a suite's flights/ folder); OUT: the output folder; NAME=DEM: a dataset
# name and its elevation model (with a raw grid's `<dem>.json` sidecar), copied to a temporary
# folder first (its bake is written there).
# Environment: SIZE (1280x720), TAU (1), FRAMES (122), FPS (30), RUNS (3), DRAWN_RUNS (1),
# SKIP (2).
# Writes OUT/cpu_frame.csv and OUT/cpu_frame.md; prints a line per flight and a summary.
set -uo pipefail
if [ $# -lt 4 ]; then
  sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'
  exit 2
fi
aerie=$1 flights=$2 out=$3
shift 3
size=${SIZE:-1280x720} tau=${TAU:-1} frames=${FRAMES:-122} fps=${FPS:-30} runs=${RUNS:-3}
drawn_runs=${DRAWN_RUNS:-1}
skip=${SKIP:-2}
if [ ! -x "$aerie" ]; then echo "cpu-frame: $aerie: not an executable" >&2; exit 2; fi
if [ ! -d "$flights" ]; then echo "cpu-frame: $flights: no such folder" >&2; exit 2; fi
for n in "$frames" "$runs" "$drawn_runs" "$skip"; do
  case $n in '' | *[!0-9]*) echo "cpu-frame: '$n' is not a whole number" >&2; exit 2 ;; esac
done
if [ "$runs" -lt 1 ] || [ "$drawn_runs" -lt 1 ]; then echo "cpu-frame: RUNS and DRAWN_RUNS must be at least 1" >&2; exit 2; fi
if [ "$skip" -ge "$frames" ]; then echo "cpu-frame: SKIP $skip leaves no frame of $frames" >&2; exit 2; fi
command -v python3 > /dev/null || { echo "cpu-frame: python3 is needed for the percentiles" >&2; exit 2; }
mkdir -p "$out/runs" || exit 1
data=$(mktemp -d) || exit 1
trap 'rm -rf "$data"' EXIT
csv="$out/cpu_frame.csv"
echo "flight,frames,select_plan_median_us,select_plan_p99_us,stage_record_submit_median_us,stage_record_submit_p99_us,whole_median_us,whole_p99_us,whole_max_us,startup_max_us,triangles_median,instances_median" > "$csv"
for pair in "$@"; do
  name=${pair%%=*} dem=${pair#*=}
  if [ "$name" = "$pair" ] || [ -z "$name" ] || [ ! -e "$dem" ]; then
    echo "cpu-frame: '$pair' is not NAME=DEM with an existing DEM" >&2; exit 2
  fi
  mkdir -p "$data/$name" && cp -r "$dem" "$data/$name/" || exit 1
  # A raw grid's sidecar (`aerie gen-dem` writes `<dem>.json`) goes with it.
  if [ -f "$dem.json" ]; then cp "$dem.json" "$data/$name/" || exit 1; fi
  local_dem="$data/$name/$(basename "$dem")"
  found=0
  for path in "$flights/$name"-*.csv; do
    [ -e "$path" ] || continue
    found=1
    flight=$(basename "$path" .csv)
    o="$out/runs/$flight"
    rm -rf "$o"-*
    common=(--dem "$local_dem" --path "$path" --size "$size" --tau "$tau" --frames "$frames" --fps "$fps")
    ok=1
    for r in $(seq 1 "$runs"); do
      "$aerie" fly --no-draw --pace 0 "${common[@]}" --out "$o-nodraw$r" > "$o-nodraw$r.log" 2>&1 || ok=0
    done
    for r in $(seq 1 "$drawn_runs"); do
      "$aerie" fly "${common[@]}" --every 100000 --out "$o-drawn$r" > "$o-drawn$r.log" 2>&1 || ok=0
    done
    if [ $ok = 0 ]; then
      echo "cpu-frame: $flight: a run failed (logs in $out/runs/)" >&2
      continue
    fi
    python3 - "$flight" "$o" "$runs" "$skip" "$drawn_runs" >> "$csv" << 'PY'
import csv, sys
flight, o, runs, skip = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
drawn_runs = int(sys.argv[5])
def rows(d):
    return list(csv.DictReader(open(d + "/frames.csv")))
nodraw = [rows(f"{o}-nodraw{r}") for r in range(1, runs + 1)]
drawns = [rows(f"{o}-drawn{r}") for r in range(1, drawn_runs + 1)]
drawn = drawns[0]
n = min(*(len(r) for r in drawns), *(len(r) for r in nodraw))
plan = [min(float(r[i]["cpu_thread_plan_us"]) for r in nodraw) for i in range(n)]
after = [min(float(d[i]["cpu_thread_us"]) - float(d[i]["cpu_thread_plan_us"]) for d in drawns)
         for i in range(n)]
whole = [a + b for a, b in zip(plan, after)]
def q(v, p):
    v = sorted(v[skip:])
    return v[round(p * (len(v) - 1))]
tri = [float(r["triangles"]) for r in drawn[skip:n]]
inst = [float(r["instances"]) for r in drawn[skip:n]]
print(f"{flight},{n - skip},{q(plan, .5):.0f},{q(plan, .99):.0f},{q(after, .5):.0f},"
      f"{q(after, .99):.0f},{q(whole, .5):.0f},{q(whole, .99):.0f},{max(whole[skip:]):.0f},"
      f"{max(whole[:skip]):.0f},{q(tri, .5):.0f},{q(inst, .5):.0f}")
PY
    tail -1 "$csv" | awk -F, '{ printf "%-28s select+plan %5s / %5s µs, staging+recording+submission %4s / %4s µs, whole %5s / %5s µs (median / p99)\n", $1, $3, $4, $5, $6, $7, $8 }'
  done
  [ $found = 1 ] || echo "cpu-frame: no $flights/$name-*.csv" >&2
done
python3 - "$csv" "$out/cpu_frame.md" "$size" "$tau" "$fps" "$skip" << 'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
size, tau, fps, skip = sys.argv[3:7]
lines = [f"# The whole CPU frame, {size}, τ = {tau} px, {fps} fps (frame thread's clock; first {skip} frames apart)", "",
         "| flight | frames | selection + plan median / p99 µs | staging + recording + submission median / p99 µs | whole median / p99 / max µs | start-up frames max µs | triangles | instances |",
         "|---|---|---|---|---|---|---|---|"]
for r in rows:
    ok = "✓" if float(r["whole_p99_us"]) <= 500 else "✗"
    lines.append(f"| {r['flight']} | {r['frames']} | {r['select_plan_median_us']} / {r['select_plan_p99_us']} | "
                 f"{r['stage_record_submit_median_us']} / {r['stage_record_submit_p99_us']} | "
                 f"{r['whole_median_us']} / {r['whole_p99_us']} {ok} / {r['whole_max_us']} | {r['startup_max_us']} | "
                 f"{r['triangles_median']} | {r['instances_median']} |")
met = sum(float(r["whole_p99_us"]) <= 500 for r in rows)
lines += ["", f"Whole CPU frame p99 ≤ 0.5 ms on {met} of {len(rows)} flights."]
open(sys.argv[2], "w").write("\n".join(lines) + "\n")
print(f"cpu-frame: {len(rows)} flights, whole CPU frame p99 ≤ 0.5 ms on {met}; {sys.argv[2]}")
PY
