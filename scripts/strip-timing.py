#!/usr/bin/env python3
"""JSON or JSONL on stdin, the same on stdout without wall-clock keys
(seconds, elapsed, timestamps): what a refactor may change."""
import json, sys
DROP = {"seconds", "elapsed_s", "wall_s", "cpu_s", "started", "finished", "timestamp", "created"}
def strip(v):
    if isinstance(v, dict):
        return {k: strip(x) for k, x in v.items() if k not in DROP}
    if isinstance(v, list):
        return [strip(x) for x in v]
    return v
if __name__ == "__main__":  # (replay-scale.sh's comparison imports DROP and strip)
    text = sys.stdin.read()
    try:
        print(json.dumps(strip(json.loads(text)), indent=1, sort_keys=True))
    except json.JSONDecodeError:
        # a batch's lines come in completion order: sorted, they compare
        lines = [json.dumps(strip(json.loads(l)), sort_keys=True) for l in text.splitlines() if l.strip()]
        print("\n".join(sorted(lines)))
