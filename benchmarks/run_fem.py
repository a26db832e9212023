#!/usr/bin/python3
"""Side-by-side P2/P3 Poisson benchmark: curvefem vs DOLFINx (Debian python3-dolfinx), same
problem, same DOF count, one run. Writes benchmarks/results/fem.md.

Usage (from the repository root, after `tools/bootstrap build`):
  BUILD_DIR=build-release /usr/bin/python3 benchmarks/run_fem.py [--n 29] [--p 2]
It builds the Release benchmark target itself. Run it on a quiet machine.
"""
import argparse
import json
import os
import platform
import subprocess
import sys
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--n", type=int, default=29)
ap.add_argument("--p", type=int, default=2)
ap.add_argument("--repeat", type=int, default=2)
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/fem.md"))
args = ap.parse_args()
build = os.environ.get("BUILD_DIR", os.path.join(root, "build-release"))

subprocess.run(["cmake", "-S", root, "-B", build, "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release"],
               check=True, stdout=subprocess.DEVNULL)
subprocess.run(["cmake", "--build", build, "--target", "curvefem_bench_poisson"], check=True,
               stdout=subprocess.DEVNULL)
ours = os.path.join(build, "benchmarks/curvefem_bench_poisson")
peer = os.path.join(root, "benchmarks/peers/dolfinx_poisson.py")


def run(cmd):
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def best(cmd):
    """Best of `repeat` runs (per stage), after the runs are done."""
    runs = [run(cmd) for _ in range(args.repeat)]
    r = dict(runs[0])
    for k in ("assembly_s", "setup_s", "solve_s", "solve_total_s", "total_s", "errors_s"):
        r[k] = min(x[k] for x in runs)
    return r


# Warm the DOLFINx JIT cache (FFCx forms) so compilation is not timed.
run(["/usr/bin/python3", peer, "4", str(args.p), "cg"])
rows = []
for solver in ("direct", "cg"):
    rows.append(best([ours, str(args.n), str(args.p), solver, "1"]))
    rows.append(best([ours, str(args.n), str(args.p), solver, "2"]))
    rows.append(best(["/usr/bin/python3", peer, str(args.n), str(args.p), solver]))

lines = []
lines.append(f"# p-FEM benchmark: P{args.p} Poisson on the unit cube, curvefem vs DOLFINx\n")
lines.append(f"Measured {time.strftime('%Y-%m-%d')} on {platform.node()} ({os.cpu_count()} cores), "
             f"best of {args.repeat} runs per row, in one run of:\n")
lines.append("```\n/usr/bin/python3 benchmarks/run_fem.py --n %d --p %d --repeat %d\n```\n" %
             (args.n, args.p, args.repeat))
lines.append("Problem: −Δu = f, u = cos πx cos πy cos πz, Dirichlet u on the boundary, "
             f"{rows[0]['tets']} tetrahedra (6 per cube of an {args.n}³ grid), "
             f"{rows[0]['dofs']} DOFs for both codes. Direct = CHOLMOD supernodal Cholesky "
             "(OpenBLAS), cg = CG + PETSc GAMG, rtol 1e-10. Times in seconds; DOLFINx's JIT "
             "compilation is excluded (warm cache). curvefem 'threads' = oneTBB workers in "
             "assembly; DOLFINx runs on 1 MPI rank.\n")
lines.append("| code | threads | solver | DOFs | iterations | assembly | solver set-up | solve | "
             "assembly+solve | L2 error | H1-semi error | peak RSS MB |")
lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
for r in rows:
    lines.append("| {code} | {threads} | {solver} | {dofs} | {iterations} | {assembly_s:.3f} | "
                 "{setup_s:.3f} | {solve_s:.3f} | {sum:.3f} | {l2_error:.4e} | {h1_semi_error:.4e} | "
                 "{peak_rss_mb:.0f} |".format(sum=r["assembly_s"] + r["solve_total_s"], **r))
lines.append("\nRatios curvefem / DOLFINx (below 1: curvefem faster):\n")
lines.append("| solver | threads | assembly | set-up + solve | assembly + solve |")
lines.append("|---|---|---|---|---|")
for i in range(0, len(rows), 3):
    peer_row = rows[i + 2]
    for r in rows[i:i + 2]:
        lines.append("| {} | {} | {:.2f} | {:.2f} | {:.2f} |".format(
            r["solver"], r["threads"], r["assembly_s"] / peer_row["assembly_s"],
            r["solve_total_s"] / peer_row["solve_total_s"],
            (r["assembly_s"] + r["solve_total_s"]) /
            (peer_row["assembly_s"] + peer_row["solve_total_s"])))
text = "\n".join(lines) + "\n"
with open(args.out, "w") as f:
    f.write(text)
print(text)
