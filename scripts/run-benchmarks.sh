#!/usr/bin/env bash
# Runs every Google Benchmark program of a build folder; results (JSON) go to
# BUILD/bench-results/ and a median summary to stdout.
set -euo pipefail
build=${1:-build}
out="$build/bench-results"
mkdir -p "$out"
for exe in "$build"/bench/bench_*; do
  [ -x "$exe" ] || continue
  name=$(basename "$exe")
  echo "== $name"
  "$exe" --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
         --benchmark_out="$out/$name.json" --benchmark_out_format=json \
         --benchmark_filter="${BENCH_FILTER:-.}" | grep -E 'median|Benchmark|^-' || true
done
