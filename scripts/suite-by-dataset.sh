#!/usr/bin/env bash
# Runs a bench suite one dataset at a time within a wall-clock budget: each dataset's flights go
# through `aerie bench --suite` on a copy of the suite file that keeps only that dataset, into
# OUT/<dataset>/ (its own suite.md, ratios.csv, curves.csv). A dataset the budget cuts off is
# stopped and named; the datasets before it keep their whole reports. For a GPU lent for a few
# minutes, or a CI job with a time limit.
#
#   scripts/suite-by-dataset.sh AERIE SUITE OUT BUDGET_S [DATASET ...]
#
# AERIE: the aerie binary (a release build); SUITE: the suite TOML; OUT: the output folder;
# BUDGET_S: seconds for the whole run; DATASET: run only these (default: every dataset, in the
# file's order). Prints a line per dataset and writes OUT/datasets.csv (name, exit code, seconds).
# Each dataset runs with `--resume`: run again with the same OUT, the script goes on where the
# last one stopped (flights already benched are taken from their records, not flown again).
set -uo pipefail
if [ $# -lt 4 ]; then
  sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'
  exit 2
fi
aerie=$1 suite=$2 out=$3 budget=$4
shift 4
if [ ! -x "$aerie" ]; then echo "suite-by-dataset: $aerie: not an executable" >&2; exit 2; fi
if [ ! -f "$suite" ]; then echo "suite-by-dataset: $suite: no such suite file" >&2; exit 2; fi
case $budget in '' | *[!0-9]*) echo "suite-by-dataset: BUDGET_S '$budget' is not a whole number of seconds" >&2; exit 2 ;; esac

# The dataset names, in the file's order.
names=$(awk '/^\[\[dataset\]\]/ { d = 1; next } /^\[/ { d = 0 }
  d && /^name *=/ { sub(/^name *= *"/, ""); sub(/".*$/, ""); print; d = 0 }' "$suite")
if [ $# -gt 0 ]; then
  for want in "$@"; do
    grep -qx -- "$want" <<<"$names" || { echo "suite-by-dataset: no dataset '$want' in $suite (it has: $(echo $names))" >&2; exit 2; }
  done
  names=$(printf '%s\n' "$@")
fi

mkdir -p "$out"
echo "dataset,exit_code,seconds" >"$out/datasets.csv"
start=$(date +%s)
dir=$(dirname "$suite")
failed=0
for name in $names; do
  left=$((budget - ($(date +%s) - start)))
  if [ "$left" -lt 30 ]; then
    echo "suite-by-dataset: $name skipped: ${left} s of the budget left"
    echo "$name,skipped,0" >>"$out/datasets.csv"
    failed=1
    continue
  fi
  # The suite file with only this dataset, beside the original so relative paths still hold.
  part="$dir/.suite-part-$name-$$.toml"
  awk -v keep="$name" '
    function flush() { if (inds && keepb) printf "%s", buf; buf = ""; inds = 0; keepb = 0 }
    /^\[/ { flush(); if ($0 == "[[dataset]]") inds = 1 }
    { if (inds) { buf = buf $0 "\n"; if ($0 ~ "^name *= *\"" keep "\"") keepb = 1 } else print }
    END { flush() }' "$suite" >"$part"
  t0=$(date +%s)
  echo "suite-by-dataset: $name (${left} s of the budget left)"
  timeout --signal=INT --kill-after=20 "$left" "$aerie" bench --suite "$part" --out "$out/$name" --resume
  rc=$?
  rm -f "$part"
  # The report names the suite file it read: the original, not the temporary part.
  [ -f "$out/$name/suite.md" ] && sed -i "1s|$part|$suite, dataset $name|" "$out/$name/suite.md"
  dt=$(($(date +%s) - t0))
  echo "$name,$rc,$dt" >>"$out/datasets.csv"
  if [ "$rc" -eq 0 ]; then
    echo "suite-by-dataset: $name done in $dt s"
  else
    echo "suite-by-dataset: $name stopped with exit code $rc after $dt s$([ "$rc" -eq 124 ] && echo ' (the budget ran out)')"
    failed=1
  fi
done
echo "suite-by-dataset: $(($(date +%s) - start)) s in all; $out/datasets.csv"
exit $failed
