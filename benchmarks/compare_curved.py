#!/usr/bin/env python3
"""Before/after table of two run_curved.py runs (same meshes, same order).

Reads the raw JSON lines each run wrote (run_curved.py appends them to /tmp/curved_runs.jsonl;
copy each run's lines to its own file) and, with --before-work/--after-work, the runs' output
directories, to say whether the meshes are byte-identical (mesh.msh and boundary_map.json).

    /usr/bin/python3 benchmarks/compare_curved.py --before B.jsonl --after A.jsonl \
        --before-work /tmp/cb_before --after-work /tmp/cb_after --out OUT.md
"""
import argparse
import datetime
import filecmp
import json
import os
import shlex
import statistics
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from curved_stages import coarsening_seconds  # noqa: E402

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--before", required=True)
ap.add_argument("--after", required=True)
ap.add_argument("--before-work")
ap.add_argument("--after-work")
ap.add_argument("--label-before", default="before")
ap.add_argument("--label-after", default="after")
ap.add_argument("--note", default="")
ap.add_argument("--before-overlapping-stages", action="store_true",
                help="the before binary predates cf2f4f1, whose report.json counted the linear "
                     "phase inside `coarsen` too: count it once")
ap.add_argument("--out", required=True)
args = ap.parse_args()


def command_line():
    """This call's arguments, quoted, with the note's text left out (it follows below)."""
    out, skip = [], False
    for a in sys.argv[1:]:
        if skip:
            out.append("'...'")
            skip = False
            continue
        skip = a == "--note"
        out.append(shlex.quote(a))
    return " ".join(out)


def load(path):
    out = {}
    with open(path) as f:
        for line in f:
            r = json.loads(line)
            out[(r["mesh"], r["order"])] = r
    return out


def fmt(x, f="%.2f"):
    return f % x if isinstance(x, (int, float)) else "–"


def identical(key):
    if not (args.before_work and args.after_work):
        return None
    d = "%s_k%d" % key
    same = True
    for name in ("mesh.msh", "boundary_map.json"):
        a = os.path.join(args.before_work, d, name)
        b = os.path.join(args.after_work, d, name)
        if not (os.path.exists(a) and os.path.exists(b)):
            return None
        same = same and filecmp.cmp(a, b, shallow=False)
    return same


before, after = load(args.before), load(args.after)
keys = [k for k in after if k in before]
head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                      cwd=os.path.dirname(os.path.abspath(__file__))).stdout.strip()
w = ["# Curved meshing time: %s → %s\n" % (args.label_before, args.label_after),
     "Generated %s by `%s`; HEAD %s.\n" % (
         datetime.datetime.now().strftime("%Y-%m-%d %H:%M"),
         "/usr/bin/python3 benchmarks/compare_curved.py " + command_line(), head)]
if args.note:
    w.append(args.note + "\n")
w.append("Whole `curvefem mesh` runs (report.json `time_s.total`: curving, validation and map "
         "roundtrip included; process start-up not). Coarsening = every coarsening stage and "
         "discarded attempt (run_curved.coarsening_seconds). Gmsh dense = Gmsh's "
         "tetrahedralization of the input itself in the after run (tetfill_tool, "
         "`gmsh_seconds`). Same = mesh.msh and boundary_map.json byte-identical.\n")
w.append("| mesh | K | input F | coarse F before → after | same | whole s before → after | "
         "speed-up | coarsening s before → after | Gmsh dense s | after / dense |")
w.append("|---|---|---|---|---|---|---|---|---|---|")
ups, cups, over = [], [], []
for key in keys:
    b, a = before[key]["report"] or {}, after[key]["report"] or {}
    tb, ta = b.get("time_s", {}).get("total"), a.get("time_s", {}).get("total")
    cb, ca = coarsening_seconds(b), coarsening_seconds(a)
    if cb and args.before_overlapping_stages:
        cb -= b.get("time_s", {}).get("coarsen (linear phase)", 0.0)
    dense = (after[key].get("dense") or {}).get("gmsh_seconds")
    up = tb / ta if tb and ta else None
    if up:
        ups.append(up)
    if cb and ca:
        cups.append(cb / ca)
    if ta and dense:
        over.append((key[0], ta / dense))
    same = identical(key)
    w.append("| %s | %d | %s | %s → %s | %s | %s → %s | %s | %s → %s | %s | %s |" % (
        key[0], key[1], a.get("input_faces", "–"), b.get("coarse_faces", "–"),
        a.get("coarse_faces", "–"), {True: "yes", False: "NO", None: "?"}[same],
        fmt(tb, "%.1f"), fmt(ta, "%.1f"), fmt(up, "%.2fx"), fmt(cb, "%.1f"), fmt(ca, "%.1f"),
        fmt(dense, "%.2f"), fmt(ta / dense if ta and dense else None, "%.1f")))
w.append("")
if ups:
    w.append("- Whole run: median speed-up %.2fx (%.2f–%.2fx) over %d meshes." % (
        statistics.median(ups), min(ups), max(ups), len(ups)))
if cups:
    w.append("- Coarsening: median speed-up %.2fx (%.2f–%.2fx)." % (
        statistics.median(cups), min(cups), max(cups)))
if over:
    met = [m for m, x in over if x <= 1]
    w.append("- Curved meshing no slower than Gmsh's dense tetrahedralization of the same input "
             "on %d of %d meshes (%s); median whole run / dense %.1f." % (
                 len(met), len(over), ", ".join(met) or "none",
                 statistics.median(x for _, x in over)))
with open(args.out, "w") as f:
    f.write("\n".join(w) + "\n")
print("\n".join(w))
