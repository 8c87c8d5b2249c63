#!/usr/bin/env python3
"""Runs the README's example invocations as a newcomer would, and checks the
numbers the docs quote against the program (issue 41 item 7).

Usage: scripts/readme-examples.py PIEZOBENCH README.md WORKDIR

Every line of the README's "A few invocations" block that starts with
`piezobench`, its optional [--option] parts left out, that names no
placeholder (CAP.h5, a|b choices, a lab's folder, a server that runs until
stopped) is run in WORKDIR, in order (so
`demo` writes the demo-out/ files the later lines read), with the repository's
fixtures/ and docs/ beside it. Each must exit 0. Every `demo` line is then run
again with --json and judged against the acceptance of issue 41: the four
constants with finite sigma, status ok, and within 3 sigma of the simulated
bench's true values (the demo's report carries them as "true"; no estimator
reads them).

Quoted numbers: README.md and docs/*.md mark each number they quote from the
program with a comment on a line of its own beside it,
    <!-- doc-check: ARGS | PATH | QUOTED -->
ARGS the command after `piezobench` (run with --json, in WORKDIR), PATH a
dotted path into its JSON (an integer indexes an array, a word picks the
array element whose "name" is that word), QUOTED the number as the text prints
it. The program's value must round to it: within half a unit of its last digit.

Exit 0 when all hold, 1 with the failures listed.
"""
import decimal
import glob
import json
import math
import os
import re
import shlex
import subprocess
import sys


def example_lines(readme):
    text = open(readme, encoding="utf-8").read()
    start = text.index("A few invocations")
    block = text[text.index("```sh", start) + 5:]
    block = block[:block.index("```")]
    lines, cur = [], ""
    for raw in block.splitlines():
        line = raw.rstrip()
        if cur:
            cur += " " + line.strip().rstrip("\\").strip()
            if not line.endswith("\\"):
                lines.append(cur)
                cur = ""
            continue
        if not line.startswith("piezobench "):
            continue
        if line.endswith("\\"):
            cur = line.rstrip("\\").strip()
        else:
            lines.append(line)
    return lines


PLACEHOLDER = re.compile(r"\[|\||\bCAP\b|CAP\.h5|CAPTURE|PLAN|line3/|shard-\*|sweep\.txt|sim-instrument")


def runnable(line):
    """The line without its comment and its optional [..] parts; None when a placeholder stays."""
    cmd = line.split("#", 1)[0].strip()
    while True:
        stripped = re.sub(r"\s*\[[^\[\]]*\]", "", cmd)
        if stripped == cmd:
            break
        cmd = stripped
    return None if PLACEHOLDER.search(cmd) else cmd


# A marker stands on a line of its own (a page may show the syntax in running text).
DOC_CHECK = re.compile(r"^[ \t]*<!--\s*doc-check:\s*(.+?)\s*\|\s*(\S+)\s*\|\s*(\S+)\s*-->", re.M)


def json_at(j, path):
    for tok in path.split("."):
        if isinstance(j, list):
            if re.fullmatch(r"-?\d+", tok):
                j = j[int(tok)]
            else:
                j = next(e for e in j if isinstance(e, dict) and e.get("name") == tok)
        else:
            j = j[tok]
    return j


