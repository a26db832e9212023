#!/usr/bin/python3
"""The coarse-linear peer (issue 22): what a user who wants a coarse mesh today would run, against
the curved pipeline, at equal distance bounds and compared at equal DOFs.

Peer: CGAL Mesh_3 on the polyhedral input (Debian python3-pygalmesh,
`generate_volume_mesh_from_surface_mesh` with max_facet_distance = ε × the longest bbox edge,
min_facet_angle 25°, max_circumradius_edge_ratio 3, no cell size), written as Gmsh 4.1 with
meshio, then P2 on its straight tets through `curvefem run` (`meshing.method` given).
Curved: `curvefem run` on the dense input, `meshing.method` curved, order 3, P2 and P3, at the
same ε. Both solve the same manufactured Poisson problem, -Δu = f with u = sin(3x/L) cos(2y/L)
e^(z/L) (L the longest bbox edge, coordinates from the bbox centre), Dirichlet u on the whole
boundary, the data painted on the input: the curved run reads them at φ⁻¹(x) (its bijective
map), the peer at the closest point of the input (`geometry.data_surface`), as a user with data
on the dense surface would transfer them.
Errors are curvefem's L2 error against the exact u on each run's own domain (report.json), so
both include their geometric error; DOFs and whole-run times (the peer: Mesh_3 + the run).

Usage (from the repository root):
  /usr/bin/python3 benchmarks/run_coarse_linear.py [--meshes spot.obj bunny.obj ...]
      [--eps 0.02 0.01 0.005] [--exe build/tools/curvefem/curvefem] [--threads 2]
Writes benchmarks/results/coarse_linear.md. Needs python3-pygalmesh and python3-meshio.
"""
import argparse
import datetime
import json
import math
import os
import shlex
import subprocess
import sys
import time

import meshio
import numpy as np
import pygalmesh

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--data", default="/work/shared/data/dev")
ap.add_argument("--meshes", nargs="+", default=["spot.obj", "bunny.obj", "fertility.obj",
                                                 "rocker_arm.obj"])
ap.add_argument("--eps", nargs="+", type=float, default=[0.02, 0.01, 0.005])
ap.add_argument("--degrees", nargs="+", type=int, default=[2, 3])
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--timeout", type=float, default=1800)
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/coarse_linear.md"))
ap.add_argument("--work", default="/tmp/coarse_linear_bench")
ap.add_argument("--note", default="")
args = ap.parse_args()
command = "/usr/bin/python3 " + " ".join(
    shlex.quote(a) for a in ["benchmarks/run_coarse_linear.py"] + sys.argv[1:])


def problem(vertices):
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    c, L = (lo + hi) / 2, float((hi - lo).max())
    X = "((x-(%.17g))/%.17g)" % (c[0], L)
    Y = "((y-(%.17g))/%.17g)" % (c[1], L)
    Z = "((z-(%.17g))/%.17g)" % (c[2], L)
    u = "sin(3*%s)*cos(2*%s)*exp(%s)" % (X, Y, Z)
    # -Δu = (9 + 4 - 1) u / L²
    f = "%.17g*%s" % (12.0 / (L * L), u)
    return u, f


def run_case(case, out):
    path = out + ".json"
    with open(path, "w") as fh:
        json.dump(case, fh, indent=1)
    start = time.time()
    try:
        p = subprocess.run([args.exe, "run", path, "-o", out, "-q", "--threads", str(args.threads)],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           timeout=args.timeout)
        code = p.returncode
        err = p.stderr.strip().splitlines()[-1] if p.stderr.strip() else ""
    except subprocess.TimeoutExpired:
        code, err = "timeout", ""
    seconds = time.time() - start
    try:
        with open(os.path.join(out, "report.json")) as fh:
            rep = json.load(fh)
    except (OSError, ValueError):
        rep = {}
    return code, seconds, rep, err


def rel_l2(rep):
    if "l2_error" in rep and rep.get("l2_norm_exact", 0) > 0:
        return rep["l2_error"] / rep["l2_norm_exact"]
    return None


