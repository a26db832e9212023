#!/usr/bin/python3
"""Before/after table of two robustness runs (issue 21), optionally with the FEM consequence.

Reads the raw records (runs.jsonl) of two `run_robustness.py` runs on the same inputs and orders
and writes, per run, the coarse face count, tets, min scaled Jacobian, tets below 0.01, max curved
MIPS, slab / interior min scaled Jacobian and wall time before → after. With --fem, every pair of
valid meshes also gets a P2 Poisson solve with CG + GAMG on each (`curvefem run` of a given-mesh
case: Dirichlet on the whole boundary, u = sin(2πx/L)·cos(2πy/L)·e^(z/L) with L the bounding
box's longest side, solver.type cg, rtol 1e-10), and the table reports the iteration counts and
the relative L2 errors: conditioning is what element quality buys.

Usage (from the repository root):
  /usr/bin/python3 benchmarks/compare_robustness.py --before WORK0/runs.jsonl [...] --after WORK1/runs.jsonl [...]
      [--fem] [--exe build/tools/curvefem/curvefem] [--out benchmarks/results/X.md] [--note TEXT]
The mesh folders are WORK/<name>_k<K> next to each runs.jsonl. Standard library only.
"""
import argparse
import datetime
import json
import math
import os
import shlex
import subprocess
import sys
import tempfile

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--before", required=True, nargs="+", help="runs.jsonl file(s)")
ap.add_argument("--after", required=True, nargs="+", help="runs.jsonl file(s)")
ap.add_argument("--label-before", default="before")
ap.add_argument("--label-after", default="after")
ap.add_argument("--fem", action="store_true", help="P2 Poisson CG + GAMG iterations per mesh")
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--out", default="/tmp/compare_robustness.md")
ap.add_argument("--note", default="")
args = ap.parse_args()
command = "/usr/bin/python3 " + " ".join(
    shlex.quote(a) for a in ["benchmarks/compare_robustness.py"] + sys.argv[1:])


def load(paths):
    recs = {}
    for path in paths:
        with open(path) as f:
            for line in f:
                if line.strip():
                    r = json.loads(line)
                    r["work"] = os.path.dirname(os.path.abspath(path))
                    recs[(r["name"], r["order"])] = r  # the last record of a key wins
    return recs


def bbox_of_msh(path):
    """Bounding box of the nodes of a Gmsh 4.1 ASCII file (the mesher's output format)."""
    lo, hi = [math.inf] * 3, [-math.inf] * 3
    with open(path) as f:
        lines = iter(f)
        for line in lines:
            if line.strip() == "$Nodes":
                blocks, _, _, _ = map(int, next(lines).split())
                for _ in range(blocks):
                    _, _, _, n = map(int, next(lines).split())
                    for _ in range(n):
                        next(lines)
                    for _ in range(n):
                        p = list(map(float, next(lines).split()))
                        for c in range(3):
                            lo[c], hi[c] = min(lo[c], p[c]), max(hi[c], p[c])
                break
    return lo, hi


def fem(mesh_dir):
    msh = os.path.join(mesh_dir, "mesh.msh")
    if not os.path.exists(msh):
        return None
    lo, hi = bbox_of_msh(msh)
    L = max(h - l for l, h in zip(lo, hi))
    w = 2 * math.pi / L
    u = f"sin({w!r}*x)*cos({w!r}*y)*exp(z/{L!r})"
    # -Δu = (2w² − 1/L²) u
    rhs = f"{2 * w * w - 1 / (L * L)!r}*{u}"
    case = {"geometry": {"mesh": msh}, "meshing": {"method": "given"},
            "physics": {"type": "poisson"}, "discretization": {"degree": 2}, "rhs": rhs,
            "boundary_conditions": [{"type": "dirichlet", "select": {"all": True}, "value": u}],
            "exact": u, "solver": {"type": "cg", "rtol": 1e-10}}
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "case.json")
        with open(path, "w") as f:
            json.dump(case, f)
        out = os.path.join(tmp, "out")
        p = subprocess.run([args.exe, "run", path, "-o", out, "-q", "--threads", str(args.threads)],
                           capture_output=True, text=True)
        if p.returncode != 0:
            return {"error": (p.stderr.strip().splitlines() or ["?"])[-1][:100]}
        with open(os.path.join(out, "report.json")) as f:
            r = json.load(f)
    solver = r.get("solver", {})
    l2 = r.get("l2_error") / r["l2_norm_exact"] if r.get("l2_norm_exact") else None
    return {"iterations": solver.get("iterations"), "l2": l2, "dofs": r.get("dofs")}


def g(x, fmt="{:.3g}"):
    if x is None:
        return "—"
    return fmt.format(x) if isinstance(x, float) else str(x)


