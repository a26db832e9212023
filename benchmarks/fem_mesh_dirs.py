#!/usr/bin/env python3
"""FEM error on saved curved meshes, by hand (issue 21: what a mesh change costs the solve).

For each `curvefem mesh` output folder, runs `curvefem run` on it through `geometry.mesh_dir`
(no re-meshing) with Poisson, Dirichlet everywhere, u = sin(wx) cos(wy) e^(z/L), w = 2π/L,
L the longest bounding-box edge of the mesh (the problem of compare_robustness.py --fem), at
each degree p given (iso-parametric: the map lowered to degree p where p < k), with the default
direct solve, and prints the relative L2 error, the H1 error and the DOFs.

  /usr/bin/python3 benchmarks/fem_mesh_dirs.py --exe BIN --degrees 2,3,4 DIR [DIR ...]
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile


def msh_bbox(path):
    """Bounding box of the nodes of a Gmsh 4 ASCII file."""
    lo, hi = [math.inf] * 3, [-math.inf] * 3
    lines = open(path).read().split("\n")
    i = lines.index("$Nodes")
    blocks = int(lines[i + 1].split()[0])
    j = i + 2
    for _ in range(blocks):
        n = int(lines[j].split()[3])
        j += 1 + n
        for t in range(n):
            x = [float(v) for v in lines[j + t].split()[:3]]
            for a in range(3):
                lo[a], hi[a] = min(lo[a], x[a]), max(hi[a], x[a])
        j += n
    return lo, hi


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--exe", required=True)
    ap.add_argument("--degrees", default="2,3,4")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("dirs", nargs="+")
    args = ap.parse_args()
    degrees = [int(p) for p in args.degrees.split(",")]
    for d in args.dirs:
        d = os.path.abspath(d)
        lo, hi = msh_bbox(os.path.join(d, "mesh.msh"))
        L = max(h - l for l, h in zip(lo, hi))
        w = 2 * math.pi / L
        u = f"sin({w!r}*x)*cos({w!r}*y)*exp(z/{L!r})"
        rhs = f"{2 * w * w - 1 / (L * L)!r}*{u}"
        row = []
        for p in degrees:
            case = {"geometry": {"mesh_dir": d}, "physics": {"type": "poisson"},
                    "discretization": {"degree": p}, "rhs": rhs,
                    "boundary_conditions": [{"type": "dirichlet", "select": {"all": True},
                                             "value": u}],
                    "exact": u}
            with tempfile.TemporaryDirectory() as tmp:
                path = os.path.join(tmp, "case.json")
                json.dump(case, open(path, "w"))
                r = subprocess.run([args.exe, "run", path, "-o", os.path.join(tmp, "out"), "-q",
                                    "--threads", str(args.threads)], capture_output=True, text=True)
                if r.returncode:
                    row.append(f"p={p} exit {r.returncode}: {r.stderr.strip()[-200:]}")
                    continue
                rep = json.load(open(os.path.join(tmp, "out", "report.json")))
            row.append(f"p={p} L2rel {rep['l2_error'] / rep['l2_norm_exact']:.4e} "
                       f"H1 {rep.get('h1_error')} dofs {rep.get('dofs')}")
        print(d, " | ".join(row), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
