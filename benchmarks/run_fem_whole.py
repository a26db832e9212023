#!/usr/bin/python3
"""Whole-run benchmark (issue 24): `curvefem run` against DOLFINx on the same Gmsh mesh.

P_p Poisson on the unit cube meshed by Gmsh (OpenCASCADE box, characteristic length h),
u = cos πx cos πy cos πz, no exact_gradient in the curvefem case (its error stage differentiates
the expression itself), both codes computing the L2 and H1-semi errors with the same quadrature
degree (curvefem's default for straight P_p: 2p + 6). Each command is run `--repeat` times as a
whole process (wall time from here, process start to exit, outputs included); medians reported.
DOLFINx's form compilation is warmed by one run first (its cache then holds the forms).

Writes benchmarks/results/fem_whole_run.md. Run by hand on a quiet machine:
  /usr/bin/python3 benchmarks/run_fem_whole.py [--h 0.04] [--p 2] [--repeat 3]
Subsets (e.g. a before/after of one binary): --exe B --solvers auto --threads 1,2 --no-peer
--out F, --peer-solvers cg-gamg.
"""
import argparse
import json
import os
import statistics
import sys
import tempfile
import time

from whole_run_common import gmsh_box, timed

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--h", type=float, default=0.04)
ap.add_argument("--p", type=int, default=2)
ap.add_argument("--repeat", type=int, default=3)
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/fem_whole_run.md"))
ap.add_argument("--work", default=None)
ap.add_argument("--note", default="")
ap.add_argument("--solvers", default="auto,direct,cg",
                help="curvefem solver types, comma-separated")
ap.add_argument("--threads", default="1,2", help="curvefem thread counts, comma-separated")
ap.add_argument("--no-peer", action="store_true", help="skip DOLFINx (curvefem rows only)")
ap.add_argument("--peer-solvers", default="cg-boomeramg,cg-gamg,direct",
                help="DOLFINx solvers, comma-separated")
args = ap.parse_args()

work = args.work or tempfile.mkdtemp(prefix="fem_whole_")
os.makedirs(work, exist_ok=True)
peer = os.path.join(root, "benchmarks/peers/dolfinx_poisson_msh.py")
qdeg = 2 * args.p + 6  # fem::default_quadrature_degree(p, 1, error)

msh = gmsh_box(work, "cube", (1, 1, 1), args.h, {1: [1, 2, 3, 4, 5, 6]})

u = "cos(pi*x)*cos(pi*y)*cos(pi*z)"


def case(solver):
    c = {"geometry": {"mesh": msh}, "physics": {"type": "poisson"},
         "discretization": {"degree": args.p}, "rhs": "3*pi^2*" + u,
         "boundary_conditions": [{"type": "dirichlet", "select": {"all": True}, "value": u}],
         "exact": u}
    if solver != "auto":
        c["solver"] = {"type": solver}
    path = os.path.join(work, f"case_{solver}.json")
    with open(path, "w") as f:
        json.dump(c, f)
    return path


rows = []


def curvefem(solver, threads):
    out = os.path.join(work, f"out_{solver}_{threads}")
    cmd = [args.exe, "run", case(solver), "-o", out, "--quiet", "--threads", str(threads)]
    walls, rep = [], None
    for _ in range(args.repeat):
        wall, _ = timed(cmd)
        walls.append(wall)
        with open(os.path.join(out, "report.json")) as f:
            rep = json.load(f)
    ts = rep["time_s"]
    rows.append({"code": "curvefem", "threads": threads, "solver": rep["solver"]["method"],
                 "dofs": rep["dofs"], "iterations": rep["solver"]["iterations"],
                 "wall": statistics.median(walls), "mesh": ts.get("load_mesh", 0),
                 "space": ts.get("build_space", 0), "assembly": ts["assembly"],
                 "solve": ts["solve"], "errors": ts["errors"], "output": ts.get("output", 0),
                 "l2": rep["l2_error"], "h1": rep["h1_semi_error"]})


def dolfinx(solver):
    cmd = ["/usr/bin/python3", peer, msh, str(args.p), solver, str(qdeg)]
    timed(cmd)  # warm the form cache
    walls, rep = [], None
    for _ in range(args.repeat):
        wall, out = timed(cmd)
        walls.append(wall)
        rep = json.loads(out.strip().splitlines()[-1])
    rows.append({"code": "dolfinx", "threads": 1, "solver": solver, "dofs": rep["dofs"],
                 "iterations": rep["iterations"], "wall": statistics.median(walls),
                 "mesh": rep["mesh"], "space": rep["space"], "assembly": rep["assembly"],
                 "solve": rep["solve"], "errors": rep["errors"], "output": 0.0,
                 "l2": rep["l2_error"], "h1": rep["h1_semi_error"]})


for solver in args.solvers.split(","):
    for threads in (int(t) for t in args.threads.split(",")):
        curvefem(solver, threads)
if not args.no_peer:
    for solver in args.peer_solvers.split(","):
        dolfinx(solver)

best_peer = min((r["wall"] for r in rows if r["code"] == "dolfinx"), default=float("nan"))
with open(args.out + ".tmp", "w") as f:
    f.write("# Whole `curvefem run` against DOLFINx (issue 24)\n\n")
    f.write(f"Generated {time.strftime('%Y-%m-%d %H:%M')} by `/usr/bin/python3 "
            f"benchmarks/run_fem_whole.py {' '.join(sys.argv[1:])}`"
            f" on {os.cpu_count()} cores. {args.note}\n\n")
    f.write(f"P{args.p} Poisson on the unit cube (Gmsh, h = {args.h}), u = cos πx cos πy cos πz, "
            "Dirichlet everywhere; both codes compute the L2 and H1-semi errors with quadrature "
            f"degree {qdeg}. curvefem's case has no exact_gradient. wall = median whole-process "
            "time over the repeats (curvefem: reading the case and mesh, solving, errors, the "
            "error estimate, writing volume.vtu and report.json; DOLFINx: Python start-up and "
            "imports, meshio read, forms from a warm JIT cache, no output file). Stage columns "
            "are each code's own timers (s). DOLFINx runs on one MPI rank; curvefem's threads "
            "are oneTBB workers.\n\n")
    f.write("| code | threads | solver | DOFs | iterations | wall s | mesh | space | assembly | "
            "solve | errors | output | L2 error | H1-semi error | wall / fastest DOLFINx |\n")
    f.write("|" + "---|" * 15 + "\n")
    for r in rows:
        f.write(f"| {r['code']} | {r['threads']} | {r['solver']} | {r['dofs']} | "
                f"{r['iterations']} | {r['wall']:.2f} | {r['mesh']:.2f} | {r['space']:.2f} | "
                f"{r['assembly']:.2f} | {r['solve']:.2f} | {r['errors']:.2f} | "
                f"{r['output']:.2f} | {r['l2']:.9e} | {r['h1']:.9e} | "
                f"{r['wall'] / best_peer:.2f} |\n")
os.replace(args.out + ".tmp", args.out)
print(open(args.out).read())
