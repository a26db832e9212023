"""Meshes as arrays, saved meshes loaded back (curvefem.load_mesh) and meshio export
(Domain.to_meshio, RunResult.to_meshio) — ctest python.pytest."""

import json

import meshio  # Debian's python3-meshio (tools/bootstrap installs it)
import numpy as np
import pytest

import curvefem

EXACT = "sin(x)*cos(y)*exp(z)"
SPHERE = {"builtin_surface": {"shape": "sphere", "level": 2}, "features": "none"}


def sphere_case(order=2, degree=2, eps=0.02, value=EXACT, exact=EXACT):
    case = curvefem.case(
        geometry=dict(SPHERE),
        meshing={"method": "curved", "order": order, "eps": eps},
        physics={"type": "poisson"},
        discretization={"degree": degree},
        rhs=EXACT if exact == EXACT else "0",
        boundary_conditions=[{"type": "dirichlet", "select": {"all": True}, "value": value}])
    if exact is not None:
        case["exact"] = exact
    return case


def cube_case(order, degree):
    exact = "x*x*y + z"
    return curvefem.case(
        geometry={"builtin": {"shape": "cube", "divisions": 2, "order": order}},
        physics={"type": "poisson"}, discretization={"degree": degree}, rhs="-2*y",
        boundary_conditions=[{"type": "dirichlet", "select": {"all": True}, "value": exact}],
        exact=exact)


@pytest.fixture(scope="module")
def saved_run(tmp_path_factory):
    """A curved order-2 run of the sphere, saved (mesh.msh, boundary_map.json, ...)."""
    out = tmp_path_factory.mktemp("saved") / "run"
    return out, curvefem.run(sphere_case(), output_dir=out)


def p2_triangle_basis(u, v):
    """P2 triangle shape functions in canonical order: corners, edges (0,1) (0,2) (1,2)."""
    l0, l1, l2 = 1 - u - v, u, v
    return np.stack([l0 * (2 * l0 - 1), l1 * (2 * l1 - 1), l2 * (2 * l2 - 1),
                     4 * l0 * l1, 4 * l0 * l2, 4 * l1 * l2], axis=1)


def test_domain_arrays_have_the_shapes_of_an_order_2_mesh_and_phi_is_face_u_v(saved_run):
    _, run = saved_run
    d = run.domain
    n_tets = run.report["tets"]
    assert d.order == 2
    assert d.cells.shape == (n_tets, 10) and d.corners.shape == (n_tets, 4)
    assert d.nodes.shape[1] == 3 and d.cells.max() == len(d.nodes) - 1  # every node is used
    # Corner tets positively oriented (the convention of Domain.corners).
    X, c = d.nodes, d.corners
    det = np.einsum("ij,ij->i", np.cross(X[c[:, 1]] - X[c[:, 0]], X[c[:, 2]] - X[c[:, 0]]),
                    X[c[:, 3]] - X[c[:, 0]])
    assert (det > 0).all()
    # The boundary triangles phi maps onto: order 2 (6 nodes), copies of volume nodes.
    faces = run.report["meshing"]["coarse_faces"]
    assert d.boundary_cells.shape == (faces, 6)
    b2v = d.boundary_node_to_volume
    assert len(b2v) == len(d.boundary_nodes) and (b2v >= 0).all()
    assert np.array_equal(d.boundary_nodes, d.nodes[b2v])
    # phi as (face, u, v): evaluating the P2 boundary triangle there gives Domain.phi().
    n = run.report["meshing"]["input_vertices"]
    assert d.vertex_face.shape == (n,) and d.vertex_uv.shape == (n, 2)
    assert (d.vertex_face >= 0).all() and d.vertex_face.max() < faces
    uv = d.vertex_uv
    assert (uv >= -1e-9).all() and (uv.sum(axis=1) <= 1 + 1e-9).all()
    N = p2_triangle_basis(uv[:, 0], uv[:, 1])
    nodes = d.boundary_nodes[d.boundary_cells[d.vertex_face]]  # n x 6 x 3
    image = np.einsum("nk,nkd->nd", N, nodes)
    assert np.abs(image - d.phi()).max() < 1e-12
    assert np.abs(d.phi() - run.surface_images).max() < 1e-12
    # Per-tet quality: one value per tet, its minimum the report's.
    quality = {name: np.asarray(v) for name, comps, v in d.cell_quality}
    assert quality["scaled_jacobian"].shape == (n_tets,)
    assert quality["scaled_jacobian"].min() == pytest.approx(
        run.report["meshing"]["validation"]["min_scaled_jacobian"], rel=1e-12)
    assert (quality["certified"] == 1).all()


