#!/usr/bin/python3
"""The curved-aware coarsening's local repair against the re-coarsening it replaces (issue 21's
time target, issue 22's "coarsening without discarded attempts"), on the dev meshes.

For every mesh and order K it runs, side by side in one run (the two modes alternate which goes
first from mesh to mesh):
  repair      `curvefem mesh INPUT -o DIR --order K --eps EPS -q --threads T` (the default: after a
              miss the last coarse shell is repaired by splits, SimplifyOptions::repair)
  re-coarsen  the same with --no-curved-repair (after a miss the input is coarsened again)
and, once per mesh, the peer a user would otherwise run: Gmsh's tetrahedralization of the dense
input itself, boundary unchanged (`tetfill_tool`, built with `ninja -C build
benchmarks/tetfill_tool`; whole-process wall time). Every validity figure comes from the run's
report.json, whose guarantees the independent validator computed.

Usage (from the repository root):
  /usr/bin/python3 benchmarks/run_repair.py [--meshes spot.obj ...] [--orders 3] [--eps 0.01]
      [--threads 2] [--timeout 900] [--exe build/tools/curvefem/curvefem] [--note TEXT]
Writes benchmarks/results/repair.md; raw JSON lines go to /tmp/repair_runs.jsonl.
Standard library only.
"""
import argparse
import datetime
import json
import os
import shlex
import statistics
import subprocess
import sys
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--data", default="/work/shared/data/dev")
ap.add_argument("--meshes", nargs="+")
ap.add_argument("--orders", nargs="+", type=int, default=[3])
ap.add_argument("--eps", type=float, default=0.01)
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--timeout", type=float, default=900)
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--tetfill-tool", default=os.path.join(root, "build/benchmarks/tetfill_tool"))
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/repair.md"))
ap.add_argument("--work", default="/tmp/repair_bench")
ap.add_argument("--note", default="")
args = ap.parse_args()
command = "/usr/bin/python3 " + " ".join(
    shlex.quote(a) for a in ["benchmarks/run_repair.py"] + sys.argv[1:])


def manifest():
    with open(os.path.join(args.data, "MANIFEST.tsv")) as f:
        rows = [l.rstrip("\n").split("\t") for l in f if l.strip()]
    return [dict(zip(rows[0], r)) for r in rows[1:]]


def run(cmd):
    start = time.time()
    try:
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           timeout=args.timeout)
        code = p.returncode
        out = p.stdout
    except subprocess.TimeoutExpired:
        code, out = "timeout", ""
    return code, time.time() - start, out


def mesh_run(path, out_dir, k, extra):
    subprocess.run(["rm", "-rf", out_dir])
    code, secs, _ = run([args.exe, "mesh", path, "-o", out_dir, "--order", str(k), "--eps",
                         str(args.eps), "-q", "--threads", str(args.threads)] + extra)
    rec = {"exit": code, "seconds": secs}
    try:
        with open(os.path.join(out_dir, "report.json")) as f:
            r = json.load(f)
    except (OSError, ValueError):
        return rec
    c = r.get("coarsening", {})
    rec.update(valid=r.get("valid"), faces=r.get("output_boundary_faces"),
               tets=r.get("output_tets"), min_sj=r.get("min_scaled_jacobian"),
               max_distance=r.get("max_distance_rel"), attempts=c.get("curved_attempts"),
               repairs=c.get("curved_repairs"), repair_failures=c.get("repair_failures"),
               repair_splits=c.get("repair_splits"),
               discarded=sum(v for s, v in r.get("time_s", {}).items()
                             if s.startswith("discarded")))
    return rec


