"""The curvefem Python module over the build tree (ctest: python.pytest; run by hand with
PYTHONPATH=<build>/python /usr/bin/python3 -m pytest python/tests)."""

import json
import math
import os
import pathlib
import subprocess

import numpy as np
import pytest

import curvefem

SOURCE = pathlib.Path(os.environ.get("CURVEFEM_SOURCE_DIR",
                                     pathlib.Path(__file__).resolve().parents[2]))
BUILD = pathlib.Path(curvefem.__file__).resolve().parents[2]
CLI = BUILD / "tools" / "curvefem" / "curvefem"

EXACT = "sin(x)*cos(y)*exp(z)"


def sphere_case(method="curved", order=2, degree=2, level=2):
    meshing = {"method": method}
    if method == "curved":
        meshing.update(order=order, eps=0.02)
    return curvefem.case(
        geometry={"builtin_surface": {"shape": "sphere", "level": level}, "features": "none"},
        meshing=meshing,
        physics={"type": "poisson"},
        discretization={"degree": degree},
        rhs=EXACT,
        boundary_conditions=[{"type": "dirichlet", "select": {"all": True}, "value": EXACT}],
        exact=EXACT,
    )


def cube_case(divisions, degree, exact="x*x*y + z*z*z", lap="-(2*y + 6*z)"):
    return curvefem.case(
        geometry={"builtin": {"shape": "cube", "divisions": divisions, "order": 1}},
        physics={"type": "poisson"},
        discretization={"degree": degree},
        rhs=lap,
        boundary_conditions=[{"type": "dirichlet", "select": {"all": True}, "value": exact}],
        exact=exact,
    )


def exact_at(points):
    x, y, z = points[:, 0], points[:, 1], points[:, 2]
    return np.sin(x) * np.cos(y) * np.exp(z)


def test_run_curved_sphere_returns_the_report_and_the_solution_on_every_input_vertex(tmp_path):
    stages = []
    result = curvefem.run(sphere_case(), output_dir=tmp_path / "out",
                          progress=lambda s, f: stages.append(s))
    assert result.valid and result.exit_code == 0
    r = result.report
    assert r["method"] == "curved" and r["order"] == 2 and r["degree"] == 2
    assert r["mesh_valid"] is True
    assert r["meshing"]["validation"]["min_jacobian_certified"] is True
    # P2 on an order-2 mesh within eps = 2% of a 320-face icosphere, boundary data read at
    # φ⁻¹(x) on the input: measured 5.7e-3 (the O(eps) geometric error dominates).
    assert 1e-4 < r["l2_error"] < 1e-2
    n = r["meshing"]["input_vertices"]
    assert n == 162  # icosphere level 2
    values, images = result.surface_values, result.surface_images
    assert values.shape == (n, 1) and images.shape == (n, 3)
    # u_h(φ(v)) against u(v): the reported surface errors, recomputed here from the arrays.
    V = result.domain.input_vertices
    err = np.abs(values[:, 0] - exact_at(V))
    assert err.max() == pytest.approx(r["surface_max_error"], rel=1e-9)
    assert np.abs(images - V).max() <= 0.02 * 2 * (1 + 1e-9)  # φ moves a vertex by ≤ ε
    assert {"load surface", "build space", "solve poisson", "write output"} <= set(stages)
    for name in ("volume.vtu", "surface.vtu", "result.pvd", "resolved_case.json", "report.json"):
        assert (tmp_path / "out" / name).is_file()
    on_disk = json.loads((tmp_path / "out" / "report.json").read_text())
    assert on_disk["l2_error"] == r["l2_error"] and on_disk["dofs"] == r["dofs"]


def test_the_module_and_the_cli_give_the_same_numbers(tmp_path):
    if not CLI.is_file():
        pytest.skip("the curvefem binary is not built next to the module: %s" % CLI)
    case = sphere_case(method="dense", level=2)
    case["output"] = {"dir": str(tmp_path / "cli")}
    path = tmp_path / "case.json"
    path.write_text(json.dumps(case))
    subprocess.run([str(CLI), "run", str(path), "--quiet"], check=True)
    cli = json.loads((tmp_path / "cli" / "report.json").read_text())
    py = curvefem.run(path, output_dir=tmp_path / "py").report
    for key in ("tets", "dofs", "l2_error", "h1_semi_error", "surface_max_error"):
        assert py[key] == cli[key], key


