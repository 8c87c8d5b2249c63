#!/usr/bin/env python3
"""Issue 33's acceptance study on the simulated bench, through the CLI.

20 tubes within +-12 % of apc850's isotropic constants, one exp_decay shot at
1-3 % white noise; each captured twice with the same seed: clean, and with DC
offsets of 2-8 mV, 50 or 60 Hz hum of 2-10 mV and 1/f noise at 1 %. Both are
updated (output-error fit) and the disturbed one diagnosed. Prints per tube
the constants' errors, the sigma ratio disturbed/clean and the verdict, then
the acceptance counts.

Widened (issue 40 item 4), with a shot count: K shots per capture, and what
another bench does differently besides: each shot's own offset per channel
(offset_shot, 0.5-3 mV), hum at its own phase per shot and channel, 1/f
noise independent per shot, 50 or 60 Hz, and every other tube recorded
longer than a mains cycle (25 ms at 2 MS/s) instead of 2 ms at 10 MS/s.

usage: scripts/disturbance-study.py BUILD/ui/piezobench WORKDIR [N] [SHOTS]
"""
import json, math, os, random, subprocess, sys

exe, work = sys.argv[1], sys.argv[2]
n = int(sys.argv[3]) if len(sys.argv) > 3 else 20
shots = int(sys.argv[4]) if len(sys.argv) > 4 else 1
wide = len(sys.argv) > 4  # the widened study (issue 40): see the docstring
os.makedirs(work, exist_ok=True)
rng = random.Random(33)
NOM = {"YE11": 6.66e10, "nu12": 0.3333, "d31": -2.1e-10, "epsT33_rel": 2294.0}  # apc850 isotropic class (sim truth names)
BOUND = {"YE11": 1.0, "nu12": 3.0, "d31": 3.0, "epsT33_rel": 1.0}


def run(args):
    p = subprocess.run([exe] + args, capture_output=True, text=True)
    return p


def chance_within(fit, truth, draws=4000, key="sigma"):
    """The chance that the four constants fall within BOUND when each is off by
    its own sigma, with the fit's correlations (nu12 and d31 near -1): what the
    fit's information allows, by Monte Carlo (Cholesky by hand, no numpy)."""
    names = [k for k in BOUND]
    par = {p["name"]: p for p in fit["parameters"]}
    cn = fit.get("correlation", {}).get("names", [])
    cm = fit.get("correlation", {}).get("matrix", [])
    sig = [par[n][key] / abs(truth[n]) * 100 for n in names]  # %
    c = [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]
    for i, a in enumerate(names):
        for j, b in enumerate(names):
            if a in cn and b in cn:
                c[i][j] = cm[cn.index(a)][cn.index(b)]
    cov = [[c[i][j] * sig[i] * sig[j] + (1e-12 if i == j else 0) for j in range(4)] for i in range(4)]
    L = [[0.0] * 4 for _ in range(4)]
    for i in range(4):
        for j in range(i + 1):
            v = cov[i][j] - sum(L[i][k] * L[j][k] for k in range(j))
            L[i][j] = math.sqrt(max(v, 1e-18)) if i == j else v / L[j][j]
    g = random.Random(7)
    hit = 0
    for _ in range(draws):
        z = [g.gauss(0, 1) for _ in range(4)]
        x = [sum(L[i][k] * z[k] for k in range(i + 1)) for i in range(4)]
        hit += all(abs(x[i]) <= BOUND[names[i]] for i in range(4))
    return hit / draws


