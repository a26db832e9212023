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
ap.add_argument("--ball-h", type=float, default=0.1)
ap.add_argument("--ball-p", type=int, default=3)
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/fem.md"))
args = ap.parse_args()
build = os.environ.get("BUILD_DIR", os.path.join(root, "build-release"))

subprocess.run(["cmake", "-S", root, "-B", build, "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release"],
               check=True, stdout=subprocess.DEVNULL)
subprocess.run(["cmake", "--build", build, "--target", "curvefem_bench_poisson",
                "curvefem_bench_poisson_ball"], check=True, stdout=subprocess.DEVNULL)
ours = os.path.join(build, "benchmarks/curvefem_bench_poisson")
peer = os.path.join(root, "benchmarks/peers/dolfinx_poisson.py")
ours_ball = os.path.join(build, "benchmarks/curvefem_bench_poisson_ball")
peer_ball = os.path.join(root, "benchmarks/peers/dolfinx_poisson_ball.py")
ball_msh = os.path.join(build, "benchmarks/ball.msh")


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


def emit_table(rows, lines, error_format):
    """Rows of (ours 1 thread, ours 2 threads, peer) per solver, then the ratios to the peer."""
    lines.append("| code | threads | solver | DOFs | iterations | assembly | solver set-up | solve | "
                 "assembly+solve | L2 error | H1-semi error | peak RSS MB |")
    lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        lines.append(("| {code} | {threads} | {solver} | {dofs} | {iterations} | {assembly_s:.3f} | "
                      "{setup_s:.3f} | {solve_s:.3f} | {sum:.3f} | " + error_format +
                      " | {peak_rss_mb:.0f} |").format(sum=r["assembly_s"] + r["solve_total_s"], **r))
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


# Warm the DOLFINx JIT cache (FFCx forms) so compilation is not timed.
run(["/usr/bin/python3", peer, "4", str(args.p), "cg"])
rows = []
for solver in ("direct", "cg"):
    rows.append(best([ours, str(args.n), str(args.p), solver, "1"]))
    rows.append(best([ours, str(args.n), str(args.p), solver, "2"]))
    rows.append(best(["/usr/bin/python3", peer, str(args.n), str(args.p), solver]))

# Curved ball: the mesh is written once by curvefem (Gmsh, order = p) and read by both codes.
p = args.ball_p
h = str(args.ball_h)
run([ours_ball, h, str(p), str(p), "direct", "1", ball_msh])  # writes the mesh
run(["/usr/bin/python3", peer_ball, ball_msh, str(p), "cg"])  # JIT warm-up
ball_rows = []
for solver in ("direct", "cg"):
    ball_rows.append(best([ours_ball, h, str(p), str(p), solver, "1", ball_msh]))
    ball_rows.append(best([ours_ball, h, str(p), str(p), solver, "2", ball_msh]))
    ball_rows.append(best(["/usr/bin/python3", peer_ball, ball_msh, str(p), solver]))

lines = []
lines.append(f"# p-FEM benchmark: P{args.p} Poisson on the unit cube, curvefem vs DOLFINx\n")
lines.append(f"Measured {time.strftime('%Y-%m-%d')} on {platform.node()} ({os.cpu_count()} cores), "
             f"best of {args.repeat} runs per row, in one run of:\n")
lines.append("```\n/usr/bin/python3 benchmarks/run_fem.py --n %d --p %d --repeat %d --ball-h %g "
             "--ball-p %d\n```\n" % (args.n, args.p, args.repeat, args.ball_h, args.ball_p))
lines.append("Problem: −Δu = f, u = cos πx cos πy cos πz, Dirichlet u on the boundary, "
             f"{rows[0]['tets']} tetrahedra (6 per cube of an {args.n}³ grid), "
             f"{rows[0]['dofs']} DOFs for both codes. Direct = CHOLMOD supernodal Cholesky "
             "(OpenBLAS), cg = CG + PETSc GAMG, rtol 1e-10. Times in seconds; DOLFINx's JIT "
             "compilation is excluded (warm cache). curvefem 'threads' = oneTBB workers in "
             "assembly; DOLFINx runs on 1 MPI rank.\n")
emit_table(rows, lines, "{l2_error:.4e} | {h1_semi_error:.4e}")
lines.append(f"\n## P{p} on a curved unit ball (geometric order {p})\n")
lines.append(f"The unit ball meshed by Gmsh with h = {args.ball_h} at geometric order {p} "
             "(boundary nodes on the sphere), written to MSH by curvefem and read by both codes "
             "(DOLFINx through gmshio), so both solve on the same curved mesh: "
             f"{ball_rows[0]['tets']} tetrahedra, {ball_rows[0]['dofs']} DOFs. −Δu = f with "
             "u = (1 − r²) cos(x + 2y + 3z), u = 0 on the mesh boundary; errors on the mesh.\n")
emit_table(ball_rows, lines, "{l2_error:.6e} | {h1_semi_error:.6e}")
lines.append("\nNot compared yet: deal.II (Debian libdeal.ii-dev 9.4 has only P1/P2 on "
             "tetrahedra; its peer program is still to be written).")
text = "\n".join(lines) + "\n"
with open(args.out, "w") as f:
    f.write(text)
print(text)