def test_stages_mesh_once_and_solve_two_problems_on_it():
    first = sphere_case(method="curved")
    second = dict(first, physics={"type": "poisson", "kappa": "2"}, rhs="-36*x*y*z",
                  boundary_conditions=[{"type": "dirichlet", "select": {"all": True},
                                        "value": "x*y*z*(x*x+y*y+z*z)"}],
                  exact="x*y*z*(x*x+y*y+z*z)")
    second.pop("exact_gradient", None)
    domain = curvefem.mesh(first)
    assert domain.valid and domain.order == 2
    disc = curvefem.discretize(first, domain)
    whole = curvefem.run(first, write=False)
    a = curvefem.solve(first, domain, disc)
    e_a = curvefem.compute_errors(first, disc, a)
    # One mesh, the same numbers as the whole pipeline.
    assert e_a["l2_error"] == pytest.approx(whole.report["l2_error"], rel=1e-12)
    assert disc.dofs == whole.report["dofs"]
    # A second problem on the same mesh and space: -div(2 grad u) = f with u of degree 5.
    b = curvefem.solve(second, domain, disc)
    e_b = curvefem.compute_errors(second, disc, b)
    alone_run = curvefem.run(second, write=False)  # meshes again: the same (deterministic) mesh
    alone = alone_run.report
    assert alone["tets"] == whole.report["tets"]
    assert e_b["l2_error"] == pytest.approx(alone["l2_error"], rel=1e-12)
    assert e_b["l2_error"] < 0.1 * e_b["l2_norm_exact"]  # measured 6.4% (eps = 2% geometry)
    # Dirichlet data everywhere, read at φ⁻¹(x): u_h(φ(v)) is u(v) up to the boundary
    # interpolation error; φ(v) is within eps of v.
    values, images = curvefem.transfer_to_input(second, domain, disc, b)
    V = domain.input_vertices
    x, y, z = V[:, 0], V[:, 1], V[:, 2]
    err = np.abs(values[:, 0] - x * y * z * (x * x + y * y + z * z)).max()
    assert err < 0.05  # measured 0.026 (|u| <= 0.19; P2 on ~100 coarse faces, u of degree 5)
    assert np.array_equal(values, alone_run.surface_values)
    assert np.linalg.norm(images - V, axis=1).max() <= 0.02 * 2 * (1 + 1e-9)


def test_p1_and_p2_converge_at_their_rates_on_the_builtin_cube():
    for degree, expected in ((1, 2.0), (2, 3.0)):
        errors = [curvefem.run(cube_case(n, degree), write=False).report["l2_error"]
                  for n in (2, 4)]
        rate = math.log(errors[0] / errors[1], 2)
        assert rate == pytest.approx(expected, abs=0.35), (degree, errors)


def test_solution_values_are_per_node_and_exact_for_a_quadratic_with_p2():
    result = curvefem.run(cube_case(2, 2, exact="x*x + y*z", lap="-2"), write=False)
    u = result.solution.values
    assert u.shape == (result.report["nodes"], 1)
    assert result.report["l2_error"] < 1e-10  # a quadratic is in the P2 space


def test_a_bad_case_raises_input_error_naming_the_key():
    case = sphere_case()
    case["meshing"]["orderr"] = 3
    with pytest.raises(curvefem.InputError) as info:
        curvefem.read_case(case)
    assert "/meshing/orderr" in str(info.value) and "unknown key" in str(info.value)
    assert info.value.exit_code == 2
    assert issubclass(curvefem.InputError, curvefem.Error)


def test_a_missing_surface_raises_and_check_reports_defects(tmp_path):
    case = sphere_case()
    case["geometry"] = {"surface": str(tmp_path / "missing.obj")}
    with pytest.raises(curvefem.Error) as info:
        curvefem.run(case, write=False)
    assert info.value.exit_code in (2, 4)
    open_box = tmp_path / "open.obj"
    open_box.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\n")
    report = curvefem.check(open_box)
    assert report["acceptable"] is False and report["closed"] is False
    assert report["boundary_edges"] == 3


