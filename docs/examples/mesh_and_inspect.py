"""Mesh a built-in surface and inspect the curved mesh's quality.

A torus (a dense triangle surface made in code) becomes a coarse, curved order-2 tet mesh whose
boundary lies within eps of the input; the numbers printed come from the independent validator's
report (Domain.report) and from the mesh's own arrays (Domain.nodes / cells / phi).

    PYTHONPATH=build/python /usr/bin/python3 docs/examples/mesh_and_inspect.py --out /tmp/inspect

Writes OUT/mesh.vtu (through meshio; open it in ParaView) and OUT/summary.json.
"""

import argparse
import json
import pathlib

import numpy as np

import curvefem

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--out", default="out/examples/mesh_and_inspect", help="output folder")
parser.add_argument("--eps", type=float, default=0.02, help="distance bound (relative)")
args = parser.parse_args()
out = pathlib.Path(args.out)
out.mkdir(parents=True, exist_ok=True)

case = curvefem.case(
    geometry={"builtin_surface": {"shape": "torus", "R": 1, "r": 0.4, "nu": 32, "nv": 16}},
    meshing={"method": "curved", "order": 2, "eps": args.eps},
)
domain = curvefem.mesh(case)  # meshing + independent validation; no physics
report = domain.report  # report.json's "meshing" section
validation = report["validation"]

# The quality numbers of the validator (report.json, meshing.validation).
print("input: %d vertices, %d faces -> %d coarse boundary faces" % (
    report["input_vertices"], report["input_faces"], report["coarse_faces"]))
print("tets: %d of order %d (%d nodes), valid: %s" % (
    len(domain.cells), domain.order, len(domain.nodes), domain.valid))
print("max distance of phi(v) from v: %.4f of the bbox (eps %.4f)" % (
    validation["max_distance_rel"], args.eps))
print("min scaled Jacobian %.3f, mean MIPS %.2f, max MIPS %.2f" % (
    validation["min_scaled_jacobian"], validation["mean_mips"], validation["max_mips"]))
print("min det J / max det J per tet (worst): %.3f" % (
    validation["distortion"]["min_jacobian_ratio"]))

# The same mesh as arrays: corner tets, their volumes, and phi at every input vertex.
X = domain.nodes
c = domain.corners
det = np.einsum("ij,ij->i", np.cross(X[c[:, 1]] - X[c[:, 0]], X[c[:, 2]] - X[c[:, 0]]),
                X[c[:, 3]] - X[c[:, 0]])
volume = det.sum() / 6
exact_volume = 2 * np.pi**2 * 1.0 * 0.4**2  # the smooth torus the input approximates
V = domain.input_vertices
bbox = (V.max(axis=0) - V.min(axis=0)).max()
offset = np.linalg.norm(domain.phi() - V, axis=1).max() / bbox
print("straight corner tets: all positive %s, volume %.4f (smooth torus %.4f)" % (
    bool((det > 0).all()), volume, exact_volume))
print("max |phi(v) - v| from the arrays: %.4f of the bbox" % offset)

# Per-tet quality as arrays (the cell fields of mesh.vtu) and a file for ParaView via meshio.
quality = {name: np.asarray(values) for name, _, values in domain.cell_quality}
mesh = domain.to_meshio()
mesh.write(out / "mesh.vtu")
print("cell fields: %s; wrote %s" % (", ".join(sorted(quality)), out / "mesh.vtu"))

summary = {
    "valid": domain.valid,
    "tets": len(domain.cells),
    "nodes": len(domain.nodes),
    "cell_type": mesh.cells[0].type,
    "coarse_faces": report["coarse_faces"],
    "input_faces": report["input_faces"],
    "eps": args.eps,
    "max_distance_rel": validation["max_distance_rel"],
    "phi_offset_rel_from_arrays": offset,
    "min_scaled_jacobian": validation["min_scaled_jacobian"],
    "min_scaled_jacobian_from_cells": float(quality["scaled_jacobian"].min()),
    "nonpositive_corner_tets": int((det <= 0).sum()),
    "volume_ratio": volume / exact_volume,
    # The arrays against the validator's report (both must agree):
    "phi_offset_minus_report": abs(offset - validation["max_distance_rel"]),
    "min_scaled_jacobian_minus_report": abs(float(quality["scaled_jacobian"].min())
                                            - validation["min_scaled_jacobian"]),
}
(out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
