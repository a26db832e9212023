#!/usr/bin/python3
"""Whole-pipeline sweep over the 19 dev meshes of ../shared/data: `curvefem run` end to end
(dense input -> curved mesh -> P_p Poisson with data painted on the input -> solution on every
input vertex), side by side with the dense-linear pipeline on the same case.

The case is made for each mesh from its bounding box (centre c, longest edge L): with
X = (x - c) / L, the manufactured solution u = sin(3 X1) cos(2 X2) exp(X3) (so every shape sees
about the same number of oscillations), f = -lap u = 12 u / L^2, Dirichlet data off the upward
normal cone (60 degrees) of the input and on that cone the flux grad u . n, written with the
input's normal (nx, ny, nz). Two runs per mesh, one after the other:
  curved  meshing.method curved, order K, degree P, eps (defaults 3, 3, 0.01);
  dense   meshing.method dense, degree 1 (the input tetrahedralized by Gmsh, P1).
From report.json: DOFs, tets, stage times, validity of the curved mesh, volume L2 error, error at
the dense input vertices and how many of them got no value. Goal of issue 7: >= 50x fewer DOFs
and >= 20x less total time at equal or better error.

Usage (from the repository root, after `tools/bootstrap build`):
  /usr/bin/python3 benchmarks/run_pipeline_sweep.py [--exe build/tools/curvefem/curvefem]
      [--meshes bunny.obj ...] [--order 3] [--degree 3] [--eps 0.01] [--timeout 900]
      [--work out-sweep] [--out benchmarks/results/pipeline_sweep.md]
One run at a time; `uptime` is recorded before each. Runs stay in --work; a final
"## Notes (hand-written, kept by run_pipeline_sweep.py)" section of the previous --out is kept.
"""
import argparse
import datetime
import functools
import json
import os
import shlex
import subprocess
import sys
import time

from manufactured import obj_bbox, scaled_solution

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NOTES_HEADER = "## Notes (hand-written, kept by run_pipeline_sweep.py)"
data = os.path.join(os.path.dirname(root), "shared", "data", "dev")

ap = argparse.ArgumentParser()
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--meshes", nargs="+")
ap.add_argument("--order", type=int, default=3)
ap.add_argument("--degree", type=int, default=3)
ap.add_argument("--eps", type=float, default=0.01)
ap.add_argument("--timeout", type=float, default=900)
ap.add_argument("--work", default=os.path.join(root, "out-sweep"))
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/pipeline_sweep.md"))
ap.add_argument("--reuse", action="store_true",
                help="keep the runs of WORK/sweep_runs.json whose case file is unchanged, except "
                "those of the methods given to --rerun")
ap.add_argument("--rerun", nargs="*", default=[], metavar="METHOD")
args = ap.parse_args()


def sh(cmd):
    return subprocess.run(cmd, shell=True, capture_output=True, text=True).stdout.strip()


def manifest():
    with open(os.path.join(data, "MANIFEST.tsv")) as f:
        rows = [line.rstrip("\n").split("\t") for line in f if line.strip()]
    head = rows[0]
    return [dict(zip(head, r)) for r in rows[1:]]


@functools.lru_cache(maxsize=None)
def bbox(path):  # read once per mesh (the curved and the dense case both need it)
    return obj_bbox(path)


def case(path, method):
    u, grad, f, _, L, _ = scaled_solution(*bbox(path))
    flux = "(%s)*nx + (%s)*ny + (%s)*nz" % tuple(grad)
    cone = {"normal": {"direction": [0, 0, 1], "angle": 60}}
    meshing = {"method": "dense"} if method == "dense" else \
        {"method": "curved", "order": args.order, "eps": args.eps}
    return {
        "geometry": {"surface": path},
        "meshing": meshing,
        "physics": {"type": "poisson"},
        "discretization": {"degree": 1 if method == "dense" else args.degree},
        "rhs": f,
        "boundary_conditions": [
            {"type": "dirichlet", "select": {"not": cone}, "value": u},
            {"type": "neumann", "select": cone, "value": flux}],
        "exact": u,
        "exact_gradient": grad,
    }


