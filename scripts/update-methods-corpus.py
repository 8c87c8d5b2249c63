#!/usr/bin/python3
"""Issue 40's acceptance table: the seed's chain on another tool's captures.

Runs `piezobench update NN/fit.h5 --method cmcm --json` and `--method lm` on the
twenty captures of shared/corpus/refsim-v1 and prints per case and method the
status, each constant's (value - truth)/sigma (a `*` marks a constant whose own
status is not `ok`), the features used and the reason of a refusal; then the
rule: every `converged` answer within 3 sigma of the truth, none `converged`
with a feature outside its band or a constant more than 10 sigma off.
truth.json is read here, for the check only.

usage: scripts/update-methods-corpus.py [BUILD/ui/piezobench] [CORPUS] [CASES]
  defaults: build/ui/piezobench, ../shared/corpus/refsim-v1, 01..20 (CASES: 03,11,12)
"""
import json, math, os, subprocess, sys

here = os.path.dirname(os.path.abspath(__file__))
exe = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "build", "ui", "piezobench")
corpus = sys.argv[2] if len(sys.argv) > 2 else os.path.join(here, "..", "..", "shared", "corpus", "refsim-v1")
cases = sys.argv[3].split(",") if len(sys.argv) > 3 else ["%02d" % i for i in range(1, 21)]
NAMES = [("YE11", "YE11_pa"), ("nu12", "nu12"), ("d31", "d31_c_per_n"), ("epsT33_rel", "epsT33_rel")]

rows, bad = [], []
print("%-4s %-6s %-16s %9s %9s %9s %9s  %-6s  %s" % ("case", "method", "status", "YE11", "nu12", "d31", "epsT33",
                                                     "effect", "features (kHz) / reason"))
for case in cases:
    d = os.path.join(corpus, case)
    truth = json.load(open(os.path.join(d, "truth.json")))
    eff = truth.get("effect") or {}
    effect = eff.get("name", "none") if isinstance(eff, dict) else str(eff)
    for method in ("cmcm", "lm"):
        p = subprocess.run([exe, "update", os.path.join(d, "fit.h5"), "--method", method, "--json"],
                           capture_output=True, text=True)
        try:
            j = json.loads(p.stdout)
        except ValueError:
            print("%-4s %-6s exit %d: %s" % (case, method, p.returncode, p.stderr.strip()[:200]))
            bad.append((case, method, "no JSON"))
            continue
        status = j.get("status", "?")
        zs = []
        for name, key in NAMES:
            par = next((q for q in j.get("parameters", []) if q["name"] == name), None)
            if par is None or par.get("sigma") in (None, 0):
                zs.append("%9s" % "-")
                continue
            z = (par["value"] - truth["material"][key]) / par["sigma"]
            zs.append("%+8.2f%s" % (z, " " if par["status"] == "ok" else "*"))
            if status == "converged" and abs(z) > 3:
                bad.append((case, method, "%s off by %.1f sigma" % (name, z)))
        f = j.get("features", {})
        feats = ",".join("%.1f" % (x / 1e3) for x in f.get("resonances_hz", [])) + " / " + \
            ",".join("%.1f" % (x / 1e3) for x in f.get("antiresonances_hz", []))
        band = f.get("band", {})
        if status == "converged":
            for x in f.get("resonances_hz", []) + f.get("antiresonances_hz", []):
                if not band.get("lo_hz", 0) <= x <= band.get("hi_hz", 0):
                    bad.append((case, method, "converged with %.0f Hz outside its band" % x))
        elif not j.get("message"):
            bad.append((case, method, "refused without a reason"))
        print("%-4s %-6s %-16s %s  %-6s  %s%s" % (case, method, status, " ".join(zs), effect[:6], feats,
                                                  "" if status == "converged" else "  | " + j.get("message", "")[:160]))
        rows.append((case, method, status))

for method in ("cmcm", "lm"):
    conv = sum(1 for r in rows if r[1] == method and r[2] == "converged")
    print("%s: %d of %d converged, %d refused" % (method, conv, sum(1 for r in rows if r[1] == method),
                                                 sum(1 for r in rows if r[1] == method and r[2] != "converged")))
print("rule broken: %d%s" % (len(bad), "" if not bad else " - " + "; ".join("%s %s %s" % b for b in bad)))
sys.exit(1 if bad else 0)
