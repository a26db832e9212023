#!/usr/bin/python3
"""Whole-run elasticity benchmark (issue 24): `curvefem run` against DOLFINx on one Gmsh mesh.

Linear elasticity P_p on the beam [0, L] x [0, 1] x [0, 1] (Gmsh OpenCASCADE box, characteristic
length h), clamped at x = 0, traction (0, 0, -1) on x = L, E = 1000, nu = 0.3. Both codes solve
with CG + GAMG (rtol 1e-10) and the rigid-body modes as near-nullspace; curvefem also with its
`auto` choice. Compared: iterations, stage times, whole-process wall time (median of --repeat),
and the largest nodal |u| (same DOF points on the same mesh). DOLFINx's forms come from a warm
JIT cache.

Writes benchmarks/results/elasticity_whole_run.md. Run by hand on a quiet machine:
  /usr/bin/python3 benchmarks/run_elasticity_whole.py [--h 0.06] [--length 4] [--p 2]
"""
import argparse
import json
import os
import statistics
import tempfile
import time

import meshio
import numpy as np
from whole_run_common import gmsh_box, timed

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--h", type=float, default=0.06)
ap.add_argument("--length", type=float, default=4.0)
ap.add_argument("--p", type=int, default=2)
ap.add_argument("--repeat", type=int, default=3)
ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
ap.add_argument("--solvers", nargs="+", default=["cg", "auto"])
ap.add_argument("--peer-solvers", nargs="+", default=["cg-gamg", "direct"])
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/elasticity_whole_run.md"))
ap.add_argument("--work", default=None)
ap.add_argument("--note", default="")
args = ap.parse_args()

work = args.work or tempfile.mkdtemp(prefix="elasticity_whole_")
os.makedirs(work, exist_ok=True)
peer = os.path.join(root, "benchmarks/peers/dolfinx_elasticity_msh.py")
# OpenCASCADE box faces: 1 x = 0, 2 x = L, 3..6 the sides.
msh = gmsh_box(work, "beam", (args.length, 1, 1), args.h, {1: [1], 2: [2], 3: [3, 4, 5, 6]})

rows = []
for solver in args.solvers:
    case = {"geometry": {"mesh": msh},
            "physics": {"type": "linear_elasticity", "E": 1000.0, "nu": 0.3},
            "discretization": {"degree": args.p},
            "boundary_conditions": [
                {"type": "dirichlet", "select": {"tag": 1}, "value": [0, 0, 0]},
                {"type": "neumann", "select": {"tag": 2}, "value": [0, 0, -1]}]}
    if solver != "auto":
        case["solver"] = {"type": solver}
    path = os.path.join(work, f"case_{solver}.json")
    with open(path, "w") as f:
        json.dump(case, f)
    for threads in args.threads:
        out = os.path.join(work, f"out_{solver}_{threads}")
        walls = [timed([args.exe, "run", path, "-o", out, "--quiet", "--threads", str(threads)])[0]
                 for _ in range(args.repeat)]
        with open(os.path.join(out, "report.json")) as f:
            rep = json.load(f)
        vol = meshio.read(os.path.join(out, "volume.vtu"))
        u = vol.point_data["displacement"]
        ts = rep["time_s"]
        rows.append({"code": "curvefem", "threads": threads, "solver": rep["solver"]["method"],
                     "dofs": rep["dofs"], "iterations": rep["solver"]["iterations"],
                     "wall": statistics.median(walls), "assembly": ts["assembly"],
                     "solve": ts["solve"], "max_u": float(np.sqrt((u**2).sum(axis=1)).max())})
for solver in args.peer_solvers:
    cmd = ["/usr/bin/python3", peer, msh, str(args.p), solver]
    timed(cmd)  # warm the form cache
    walls, rep = [], None
    for _ in range(args.repeat):
        wall, out = timed(cmd)
        walls.append(wall)
        rep = json.loads(out.strip().splitlines()[-1])
    rows.append({"code": "dolfinx", "threads": 1, "solver": solver, "dofs": rep["dofs"],
                 "iterations": rep["iterations"], "wall": statistics.median(walls),
                 "assembly": rep["assembly"], "solve": rep["solve"],
                 "max_u": rep["max_nodal_displacement"]})

best_peer = min(r["wall"] for r in rows if r["code"] == "dolfinx")
with open(args.out + ".tmp", "w") as f:
    f.write("# Whole `curvefem run` against DOLFINx: linear elasticity (issue 24)\n\n")
    f.write(f"Generated {time.strftime('%Y-%m-%d %H:%M')} by `/usr/bin/python3 "
            f"benchmarks/run_elasticity_whole.py --h {args.h} --length {args.length} --p {args.p} "
            f"--repeat {args.repeat} --solvers {' '.join(args.solvers)} --peer-solvers "
            f"{' '.join(args.peer_solvers)}` on {os.cpu_count()} cores. {args.note}\n\n")
    f.write(f"P{args.p} linear elasticity on the beam [0, {args.length}] x [0, 1] x [0, 1] (Gmsh, "
            f"h = {args.h}), clamped at x = 0, traction (0, 0, -1) on x = {args.length}, E = 1000, "
            "nu = 0.3. CG to rtol 1e-10 with GAMG and the rigid-body modes in both codes. wall = "
            "median whole-process time (curvefem writes volume.vtu and report.json; DOLFINx "
            "writes nothing, forms from a warm JIT cache); assembly and solve from each code's "
            "own timers (s). max |u| = largest displacement over the DOF points.\n\n")
    f.write("| code | threads | solver | unknowns | iterations | wall s | assembly | solve | "
            "max abs u | wall / fastest DOLFINx |\n")
    f.write("|" + "---|" * 10 + "\n")
    for r in rows:
        f.write(f"| {r['code']} | {r['threads']} | {r['solver']} | {r['dofs']} | "
                f"{r['iterations']} | {r['wall']:.2f} | {r['assembly']:.2f} | {r['solve']:.2f} | "
                f"{r['max_u']:.9e} | {r['wall'] / best_peer:.2f} |\n")
os.replace(args.out + ".tmp", args.out)
print(open(args.out).read())