def test_load_mesh_reads_the_saved_mesh_bit_identically_and_solves_on_it(saved_run):
    out, first = saved_run
    d = curvefem.load_mesh(out)
    assert d.method == "curved" and d.valid and d.order == 2
    for name in ("nodes", "cells", "vertex_face", "vertex_uv", "boundary_nodes",
                 "boundary_cells", "input_vertices", "input_faces"):
        assert np.array_equal(getattr(d, name), getattr(first.domain, name)), name
    assert d.report["reused"]["mesh_dir"] == str(out)
    assert d.report["validation"]["valid"] is True
    # The same physics on the loaded Domain, stage by stage: bit-identical errors.
    case = sphere_case()
    disc = curvefem.discretize(case, d)
    errors = curvefem.compute_errors(case, disc, curvefem.solve(case, d, disc))
    assert disc.dofs == first.report["dofs"]
    assert errors["l2_error"] == first.report["l2_error"]
    assert errors["h1_semi_error"] == first.report["h1_semi_error"]
    # New boundary data (u = x y z + z, harmonic) through geometry.mesh_dir: the stages on
    # the loaded Domain and curvefem.run give the same numbers, and nothing is meshed.
    new = sphere_case(value="x*y*z + z", exact="x*y*z + z")
    new["geometry"] = {"mesh_dir": str(out)}
    new.pop("meshing")
    disc = curvefem.discretize(new, d)
    staged = curvefem.compute_errors(new, disc, curvefem.solve(new, d, disc))
    again = curvefem.run(new, write=False)
    assert "meshing" not in again.timings
    assert again.report["l2_error"] == staged["l2_error"]
    assert staged["l2_error"] < 0.05 * staged["l2_norm_exact"]  # eps = 2% geometry


def test_load_mesh_without_validation_and_a_folder_that_is_not_a_mesh(saved_run, tmp_path):
    out, first = saved_run
    d = curvefem.load_mesh(out, validate=False)
    assert "validation" not in d.report and len(d.cell_quality) == 0
    assert np.array_equal(d.cells, first.domain.cells)
    with pytest.raises(curvefem.InputError) as info:
        curvefem.load_mesh(tmp_path)
    assert "mesh.msh" in str(info.value) and info.value.exit_code == 2


def test_load_mesh_refuses_a_changed_input(saved_run, tmp_path):
    out, _ = saved_run
    import shutil
    copy = tmp_path / "copy"
    shutil.copytree(out, copy)
    saved = json.loads((copy / "boundary_map.json").read_text())
    input_file = copy / saved["input"]
    assert input_file.is_file()  # a built-in surface's run saves it as input.msh
    input_file.write_bytes(input_file.read_bytes() + b"\n")
    with pytest.raises(curvefem.InputError) as info:
        curvefem.load_mesh(copy)
    assert "changed" in str(info.value)


def test_tetra10_nodes_follow_meshio_s_edge_order_on_a_straight_order_2_cube():
    d = curvefem.mesh(cube_case(order=2, degree=2))
    m = d.to_meshio()
    assert len(m.cells) == 1 and m.cells[0].type == "tetra10"
    conn = m.cells[0].data
    assert conn.shape == (6 * 8, 10) and len(m.points) == len(d.nodes)
    # meshio / VTK quadratic tetra: nodes 4..9 are the midpoints of 01 12 02 03 13 23.
    P = m.points[conn]
    for k, (a, b) in enumerate([(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)]):
        assert np.abs(P[:, 4 + k] - 0.5 * (P[:, a] + P[:, b])).max() < 1e-14, (a, b)
    straight = d.to_meshio(high_order="corners")
    assert straight.cells[0].type == "tetra" and straight.cells[0].data.shape == (48, 4)
    assert len(straight.points) == 27  # the 3 x 3 x 3 cube vertices only


