#!/usr/bin/python3
"""Issue 39's acceptance study: `piezobench figures FILE --json` on every file of
a corpus of REAL impedance files (fixtures/real/manifest.json, or any folder
laid out the same way: <root>/<id>/<file>), judged against what the data show,
measured by an independent reader (scripts/real-file-features.py).

Usage: real-files-study.py PIEZOBENCH MANIFEST [--root DIR] [--root-env VAR] [--half dev|judge|all] [--json OUT]

For each file:
  read     exit 0 with figures, or exit 2 with a message naming the file
           (never a crash, never an internal error);
  modes    every mode whose status is "ok" and Qm >= 20: fs within 3 sigma plus
           one grid step of the data's conductance maximum nearest it, fp of
           the data's resistance maximum (the reference reader's lists; the
           |Z| minimum and maximum for a file fitted in |Z| alone, its phase
           untrusted; a mode with no such extremum in its window counts as a
           violation);
  misfit   0 files whose |Z| misfit exceeds 10 % while a k_eff claims
           sigma below 2 % and neither the fit's nor the mode's status says so;
  analyzer where the analyzer saved its own circuit (manifest analyzer_circuit:
           R1, L1, C1, C0): our nearest mode's fs within 0.1 %, k_eff within
           2 %, and our |Y| misfit no worse than the analyzer circuit's on the
           same data.
Exit 1 when any acceptance rule fails, 0 otherwise; the table goes to stdout.
"""
import argparse
import importlib.util
import json
import math
import os
import re
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def load_reference_reader():
    spec = importlib.util.spec_from_file_location("rff", os.path.join(HERE, "real-file-features.py"))
    m = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(m)
    return m


def analyzer_circuit(text):
    """R1, L1, C1, C0 from the manifest's description of the analyzer's own circuit."""
    if not text:
        return None
    units = {"": 1, "m": 1e-3, "u": 1e-6, "µ": 1e-6, "n": 1e-9, "p": 1e-12, "f": 1e-15, "k": 1e3, "M": 1e6}
    out = {}
    for name in ("R1", "L1", "C1", "C0"):
        m = re.search(name + r"\s*=?\s*([-+0-9.eE]+)\s*([munpfkMµ]?)(ohm|Ω|H|F)", text)
        if not m:
            return None
        out[name] = float(m.group(1)) * units[m.group(2)]
    return out


def circuit_z(c, f):
    w = 2 * np.pi * f
    s = 1j * w
    yb = 1.0 / (c["R1"] + s * c["L1"] + 1.0 / (s * c["C1"]))
    return 1.0 / (s * c["C0"] + yb)


def y_misfit(zd, zm):
    return float(np.sqrt(np.mean((np.abs(zd) / np.abs(zm) - 1.0) ** 2)))


def grid_step(f, x):
    i = int(np.clip(np.searchsorted(f, x), 1, len(f) - 1))
    return float(max(f[i] - f[i - 1], f[min(i + 1, len(f) - 1)] - f[i]))


def nearest_in(window, values, x):
    lo, hi = window
    c = [v for v in values if (lo is None or v >= lo) and (hi is None or v <= hi)]
    return min(c, key=lambda v: abs(v - x)) if c else None


