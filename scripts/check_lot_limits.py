#!/usr/bin/env python3
"""Independent check of `piezobench replay --limits`: re-judges every record of
a replay's JSON lines against the limits file (read with tomllib, paths
resolved here by a separate implementation of README's path rules) and
compares the counts, each capture's status and the per-limit statistics
(n, mean, sd, Cpk) with what piezobench wrote (its --json "lot" object and
the "limits" object of each line).

    scripts/check_lot_limits.py LIMITS.toml RESULTS.jsonl REPLAY.json

Prints the counts; exit 0 when everything agrees, 1 otherwise.
"""
import json
import math
import re
import statistics
import sys
import tomllib

SEGMENT = re.compile(r"([A-Za-z0-9_-]*)((?:\[[^\]]*\])*)$")


def resolve(result, path):
    """The value at `path` in `result`, or None (absent, null or NaN)."""
    return resolve_with_holder(result, path)[1]


def resolve_with_holder(result, path):
    """(the object that holds the value, the value) at `path`; (None, None) if absent."""
    node, holder = result, None
    segments, depth, cur = [], 0, ""
    for ch in path:  # '.' splits keys outside brackets only ([fs_hz=45e3..56e3])
        depth += (ch == "[") - (ch == "]")
        if ch == "." and depth == 0:
            segments.append(cur)
            cur = ""
        else:
            cur += ch
    segments.append(cur)
    for seg in segments:
        m = SEGMENT.match(seg)
        if not m:
            raise ValueError(f"bad path {path!r}")
        key, brackets = m.group(1), m.group(2)
        if key:
            holder = node
            if isinstance(node, dict):
                if key not in node:
                    return None, None
                node = node[key]
            elif isinstance(node, list):
                named = [e for e in node if isinstance(e, dict) and e.get("name") == key]
                if not named:
                    return None, None
                node = named[0]
            else:
                return None, None
        for sel in re.findall(r"\[([^\]]*)\]", brackets):
            if not isinstance(node, list):
                return None, None
            if "=" in sel:
                field, rng = sel.split("=", 1)
                lo, hi = (float(x) for x in rng.split("..", 1))
                hits = [e for e in node if isinstance(e, dict) and isinstance(e.get(field), (int, float))
                        and not isinstance(e.get(field), bool) and lo <= e[field] <= hi]
                if not hits:
                    return None, None
                node = hits[0]
            else:
                i = int(sel)
                if i >= len(node):
                    return None, None
                node = node[i]
    if isinstance(node, dict) and isinstance(node.get("updated"), (int, float)) and not isinstance(node.get("updated"), bool):
        holder, node = node, node["updated"]
    return holder, node


# README "Limits and the lot report": a figure whose own status says it is
# unreliable, or a constant not identifiable, is not a measurement; nor is a
# value the quantity cannot physically take (by the path's last key).
NOT_A_MEASUREMENT = {"unreliable", "not identifiable", "not_identifiable", "non_physical"}


def last_key(path):
    seg = re.split(r"\.(?![^\[]*\])", path)[-1]
    return re.sub(r"\[.*$", "", seg)


def physically_impossible(key, x):
    sigma = key.endswith("_sigma")
    if ("tan_delta" in key or key == "loss_tangent") and not sigma and x < 0:
        return True
    if key in ("k_eff", "k33", "k31", "kp", "kt") and not 0 < x < 1:
        return True
    if ("capacitance" in key or key in ("c0_f", "c1_f")) and not sigma and x <= 0:
        return True
    if key.startswith("qm") and not sigma and key != "qm_inverse" and x <= 0:
        return True
    if key.endswith("_hz") and x <= 0:
        return True
    if key in ("YE11", "epsT33_rel") and x <= 0:
        return True
    return key == "nu12" and not -1 < x < 0.5


def judge(limit, result):
    """'pass' | 'below min' | 'above max' | 'not allowed' | 'not measured'."""
    holder, v = resolve_with_holder(result, limit["quantity"])
    if isinstance(holder, dict) and holder is not v and holder.get("status") in NOT_A_MEASUREMENT:
        return "not measured", None
    if "allowed" in limit:
        if not isinstance(v, (str, bool)):
            return "not measured", None
        # JSON equality: True is not 1, "none" is "none".
        ok = any(type(a) is type(v) and a == v for a in limit["allowed"])
        return ("pass" if ok else "not allowed"), v
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        return "not measured", None
    if physically_impossible(last_key(limit["quantity"]), v):
        return "not measured", None
    if "min" in limit and v < limit["min"]:
        return "below min", v
    if "max" in limit and v > limit["max"]:
        return "above max", v
    return "pass", v