def doc_checks(exe, root, work, failures):
    """The <!-- doc-check --> markers of README.md and docs/*.md; returns how many ran."""
    cache, n = {}, 0
    files = [os.path.join(root, "README.md")] + sorted(glob.glob(os.path.join(root, "docs", "*.md")))
    for path in files:
        text = open(path, encoding="utf-8").read()
        for m in DOC_CHECK.finditer(text):
            args, jpath, quoted = m.group(1), m.group(2), m.group(3)
            where = f"{os.path.relpath(path, root)}: {quoted} ({args} | {jpath})"
            if args not in cache:
                r = subprocess.run([exe, "--json"] + shlex.split(args), cwd=work, capture_output=True, text=True,
                                   timeout=600)
                cache[args] = json.loads(r.stdout) if r.returncode == 0 else f"exit {r.returncode}: {r.stderr[-300:]}"
            j = cache[args]
            n += 1
            if isinstance(j, str):
                failures.append(f"{where}: the command failed ({j})")
                continue
            try:
                value = float(json_at(j, jpath))
            except (KeyError, IndexError, StopIteration, TypeError, ValueError) as e:
                failures.append(f"{where}: no number at {jpath} ({e!r})")
                continue
            q = decimal.Decimal(quoted)
            tol = 0.5 * 10 ** q.as_tuple().exponent
            ok = abs(value - float(q)) <= tol * (1 + 1e-9)
            print(f"{'ok' if ok else 'STALE':>8}  {where}: the program gives {value:.6g}")
            if not ok:
                failures.append(f"{where}: the program gives {value:.6g} (quoted to +-{tol:g})")
    return n


def main():
    if len(sys.argv) != 4:
        print(__doc__, file=sys.stderr)
        return 2
    exe, readme, work = os.path.abspath(sys.argv[1]), sys.argv[2], sys.argv[3]
    root = os.path.dirname(os.path.abspath(readme))
    os.makedirs(work, exist_ok=True)
    for name in ("fixtures", "docs"):
        link = os.path.join(work, name)
        if not os.path.exists(link):
            os.symlink(os.path.join(root, name), link)
    for stale in ("s.h5", "diagnosis.png", "modes.png"):
        if os.path.exists(os.path.join(work, stale)):
            os.remove(os.path.join(work, stale))
    failures, ran, demos = [], 0, []
    env = dict(os.environ)
    for line in example_lines(readme):
        cmd = runnable(line)
        if not cmd:
            print(f"skipped (placeholders): {line.split('#', 1)[0].strip()}")
            continue
        # The README's "piezobench" is the built binary; "&&" chains as in a shell.
        parts = [p.strip() for p in cmd.split("&&")]
        for part in parts:
            argv = shlex.split(part)
            argv[0] = exe
            r = subprocess.run(argv, cwd=work, env=env, capture_output=True, text=True, timeout=600)
            ran += 1
            status = "ok" if r.returncode == 0 else f"exit {r.returncode}"
            print(f"{status:>8}  {part}")
            if r.returncode != 0:
                failures.append(f"{part}: exit {r.returncode}: {r.stderr.strip()[-400:]}")
            if argv[1] == "demo":
                demos.append(argv)
    for argv in demos:
        out = os.path.join(work, "demo-json")
        r = subprocess.run([exe, "--json"] + argv[1:] + ["--out", out], cwd=work, capture_output=True,
                           text=True, timeout=600)
        label = " ".join(argv[1:])
        if r.returncode != 0:
            failures.append(f"demo {label} --json: exit {r.returncode}")
            continue
        j = json.loads(r.stdout)
        params = j.get("parameters", [])
        if len(params) != 4:
            failures.append(f"demo {label}: {len(params)} constants, 4 expected")
        for p in params:
            v, s, t = p.get("updated"), p.get("sigma"), p.get("true")
            ok = (p.get("status") == "ok" and isinstance(s, (int, float)) and math.isfinite(s) and s > 0
                  and isinstance(t, (int, float)) and abs(v - t) <= 3 * s)
            z = (v - t) / s if ok or (isinstance(s, (int, float)) and s and isinstance(t, (int, float))) else float("nan")
            print(f"  demo {label}: {p['name']} {v:.6g} +- {s if s is not None else 'null'} "
                  f"(true {t}, {z:+.2f} sigma) {p.get('status')}")
            if not ok:
                failures.append(f"demo {label}: {p['name']} = {v} +- {s}, status {p.get('status')}, true {t}")
    checks = doc_checks(exe, root, work, failures)
    print(f"readme-examples: {ran} invocation(s) run, {len(demos)} demo(s) judged, {checks} quoted number(s) "
          f"checked, {len(failures)} failure(s)")
    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
