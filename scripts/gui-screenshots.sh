#!/usr/bin/env bash
# The GUI's screenshots in docs/, made anew by the headless GUI (xvfb-run):
#   docs/gui-1280x800.png    default window, after "Measure and update" with a
#                            15 ohm series resistance (the corrected result)
#   docs/gui-1600x1000.png   the larger window, limits loaded (PASS/FAIL banner)
#   docs/gui-replay.png      a replayed refsim capture with its hold-out (if ../shared is there)
# Usage: scripts/gui-screenshots.sh [BUILD_DIR]   (make screenshots)
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
gui="$root/$build/ui/piezobench-gui"
[ -x "$gui" ] || { echo "gui-screenshots: $gui not built (make build)" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
xvfb-run -a -s "-screen 0 1700x1100x24" "$gui" --sim-effects series_resistance=15 --no-calibrate \
  --click 'Measure and update' --wait-job --width 1280 --height 800 --timeout 300 \
  --screenshot "$root/docs/gui-1280x800.png"
xvfb-run -a -s "-screen 0 1700x1100x24" "$gui" --limits "$root/docs/limits-example.toml" \
  --click 'Limits...' --click 'Measure and update' --wait-job --width 1600 --height 1000 --timeout 300 \
  --screenshot "$root/docs/gui-1600x1000.png"
# The Modes view: per-mode figures and the selected mode's admittance plane.
xvfb-run -a -s "-screen 0 1700x1100x24" "$gui" --click 'Measure and update' --click Modes --wait-job \
  --width 1280 --height 800 --timeout 300 --screenshot "$root/docs/gui-modes.png"
corpus="$root/../shared/corpus/refsim-v1/05"
if [ -f "$corpus/fit.h5" ]; then
  xvfb-run -a -s "-screen 0 1700x1100x24" "$gui" --replay "$corpus/fit.h5" --replay-heldout "$corpus/holdout.h5" \
    --click 'Replay capture' --wait-job --width 1280 --height 800 --timeout 300 \
    --screenshot "$root/docs/gui-replay.png"
fi
echo "gui-screenshots: docs/gui-1280x800.png docs/gui-1600x1000.png docs/gui-modes.png${corpus:+ docs/gui-replay.png}"
