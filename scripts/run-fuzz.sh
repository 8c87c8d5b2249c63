#!/usr/bin/env bash
# Runs libFuzzer harnesses built by `make fuzz` (PIEZO_FUZZ=ON), each for a
# fixed time, and writes what they find into tests/fuzz/regressions/<name>/
# (crash-*, oom-*, timeout-*, leak-*: libFuzzer's names). The corpus that
# libFuzzer grows is kept in <build>/fuzz-corpus/<name>/, not in the
# repository; tests/fuzz/corpus/<name>/ holds the small seeds.
#
#   scripts/run-fuzz.sh BUILD_DIR SECONDS NAME...
# Environment: FUZZ_FLAGS (more libFuzzer flags, e.g. "-fork=1 -ignore_crashes=1"
# to keep going after a finding), FUZZ_MAX_LEN (4096), FUZZ_MALLOC_MB (512).
# Exit status: 0 when no harness found anything.
set -uo pipefail

if [ $# -lt 3 ]; then
  echo "usage: $0 BUILD_DIR SECONDS NAME..." >&2
  exit 2
fi
build=$(cd "$1" && pwd)
secs=$2
shift 2
root=$(cd "$(dirname "$0")/.." && pwd)
summary=$build/fuzz-summary.txt
: >"$summary"
status=0

for name in "$@"; do
  bin=$build/tests/fuzz/fuzz_$name
  if [ ! -x "$bin" ]; then
    echo "run-fuzz: $bin is missing (build it with --target fuzz_$name)" >&2
    status=1
    continue
  fi
  seeds=$root/tests/fuzz/corpus/$name
  regress=$root/tests/fuzz/regressions/$name
  work=$build/fuzz-corpus/$name
  log=$build/fuzz-$name.log
  mkdir -p "$work" "$regress"
  args=(-max_total_time="$secs" -timeout=25 -rss_limit_mb=2048
        -malloc_limit_mb="${FUZZ_MALLOC_MB:-512}" -max_len="${FUZZ_MAX_LEN:-4096}"
        -artifact_prefix="$regress/" -print_final_stats=1)
  [ -f "$root/tests/fuzz/dict/$name.dict" ] && args+=(-dict="$root/tests/fuzz/dict/$name.dict")
  # shellcheck disable=SC2206
  [ -n "${FUZZ_FLAGS:-}" ] && args+=(${FUZZ_FLAGS})
  echo "== fuzz_$name for ${secs} s (log: $log)"
  # libFuzzer reads every directory given; it writes new inputs to the first.
  # The regressions replay first thing: a finding that is back stops the run.
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    "$bin" "${args[@]}" "$work" "$seeds" "$regress" >"$log" 2>&1
  rc=$?
  grep -E '^#[0-9]+[[:space:]]+(INITED|DONE)|^(==[0-9]+==)?ERROR|FUZZ FINDING|Test unit written|^SUMMARY' "$log" | head -20
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log")
  rss=$(sed -n 's/^stat::peak_rss_mb: *//p' "$log")
  last=$(grep -E '^#[0-9]+[[:space:]]' "$log" | tail -1)
  cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
  ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
  corp=$(sed -n 's/.* corp: \([0-9]*\/[0-9a-zA-Z]*\).*/\1/p' <<<"$last")
  result=ok
  if [ $rc -ne 0 ]; then
    result="FINDING (exit $rc): $(sed -n 's/.*Test unit written to //p' "$log" | tail -1)"
    status=1
  fi
  printf '%-15s %8s s  %10s execs  %7s exec/s  cov %6s  ft %6s  corp %-12s rss %5s MB  %s\n' \
    "$name" "$secs" "${execs:-?}" "${rate:-?}" "${cov:-?}" "${ft:-?}" "${corp:-?}" "${rss:-?}" "$result" \
    | tee -a "$summary"
done
echo "== summary ($summary)"
cat "$summary"
exit $status