def previous_runs():
    try:
        with open(os.path.join(args.work, "sweep_runs.json")) as f:
            return {(r["name"], r["method"]): r for row in json.load(f) for r in row[1:]}
    except (OSError, ValueError, KeyError):
        return {}


PREVIOUS = previous_runs() if args.reuse else {}


def run(name, method, path):
    d = os.path.join(args.work, name)
    os.makedirs(d, exist_ok=True)
    spec = case(path, method)
    old = PREVIOUS.get((name, method))
    if old and old.get("case") == spec and method not in args.rerun and old.get("report"):
        old["reused"] = True
        print("%-22s %-6s reused" % (name, method), file=sys.stderr, flush=True)
        return old
    file = os.path.join(d, method + ".json")
    with open(file, "w") as f:
        json.dump(spec, f, indent=1)
    out = os.path.join(d, method)
    cmd = [args.exe, "run", "-q", file, "-o", out]
    load = sh("uptime")
    start = time.time()
    with open(os.path.join(d, method + ".log"), "w") as log:
        try:
            code = subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT,
                                  timeout=args.timeout).returncode
        except subprocess.TimeoutExpired:
            code = "timeout"
    wall = time.time() - start
    r = {"name": name, "method": method, "exit": code, "wall": wall, "uptime": load,
         "command": " ".join(shlex.quote(c) for c in cmd), "case": spec,
         "date": datetime.datetime.now().strftime("%Y-%m-%d %H:%M")}
    rep = os.path.join(out, "report.json")
    if code in (0, 3) and os.path.exists(rep):
        with open(rep) as f:
            r["report"] = json.load(f)
    else:
        with open(os.path.join(d, method + ".log")) as f:
            r["tail"] = " / ".join(f.read().strip().splitlines()[-2:])
    print("%-22s %-6s exit %s %.1f s" % (name, method, code, wall), file=sys.stderr, flush=True)
    return r


def times(rep):
    t = rep["time_s"]
    mesh = sum(t.get(k, 0.0) for k in ("load_surface", "meshing"))
    solve = sum(t.get(k, 0.0) for k in ("build_space", "assembly", "solve"))
    return mesh, solve, t["total"], t["total"] - t.get("errors", 0.0) - t.get("error_estimate", 0.0)


def g(x, spec="%.3g"):
    return "—" if x is None else spec % x


