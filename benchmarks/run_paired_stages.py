#!/usr/bin/env python3
"""Two `curvefem` binaries side by side on the same surfaces: whole-run and per-stage seconds.

For every surface and order the two binaries run `curvefem mesh` one after the other (which goes
first alternates between repeats, so drift of a shared machine hits both), each with the same
options; the table gives the medians of report.json's `time_s` per binary and their ratio, and
whether the outputs are byte-identical (mesh.msh and boundary_map.json), which is what a change
that only makes the same computation faster must show.

    /usr/bin/python3 benchmarks/run_paired_stages.py --a OLD --b NEW --label-a before \
        --label-b after --orders 3 4 --repeat 2 --work /tmp/paired --out OUT.md \
        --files ../shared/data/dev/elephant.obj ...
"""
import argparse
import datetime
import filecmp
import json
import os
import shlex
import shutil
import statistics
import subprocess
import sys

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--a", required=True, help="first binary (the reference)")
ap.add_argument("--b", required=True, help="second binary")
ap.add_argument("--label-a", default="a")
ap.add_argument("--label-b", default="b")
ap.add_argument("--files", nargs="+", required=True)
ap.add_argument("--orders", nargs="+", type=int, default=[3])
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--repeat", type=int, default=1)
ap.add_argument("--timeout", type=int, default=1800)
ap.add_argument("--extra", default="", help="more `curvefem mesh` options, one string")
ap.add_argument("--stages", nargs="+", default=["optimize", "thicken", "validate"],
                help="report.json time_s stages given their own columns")
ap.add_argument("--work", required=True)
ap.add_argument("--out", required=True)
args = ap.parse_args()

os.makedirs(args.work, exist_ok=True)
started = datetime.datetime.now()


def run(binary, surface, order, out):
    shutil.rmtree(out, ignore_errors=True)  # no earlier run's files can stand in for this one's
    cmd = [binary, "mesh", surface, "-o", out, "--order", str(order), "-q",
           "--threads", str(args.threads)] + shlex.split(args.extra)
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
    report = os.path.join(out, "report.json")
    if proc.returncode != 0 or not os.path.exists(report):
        return {"exit": proc.returncode, "error": (proc.stderr or proc.stdout)[-300:]}
    with open(report) as f:
        rep = json.load(f)
    return {"exit": 0, "time": rep.get("time_s", {}), "faces": rep.get("coarse_faces"),
            "tets": rep.get("output_tets")}


def identical(da, db):
    return all(os.path.exists(os.path.join(d, n)) for d in (da, db)
               for n in ("mesh.msh", "boundary_map.json")) and all(
        filecmp.cmp(os.path.join(da, n), os.path.join(db, n), shallow=False)
        for n in ("mesh.msh", "boundary_map.json"))


def med(runs, stage):
    vals = [r["time"].get(stage, 0.0) for r in runs if r["exit"] == 0]
    return statistics.median(vals) if vals else None


def fmt(x):
    return "–" if x is None else "%.2f" % x


rows = []
for surface in args.files:
    name = os.path.splitext(os.path.basename(surface))[0]
    for order in args.orders:
        res = {"a": [], "b": []}
        same = True
        for rep in range(args.repeat):
            outs = {}
            for side in (("a", "b") if rep % 2 == 0 else ("b", "a")):
                binary = args.a if side == "a" else args.b
                outs[side] = os.path.join(args.work, "%s_k%d_%s" % (name, order, side))
                res[side].append(run(binary, surface, order, outs[side]))
            ok = res["a"][-1]["exit"] == 0 and res["b"][-1]["exit"] == 0
            same = same and ok and identical(outs["a"], outs["b"])
        rows.append((name, order, res, same))
        ta, tb = med(res["a"], "total"), med(res["b"], "total")
        print("%s K=%d: %s -> %s s, same %s" % (name, order, fmt(ta), fmt(tb), same),
              file=sys.stderr, flush=True)


lines = [
    "# `curvefem mesh`: %s → %s, stage by stage" % (args.label_a, args.label_b),
    "",
    "Written by `benchmarks/run_paired_stages.py` on %s. Command: `/usr/bin/python3 "
    "benchmarks/run_paired_stages.py %s`." % (started.strftime("%Y-%m-%d %H:%M"),
                                               " ".join(shlex.quote(a) for a in sys.argv[1:])),
    "",
    "Medians of %d paired run(s) per surface and order (the two binaries one after the other, "
    "the first alternating), %d thread(s); report.json `time_s` (process start-up not included). "
    "same = mesh.msh and boundary_map.json byte-identical in every pair." % (
        args.repeat, args.threads),
    "",
    "| surface | K | coarse faces | tets | same | whole s %s → %s | ratio | %s |" % (
        args.label_a, args.label_b, " | ".join("%s s" % s for s in args.stages)),
    "|---|---|---|---|---|---|---|%s" % ("---|" * len(args.stages)),
]
ratios = []
for name, order, res, same in rows:
    ok = [r for r in res["b"] if r["exit"] == 0]
    oka = [r for r in res["a"] if r["exit"] == 0]
    if not ok or not oka:
        lines.append("| %s | %d | – | – | – | exit %s / %s | | %s |" % (
            name, order, res["a"][-1]["exit"], res["b"][-1]["exit"],
            " | ".join("" for _ in args.stages)))
        continue
    ta, tb = med(res["a"], "total"), med(res["b"], "total")
    ratios.append(tb / ta)
    lines.append("| %s | %d | %s | %s | %s | %.1f → %.1f | %.2f | %s |" % (
        name, order, ok[-1]["faces"], ok[-1]["tets"], "yes" if same else "NO", ta, tb, tb / ta,
        " | ".join("%s → %s" % (fmt(med(res["a"], s)), fmt(med(res["b"], s)))
                   for s in args.stages)))
if ratios:
    lines += ["", "- Whole run %s / %s: median %.2f (%.2f–%.2f) over %d runs; identical outputs "
              "on %d of %d." % (args.label_b, args.label_a, statistics.median(ratios),
                                min(ratios), max(ratios), len(ratios),
                                sum(1 for r in rows if r[3]), len(rows))]
with open(args.out, "w") as f:
    f.write("\n".join(lines) + "\n")
print("wrote", args.out, file=sys.stderr)