def val(d, k):
    v = d.get(k) or {}
    return v.get("value"), v.get("sigma")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("piezobench")
    ap.add_argument("manifest")
    ap.add_argument("--root", default=None)
    ap.add_argument("--root-env", default=None, help="an environment variable that, when set, names the root instead")
    ap.add_argument("--half", default="all")
    ap.add_argument("--json", default=None)
    a = ap.parse_args()
    root = a.root or os.path.dirname(os.path.abspath(a.manifest))
    if a.root_env and os.environ.get(a.root_env):
        root = os.environ[a.root_env]
    if not os.path.isdir(root):
        print("real-files-study: no corpus at %s (set %s or place the files there): skipped" % (root, a.root_env or "--root"))
        return 77
    entries = json.load(open(a.manifest))
    rff = load_reference_reader()
    failures, rows, report = [], [], []
    for e in entries:
        if a.half != "all" and e.get("half") != a.half:
            continue
        path = os.path.join(root, e["id"], os.path.basename(e["path"]))
        if not os.path.exists(path):
            continue
        # reader_args are the reference reader's (scripts/real-file-features.py);
        # piezobench_args, when given, ours (e.g. --columns for a headerless table).
        args = [a.piezobench, "figures", path, "--json"] + e.get("piezobench_args", [])
        p = subprocess.run(args, capture_output=True, text=True, timeout=600)
        rec = {"id": e["id"], "exit": p.returncode, "violations": [], "checked": 0}
        report.append(rec)
        if p.returncode != 0:
            msg = (p.stderr.strip() or p.stdout.strip()).splitlines()
            msg = msg[-1] if msg else ""
            rec["message"] = msg
            named = os.path.basename(path) in msg
            if p.returncode != 2 or not named:
                rec["violations"].append("refused without naming the file, or not as bad input (exit %d): %s" % (p.returncode, msg))
            rows.append((e["id"], "refused", msg[:90]))
            failures += rec["violations"]
            continue
        j = json.loads(p.stdout)
        try:
            ra = e.get("reader_args") or []
            colspec = ra[ra.index("--columns") + 1] if "--columns" in ra else None
            mode = ra[ra.index("--s2p-mode") + 1] if "--s2p-mode" in ra else "series"
            if set(ra) - {"--columns", "--s2p-mode", colspec, mode}:
                raise ValueError("the reference reader needs %s" % ra)
            f, z, _ = rff.read_any(path, mode, colspec)
            f = np.asarray(f, float)
        except Exception as ex:  # the reference reader cannot: the data checks are skipped
            f, z = None, None
            rec["reference_reader"] = str(ex)
        misfit = j["fit"].get("misfit_abs_rel_rms") or 0.0
        fit_ok = j.get("status", "ok") == "ok"
        for m in j["modes"]:
            ok = m.get("status", "ok") == "ok"
            fs, sfs = val(m, "fs_hz")
            fp, sfp = val(m, "fp_hz")
            k, sk = val(m, "k_eff_ieee176")
            q, _ = val(m, "qm_branch")
            if misfit > 0.10 and k and sk is not None and sk < 0.02 * k and ok and fit_ok:
                rec["violations"].append("misfit %.1f %% but mode at %.6g Hz claims k_eff %.3f +/- %.3g with status ok" % (100 * misfit, fs, k, sk))
            if not ok or f is None or q is None or q < 20:
                continue
            win = tuple(m.get("window_hz", [None, None]))
            # A file whose phase cannot be trusted is fitted in |Z| alone: what its
            # data show of fs and fp are then the |Z| minimum and maximum.
            keys = ("z_min_hz", "z_max_hz") if j.get("magnitude_only") else ("conductance_peaks_hz", "r_max_hz")
            for name, x, s, key in (("fs", fs, sfs, keys[0]), ("fp", fp, sfp, keys[1])):
                if x is None:
                    continue
                ref = nearest_in(win, e.get(key) or [], x)
                rec["checked"] += 1
                if ref is None:
                    rec["violations"].append("%s %.7g Hz (ok): no %s of the data in its window %s" % (name, x, key, win))
                    continue
                tol = 3 * (s or 0) + grid_step(f, ref)
                if abs(x - ref) > tol:
                    rec["violations"].append("%s %.7g +/- %.3g Hz (ok) but the data's is at %.7g Hz" % (name, x, s or float("nan"), ref))
        c = analyzer_circuit(e.get("analyzer_circuit"))
        if c and j["modes"]:
            fs_a = 1 / (2 * math.pi * math.sqrt(c["L1"] * c["C1"]))
            fp_a = fs_a * math.sqrt(1 + c["C1"] / c["C0"])
            k_a = math.sqrt(1 - (fs_a / fp_a) ** 2)
            m = min(j["modes"], key=lambda m: abs((val(m, "fs_hz")[0] or 0) - fs_a))
            fs, _ = val(m, "fs_hz")
            k, _ = val(m, "k_eff_ieee176")
            ours = j["fit"].get("misfit_admittance_abs_rel_rms")
            # Their |Y| misfit needs the data (the reference reader's); without it only fs and k_eff are judged.
            theirs = y_misfit(np.asarray(z), circuit_z(c, f)) if f is not None else None
            rec["analyzer"] = {"fs_rel": fs / fs_a - 1, "k_rel": (k / k_a - 1) if k else None,
                               "y_misfit_ours": ours, "y_misfit_analyzer": theirs}
            if abs(fs / fs_a - 1) > 1e-3:
                rec["violations"].append("fs %.7g Hz is %.3f %% from the analyzer's %.7g Hz" % (fs, 100 * (fs / fs_a - 1), fs_a))
            if not k or abs(k / k_a - 1) > 0.02:
                rec["violations"].append("k_eff %s is off the analyzer's %.4f by more than 2 %%" % (k, k_a))
            if ours is not None and theirs is not None and ours > theirs:
                rec["violations"].append("|Y| misfit %.3g %% worse than the analyzer circuit's %.3g %%" % (100 * ours, 100 * theirs))
        status = j.get("status", "?")
        n_ok = sum(1 for m in j["modes"] if m.get("status", "ok") == "ok")
        rows.append((e["id"], "%s, %d modes (%d ok), |Z| misfit %.2g %%" % (status, len(j["modes"]), n_ok, 100 * misfit),
                     "; ".join(rec["violations"])[:200] or "-"))
        failures += rec["violations"]
    w = max([len(r[0]) for r in rows] + [4])
    for r in rows:
        print("%-*s  %-50s  %s" % (w, r[0], r[1], r[2]))
    print("%d files, %d violations" % (len(rows), len(failures)))
    if a.json:
        json.dump(report, open(a.json, "w"), indent=1)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
