"""A load-case study: one mesh, one function space, one factorization, several loads.

A cantilever bar (a built-in box surface, 4 x 0.5 x 0.5, clamped at x = 0) is meshed once — with
the dense method (the input's 768 triangles filled with tets, phi = identity): a flat box leaves
the curved mesher nothing to curve, and its coarsening reduces the bar to a handful of tets — and
solved for three load cases in one run: a tip traction on the end face, its own weight (a body
force), and both together. Linear elasticity superposes, so "both" must equal the sum of the
other two on every input vertex; the tip deflections are compared with Euler-Bernoulli beam
theory. The deflection lines are plotted with matplotlib (Agg backend: no display needed).

    PYTHONPATH=build/python /usr/bin/python3 docs/examples/load_case_study.py --out /tmp/study

Writes OUT/deflection.png, OUT/result.vtu (meshio) and OUT/summary.json.
"""

import argparse
import json
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import curvefem  # noqa: E402

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--out", default="out/examples/load_case_study", help="output folder")
args = parser.parse_args()
out = pathlib.Path(args.out)
out.mkdir(parents=True, exist_ok=True)

L, h = 4.0, 0.5  # length, square cross-section side
E, nu = 1000.0, 0.3
tip = 0.1  # traction on the end face (force per area, -z)
weight = 0.05  # body force per volume (-z)
clamp = {"type": "dirichlet", "select": {"tag": 1}, "value": [0, 0, 0]}  # face x = 0
tip_load = {"type": "neumann", "select": {"tag": 2}, "value": [0, 0, -tip]}  # face x = L

case = curvefem.case(
    geometry={"builtin_surface": {"shape": "box", "lo": [0, 0, 0], "hi": [L, h, h],
                                  "divisions": 8}},
    meshing={"method": "dense"},
    physics={"type": "linear_elasticity", "E": E, "nu": nu},
    discretization={"degree": 2},
    load_cases=[
        {"name": "tip", "boundary_conditions": [clamp, tip_load]},
        {"name": "weight", "rhs": [0, 0, -weight], "boundary_conditions": [clamp]},
        {"name": "both", "rhs": [0, 0, -weight], "boundary_conditions": [clamp, tip_load]},
    ],
)
result = curvefem.run(case, output_dir=out / "run")
report = result.report
print("%d tets, %d DOFs; %d load cases, %d factorization(s), %d reuse(s)" % (
    report["tets"], report["dofs"], len(result.load_names), report["factorizations"],
    report["factorization_reuses"]))

# Displacements on the dense input's vertices, one array per load case.
V = result.domain.input_vertices
u = result.surface_values_by_load
scale = np.abs(u["both"]).max()
superposition = np.abs(u["both"] - u["tip"] - u["weight"]).max() / scale
print("superposition: max |u_both - u_tip - u_weight| / max |u_both| = %.2e" % superposition)

# Euler-Bernoulli: tip deflection F L^3 / (3 E I) for the end load F, q L^4 / (8 E I) for the
# distributed weight q (shear deformation adds a few percent at L / h = 8).
inertia = h**4 / 12
beam = {"tip": tip * h * h * L**3 / (3 * E * inertia),
        "weight": weight * h * h * L**4 / (8 * E * inertia)}
at_tip = np.isclose(V[:, 0], L)
ratio = {}
for name in ("tip", "weight"):
    deflection = -u[name][at_tip, 2].mean()
    ratio[name] = deflection / beam[name]
    print("%-6s tip deflection %.5f, beam theory %.5f (ratio %.3f)" % (
        name, deflection, beam[name], ratio[name]))

# The deflection lines along the bar (input vertices on the top centre line y = h/2, z = h).
line = np.isclose(V[:, 2], h) & np.isclose(V[:, 1], h / 2)
order = np.argsort(V[line, 0])
fig, ax = plt.subplots(figsize=(6, 3.5))
for name in result.load_names:
    ax.plot(V[line, 0][order], u[name][line, 2][order], marker="o", ms=3, label=name)
x = np.linspace(0, L, 50)
ax.plot(x, -tip * h * h * x**2 * (3 * L - x) / (6 * E * inertia), "k:", lw=1,
        label="beam theory")
ax.plot(x, -weight * h * h * x**2 * (6 * L * L - 4 * L * x + x * x) / (24 * E * inertia), "k:",
        lw=1)
ax.set_xlabel("x")
ax.set_ylabel("u_z on the top centre line")
ax.set_title("cantilever, %d tets, P2, one factorization" % report["tets"])
ax.legend()
fig.tight_layout()
fig.savefig(out / "deflection.png", dpi=100)

# Every load case's displacement on one mesh file for ParaView (point data displacement_<name>).
mesh = result.to_meshio()
mesh.write(out / "result.vtu")
print("wrote %s and %s" % (out / "deflection.png", out / "result.vtu"))

summary = {
    "tets": report["tets"],
    "dofs": report["dofs"],
    "load_cases": len(result.load_names),
    "factorizations": report["factorizations"],
    "factorization_reuses": report["factorization_reuses"],
    "superposition_rel": superposition,
    "tip_ratio_to_beam_theory": ratio["tip"],
    "weight_ratio_to_beam_theory": ratio["weight"],
    "line_vertices": int(line.sum()),
    "png_bytes": (out / "deflection.png").stat().st_size,
    "point_fields": sorted(mesh.point_data),
}
(out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