rows = []
k = -1
while len(rows) < n:
    k += 1
    truth = {key: v * (1 + rng.uniform(-0.12, 0.12)) for key, v in NOM.items()}
    noise = rng.uniform(0.01, 0.03)
    off = rng.uniform(0.002, 0.008)
    hum = rng.uniform(0.002, 0.010)
    mains = rng.choice([50, 60])
    seed = 1000 + k
    sset = ",".join("%s=%.6g" % (key, v) for key, v in truth.items())
    dist = "offset=%.4f,hum=%.4f,mains=%d,pink=1" % (off, hum, mains)
    record = []
    if wide:
        dist += ",offset_shot=%.4f" % rng.uniform(0.0005, 0.003)
        if k % 2:
            record = ["--rate", "2e6", "--samples", "50000"]  # 25 ms: longer than a mains cycle
    res = {}
    for tag, extra in (("clean", []), ("dist", ["--disturbance", dist])):
        cap = os.path.join(work, "t%02d-%s.h5" % (k, tag))
        p = run(["measure", "--shots", str(shots), "--noise", "%.4f" % noise, "--seed", str(seed), "--sim-isotropic",
                 "--sim-set", sset, "--out", cap, "--overwrite"] + record + extra)
        if p.returncode != 0:
            break
        u = run(["update", cap, "--json"])
        res[tag] = json.loads(u.stdout) if u.stdout.strip() else None
    if len(res) < 2 or res.get("dist") is None or res.get("clean") is None:
        print("%2d skipped (no valid tube: %s)" % (k, p.stderr.strip()[:100]), flush=True)
        continue
    d = run(["diagnose", os.path.join(work, "t%02d-dist.h5" % k), "--json"])
    diag = json.loads(d.stdout) if d.stdout.strip() else {}
    vname = diag.get("verdict_effect", "no diagnosis: " + d.stderr.strip()[:80])
    row = {"k": k, "noise": noise, "hum": hum, "mains": mains, "verdict": vname, "within": True, "err": {}, "ratio": {}}
    for par in res["dist"]["parameters"]:
        name = par["name"]
        if name not in truth:
            continue
        err = (par["value"] / truth[name] - 1) * 100
        clean = next(p for p in res["clean"]["parameters"] if p["name"] == name)
        row["err"][name] = err
        row.setdefault("err_clean", {})[name] = (clean["value"] / truth[name] - 1) * 100
        row["ratio"][name] = par["sigma"] / clean["sigma"]
        row["within"] &= abs(err) <= BOUND[name]
        row["within_clean"] = row.get("within_clean", True) and abs((clean["value"] / truth[name] - 1) * 100) <= BOUND[name]
        row["within3s"] = row.get("within3s", True) and abs(par["value"] - truth[name]) <= 3 * par["sigma"]
        row.setdefault("status", []).append(par["status"])
    row["p_within"] = chance_within(res["dist"], truth)
    row["p_within_clean"] = chance_within(res["clean"], truth)
    row["p_within_stat"] = chance_within(res["dist"], truth, key="sigma_statistical")
    row["p_within_clean_stat"] = chance_within(res["clean"], truth, key="sigma_statistical")
    row["chi2"] = res["dist"]["fit"]["chi2_per_dof"]
    row["chi2_clean"] = res["clean"]["fit"]["chi2_per_dof"]
    row["baseline"] = res["dist"]["fit"].get("baseline", {})
    rows.append(row)
    print("%2d %s noise %.1f%% hum %.1f mV %d Hz | err %s (clean %s) %s | sigma ratio %s | chi2 %.2f (clean %.2f) | %s" % (
        k, "%d shot(s)%s" % (shots, " 25 ms" if record else ""), noise * 100, hum * 1e3, mains,
        " ".join("%s %+.2f" % (a, b) for a, b in row["err"].items()),
        " ".join("%+.2f" % b for b in row["err_clean"].values()), ",".join(s[:2] for s in row["status"]),
        " ".join("%.2f" % v for v in row["ratio"].values()), row["chi2"], row["chi2_clean"], vname), flush=True)

within = sum(r["within"] for r in rows)
ratio_ok = sum(max(r["ratio"].values()) <= 1.5 for r in rows)
print("constants within 1/3/3/1 %%: %d/%d (the same captures without the disturbances: %d/%d)" % (
    within, len(rows), sum(r["within_clean"] for r in rows), len(rows)))
print("... expected from the fits' own sigmas and correlations: %.1f/%d (clean %.1f/%d); from the statistical "
      "part alone (no R1/Cp/gain tolerances, which the simulated bench does not have): %.1f/%d (clean %.1f/%d)" % (
    sum(r["p_within"] for r in rows), len(rows), sum(r["p_within_clean"] for r in rows), len(rows),
    sum(r["p_within_stat"] for r in rows), len(rows), sum(r["p_within_clean_stat"] for r in rows), len(rows)))
print("every constant within 3 of its sigmas: %d/%d" % (sum(r["within3s"] for r in rows), len(rows)))
print("sigmas within 1.5x of the clean capture's: %d/%d (max ratio %.2f, median of the max %.2f)" % (
    ratio_ok, len(rows), max(max(r["ratio"].values()) for r in rows),
    sorted(max(r["ratio"].values()) for r in rows)[len(rows) // 2]))
print("verdicts: %s" % {v: sum(r["verdict"] == v for r in rows) for v in set(r["verdict"] for r in rows)})
# Acceptance (issue 33): verdict none and sigmas within 1.5x in >= 18/20, no
# catalogue effect named. The constants' 1/3/3/1 % bound is printed, not
# asserted: the same captures without any disturbance miss it too (13/20 on
# 2026-11-26: one shot at 1-3 % noise gives nu12 and d31 sigmas of 2-5 %).
need = int(math.ceil(0.9 * len(rows)))
nones = sum(r["verdict"] == "none" for r in rows)
named = sum(r["verdict"] not in ("none", "unexplained", "non_stationary") for r in rows)
if nones < need or ratio_ok < need or named:
    sys.exit("FAILED: verdict none %d, sigmas within 1.5x %d (need %d), effects named %d" % (nones, ratio_ok, need, named))

