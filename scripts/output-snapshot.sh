#!/usr/bin/env bash
# The outputs a refactor must leave unchanged (issues 42/43 acceptance):
# demo --json, the corpus replay JSONL, four diagnoses with hold-out,
# figures and impedance JSON, and the replay report's plots, with wall-clock
# keys removed. Usage: scripts/output-snapshot.sh PIEZOBENCH OUTDIR
# Compare two snapshots with: diff -r OUTDIR_A OUTDIR_B
set -euo pipefail
bin=$(readlink -f "$1"); out=$2
here=$(cd "$(dirname "$0")/.." && pwd)
corpus=${PIEZO_CORPUS:-$here/../shared/corpus/refsim-v1}
mkdir -p "$out"; out=$(readlink -f "$out")
norm() { python3 "$here/scripts/strip-timing.py"; }
cd "$(mktemp -d)"
"$bin" demo --json 2>/dev/null | norm >"$out/demo.json"
"$bin" replay "$corpus" --jobs 2 --out r.h5 --jsonl r.jsonl --report rep --limits "$here/docs/limits-example.toml" >/dev/null 2>&1 || true
norm <r.jsonl >"$out/replay.jsonl"
for n in 03 07 12 18; do
  "$bin" diagnose "$corpus/$n/fit.h5" --holdout "$corpus/$n/holdout.h5" --json --plot "diagnose-$n.png" 2>/dev/null | norm >"$out/diagnose-$n.json" || true
done
"$bin" figures "$corpus/20/fit.h5" --json --plot figures-20.png 2>/dev/null | norm >"$out/figures-20.json" || true
"$bin" impedance "$corpus/05/fit.h5" --json 2>/dev/null | norm >"$out/impedance-05.json" || true
mkdir -p "$out/plots"; cp ./*.png "$out/plots/" 2>/dev/null || true
find rep -name '*.svg' -o -name '*.png' | while read -r f; do
  cp "$f" "$out/plots/$(echo "$f" | tr / _)"; done
