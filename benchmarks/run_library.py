#!/usr/bin/python3
"""The pipeline as a library (issue 23): mesh reuse, load cases in one run, and the Python module
against the CLI, on the shipped elephant elasticity case (cases/elasticity_curved_elephant.json).

In one run, each timed as a whole process (wall time, `curvefem run -q --threads T`):
  first      the shipped case: mesh, solve, write (its output folder is then reused);
  reuse      the same physics on `"geometry": {"mesh_dir": <first's folder>}` with new boundary
             data (the clamp moved to the other end, a different traction);
  one        on the reused mesh: one load case (the shipped boundary data);
  three      on the reused mesh: three load cases (the shipped one and two more tractions) in
             one run, one mesh, one space;
  python     `curvefem.run(case)` of the Python module on the reuse case, in a fresh
             interpreter, against the CLI's report (relative L2 of the surface displacement and
             max |u| compared to 1e-12).
Every variant is run --repeat times; the table gives medians. Needs cases/data
(`tools/bootstrap data`) and the build's Python module.

Usage (from the repository root):
  /usr/bin/python3 benchmarks/run_library.py [--repeat 3] [--threads 2]
      [--exe build/tools/curvefem/curvefem] [--work /tmp/library_bench] [--out FILE]
Writes benchmarks/results/library.md. Standard library only.
"""
import argparse
import copy
import datetime
import json
import os
import shlex
import shutil
import statistics
import subprocess
import sys
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--repeat", type=int, default=3)
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--python-path", default=os.path.join(root, "build/python"))
ap.add_argument("--work", default="/tmp/library_bench")
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/library.md"))
args = ap.parse_args()
command = "/usr/bin/python3 " + " ".join(
    shlex.quote(a) for a in ["benchmarks/run_library.py"] + sys.argv[1:])

case_path = os.path.join(root, "cases/elasticity_curved_elephant.json")
with open(case_path) as f:
    shipped = json.load(f)
surface = os.path.join(root, "cases", shipped["geometry"]["surface"])
if not os.path.isfile(surface):
    sys.exit("no %s: run `tools/bootstrap data` first" % surface)
shutil.rmtree(args.work, ignore_errors=True)
os.makedirs(args.work)


def write_case(name, case):
    path = os.path.join(args.work, name + ".json")
    with open(path, "w") as f:
        json.dump(case, f, indent=1)
    return path


