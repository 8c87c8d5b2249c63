#!/usr/bin/env bash
# The scale acceptance run of headless replay (issue 9). Not part of `make test`:
# it takes a few minutes and a few hundred MB of disk.
#
#   scripts/replay-scale.sh [BUILD_DIR] [N] [JOBS] [WORKDIR]
#
# 1. makes N simulated captures of the seed's lab plan (20000 samples at
#    10 MS/s, 4 shots, 0.5 % noise; the transducers' YE11 spread by ±1 %, one
#    of them 8 % soft) and truncates one of them;
# 2. replays them with --jobs JOBS under /usr/bin/time -v: peak RSS, wall
#    time, captures/s; the corrupted capture must be reported and skipped;
# 3. replays them again into a new file, SIGKILLs that run halfway, resumes
#    it and checks that the captures finished before the kill were not redone
#    (their records keep their time stamps) and that the result equals step 2;
# 4. replays 4 shards (--shard I/4), merges them and checks the merge equals
#    step 2 (order-independent; wall-clock fields ignored).
set -euo pipefail

BUILD=${1:-build}
N=${2:-200}
JOBS=${3:-2}
WORK=${4:-$(mktemp -d /tmp/piezobench-replay-scale.XXXXXX)}
PB=$(realpath "$BUILD/ui/piezobench")
STRIP=$(realpath "$(dirname "$0")/strip-timing.py")  # the wall-clock keys the comparison drops
PY=/usr/bin/python3  # Debian's, with h5py (scripts/install-deps.sh)
lines() { if [ -f "$1" ]; then wc -l <"$1"; else echo 0; fi; }
mkdir -p "$WORK"
cd "$WORK"
echo "replay-scale: $N captures, --jobs $JOBS, in $WORK"

# ------------------------------------------------------------ 1. captures
SOFT=$((N * 3 / 16))  # 37 of 200: a soft transducer the batch summary must flag
BAD=$((N / 10 + 1))   # 21 of 200: truncated, must be reported and skipped
export BAD
if [ ! -f captures/.complete ]; then
  rm -rf captures
  for ((k = 0; k < N; k++)); do
    line=$((k % 4))
    ye=$(awk -v k="$k" 'BEGIN { printf "%.5g", 6.66e10 * (1 + 0.01 * sin(k * 1.7)) }')
    if [ "$k" -eq "$SOFT" ]; then ye=6.13e10; fi
    mkdir -p "captures/line$line"
    "$PB" measure --instrument sim --sim-isotropic \
      --sim-set "YE11=$ye,nu12=0.3333,d31=-210e-12,epsT33_rel=2294" --noise 0.005 --seed $((1000 + k)) \
      --samples 20000 --rate 1e7 --shots 4 --overwrite --out "captures/line$line/T-$(printf %04d "$k").h5" >/dev/null
  done
  bad="captures/line$((BAD % 4))/T-$(printf %04d "$BAD").h5"
  truncate -s $(($(stat -c %s "$bad") / 2)) "$bad"
  touch captures/.complete
fi
echo "replay-scale: $(find captures -name '*.h5' | wc -l) captures, $(du -sh captures | cut -f1)"

# ------------------------------------------------------------ 2. the measured run
rm -rf full.h5 full.jsonl report
set +e
/usr/bin/time -v -o time-full.txt "$PB" replay captures --jobs "$JOBS" --out full.h5 --jsonl full.jsonl \
  --report report --json >full.json 2>full.err
rc=$?
set -e
[ "$rc" -eq 2 ] || { echo "expected exit 2 (one capture refused), got $rc"; cat full.err; exit 1; }
rss_kb=$(awk -F': ' '/Maximum resident set size/ { print $2 }' time-full.txt)
wall=$(awk -F': ' '/Elapsed \(wall clock\)/ { print $2 }' time-full.txt)
"$PY" - <<'EOF'
import json, os
j = json.load(open("full.json"))
print("replay-scale: replayed %d, failed %d, %.1f s, %.2f captures/s (--jobs %d)"
      % (j["replayed"], j["failed"], j["wall_s"], j["captures_per_s"], j["jobs"]))
