#!/usr/bin/python3
"""Issue 16's soak test: damaged captures through `replay` and `capture info`.

Makes N byte-mutated copies of a valid capture (1-8 random bytes overwritten
each; most of them in the file's HDF5 metadata — superblock, object headers,
B-trees, heaps — where libhdf5 has crashed on damaged files, the rest anywhere),
then
  1. replays them in batches of B (`piezobench replay BATCH --out R.h5 --jsonl
     L --jobs J`), checks that every batch process ends with exit 0 or 2 (never
     a signal, never 1), that every file of the batch has a record (ok, or failed
     with a message), and that a second run of the same command (the resume)
     completes with every file "done before" or replayed again;
  2. runs `piezobench capture info FILE` on every mutant and checks that it
     ends with exit 0 or 2, never a signal.
Prints a summary and exits non-zero on any violation.

  /usr/bin/python3 scripts/mutation-soak.py --cli build/ui/piezobench \
      --capture CAP.h5 --count 10000 --batch 100 --jobs 2 --work /tmp/soak [--resume]
Each batch is checked whole (replay, resume, capture info) and marked
batchNNNN.done; --resume goes on from the first batch not marked; --first-batch K
starts a run (on another machine, say) at batch K with the same mutants as a run from 0.
"""
import argparse
import json
import os
import random
import shutil
import subprocess
import sys
import time


def raw_data_ranges(path):
    """Byte ranges of the datasets' raw data (h5py), to tell metadata from samples."""
    try:
        import h5py
    except ImportError:
        print("soak: no h5py in this python (use /usr/bin/python3, Debian's python3-h5py):"
              " mutating bytes uniformly, not mostly metadata", file=sys.stderr)
        return []
    ranges = []
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                if obj.chunks is not None:  # chunked (often compressed): each chunk's bytes
                    for i in range(obj.id.get_num_chunks()):
                        c = obj.id.get_chunk_info(i)
                        ranges.append((c.byte_offset, c.byte_offset + c.size))
                    return
                off = obj.id.get_offset()
                if off is not None:
                    ranges.append((off, off + obj.id.get_storage_size()))
        f.visititems(visit)
    return sorted(ranges)


def replay_batch(a, d, files):
    """Replay one batch twice (the run, then the resume); returns (counts, violations)."""
    counts = {"ok": 0, "failed": 0, "crashed": 0, "hung": 0}
    bad = []
    out, jl = d + "-results.h5", d + ".jsonl"
    for f in (out, jl):
        if os.path.exists(f):
            os.remove(f)
    cmd = [a.cli, "replay", d, "--out", out, "--jsonl", jl, "--jobs", str(a.jobs),
           "--timeout", str(a.timeout), "--json"]
    p = subprocess.run(cmd, capture_output=True, text=True, errors="replace")
    if p.returncode not in (0, 2):
        return counts, ["replay %s: exit %d: %s" % (d, p.returncode, p.stderr[-400:])]
    shutil.copyfile(jl, d + ".first.jsonl")  # the resume below rewrites jl
    lines = [json.loads(x) for x in open(jl)]
    seen = {os.path.basename(x["path"]) for x in lines}
    if len(lines) != len(seen):
        twice = sorted({os.path.basename(x["path"]) for x in lines
                        if sum(1 for y in lines if y["path"] == x["path"]) > 1})
        bad.append("replay %s: %d records for %d files (twice: %s)" % (d, len(lines), len(seen), twice[:5]))
    missing = [f for f in files if f not in seen]
    if missing:
        bad.append("replay %s: no record for %s" % (d, missing[:5]))
    for x in lines:
        if x["status"] == "ok":
            counts["ok"] += 1
        else:
            counts["failed"] += 1
            kind = x.get("error", {}).get("kind", "")
            if kind in ("crashed", "hung"):
                counts[kind] += 1
            if not x.get("error", {}).get("message"):
                bad.append("replay %s: failed record without a message" % x["path"])
    p2 = subprocess.run(cmd, capture_output=True, text=True, errors="replace")  # the resume
    if p2.returncode not in (0, 2):
        bad.append("resume %s: exit %d: %s" % (d, p2.returncode, p2.stderr[-400:]))
    else:
        j = json.loads(p2.stdout)
        if j["total"] != len(files) or j["done_before"] + j["replayed"] + j["failed"] != len(files):
            bad.append("resume %s: %s" % (d, p2.stdout.strip()))
    return counts, bad


