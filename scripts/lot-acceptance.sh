#!/usr/bin/env bash
# The acceptance run of limits and the lot report (issue 19, item 4). Not part
# of `make test`: N = 200 takes about two minutes on two cores.
#
#   scripts/lot-acceptance.sh [BUILD_DIR] [N] [JOBS] [WORKDIR]
#
# 1. makes N simulated tubes (`piezobench measure`, seeded): Young's
#    modulus, d31, permittivity and Rayleigh damping spread around APC850's
#    isotropic values; every 17th tube with extra dielectric loss, every 23rd
#    mass-loaded, one soft tube; and one truncated file (an "error" record);
# 2. replays them with --limits scripts/lot-acceptance-limits.toml, --report,
#    --jsonl and --json;
# 3. re-judges every JSON line against the same limits with
#    scripts/check_lot_limits.py (tomllib, its own path resolution) and
#    requires the same pass / fail / error counts, per-capture statuses, and
#    per-limit n, mean, sd and Cpk as piezobench's lot summary.
set -euo pipefail

BUILD=${1:-build}
N=${2:-200}
JOBS=${3:-2}
WORK=${4:-$(mktemp -d /tmp/piezobench-lot.XXXXXX)}
PB=$(realpath "$BUILD/ui/piezobench")
HERE=$(dirname "$(realpath "$0")")
LIMITS="$HERE/lot-acceptance-limits.toml"
mkdir -p "$WORK"
cd "$WORK"
echo "lot-acceptance: $N tubes, --jobs $JOBS, in $WORK"

# ------------------------------------------------------------ 1. the lot
if [ ! -f lot/.complete ]; then
  rm -rf lot
  mkdir -p lot
  for ((k = 0; k < N; k++)); do
    # Three roughly normal deviates per tube (sum of 4 uniforms, seeded by k).
    read -r ye d31 eps beta < <(awk -v k="$k" 'function g() { return (rand() + rand() + rand() + rand() - 2) * 1.7 }
      BEGIN { srand(1000 + k); printf "%.6g %.6g %.6g %.4g\n", 6.66e10 * (1 + 0.012 * g()),
              -210e-12 * (1 + 0.03 * g()), 2294 * (1 + 0.03 * g()), 1e-7 * (0.6 + 0.8 * rand()) }')
    if [ "$k" -eq 37 ]; then ye=6.13e10; fi  # a soft tube: an outlier the report must flag
    effects=()
    if [ $((k % 17)) -eq 5 ]; then effects+=(--effect dielectric_loss=0.03); fi
    if [ $((k % 23)) -eq 7 ]; then effects+=(--effect mass_loading=0.04); fi
    "$PB" measure --instrument sim --sim-isotropic \
      --sim-set "YE11=$ye,nu12=0.3333,d31=$d31,epsT33_rel=$eps" --rayleigh-beta "$beta" \
      "${effects[@]}" --noise 0.005 --seed $((2000 + k)) \
      --samples 20000 --rate 1e7 --shots 4 --overwrite --out "lot/T-$(printf %04d "$k").h5" >/dev/null
  done
  bad="lot/T-$(printf %04d $((N / 2))).h5"
  truncate -s $(($(stat -c %s "$bad") / 2)) "$bad"
  touch lot/.complete
fi
echo "lot-acceptance: $(find lot -name '*.h5' | wc -l) captures, $(du -sh lot | cut -f1)"

# ------------------------------------------------------------ 2. replay with limits
rm -rf results.h5 results.jsonl report
set +e
"$PB" replay lot --jobs "$JOBS" --out results.h5 --jsonl results.jsonl --report report \
  --limits "$LIMITS" --json >replay.json 2>replay.err
rc=$?
set -e
[ "$rc" -eq 2 ] || { echo "expected exit 2 (the truncated capture refused), got $rc"; tail replay.err; exit 1; }
for f in lot.md lot.json lot_histograms.svg lot_histograms.png; do
  [ -s "report/$f" ] || { echo "report/$f missing"; exit 1; }
done

# ------------------------------------------------------------ 3. the independent check
python3 "$HERE/check_lot_limits.py" "$LIMITS" results.jsonl replay.json
# ... and the check can fail: one passing capture's stored verdict flipped to "fail" must be caught.
python3 - <<'PY'
import json
lines = [json.loads(l) for l in open("results.jsonl")]
for l in lines:
    if l.get("limits", {}).get("status") == "pass":
        l["limits"]["status"] = "fail"
        break
open("tampered.jsonl", "w").write("".join(json.dumps(l) + "\n" for l in lines))
PY
if python3 "$HERE/check_lot_limits.py" "$LIMITS" tampered.jsonl replay.json >tampered.out; then
  echo "the independent check did not notice a flipped verdict"; exit 1
fi
echo "lot-acceptance: a flipped verdict is caught ($(grep -c 'piezobench says' tampered.out) mismatch)"
echo "lot-acceptance: report in $WORK/report/lot.md"
