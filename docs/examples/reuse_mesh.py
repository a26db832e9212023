"""Reuse a saved curved mesh: mesh once, then solve new boundary conditions without meshing.

A curved run saves its mesh and boundary map (mesh.msh, boundary_map.json) in its output folder.
`curvefem.load_mesh(folder)` reads them back as a Domain (checked against the input's checksum and
validated again), and a case with `"geometry": {"mesh_dir": folder}` runs new physics on it, either
stage by stage on the loaded Domain or with `curvefem.run`. Both must give the same numbers as a
run that meshes again (meshing is deterministic).

    PYTHONPATH=build/python /usr/bin/python3 docs/examples/reuse_mesh.py --out /tmp/reuse

Writes OUT/first (the saved run), OUT/second.vtu, OUT/second_surface.vtu (meshio) and
OUT/summary.json.
"""

import argparse
import json
import pathlib
import shutil
import time

import numpy as np

import curvefem

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--out", default="out/examples/reuse_mesh", help="output folder")
args = parser.parse_args()
out = pathlib.Path(args.out)
shutil.rmtree(out / "first", ignore_errors=True)  # a run refuses no folder, but start clean
out.mkdir(parents=True, exist_ok=True)

sphere = {"builtin_surface": {"shape": "sphere", "level": 3}, "features": "none"}
meshing = {"method": "curved", "order": 2, "eps": 0.02}

# 1. The first run meshes and saves everything into OUT/first.
first_case = curvefem.case(
    geometry=sphere, meshing=meshing, physics={"type": "poisson"},
    discretization={"degree": 2},
    boundary_conditions=[{"type": "dirichlet", "select": {"all": True}, "value": "x"}])
start = time.perf_counter()
first = curvefem.run(first_case, output_dir=out / "first")
first_s = time.perf_counter() - start
print("first run: %d tets, meshing %.2f s of %.2f s" % (
    first.report["tets"], first.timings.get("meshing", 0.0), first_s))

# 2. Load the saved mesh: no meshing, the arrays of the first run.
domain = curvefem.load_mesh(out / "first")
same_mesh = (np.array_equal(domain.nodes, first.domain.nodes)
             and np.array_equal(domain.cells, first.domain.cells)
             and np.array_equal(domain.vertex_face, first.domain.vertex_face)
             and np.array_equal(domain.vertex_uv, first.domain.vertex_uv))
print("loaded: %d tets of order %d, valid %s, phi of %d input vertices as (face, u, v); "
      "identical to the first run's arrays: %s" % (
          len(domain.cells), domain.order, domain.valid, len(domain.vertex_face), same_mesh))

# 3. New boundary conditions on it: u prescribed below z = 0.3, a flux through the cap above it
#    (grad u . n, with n the curved mesh's normal), for the harmonic u = x y z + 2 z.
exact = "x*y*z + 2*z"
second_case = curvefem.case(
    geometry={"mesh_dir": str(out / "first")},
    physics={"type": "poisson"},
    discretization={"degree": 2},
    rhs="0",
    boundary_conditions=[
        {"type": "dirichlet", "select": {"plane": {"point": [0, 0, 0.3], "normal": [0, 0, -1]}},
         "value": exact},
        {"type": "neumann", "select": {"plane": {"point": [0, 0, 0.3], "normal": [0, 0, 1]}},
         "value": "y*z*nx + x*z*ny + (x*y + 2)*nz"}],
    exact=exact)
start = time.perf_counter()
disc = curvefem.discretize(second_case, domain)
solution = curvefem.solve(second_case, domain, disc)
errors = curvefem.compute_errors(second_case, disc, solution)
stages_s = time.perf_counter() - start
print("stage by stage on the loaded mesh: L2 error %.3e (relative %.2e), %.2f s" % (
    errors["l2_error"], errors["l2_error"] / errors["l2_norm_exact"], stages_s))

# 4. The same case through curvefem.run (it loads OUT/first itself), and meshed again.
start = time.perf_counter()
second = curvefem.run(second_case, write=False)
second_s = time.perf_counter() - start
remeshed_case = dict(second_case, geometry=sphere, meshing=meshing)
remeshed = curvefem.run(remeshed_case, write=False)
print("run on the saved mesh: L2 %.3e in %.2f s (timings: %s); meshed again: L2 %.3e" % (
    second.report["l2_error"], second_s, ", ".join(sorted(second.timings)),
    remeshed.report["l2_error"]))

second.to_meshio().write(out / "second.vtu")
second.surface_to_meshio().write(out / "second_surface.vtu")

summary = {
    "tets": len(domain.cells),
    "same_mesh_arrays": same_mesh,
    "loaded_valid": domain.valid,
    "l2_error_stages": errors["l2_error"],
    "l2_error_run": second.report["l2_error"],
    "l2_error_remeshed": remeshed.report["l2_error"],
    "l2_error_rel": errors["l2_error"] / errors["l2_norm_exact"],
    "meshed_in_second_run": "meshing" in second.timings,
    # The loaded mesh, the run on mesh_dir and a run meshing again must agree to the bit:
    "l2_run_minus_stages": abs(second.report["l2_error"] - errors["l2_error"]),
    "l2_remeshed_minus_stages": abs(remeshed.report["l2_error"] - errors["l2_error"]),
    "first_run_s": first_s,
    "second_run_s": second_s,
}
(out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