def test_check_warns_of_the_folds_of_a_flat_tetrahedron(tmp_path):
    # Height 0.02 over a base of legs 2: its three base edges fold by 177.7-178.4 degrees.
    wafer = tmp_path / "wafer.obj"
    wafer.write_text("v 0 0 0\nv 2 0 0\nv 0 2 0\nv 0.5 0.5 0.02\n"
                     "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    report = curvefem.check(wafer)
    assert report["acceptable"] is True and report["defects"] == []
    assert [(w["kind"], w["count"]) for w in report["warnings"]] == [("near_fold", 3)]
    assert report["warnings"][0]["ids"] == [1, 2, 0, 1, 0, 2]


def test_merge_short_edges_merges_a_needle_pair_back():
    # A unit octahedron with vertex 6 put on edge 0-2 at 1e-5 of its length: faces 0-6-4 and
    # 6-0-5 are needles. Merged, the octahedron comes back (8 faces), 6 sits where 0 is mapped.
    v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    f = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
    mid = v[0] + 1e-5 * (v[2] - v[0])
    split = [[0, 6, 4], [6, 2, 4]] + f[1:4] + [[2, 6, 5], [6, 0, 5]] + f[5:]
    r = curvefem.merge_short_edges(np.vstack([v, mid]), split, 1e-4)
    assert r["candidates"] == 1 and len(r["merged"]) == 1 and r["left"] == 0
    assert r["faces"].shape == (8, 3) and r["vertices"].shape == (6, 3)
    assert r["vertex_map"][6] == r["vertex_map"][0]
    removed, kept, length = r["merged"][0]
    assert {removed, kept} == {0, 6}
    assert abs(length - 1e-5 * np.sqrt(2)) < 1e-15 and r["max_moved"] == length
    for i, face in enumerate(r["faces"]):
        assert list(face) == [r["vertex_map"][k] for k in split[r["face_origin"][i]]]
    with pytest.raises(curvefem.InputError):
        curvefem.merge_short_edges(v, [[0, 1, 9]], 1e-4)


def test_resolved_case_fills_the_defaults():
    r = curvefem.resolved(sphere_case())
    assert r["meshing"]["order"] == 2 and r["meshing"]["eps"] == 0.02
    assert r["solver"]["type"] == "auto"


def test_load_cases_on_one_curved_mesh_superpose_on_the_input_surface():
    case = sphere_case(method="curved")
    for key in ("rhs", "boundary_conditions", "exact"):
        case.pop(key)
    case["load_cases"] = [
        {"name": "a", "rhs": "1", "boundary_conditions": [
            {"type": "dirichlet", "select": {"all": True}, "value": "x"}]},
        {"name": "b", "rhs": "2", "boundary_conditions": [
            {"type": "dirichlet", "select": {"all": True}, "value": "y*z"}]},
        {"name": "ab", "rhs": "3", "boundary_conditions": [
            {"type": "dirichlet", "select": {"all": True}, "value": "x + y*z"}]},
        {"name": "exact", "rhs": EXACT, "exact": EXACT, "boundary_conditions": [
            {"type": "dirichlet", "select": {"all": True}, "value": EXACT}]},
    ]
    # u_h(φ(v)) on the input: with the default "extended" values these all-Dirichlet vertices
    # would carry their data, and the superposition below would test only the expressions.
    case["output"] = {"surface_values": "image"}
    result = curvefem.run(case, write=False)
    assert result.load_names == ["a", "b", "ab", "exact"]
    r = result.report
    assert [l["name"] for l in r["load_cases"]] == result.load_names
    s = result.surface_values_by_load
    assert np.abs(s["ab"] - s["a"] - s["b"]).max() < 1e-9
    # One Dirichlet part: one factorization, reused by the three other load cases and by the
    # re-solve of each with its shifted Dirichlet values (discretization.boundary_values_at).
    assert r["factorizations"] == 1 and r["factorization_reuses"] == 3 + 4
    # The same numbers as the single-load run on the same mesh (deterministic meshing).
    single = curvefem.run(sphere_case(method="curved"), write=False).report
    assert r["load_cases"][3]["l2_error"] == pytest.approx(single["l2_error"], rel=1e-12)
    assert r["tets"] == single["tets"]


def test_a_saved_run_is_reused_as_mesh_dir_without_meshing(tmp_path):
    first = curvefem.run(sphere_case(), output_dir=tmp_path / "first")
    case = sphere_case()
    case["geometry"] = {"mesh_dir": str(tmp_path / "first")}
    case.pop("meshing")
    again = curvefem.run(case, write=False)
    assert "meshing" not in again.timings and "load_mesh" in again.timings
    assert again.report["meshing"]["reused"]["mesh_dir"] == str(tmp_path / "first")
    assert again.report["l2_error"] == first.report["l2_error"]
    assert np.array_equal(again.surface_values, first.surface_values)
    assert again.report["meshing"]["validation"]["map_roundtrip_max_error_rel"] <= 1e-6