os.makedirs(args.work, exist_ok=True)
rows = []
for mesh in args.meshes:
    name = os.path.splitext(mesh)[0]
    src = os.path.join(args.data, mesh)
    surf = meshio.read(src)
    V = surf.points
    u, f = problem(V)
    L = float((V.max(axis=0) - V.min(axis=0)).max())
    off = os.path.join(args.work, name + ".off")
    meshio.write(off, meshio.Mesh(V, [("triangle", surf.get_cells_type("triangle"))]))
    for eps in args.eps:
        # Peer: Mesh_3 + P2 on straight tets.
        tag = "%s_eps%g" % (name, eps)
        start = time.time()
        try:
            vol = pygalmesh.generate_volume_mesh_from_surface_mesh(
                off, min_facet_angle=25.0, max_facet_distance=eps * L,
                max_circumradius_edge_ratio=3.0, verbose=False, seed=1)
            tets = vol.get_cells_type("tetra")
            msh = os.path.join(args.work, tag + "_mesh3.msh")
            meshio.write(msh, meshio.Mesh(vol.points, [("tetra", tets)]), file_format="gmsh")
            peer_mesh_s = time.time() - start
            code, s, rep, err = run_case({
                "geometry": {"mesh": msh, "data_surface": src}, "meshing": {"method": "given"},
                "physics": {"type": "poisson"}, "discretization": {"degree": 2},
                "rhs": f, "exact": u,
                "boundary_conditions": [{"type": "dirichlet", "select": {"all": True},
                                         "value": u}]}, os.path.join(args.work, tag + "_peer"))
            rows.append({"mesh": name, "eps": eps, "method": "Mesh_3 + P2", "tets": len(tets),
                         "dofs": rep.get("dofs"), "l2": rel_l2(rep), "code": code,
                         "seconds": peer_mesh_s + s, "mesh_seconds": peer_mesh_s, "error": err})
        except Exception as e:  # a failed peer run is a row, not the end of the benchmark
            rows.append({"mesh": name, "eps": eps, "method": "Mesh_3 + P2", "code": "error",
                         "error": str(e)[:120], "seconds": time.time() - start})
        print(rows[-1], flush=True)
        # Curved, order 3, P2 and P3.
        for p in args.degrees:
            code, s, rep, err = run_case({
                "geometry": {"surface": src, "features": "none"},
                "meshing": {"method": "curved", "order": 3, "eps": eps},
                "physics": {"type": "poisson"}, "discretization": {"degree": p},
                "rhs": f, "exact": u,
                "boundary_conditions": [{"type": "dirichlet", "select": {"all": True},
                                         "value": u}]},
                os.path.join(args.work, "%s_curved_p%d" % (tag, p)))
            rows.append({"mesh": name, "eps": eps, "method": "curved k=3 P%d" % p,
                         "tets": rep.get("tets"), "dofs": rep.get("dofs"), "l2": rel_l2(rep),
                         "code": code, "seconds": s,
                         "mesh_seconds": (rep.get("time_s") or {}).get("meshing"),
                         "error": err})
            print(rows[-1], flush=True)


def peer_at(mesh, dofs):
    """The peer's error at `dofs` DOFs, log-log interpolated between its runs (None outside)."""
    pts = sorted((r["dofs"], r["l2"]) for r in rows if r["mesh"] == mesh and
                 r["method"].startswith("Mesh_3") and r.get("dofs") and r.get("l2"))
    for (d0, e0), (d1, e1) in zip(pts, pts[1:]):
        if d0 <= dofs <= d1 and d1 > d0:
            t = (math.log(dofs) - math.log(d0)) / (math.log(d1) - math.log(d0))
            return math.exp(math.log(e0) + t * (math.log(e1) - math.log(e0)))
    return None


def fmt(x, spec=".3g"):
    return "-" if x is None else format(x, spec)


lines = ["# Coarse-linear peer: CGAL Mesh_3 + P2 against the curved pipeline (issue 22)", "",
         "Generated %s by `%s` on %d cores, %d threads. %s" % (
             datetime.datetime.now().strftime("%Y-%m-%d %H:%M"), command, os.cpu_count(),
             args.threads, args.note), "",
         "Poisson, u = sin(3X) cos(2Y) e^Z (X, Y, Z: coordinates from the bbox centre over the "
         "longest bbox edge), Dirichlet u everywhere. Mesh_3: max_facet_distance = ε, "
         "min_facet_angle 25°, radius-edge ratio 3, no size bound (pygalmesh 0.10, CGAL 5.5); "
         "boundary data painted on the input: the curved run reads them through φ⁻¹, the peer "
         "at the closest point of the input (geometry.data_surface). L2 rel = curvefem's L2 error / "
         "L2 norm of u on each run's own domain. vs peer = the peer's error interpolated "
         "(log-log) at the same DOFs / this run's error (> 1: curved better; - : outside the "
         "peer's DOF range). s = whole run (the peer: Mesh_3 + `curvefem run`).", "",
         "| mesh | ε | method | tets | DOFs | L2 rel | vs peer at equal DOFs | s | exit |",
         "|---|---|---|---|---|---|---|---|---|"]
for r in rows:
    ratio = None
    if not r["method"].startswith("Mesh_3") and r.get("dofs") and r.get("l2"):
        e = peer_at(r["mesh"], r["dofs"])
        ratio = e / r["l2"] if e else None
    lines.append("| %s | %g | %s | %s | %s | %s | %s | %.1f | %s |" % (
        r["mesh"], r["eps"], r["method"], r.get("tets", "-"), r.get("dofs", "-"),
        fmt(r.get("l2")), fmt(ratio, ".2f"), r["seconds"], r["code"]))
with open(args.out, "w") as fh:
    fh.write("\n".join(lines) + "\n")
print("wrote", args.out)