before, after = load(args.before), load(args.after)
keys = [k for k in before if k in after]
head = ["surface", "K", "coarse faces", "tets", "min SJ", "< 0.01", "max MIPS", "mean MIPS",
        "slab min SJ", "interior min SJ", "s"]
if args.fem:
    head += ["P2 DOFs", "P2 CG its", "P2 L2 rel"]
lines = [f"# Before/after: {args.label_before} → {args.label_after}", "",
         f"Generated {datetime.datetime.now():%Y-%m-%d %H:%M} by `{command}`; HEAD "
         + subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"], capture_output=True,
                          text=True).stdout.strip() + ".", "",
         "Each cell is before → after. SJ = sampled min scaled Jacobian; < 0.01 = tets below it; "
         "MIPS = curved MIPS (report.json's validation)."
         + (" P2 CG its: iterations of CG + GAMG (rtol 1e-10) for P2 Poisson on the mesh, "
            "Dirichlet everywhere; P2 L2 rel: its relative L2 error." if args.fem else ""), "",
         "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
goal = {"before": 0, "after": 0}
# after against before, per measure: (better, worse) counts
moved = {"min SJ": [0, 0], "tets below 0.01": [0, 0], "max MIPS": [0, 0], "mean MIPS": [0, 0],
         "tets": [0, 0]}
fem_change = {-1: 0, 0: 0, 1: 0}  # CG iterations fell / same / rose
for key in keys:
    b, a = before[key], after[key]

    def pair(field, fmt="{:.3g}", src=None):
        fb = (src(b) if src else b.get(field))
        fa = (src(a) if src else a.get(field))
        return f"{g(fb, fmt)} → {g(fa, fmt)}"

    def tag(t):
        return lambda r: r.get("by_tag", {}).get(t, {}).get("min_scaled_jacobian")

    for label, r in (("before", b), ("after", a)):
        if r.get("valid") and r["sj"] >= 1e-3 and (r.get("below") or 0) <= 0.01 * r["tets"] \
                and r["max_mips"] <= 1e4:
            goal[label] += 1
    row = [key[0], str(key[1]), pair("coarse"), pair("tets"), pair("sj"), pair("below"),
           pair("max_mips"), pair("mean_mips", "{:.1f}"), pair(None, src=tag("slab")),
           pair(None, src=tag("interior")),
           pair("wall", "{:.1f}")]
    if args.fem:
        fb = fem(os.path.join(b["work"], f"{key[0]}_k{key[1]}")) if b.get("valid") else None
        fa = fem(os.path.join(a["work"], f"{key[0]}_k{key[1]}")) if a.get("valid") else None
        its = [x.get("iterations", x.get("error")) if x else None for x in (fb, fa)]
        l2 = [x.get("l2") if x else None for x in (fb, fa)]
        dofs = [x.get("dofs") if x else None for x in (fb, fa)]
        row += [f"{g(dofs[0])} → {g(dofs[1])}", f"{g(its[0])} → {g(its[1])}",
                f"{g(l2[0])} → {g(l2[1])}"]
        if all(isinstance(x, int) for x in its):
            fem_change[(its[1] > its[0]) - (its[1] < its[0])] += 1
        print(key, its, l2, flush=True)
    lines.append("| " + " | ".join(row) + " |")
    if b.get("valid") and a.get("valid"):
        for name, field, sign in (("min SJ", "sj", 1), ("tets below 0.01", "below", -1),
                                  ("max MIPS", "max_mips", -1), ("mean MIPS", "mean_mips", -1),
                                  ("tets", "tets", -1)):
            x, y = b.get(field) or 0, a.get(field) or 0
            if x != y:
                moved[name][0 if (y - x) * sign > 0 else 1] += 1
lines += ["", "After against before, runs valid in both: " + "; ".join(
    f"{name} {'higher' if name == 'min SJ' else 'lower'} on {c[0]}, "
    f"{'lower' if name == 'min SJ' else 'higher'} on {c[1]}" for name, c in moved.items()) + ".",
          "", f"Quality goal (min SJ ≥ 1e-3, ≤ 1% of tets below 0.01, max MIPS ≤ 1e4) met on "
          f"{goal['before']} → {goal['after']} of {len(keys)} runs."]
if args.fem:
    lines.append(f"P2 Poisson CG + GAMG iterations: fewer on {fem_change[-1]}, the same on "
                 f"{fem_change[0]}, more on {fem_change[1]} meshes.")
walls = [sorted(r[k]["wall"] for k in keys) for r in (before, after)]
if keys:
    lines.append(f"Median wall time {walls[0][len(keys) // 2]:.1f} s → {walls[1][len(keys) // 2]:.1f} s.")
if args.note:
    lines += ["", "## Notes", "", args.note]
with open(args.out, "w") as f:
    f.write("\n".join(lines) + "\n")
print("wrote", args.out)