def main():
    rows = manifest()
    names = [r["file"] for r in rows]
    if args.meshes:
        names = [n for n in names if n in args.meshes]
    faces = {r["file"]: int(r["F"]) for r in rows}
    results = []
    for n in names:
        path = os.path.join(data, n)
        results.append((n, run(n[:-4], "curved", path), run(n[:-4], "dense", path)))
        with open(os.path.join(args.work, "sweep_runs.json"), "w") as f:
            json.dump([[n, c, d] for n, c, d in results], f, indent=1)

    head = sh("git -C %s rev-parse --short HEAD" % shlex.quote(root))
    dirty = " (+ uncommitted changes)" if sh("git -C %s status --porcelain -uno" %
                                             shlex.quote(root)) else ""
    lines = ["# Pipeline sweep: curved vs dense-linear `curvefem run` on the 19 dev meshes", "",
             "Generated %s by `/usr/bin/python3 benchmarks/run_pipeline_sweep.py %s`; HEAD %s%s; "
             "%s cores; one run at a time (curved, then dense, per mesh)." %
             (datetime.datetime.now().strftime("%Y-%m-%d %H:%M"), " ".join(sys.argv[1:]), head,
              dirty, sh("nproc")), "",
             "Case per mesh (bounding-box centre c, longest edge L, X = (x − c)/L): u = sin 3X₁ "
             "cos 2X₂ exp X₃, f = 12u/L², Dirichlet off the 60° upward normal cone of the input, "
             "flux ∇u·n on it with the input's normal (`nx, ny, nz`). curved: order %d, P%d, "
             "ε = %g (default options, deterministic coarsening); dense: the input tetrahedralized "
             "(Gmsh), P1. Times from report.json (meshing = load + meshing; solve = space + "
             "assembly + solve; total − errors leaves out the error integration). u is O(1) on every "
             "mesh, but the meshes differ in size: L2 = the absolute volume L2 error (compare "
             "the two pipelines on one mesh); surface L2 = the lumped L2 norm of the error over "
             "the dense input vertices (report.json `surface_l2_error`), surface max = the "
             "largest error there; unmapped = input vertices without a value." %
             (args.order, args.degree, args.eps), "",
             "| mesh | faces | method | exit | valid | DOFs | tets | meshing s | solve s | "
             "total − errors s | L2 error | surface L2 | surface max | unmapped |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    summary = []
    for n, c, d in results:
        for r in (c, d):
            rep = r.get("report")
            if rep:
                m, s, _, te = times(rep)
                valid = rep.get("mesh_valid") if r["method"] == "curved" else None
                lines.append("| %s | %d | %s | %s | %s | %d | %d | %.1f | %.1f | %.1f | %s | %s "
                             "| %s | %s |" % (
                                 n[:-4], faces[n], r["method"], r["exit"],
                                 "—" if valid is None else ("yes" if valid else "**no**"),
                                 rep["dofs"], rep["tets"], m, s, te, g(rep.get("l2_error")),
                                 g(rep.get("surface_l2_error")), g(rep.get("surface_max_error")),
                                 rep.get("surface_unmapped_vertices", "—")))
            else:
                lines.append("| %s | %d | %s | %s | | | | | | %.0f (wall) | | | | %s |" % (
                    n[:-4], faces[n], r["method"], r["exit"], r["wall"],
                    r.get("tail", "").replace("|", "/")[:160]))
        cr, dr = c.get("report"), d.get("report")
        if cr and dr:
            summary.append((n[:-4], dr["dofs"] / cr["dofs"], times(dr)[3] / times(cr)[3],
                            cr["l2_error"] / dr["l2_error"]))
    lines += ["", "## Ratios dense / curved (goal: DOFs ≥ 50×, time ≥ 20×, L2 curved / dense "
              "≤ 1)", "", "| mesh | DOFs | total − errors | L2 curved / dense | goal met |",
              "|---|---|---|---|---|"]
    met = 0
    for n, rd, rt, re in summary:
        ok = rd >= 50 and rt >= 20 and re <= 1
        met += ok
        lines.append("| %s | %.2f× | %.2f× | %.3g | %s |" % (n, rd, rt, re, "yes" if ok else "no"))
    both = len(summary)
    lines += ["", "Both pipelines finished on %d of %d meshes; goal met on %d of them. Curved DOFs "
              "below dense on %d, error at most dense's on %d, at least 20× faster on %d." % (
                  both, len(results), met, sum(rd > 1 for _, rd, _, _ in summary),
                  sum(re <= 1 for _, _, _, re in summary),
                  sum(rt >= 20 for _, _, rt, _ in summary)), "", "## Runs", ""]
    for n, c, d in results:
        for r in (c, d):
            lines.append("- `%s` (exit %s, wall %.1f s)%s — load before: `%s`" % (
                r["command"], r["exit"], r["wall"],
                " *reused* (run %s)" % r.get("date", "earlier") if r.get("reused") else "",
                r["uptime"]))
    try:  # the hand-written notes of the previous file are kept
        with open(args.out) as f:
            old = f.read()
        if NOTES_HEADER in old:
            lines += ["", old[old.index(NOTES_HEADER):].rstrip()]
    except OSError:
        pass
    with open(args.out + ".tmp", "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(args.out + ".tmp", args.out)
    print("wrote", args.out, file=sys.stderr)


main()