def info_batch(a, d, files):
    """`capture info` on every file of one batch; returns (exit-code counts, violations)."""
    codes, bad = {}, []
    for f in files:
        p = subprocess.run([a.cli, "capture", "info", os.path.join(d, f)],
                           capture_output=True, text=True, errors="replace")
        codes[str(p.returncode)] = codes.get(str(p.returncode), 0) + 1
        if p.returncode not in (0, 2):
            bad.append("capture info %s/%s: exit %d %s" % (d, f, p.returncode, p.stderr[-300:]))
    return codes, bad


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", required=True)
    ap.add_argument("--capture", required=True)
    ap.add_argument("--count", type=int, default=10000)
    ap.add_argument("--batch", type=int, default=100)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--seed", type=int, default=16)
    ap.add_argument("--timeout", type=float, default=120,
                    help="replay --timeout: seconds before a hung worker is killed (the mutants are small)")
    ap.add_argument("--work", required=True)
    ap.add_argument("--metadata-share", type=float, default=0.9)
    ap.add_argument("--skip-replay", action="store_true")
    ap.add_argument("--skip-info", action="store_true")
    ap.add_argument("--first-batch", type=int, default=0,
                    help="start at this batch: the earlier mutants are drawn (so the later ones are the "
                         "same as in a run from 0) but neither written nor replayed — to go on with "
                         "the same series on another machine")
    ap.add_argument("--resume", action="store_true",
                    help="keep WORK and the batches already checked (batchNNNN.done); "
                         "the mutants are the same for the same --seed, --count and --batch")
    a = ap.parse_args()

    data = open(a.capture, "rb").read()
    raw = raw_data_ranges(a.capture)
    meta = [i for i in range(len(data)) if not any(lo <= i < hi for lo, hi in raw)] if raw else []
    rng = random.Random(a.seed)
    if os.path.exists(a.work) and not a.resume:
        shutil.rmtree(a.work)
    os.makedirs(a.work, exist_ok=True)
    batches = []
    for b in range(0, a.count, a.batch):
        keep = b // a.batch >= a.first_batch
        d = os.path.join(a.work, "batch%04d" % (b // a.batch))
        if keep:
            os.makedirs(d, exist_ok=True)
        for k in range(b, min(a.count, b + a.batch)):
            m = bytearray(data)
            for _ in range(rng.randint(1, 8)):
                pos = rng.choice(meta) if meta and rng.random() < a.metadata_share else rng.randrange(len(m))
                m[pos] = rng.randrange(256)
            f = os.path.join(d, "m%05d.h5" % k)
            if keep and not os.path.exists(f):
                open(f, "wb").write(m)
        if keep:
            batches.append(d)
    print("soak: mutants %d..%d of %d of %s (%d bytes, %d of metadata) in %d batches"
          % (a.first_batch * a.batch, a.count - 1, a.count, a.capture, len(data), len(meta), len(batches)),
          flush=True)

    bad = []
    counts = {"ok": 0, "failed": 0, "crashed": 0, "hung": 0}
    codes = {}
    deaths = 0
    t0 = time.time()
    for i, d in enumerate(batches):
        files = sorted(f for f in os.listdir(d) if f.endswith(".h5"))
        done = d + ".done"
        if a.resume and os.path.exists(done):
            r = json.load(open(done))
        else:
            r = {"counts": {}, "codes": {}, "violations": []}
            if not a.skip_replay:
                c, v = replay_batch(a, d, files)
                r["counts"] = c
                r["violations"] += v
            if not a.skip_info:
                c, v = info_batch(a, d, files)
                r["codes"] = c
                r["violations"] += v
            json.dump(r, open(done, "w"))
        for k, n in r["counts"].items():
            counts[k] += n
        for k, n in r["codes"].items():
            codes[k] = codes.get(k, 0) + n
        bad += r["violations"]
        deaths += sum(1 for x in r["violations"] if x.startswith("replay") and "exit" in x)
        print("batch %d/%d (%.0f s): replay ok %d, failed %d (crashed %d, hung %d), batch deaths %d;"
              " capture info exit codes %s; violations %d"
              % (i + 1, len(batches), time.time() - t0, counts["ok"], counts["failed"],
                 counts["crashed"], counts["hung"], deaths, dict(sorted(codes.items())), len(bad)),
              flush=True)

    for x in bad[:20]:
        print("VIOLATION:", x)
    print("soak: %d files, replay ok %d / failed %d (crashed %d, hung %d), batch deaths %d; "
          "capture info exit codes %s; %d violation(s)"
          % (sum(len([f for f in os.listdir(d) if f.endswith(".h5")]) for d in batches),
             counts["ok"], counts["failed"], counts["crashed"], counts["hung"], deaths,
             dict(sorted(codes.items())), len(bad)))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