def main():
    meshes = [m["file"] for m in manifest()]
    if args.meshes:
        meshes = [m for m in meshes if m in args.meshes]
    os.makedirs(args.work, exist_ok=True)
    raw = open("/tmp/repair_runs.jsonl", "a")
    records = []
    for i, mesh in enumerate(meshes):
        name = os.path.splitext(mesh)[0]
        path = os.path.join(args.data, mesh)
        dense = None
        if os.path.exists(args.tetfill_tool):
            code, secs, _ = run([args.tetfill_tool, path, "--threads", str(args.threads)])
            dense = secs if code == 0 else None
        for k in args.orders:
            modes = [("repair", []), ("recoarsen", ["--no-curved-repair"])]
            if i % 2:
                modes.reverse()
            rec = {"mesh": name, "order": k, "dense_s": dense}
            for label, extra in modes:
                rec[label] = mesh_run(path, os.path.join(args.work, "%s_k%d_%s" % (name, k, label)),
                                      k, extra)
            records.append(rec)
            raw.write(json.dumps(rec) + "\n")
            raw.flush()
            print(json.dumps(rec), flush=True)
    render(records)


def fmt(x, spec="%.3g"):
    return "" if x is None else spec % x


def render(records):
    lines = ["# Local repair of the curved-aware coarsening against re-coarsening (issues 21, 22)", ""]
    lines.append("Generated %s by `%s` on %d cores; eps = %g of the longest bbox edge, %d threads. %s"
                 % (datetime.datetime.now().strftime("%Y-%m-%d %H:%M"), command, os.cpu_count(),
                    args.eps, args.threads, args.note))
    lines.append("")
    lines.append("repair = `curvefem mesh` defaults (a miss after the curved-aware coarsening is "
                 "repaired by splitting the coarse faces that missed); re-coarsen = "
                 "`--no-curved-repair` (the input is coarsened again). attempts = curved-aware "
                 "attempts run (1: no miss); repairs = of them, repairs (failed: a repair that could "
                 "not reach the bound and coarsened again). Gmsh dense = `tetfill_tool` on the input "
                 "(whole process). valid, faces, min SJ, distance: report.json (independent "
                 "validator).")
    lines.append("")
    lines.append("| mesh | K | attempts (repairs / failed) | splits | faces repair / re-coarsen | "
                 "valid | min SJ repair / re-coarsen | max dist | time s repair / re-coarsen | "
                 "ratio | Gmsh dense s | repair / Gmsh |")
    lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
    ratios, touched = [], []
    for r in records:
        a, b = r["repair"], r["recoarsen"]
        ratio = b["seconds"] / a["seconds"] if a.get("seconds") else None
        if (a.get("repairs") or 0) > 0:
            touched.append(ratio)
        ratios.append(ratio)
        lines.append("| %s | %d | %s (%s / %s) | %s | %s / %s | %s / %s | %s / %s | %s | %.1f / %.1f "
                     "| %s | %s | %s |" % (
                         r["mesh"], r["order"], a.get("attempts"), a.get("repairs"),
                         a.get("repair_failures"), a.get("repair_splits"), a.get("faces"),
                         b.get("faces"), "yes" if a.get("valid") else "NO (exit %s)" % a["exit"],
                         "yes" if b.get("valid") else "NO (exit %s)" % b["exit"],
                         fmt(a.get("min_sj")), fmt(b.get("min_sj")), fmt(a.get("max_distance")),
                         a["seconds"], b["seconds"], fmt(ratio, "%.2f"),
                         fmt(r.get("dense_s"), "%.1f"),
                         fmt(a["seconds"] / r["dense_s"] if r.get("dense_s") else None, "%.2f")))
    lines.append("")
    valid = sum(1 for r in records if r["repair"].get("valid"))
    lines.append("- Valid with repair: %d of %d runs; re-coarsen: %d of %d." % (
        valid, len(records), sum(1 for r in records if r["recoarsen"].get("valid")), len(records)))
    if touched:
        lines.append("- Runs where a repair ran: %d; re-coarsen / repair time median %.2f (min %.2f, "
                     "max %.2f)." % (len(touched), statistics.median(touched), min(touched),
                                     max(touched)))
    rep = [r["repair"]["seconds"] for r in records]
    rec = [r["recoarsen"]["seconds"] for r in records]
    if rep:
        lines.append("- Median time over these runs: repair %.1f s, re-coarsen %.1f s." % (
            statistics.median(rep), statistics.median(rec)))
    with open(args.out, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("wrote", args.out)


if __name__ == "__main__":
    main()