def test_run_result_to_meshio_writes_vtu_and_reads_back(saved_run, tmp_path):
    _, run = saved_run
    m = run.to_meshio()
    disc = run.discretization
    assert m.cells[0].type == "tetra10" and len(m.cells[0].data) == run.report["tets"]
    assert len(m.points) == run.report["nodes"] == len(disc.dof_points)
    assert m.point_data["u"].shape == (run.report["nodes"],)
    assert set(m.cell_data) >= {"scaled_jacobian", "certified"}
    path = tmp_path / "run.vtu"
    m.write(path)
    back = meshio.read(path)
    assert len(back.points) == len(m.points)
    assert back.cells[0].type == "tetra10" and np.array_equal(back.cells[0].data,
                                                               m.cells[0].data)
    assert np.array_equal(back.point_data["u"], run.solution.values[:, 0])
    assert np.array_equal(back.cell_data["scaled_jacobian"][0], m.cell_data["scaled_jacobian"][0])
    # The surface: u_h(phi(v)) on every input vertex.
    s = run.surface_to_meshio()
    assert s.cells[0].data.shape == (run.report["meshing"]["input_faces"], 3)
    assert np.array_equal(s.point_data["u"], run.surface_values[:, 0])


def test_run_result_to_meshio_writes_xdmf_and_reads_back(saved_run, tmp_path):
    # meshio's XDMF writer stores the heavy data in HDF5 (Debian's python3-h5py, in tools/bootstrap).
    _, run = saved_run
    m = run.to_meshio()
    path = tmp_path / "run.xdmf"
    m.write(path)
    assert (tmp_path / "run.h5").is_file()
    back = meshio.read(path)
    assert back.cells[0].type == "tetra10" and np.array_equal(back.cells[0].data,
                                                               m.cells[0].data)
    assert np.allclose(back.points, m.points, rtol=0, atol=0)
    assert np.array_equal(np.ravel(back.point_data["u"]), run.solution.values[:, 0])


def test_order_3_gives_corner_tets_or_vtk_lagrange_cells_matching_volume_vtu(tmp_path):
    run = curvefem.run(sphere_case(order=3, degree=3), output_dir=tmp_path / "p3")
    tets = run.report["tets"]
    disc = run.discretization
    assert disc.dof_cells.shape == (tets, 20)
    corners = run.to_meshio()
    assert corners.cells[0].type == "tetra" and corners.cells[0].data.shape == (tets, 4)
    used = np.unique(disc.dof_cells[:, :4])
    assert len(corners.points) == len(used) < len(disc.dof_points)
    assert np.array_equal(corners.points, disc.dof_points[used])
    assert np.array_equal(corners.point_data["u"], run.solution.values[used, 0])
    # Every node as VTK Lagrange cells: the same cells, node for node, as the run's own
    # volume.vtu (written by VTK with curvefem's permutation), read back by meshio.
    lagrange = run.to_meshio(high_order="lagrange")
    assert lagrange.cells[0].type == "VTK_LAGRANGE_TETRAHEDRON"
    path = tmp_path / "lagrange.vtu"
    lagrange.write(path)
    mine = meshio.read(path)
    theirs = meshio.read(tmp_path / "p3" / "volume.vtu")
    assert theirs.cells[0].type == "VTK_LAGRANGE_TETRAHEDRON"
    assert mine.cells[0].data.shape == theirs.cells[0].data.shape == (tets, 20)
    assert np.array_equal(mine.points[mine.cells[0].data], theirs.points[theirs.cells[0].data])
    assert np.allclose(mine.point_data["u"][mine.cells[0].data],
                       theirs.point_data["u"][theirs.cells[0].data], rtol=0, atol=1e-14)
    with pytest.raises(ValueError):
        run.to_meshio(high_order="bezier")


def test_named_load_cases_become_suffixed_point_fields(saved_run):
    out, _ = saved_run
    case = sphere_case()
    for key in ("rhs", "boundary_conditions", "exact"):
        case.pop(key)
    case["geometry"] = {"mesh_dir": str(out)}
    case.pop("meshing")
    case["load_cases"] = [
        {"name": "a", "boundary_conditions": [
            {"type": "dirichlet", "select": {"all": True}, "value": "x"}]},
        {"name": "b", "boundary_conditions": [
            {"type": "dirichlet", "select": {"all": True}, "value": "2*x"}]}]
    run = curvefem.run(case, write=False)
    m = run.to_meshio()
    assert sorted(m.point_data) == ["u_a", "u_b"]
    assert np.abs(m.point_data["u_b"] - 2 * m.point_data["u_a"]).max() < 1e-9
    # u = x is harmonic and in P2; its boundary data are read on the input at phi^-1(x), within
    # eps = 2% of the bbox edge (2) of x: u_h stays that close to x (measured: see below).
    assert np.abs(m.point_data["u_a"] - m.points[:, 0]).max() < 0.02 * 2
