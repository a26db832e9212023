"""The shell's applications (thesis §4.4-4.5) on one noisy surface, through the `curvefem` CLI.

A sphere with radial noise (`curvefem generate noise_sphere_5`, 1280 faces) gets:
  1. a displacement map: the coarse middle surface of its shell plus one height per sample
     (level 4) rebuild it, every rebuilt vertex on the input; the usual normal-projection baking
     of the same samples folds (self-intersecting pairs), P's does not;
  2. three nested cages, each the top surface of a shell around the one inside, checked exactly
     against each other and mapped back to the input;
  3. a geometric texture: a knob copied into every prism, exactly, without self-intersection;
  4. a Boolean union with a smaller shifted sphere, remeshed inside a shell, with a field of each
     operand carried onto the coarse result;
  5. the same two spheres written as one surface that passes through itself: refused as it is,
     and given a locally injective shell with --allow-self-intersections (thesis §4.5), verified
     against each prism's own sheet, with a smooth field carried to its middle surface and back.
Every number printed comes from the runs' report.json files (checks by meshing/check, independent
of the construction).

    PYTHONPATH=build/python /usr/bin/python3 docs/examples/shell_applications.py --out /tmp/apps

Writes OUT/<application>/ (the CLI's folders: displaced.obj, cage_*.obj, textured.obj,
remeshed.vtu, ...) and OUT/summary.json.
"""

import argparse
import json
import pathlib
import shutil
import subprocess

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--out", default="out/examples/shell_applications", help="output folder")
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


def cli(*a):
    subprocess.run([exe, *map(str, a)], check=True)


def report(name):
    return json.loads((out / name / "report.json").read_text())


surface = out / "noisy.obj"
cli("generate", "noise_sphere_5", "-q", "-o", surface)
cli("shell", surface, "-o", out / "displacement", "-q", "--threads", "1", "--displacement-map", 4)
cli("shell", surface, "-o", out / "cages", "-q", "--threads", "1", "--cages", 3)
cli("shell", surface, "-o", out / "texture", "-q", "--threads", "1", "--texture", "knob")
# A second operand: a sphere of radius 0.6 of the first's, shifted off-centre.
v, f = [], []
for line in surface.read_text().splitlines():
    if line.startswith("v "):
        v.append([float(x) for x in line.split()[1:4]])
    elif line.startswith("f "):
        f.append(line)
with open(out / "other.obj", "w") as other:
    for x in v:
        other.write("v %.17g %.17g %.17g\n" % (0.6 * x[0] + 0.7, 0.6 * x[1] + 0.2, 0.6 * x[2]))
    other.write("\n".join(f) + "\n")
cli("shell", surface, "-o", out / "boolean", "-q", "--threads", "1", "--boolean", "union",
    "--with", out / "other.obj")
# Both spheres as one surface (no Boolean): it passes through itself where they cross.
with open(out / "crossing.obj", "w") as crossing:
    for x in v:
        crossing.write("v %.17g %.17g %.17g\n" % tuple(x))
    for x in v:
        crossing.write("v %.17g %.17g %.17g\n" % (0.6 * x[0] + 0.7, 0.6 * x[1] + 0.2, 0.6 * x[2]))
    for offset in (0, len(v)):
        for line in f:
            ids = [int(t.split("/")[0]) + offset for t in line.split()[1:4]]
            crossing.write("f %d %d %d\n" % tuple(ids))
refused = subprocess.run([exe, "shell", out / "crossing.obj", "-o", out / "refused", "-q"],
                         capture_output=True, text=True)
cli("shell", out / "crossing.obj", "-o", out / "local", "-q", "--threads", "1",
    "--allow-self-intersections")

d = report("displacement")["displacement_map"]
c = report("cages")["nested_cages"]
t = report("texture")["geometric_texture"]
b = report("boolean")["boolean"]
loc = report("local")
summary = {
    "displacement_coarse_faces": d["coarse_faces"],
    "displacement_failures": d["failures"],
    "displacement_vertex_distance_rel": d["rebuilt"]["max_vertex_distance_rel"],
    "displacement_fiber_offset_rel": d["rebuilt"]["fiber_offset_max_rel"],
    "displacement_pairs_through_P": d["rebuilt"]["self_intersecting_pairs"],
    "displacement_pairs_along_normals": d["along_normals"]["self_intersecting_pairs"],
    "displacement_hausdorff_rel": d["rebuilt"]["hausdorff_rel"],
    "cages_layers": c["layers"],
    "cages_faces": [layer["faces"] for layer in c["per_layer"]],
    "cages_pairs_between_layers": c["intersecting_pairs_between_layers"],
    "cages_max_roundtrip_rel": max(layer["map_roundtrip_max_rel"] for layer in c["per_layer"]),
    "cages_map_failures": sum(layer["map_failures"] for layer in c["per_layer"]),
    "texture_copies": t["copies"],
    "texture_self_intersecting_pairs": t["self_intersecting_pairs"],
    "boolean_result_faces": b["result_faces"],
    "boolean_remeshed_faces": b["remeshed_faces"],
    "boolean_on_operand_rel": b["map_to_operand_max_distance_rel"],
    "crossing_refused_exit": refused.returncode,
    "crossing_refused_output": (out / "refused").exists(),
    "local_input_faces": loc["input_faces"],
    "local_prisms": loc["prisms"],
    "local_input_pairs": loc["local_sheets"]["input_self_intersecting_pairs"],
    "local_verified": loc["positive_verified"] and loc["intersection_free_verified"]
    and loc["is_section_verified"],
    "local_roundtrip_failures": loc["roundtrip_failures"],
    "local_roundtrip_rel": loc["roundtrip_max_error_rel"],
    "local_field_failures": loc["local_sheets"]["field_roundtrip"]["failures"],
    "local_field_max_error": loc["local_sheets"]["field_roundtrip"]["max_error"],
}
(out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
print("displacement map: %d coarse faces, Hausdorff %.3g, %d pairs through P vs %d along normals"
      % (summary["displacement_coarse_faces"], summary["displacement_hausdorff_rel"],
         summary["displacement_pairs_through_P"], summary["displacement_pairs_along_normals"]))
print("nested cages: %s faces, %d pairs between layers"
      % (summary["cages_faces"], summary["cages_pairs_between_layers"]))
print("texture: %d copies, %d self-intersecting pairs"
      % (summary["texture_copies"], summary["texture_self_intersecting_pairs"]))
print("boolean union: %d result faces remeshed to %d, images on their operands within %.2g"
      % (summary["boolean_result_faces"], summary["boolean_remeshed_faces"],
         summary["boolean_on_operand_rel"]))
print("self-intersecting union (%d pairs): refused with exit %d; locally injective shell %d -> %d "
      "prisms, verified %s, field input -> middle -> input max error %.3g"
      % (summary["local_input_pairs"], summary["crossing_refused_exit"],
         summary["local_input_faces"], summary["local_prisms"], summary["local_verified"],
         summary["local_field_max_error"]))