assert j["failed"] == 1 and j["issues"][0]["path"].endswith("T-%04d.h5" % int(os.environ["BAD"])), j["issues"]
EOF
echo "replay-scale: peak RSS $((rss_kb / 1024)) MB, wall $wall (/usr/bin/time -v)"
echo "replay-scale: JSON lines: $(lines full.jsonl)"
grep -A4 '^## Outliers' report/summary.md | tail -1 | cut -c1-160 | sed 's/^/replay-scale: first outlier: /'

# ------------------------------------------------------------ 3. kill halfway, resume
rm -rf resumed.h5 resumed.jsonl
"$PB" replay captures --jobs "$JOBS" --out resumed.h5 --jsonl resumed.jsonl >/dev/null 2>&1 &
pid=$!
while [ "$(lines resumed.jsonl)" -lt $((N / 2)) ]; do
  kill -0 "$pid" 2>/dev/null || { echo "the run to be killed ended early"; exit 1; }
  sleep 0.05
done
kill -KILL "$pid"
wait "$pid" 2>/dev/null || true
"$PY" - <<'EOF' >stamps-before.json
import h5py, json
with h5py.File("resumed.h5", "r") as f:
    g = f["results"]
    print(json.dumps({k: [g[k].attrs["replayed_utc"], float(g[k].attrs["elapsed_s"])] for k in g}))
EOF
set +e
"$PB" replay captures --jobs "$JOBS" --out resumed.h5 --json >resume.json 2>resume.err
set -e
"$PY" - <<'EOF'
import h5py, json
before = json.load(open("stamps-before.json"))
j = json.load(open("resume.json"))
print("replay-scale: killed after %d records; resume: %d done before, %d replayed, %d failed, %.1f s"
      % (len(before), j["done_before"], j["replayed"], j["failed"], j["wall_s"]))
with h5py.File("resumed.h5", "r") as f:
    g = f["results"]
    redone = [k for k, (utc, el) in before.items()
              if g[k].attrs["status"] == "ok" and (g[k].attrs["replayed_utc"] != utc or float(g[k].attrs["elapsed_s"]) != el)]
assert not redone, "redone after resume: %s" % redone
print("replay-scale: resume redid none of the finished captures")
EOF

# ------------------------------------------------------------ 4. 4 shards + merge
rm -f shard-*.h5 merged.h5
for i in 0 1 2 3; do
  "$PB" replay captures --shard "$i/4" --jobs 1 --out "shard-$i.h5" >/dev/null 2>&1 &
  if [ $(((i + 1) % JOBS)) -eq 0 ]; then wait; fi
done
wait
"$PB" replay-merge shard-0.h5 shard-1.h5 shard-2.h5 shard-3.h5 --out merged.h5

cat >compare.py <<'EOF'
# Order-independent comparison of two results files, wall-clock fields ignored
# (the keys scripts/strip-timing.py drops, at any depth: the work phases' and
# the fits' seconds are per record too). Usage: compare.py STRIP_TIMING A B
import h5py, importlib.util, json, sys
spec = importlib.util.spec_from_file_location("strip_timing", sys.argv[1])
strip_timing = importlib.util.module_from_spec(spec)
spec.loader.exec_module(strip_timing)
strip = strip_timing.strip
def content(path):
    out = {}
    with h5py.File(path, "r") as f:
        for k, g in f["results"].items():
            j = strip(json.loads(g["result_json"][()]))
            for s in j.get("result", {}).get("stages", []):
                s.pop("note", None)  # stage notes carry timings
            curves = {}
            if "curves" in g:
                for c in g["curves"].values():
                    curves[c.attrs["label"]] = (c["f_hz"][()].tobytes(), c["z_ohm"][()].tobytes())
            out[k] = (g.attrs["input_path"], g.attrs["sha256"], g.attrs["status"], json.dumps(j, sort_keys=True), curves)
    return out
a, b = content(sys.argv[2]), content(sys.argv[3])
assert a.keys() == b.keys(), "different captures: %s" % (a.keys() ^ b.keys())
diff = [k for k in a if a[k] != b[k]]
assert not diff, "%d records differ, e.g. %s" % (len(diff), a[diff[0]][0])
print("replay-scale: %s == %s (%d records, bit-identical numbers)" % (sys.argv[2], sys.argv[3], len(a)))
EOF
"$PY" compare.py "$STRIP" full.h5 merged.h5
"$PY" compare.py "$STRIP" full.h5 resumed.h5
echo "replay-scale: done ($WORK)"
