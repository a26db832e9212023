#!/usr/bin/python3
"""Where CG + GAMG overtakes CHOLMOD (issue 24): the measured table behind `solver.type` "auto".

For Poisson (u = cos πx cos πy cos πz, Dirichlet everywhere) and linear elasticity (clamped on
x = 0, traction on x = 1; GAMG with the rigid-body near-nullspace) at P1, P2 and P3 on
structured unit cubes (`geometry.builtin` cube, 6 n³ tets) of about 15k to 400k unknowns, runs
`curvefem run` with solver direct and cg (2 threads) and records the solve stage (factorization
or GAMG set-up + iterations), the whole process and its peak memory.

Writes benchmarks/results/solver_crossover.md. Run by hand on a quiet machine:
  /usr/bin/python3 benchmarks/run_solver_crossover.py [--targets 15000 40000 ...]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--targets", type=int, nargs="+", default=[15000, 40000, 90000, 180000, 350000])
ap.add_argument("--degrees", type=int, nargs="+", default=[1, 2, 3])
ap.add_argument("--physics", nargs="+", default=["poisson", "linear_elasticity"])
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--pcs", nargs="+", default=["gamg", "hypre", "ml"])
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/solver_crossover.md"))
ap.add_argument("--work", default=None)
ap.add_argument("--note", default="")
args = ap.parse_args()
work = args.work or tempfile.mkdtemp(prefix="crossover_")
os.makedirs(work, exist_ok=True)

u = "cos(pi*x)*cos(pi*y)*cos(pi*z)"


def case(physics, p, n, solver):
    kind, _, pc = solver.partition("-")
    c = {"geometry": {"builtin": {"shape": "cube", "divisions": n, "order": 1}},
         "physics": {"type": physics}, "discretization": {"degree": p},
         "solver": {"type": kind}}
    if pc:
        c["solver"]["preconditioner"] = pc
    if physics == "poisson":
        c.update({"rhs": "3*pi^2*" + u, "exact": u, "boundary_conditions": [
            {"type": "dirichlet", "select": {"all": True}, "value": u}]})
    else:
        c["physics"].update({"E": 1000.0, "nu": 0.3})
        c["boundary_conditions"] = [
            {"type": "dirichlet", "select": {"tag": 1}, "value": [0, 0, 0]},
            {"type": "neumann", "select": {"tag": 2}, "value": [0, 0, "-1"]}]
    path = os.path.join(work, f"{physics}_p{p}_n{n}_{solver}.json")
    with open(path, "w") as f:
        json.dump(c, f)
    return path


def run(path, out):
    cmd = ["/usr/bin/time", "-f", "%M", args.exe, "run", path, "-o", out, "--quiet",
           "--threads", str(args.threads)]
    t = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t
    if r.returncode != 0:
        return None
    rss_mb = int(r.stderr.strip().splitlines()[-1]) / 1024
    with open(os.path.join(out, "report.json")) as f:
        rep = json.load(f)
    return {"wall": wall, "solve": rep["time_s"]["solve"], "dofs": rep["dofs"],
            "iterations": rep["solver"]["iterations"], "rss": rss_mb,
            "method": rep["solver"]["method"]}


rows = []
for physics in args.physics:
    comps = 1 if physics == "poisson" else 3
    for p in args.degrees:
        for target in args.targets:
            n = max(2, round(((target / comps) ** (1 / 3) - 1) / p))
            res = {}
            for solver in ["direct"] + ["cg-" + pc for pc in args.pcs]:
                out = os.path.join(work, f"o_{physics}_{p}_{n}_{solver}")
                res[solver] = run(case(physics, p, n, solver), out)
            d = res["direct"]
            if d is None or any(res["cg-" + pc] is None for pc in args.pcs):
                print(f"skip {physics} p{p} n{n}: a run failed", file=sys.stderr)
                continue
            unknowns = d["dofs"]  # report.json dofs: scalar unknowns (3 per node for elasticity)
            # The crossover is against the default preconditioner (the first of --pcs).
            c = res["cg-" + args.pcs[0]]
            rows.append((physics, p, n, unknowns, d, c, res))
            print(physics, p, n, unknowns, f"direct {d['solve']:.2f}s", " ".join(
                f"{pc} {res['cg-' + pc]['solve']:.2f}s ({res['cg-' + pc]['iterations']} it)"
                for pc in args.pcs), flush=True)

with open(args.out + ".tmp", "w") as f:
    f.write("# Direct (CHOLMOD) against CG + GAMG: where `auto` switches (issue 24)\n\n")
    f.write(f"Generated {time.strftime('%Y-%m-%d %H:%M')} by `/usr/bin/python3 "
            f"benchmarks/run_solver_crossover.py` (targets {args.targets}, {args.threads} "
            f"threads) on {os.cpu_count()} cores. {args.note}\n\n")
    f.write("Structured unit cubes (6 n³ tets). Poisson: Dirichlet everywhere; elasticity: "
            "clamped x = 0, traction on x = 1, GAMG with the rigid-body near-nullspace. solve = "
            "the run's solve stage (CHOLMOD analysis + factorization + solve, or PETSc set-up + "
            "CG to rtol 1e-10); wall = the whole process; RSS = its peak memory.\n\n")
    f.write("| physics | p | n | unknowns | direct solve s | " +
            " | ".join(f"cg+{pc} solve s (it)" for pc in args.pcs) +
            f" | direct / cg+{args.pcs[0]} | direct wall s | cg+{args.pcs[0]} wall s | "
            f"direct RSS MB | cg+{args.pcs[0]} RSS MB |\n")
    f.write("|" + "---|" * (10 + len(args.pcs)) + "\n")
    for physics, p, n, unknowns, d, c, res in rows:
        f.write(f"| {physics} | {p} | {n} | {unknowns} | {d['solve']:.2f} | " +
                " | ".join(f"{res['cg-' + pc]['solve']:.2f} ({res['cg-' + pc]['iterations']})"
                           for pc in args.pcs) +
                f" | {d['solve'] / c['solve']:.2f} | {d['wall']:.2f} | "
                f"{c['wall']:.2f} | {d['rss']:.0f} | {c['rss']:.0f} |\n")
    f.write("\n## Crossover per physics and degree\n\n")
    f.write(f"Against cg+{args.pcs[0]}.\n\n")
    f.write("| physics | p | direct faster up to (unknowns) | cg faster from (unknowns) |\n")
    f.write("|---|---|---|---|\n")
    for physics in args.physics:
        for p in args.degrees:
            sel = [r for r in rows if r[0] == physics and r[1] == p]
            direct_wins = [r[3] for r in sel if r[4]["solve"] <= r[5]["solve"]]
            cg_wins = [r[3] for r in sel if r[4]["solve"] > r[5]["solve"]]
            f.write(f"| {physics} | {p} | {max(direct_wins) if direct_wins else '—'} | "
                    f"{min(cg_wins) if cg_wins else '—'} |\n")
os.replace(args.out + ".tmp", args.out)
print(open(args.out).read())