def run_cli(name, case):
    path = write_case(name, case)
    out = os.path.join(args.work, "out_" + name)
    shutil.rmtree(out, ignore_errors=True)
    start = time.time()
    p = subprocess.run([args.exe, "run", path, "-o", out, "-q", "--threads", str(args.threads)],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    wall = time.time() - start
    if p.returncode != 0:
        sys.exit("%s failed (exit %d):\n%s" % (name, p.returncode, p.stderr[-2000:]))
    with open(os.path.join(out, "report.json")) as f:
        return wall, json.load(f), out


first_case = copy.deepcopy(shipped)
first_case["geometry"]["surface"] = surface
first_case.pop("output", None)
bcs = shipped["boundary_conditions"]
clamp, load = bcs[0], bcs[1]
moved = [{"type": "dirichlet", "select": {"plane": {"point": [0, 0.35, 0], "normal": [0, 1, 0]}},
          "value": [0, 0, 0]},
         {"type": "neumann", "select": {"plane": {"point": [0, -0.4, 0], "normal": [0, -1, 0]}},
          "value": [1, 0, 0]}]

rows = {k: [] for k in ("first", "reuse", "one", "three", "python")}
reports = {}
mesh_dir = None
for i in range(args.repeat):
    wall, rep, out = run_cli("first", first_case)
    rows["first"].append(wall)
    reports["first"] = rep
    if mesh_dir is None:  # reuse the first run's mesh from here on (kept apart from later runs)
        mesh_dir = os.path.join(args.work, "mesh")
        shutil.copytree(out, mesh_dir)
reused = {k: v for k, v in first_case.items() if k not in ("geometry", "meshing",
                                                           "boundary_conditions")}
reused["geometry"] = {"mesh_dir": mesh_dir}
reuse_case = dict(reused, boundary_conditions=moved)
one_case = dict(reused, boundary_conditions=[clamp, load])
three_case = dict(reused, load_cases=[
    {"name": "shipped", "boundary_conditions": [clamp, load]},
    {"name": "sideways", "boundary_conditions": [clamp, dict(load, value=[2, 0, 0])]},
    {"name": "twist", "boundary_conditions": [clamp, dict(load, value=[0, 2, -1])]}])
for i in range(args.repeat):
    for name, case in (("reuse", reuse_case), ("one", one_case), ("three", three_case)):
        wall, rep, _ = run_cli(name, case)
        rows[name].append(wall)
        reports[name] = rep

# The Python module on the reuse case, in a fresh interpreter (import included in the time); it
# writes the CLI's files, so surface.vtu of both are compared value by value.
script = """
import json, sys, time
start = time.time()
sys.path.insert(0, %r)
import curvefem
r = curvefem.run(%r, output_dir=%r, threads=%d)
print(json.dumps({"wall": time.time() - start, "exit_code": r.exit_code}))
"""
py_case = write_case("python", reuse_case)
py_out = os.path.join(args.work, "out_python")
for i in range(args.repeat):
    shutil.rmtree(py_out, ignore_errors=True)
    start = time.time()
    p = subprocess.run(["/usr/bin/python3", "-c",
                        script % (args.python_path, py_case, py_out, args.threads)],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    wall = time.time() - start
    if p.returncode != 0 or json.loads(p.stdout.strip().splitlines()[-1])["exit_code"] != 0:
        sys.exit("python run failed:\n" + p.stderr[-2000:])
    rows["python"].append(wall)


def compare_surfaces(a, b):
    """Largest |a - b| / max |a| over the float point arrays both surface.vtu files hold."""
    sys.path.insert(0, "/usr/lib/python3/dist-packages")
    import meshio
    import numpy as np
    ma, mb = meshio.read(a), meshio.read(b)
    worst, names = 0.0, []
    for name, va in ma.point_data.items():
        if name not in mb.point_data or va.dtype.kind != "f":
            continue
        vb = mb.point_data[name]
        scale = max(float(np.abs(va).max()), 1e-300)
        worst = max(worst, float(np.abs(va - vb).max()) / scale)
        names.append(name)
    return worst, names


py_diff, py_fields = compare_surfaces(os.path.join(args.work, "out_reuse", "surface.vtu"),
                                      os.path.join(py_out, "surface.vtu"))


def dig(rep, *keys):
    for k in keys:
        if not isinstance(rep, dict) or k not in rep:
            return None
        rep = rep[k]
    return rep


med = {k: statistics.median(v) for k, v in rows.items()}
lines = [
    "# The pipeline as a library: reuse, load cases, Python (issue 23)",
    "",
    "Written by `benchmarks/run_library.py` on %s. Command: `%s`." % (
        datetime.datetime.now().strftime("%Y-%m-%d %H:%M"), command),
    "",
    "Shipped case `cases/elasticity_curved_elephant.json` (curved k = 3, ε = 1%%, P3 linear "
    "elasticity); whole-process wall times, median of %d, %d threads." % (args.repeat,
                                                                            args.threads),
    "",
    "| run | wall (s) | runs (s) | ratio |",
    "|---|---|---|---|",
]
for name, what, ref in (("first", "first run (mesh + solve)", None),
                        ("reuse", "reused mesh, new boundary data", "first"),
                        ("one", "reused mesh, one load case", "first"),
                        ("three", "reused mesh, three load cases", "one"),
                        ("python", "Python `curvefem.run`, reuse case (import included)",
                         "reuse")):
    ratio = "" if ref is None else "%.3f of %s" % (med[name] / med[ref], ref)
    lines.append("| %s | %.2f | %s | %s |" % (what, med[name],
                                             ", ".join("%.2f" % w for w in rows[name]), ratio))
lines += [
    "",
    "- DOFs: %s; factorizations in the three-case run: %s, reuses: %s." % (
        dig(reports["one"], "dofs"), dig(reports["three"], "factorizations"),
        dig(reports["three"], "factorization_reuses")),
    "- Python against the CLI on the reuse case, surface.vtu point arrays (%s): largest "
    "|difference| / max |value| = %.1e." % (", ".join(py_fields), py_diff),
    "",
]
with open(args.out, "w") as f:
    f.write("\n".join(lines))
print("\n".join(lines))
