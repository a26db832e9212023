"""Deform a closed surface without letting it cross itself (SCAF with a tet scaffold, thesis §3.2.3).

A split ring (`curvefem generate split_ring_01`: a rectangular ring cut by a narrow slit) has its
two end caps sent to each other's place. Moving those vertices there directly makes the surface
cross itself; `curvefem deform` moves them as far as it can while the solid and the space around
it stay tetrahedralized with positive tets, so the ends meet and stop. Every number printed comes
from report.json (exact checks by meshing/check and meshing/tetfill, independent of the solver).

    PYTHONPATH=build/python /usr/bin/python3 docs/examples/deform_without_self_intersection.py --out /tmp/deform

Writes OUT/ring.obj, OUT/targets.txt, OUT/closed.obj, OUT/report.json and OUT/summary.json.
"""

import argparse
import json
import pathlib
import shutil
import subprocess

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--out", default="out/examples/deform", help="output folder")
parser.add_argument("--exe", default=None, help="the curvefem executable (default: the build "
                    "tree next to the curvefem Python module, else curvefem on PATH)")
args = parser.parse_args()
out = pathlib.Path(args.out)
out.mkdir(parents=True, exist_ok=True)

exe = args.exe
if exe is None:
    try:
        import curvefem  # the build tree's module: build/python/curvefem

        candidate = pathlib.Path(curvefem.__file__).resolve().parents[2] / "tools/curvefem/curvefem"
        exe = str(candidate) if candidate.exists() else None
    except ImportError:
        pass
exe = exe or shutil.which("curvefem")
if exe is None:
    raise SystemExit("no curvefem executable: pass --exe")

ring = out / "ring.obj"
subprocess.run([exe, "generate", "split_ring_01", "-q", "-o", str(ring)], check=True)
V = [tuple(map(float, line.split()[1:4])) for line in ring.read_text().splitlines()
     if line.startswith("v ")]
# The generator's vertex order: 4 profile corners per section, the first and last sections are
# the two end caps.
last = len(V) - 4
with open(out / "targets.txt", "w") as f:
    f.write("# vertex x y z: each end cap sent to the other's place\n")
    for k in range(4):
        f.write("%d %.17g %.17g %.17g\n" % ((k,) + V[last + k]))
        f.write("%d %.17g %.17g %.17g\n" % ((last + k,) + V[k]))
subprocess.run([exe, "deform", "-q", str(ring), "-o", str(out / "closed.obj"), "--targets",
                str(out / "targets.txt"), "--iterations", "20", "--report",
                str(out / "report.json")], check=True)
r = json.loads((out / "report.json").read_text())
summary = {
    "iterations": r["iterations"],
    "naive_self_intersecting_pairs": r["naive_self_intersecting_pairs"],
    "self_intersecting_pairs": r["self_intersecting_pairs"],
    "max_pairs_over_iterations": r["max_self_intersecting_pairs_over_iterations"],
    "non_positive_tets": r["non_positive_tets"],
    "valid": r["valid"],
    "target_error_ratio": r["target_error_rel"] / r["initial_target_error_rel"],
    "energy": r["energy"],
}
(out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
print("targets applied directly: %d self-intersecting face pairs" %
      summary["naive_self_intersecting_pairs"])
print("curvefem deform: %d iterations, %d pairs (max over iterations %d), %d non-positive tets, "
      "distance to the targets x %.3f, object energy %.4f" %
      (summary["iterations"], summary["self_intersecting_pairs"],
       summary["max_pairs_over_iterations"], summary["non_positive_tets"],
       summary["target_error_ratio"], summary["energy"]))
