#!/usr/bin/env python3
"""The house's shape (issue 42):
 - the layers talk downward only (DEVELOPERS.md, CMakeLists.txt):
     ui -> jobs -> update, acquisition -> model, dsp, drivers -> numerics
   every #include "folder/..." of the production folders is read, and each
   that goes up or sideways (a back-edge) is printed;
 - no source file (production, tests, bench) is over MAX_LINES lines.
Exits 1 if either fails. Usage: scripts/check-structure.py [REPO]"""
import pathlib, re, sys

BELOW = {
    "numerics": set(),
    "drivers": {"numerics"},
    "dsp": {"numerics"},
    "model": {"numerics"},
    "acquisition": {"drivers", "dsp", "model", "numerics"},
    "update": {"dsp", "model", "numerics"},
    "jobs": {"update", "acquisition", "drivers", "dsp", "model", "numerics"},
    "ui": {"jobs", "update", "acquisition", "drivers", "dsp", "model", "numerics"},
}
MAX_LINES = 800
INCLUDE = re.compile(r'^\s*#\s*include\s+"([a-z_]+)/')

def main():
    repo = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parent.parent)
    bad, edges = [], 0
    for layer, allowed in BELOW.items():
        for f in sorted((repo / layer).rglob("*")):
            if f.suffix not in (".cpp", ".hpp", ".h", ".in"):
                continue
            for n, line in enumerate(f.read_text(errors="replace").splitlines(), 1):
                m = INCLUDE.match(line)
                if not m or m.group(1) not in BELOW:
                    continue
                edges += 1
                if m.group(1) != layer and m.group(1) not in allowed:
                    bad.append(f"{f.relative_to(repo)}:{n}: {layer}/ includes {m.group(1)}/ (not below it)")
    long = []
    for folder in list(BELOW) + ["tests", "bench"]:
        for f in sorted((repo / folder).rglob("*")):
            if f.suffix in (".cpp", ".hpp", ".h"):
                n = len(f.read_text(errors="replace").splitlines())
                if n > MAX_LINES:
                    long.append(f"{f.relative_to(repo)}: {n} lines (over {MAX_LINES}): split it by job")
    for b in bad + long:
        print(b)
    print(f"check-structure: {edges} includes between folders read, {len(bad)} back-edges; "
          f"{len(long)} source files over {MAX_LINES} lines")
    return 1 if bad or long else 0

if __name__ == "__main__":
    sys.exit(main())