def main(limits_file, jsonl_file, replay_json_file):
    with open(limits_file, "rb") as f:
        limits = tomllib.load(f)["limit"]
    records = [json.loads(line) for line in open(jsonl_file)]
    lot = json.load(open(replay_json_file))["lot"]
    problems = []
    counts = {"pass": 0, "fail": 0, "error": 0}
    values = [[] for _ in limits]
    states = [dict() for _ in limits]
    for rec in records:
        if rec.get("status") != "ok" or not isinstance(rec.get("result"), dict):
            status = "error"
        else:
            status = "pass"
            for k, lim in enumerate(limits):
                st, v = judge(lim, rec["result"])
                states[k][st] = states[k].get(st, 0) + 1
                if st != "pass":
                    status = "fail"
                if st != "not measured" and "allowed" not in lim:
                    values[k].append(v)
        counts[status] += 1
        theirs = rec.get("limits", {}).get("status")
        if theirs != status:
            problems.append(f"{rec.get('path')}: piezobench says {theirs}, this check {status}")
    print(f"independent check: {len(records)} records: {counts['pass']} pass, {counts['fail']} fail, "
          f"{counts['error']} error")
    print(f"piezobench lot:    {lot['captures']} records: {lot['pass']} pass, {lot['fail']} fail, {lot['error']} error")
    for key in ("pass", "fail", "error"):
        if counts[key] != lot[key]:
            problems.append(f"{key}: piezobench {lot[key]}, this check {counts[key]}")
    if len(records) != lot["captures"]:
        problems.append(f"records: piezobench {lot['captures']}, JSON lines {len(records)}")
    for k, (lim, q) in enumerate(zip(limits, lot["quantities"])):
        if q["quantity"] != lim["quantity"]:
            problems.append(f"limit {k}: {q['quantity']} != {lim['quantity']}")
            continue
        if states[k].get("not measured", 0) != q["not_measured"]:
            problems.append(f"{lim['quantity']}: not measured {q['not_measured']} != {states[k].get('not measured', 0)}")
        if "allowed" in lim:
            if states[k].get("not allowed", 0) != q["not_allowed"]:
                problems.append(f"{lim['quantity']}: not allowed {q['not_allowed']} != {states[k].get('not allowed', 0)}")
            print(f"  {lim['quantity']}: not allowed {states[k].get('not allowed', 0)}, not measured "
                  f"{states[k].get('not measured', 0)}")
            continue
        v = values[k]
        n = len(v)
        mean = statistics.fmean(v) if v else 0.0
        sd = statistics.stdev(v) if n > 1 else 0.0
        cpu = (lim["max"] - mean) / (3 * sd) if "max" in lim and sd > 0 else None
        cpl = (mean - lim["min"]) / (3 * sd) if "min" in lim and sd > 0 else None
        cpk = min(x for x in (cpu, cpl) if x is not None) if (cpu is not None or cpl is not None) else None
        checks = [("n", n, q["n"], 0), ("below_min", states[k].get("below min", 0), q["below_min"], 0),
                  ("above_max", states[k].get("above max", 0), q["above_max"], 0),
                  ("mean", mean, q["mean"], 1e-9), ("sd", sd, q["sd"], 1e-7)]
        if cpk is not None or q["cpk"] is not None:
            checks.append(("cpk", cpk, q["cpk"], 1e-7))
        for name, mine, theirs, rel in checks:
            if mine is None or theirs is None:
                if mine != theirs:
                    problems.append(f"{lim['quantity']} {name}: piezobench {theirs}, this check {mine}")
            elif abs(mine - theirs) > rel * max(abs(mine), abs(theirs), 1e-300):
                problems.append(f"{lim['quantity']} {name}: piezobench {theirs}, this check {mine}")
        cpk_text = f"{cpk:.3f}" if cpk is not None else "-"
        print(f"  {lim['quantity']}: n {n}, below {states[k].get('below min', 0)}, above "
              f"{states[k].get('above max', 0)}, not measured {states[k].get('not measured', 0)}, "
              f"mean {mean:.6g}, sd {sd:.3g}, Cpk {cpk_text}")
    if problems:
        print("MISMATCH:\n  " + "\n  ".join(problems))
        return 1
    print("independent check: counts, statuses and statistics agree")
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    sys.exit(main(*sys.argv[1:]))
