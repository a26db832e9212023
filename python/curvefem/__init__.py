"""curvefem: coarse, curved, certified tetrahedral meshes of dense surfaces, and p-FEM on them.

The pipeline of `curvefem run` as a Python module (the C++ pipeline library, pybind11):

    import curvefem
    result = curvefem.run({"geometry": {"builtin_surface": {"shape": "sphere"}},
                           "meshing": {"method": "curved", "order": 2},
                           "physics": {"type": "poisson"},
                           "boundary_conditions": [{"type": "dirichlet", "select": {"all": true},
                                                    "value": "x*y"}]},
                          write=False)
    result.report["l2_error"], result.surface_values     # NumPy: u at every input vertex

A case is a dict with the keys of a case file (cases/README.md), a path to a case file, or a
`Case` from `read_case`. The stages can also be called one by one (`load_surface`, `mesh`,
`discretize`, `solve`, `compute_errors`, `transfer_to_input`), e.g. to solve several physics
problems on one mesh. Errors raise `curvefem.InputError` (bad case or input; exit_code 2),
`MeshingError`, `SolverError` (3) or `IoError` (4), all subclasses of `curvefem.Error`.

Meshes as arrays: a `Domain` (from `mesh`, `load_mesh` or `RunResult.domain`) has `nodes`
(#N x 3), `cells` (#C x n_k Lagrange node ids of order k, corners first), `corners` (#C x 4),
the dense input (`input_vertices`, `input_faces`) and phi of every input vertex as (face, u, v):
`vertex_face`, `vertex_uv` into the curved boundary triangles `boundary_nodes` /
`boundary_cells`. A folder written by `curvefem mesh` or a curved `run` is read back without
meshing by `load_mesh(dir)`; `Domain.to_meshio()` and `RunResult.to_meshio()` give a
`meshio.Mesh` (Debian's python3-meshio) for XDMF, VTU, Exodus, ... Worked examples: docs/examples/.

`schema()` lists every case key (type, default, allowed values, meaning): the table the parser
takes its keys from and cases/README.md's key table is generated from.
"""

import difflib as _difflib
import json as _json
import os as _os

import numpy as _np

from . import _curvefem
from ._curvefem import (  # noqa: F401  (re-exported)
    Case,
    Discretization,
    Domain,
    Error,
    InputError,
    IoError,
    MeshingError,
    SolverError,
    Surface,
    set_log_level,
)

__all__ = [
    "Case", "Domain", "Discretization", "Error", "InputError", "IoError", "MeshingError",
    "RunResult", "SolverError", "Surface", "case", "check", "compute_errors", "discretize",
    "load_mesh", "load_surface", "merge_short_edges", "mesh", "read_case", "resolved", "run",
    "schema", "set_log_level", "solve", "study", "transfer_to_input",
]

# A library should not chatter: warnings and errors only, until set_log_level says otherwise.
set_log_level("warn")


def schema(section=None):
    """The case-file keys as a list of dicts, one per key, in the documented order (the table
    of pipeline/case_schema.cpp: the parser accepts exactly these keys, and cases/README.md's
    key table is generated from it):

    - "path": "meshing.eps"; "[]" marks an array of objects ("boundary_conditions[].select.box");
      the keys under "boundary_conditions[].select" also apply inside and / or / not;
    - "type": object, array, string, number, integer, boolean, path, expression, selection,
      number_list or any; "type_text": the README's type column;
    - "default": the value resolved_case.json gets when the key is absent, or None (required,
      optional, or depending on other keys: "default_text" says which);
    - "allowed": the string values allowed ([] when any);
    - "minimum", "maximum" (None: unbounded), "minimum_exclusive", "maximum_exclusive";
    - "when": the rules under which the key applies, all of them: {"path": other key, "values":
      [...]} (that key, resolved, is one of them) or {"path": ..., "given": bool}; a key given
      where one fails is refused, and resolved() leaves it out;
    - "defaults": defaults depending on other keys, [{"when": [...], "value": ...}], the first
      whose rules hold; "default_from": else the value of this other key (or None);
    - "doc": the meaning (Markdown).

    `section` ("meshing", "boundary_conditions[]", ...): only the keys below it."""
    keys = _json.loads(_curvefem.case_schema_json())
    if section is None:
        return keys
    return [k for k in keys if k["path"].startswith(section + ".")]


def _sections_doc():
    """One line per top-level section of a case: its keys, or the key's type and default."""
    children = {}
    for k in schema():
        top, _, rest = k["path"].partition(".")
        children.setdefault(top, [])
        if rest and "." not in rest:
            children[top].append(rest)
    by_path = {k["path"]: k for k in schema()}
    lines = []
    for top, keys in children.items():
        name = top[:-2] if top.endswith("[]") else top
        if keys:
            what = ("[{...}, ...] with keys: " if top.endswith("[]") else "{...} with keys: ")
            what += ", ".join(keys)
        else:
            k = by_path[top]
            what = "%s (default %s)" % (k["type_text"], k["default_text"])
        lines.append("        %s=%s" % (name, what.replace("\\|", "|")))
    return "\n".join(lines)


def _children(paths, path):
    """Immediate child key names (with "[]" for arrays of objects) of `path` in the schema."""
    prefix = path + "." if path else ""
    return {p[len(prefix):].split(".")[0] for p in paths if p.startswith(prefix) and p != path}


def _check_keys(value, path, paths, where):
    """InputError for the first key of `value` (at schema path `path`) that the schema lacks."""
    if path.endswith("load_cases[].boundary_conditions[]"):
        path = "boundary_conditions[]"  # the same entries as the top-level list
    if isinstance(value, list) and path.endswith("[]"):
        for i, item in enumerate(value):
            _check_keys(item, path, paths, "%s[%d]" % (where, i))
        return
    if not isinstance(value, dict):
        return  # types and values are read_case's to check
    allowed = _children(paths, path)
    if not allowed and path:
        return  # a free-form object (a map of tags, ...)
    for key, item in value.items():
        name = where + "." + key if where else key
        if key in allowed:
            child = path + "." + key if path else key
            if path.endswith(".select") and key in ("and", "or") and isinstance(item, list):
                for i, sel in enumerate(item):
                    _check_keys(sel, path, paths, "%s[%d]" % (name, i))
            elif path.endswith(".select") and key == "not":
                _check_keys(item, path, paths, name)
            else:
                _check_keys(item, child, paths, name)
        elif key + "[]" in allowed:
            _check_keys(item, (path + "." if path else "") + key + "[]", paths, name)
        else:
            known = sorted(k.removesuffix("[]") for k in allowed)
            close = _difflib.get_close_matches(key, known, n=1)
            raise InputError("%s: unknown case key %r%s; the keys %s are %s" % (
                name, key, " (did you mean %r?)" % close[0] if close else "",
                "under " + where if where else "at the top level", ", ".join(known)))


def case(**sections):
    """A case dict from keyword arguments, one per top-level section of a case file:
    case(geometry={...}, meshing={...}, physics={...}, boundary_conditions=[...], ...).

    Every key, at every depth, is checked against the schema at once: an unknown one raises
    InputError naming it, its place and the nearest known key (values are checked by
    read_case, which every function taking a case calls).

    The sections and their keys (`schema()` has each key's type, default and meaning)::

"""
    _check_keys(sections, "", [k["path"] for k in schema()], "")
    return dict(sections)


if case.__doc__:  # None under python -OO
    case.__doc__ += _sections_doc()


def read_case(case, output_dir=None, base_dir=None):
    """A validated `Case` (defaults injected) from a dict, a JSON text or a case file path.

    Relative paths in a dict resolve against `base_dir` (default: the working directory);
    `output_dir` replaces output.dir. Raises InputError naming the JSON path of a bad key."""
    if isinstance(case, Case):
        return case
    output = "" if output_dir is None else _os.fspath(output_dir)
    if isinstance(case, dict):
        base = _os.fspath(base_dir) if base_dir is not None else _os.getcwd()
        return _curvefem.read_case_json(_json.dumps(case), _os.path.join(base, "<python case>"),
                                        output)
    return _curvefem.read_case(_os.fspath(case), output)


def study(study, output_dir=None, threads=0, progress=None, base_dir=None):
    """A convergence study, as `curvefem study` runs it (cases/README.md, Studies): every run of
    the sweep through the pipeline, then study.csv, study.png and study.json in output_dir
    (default: the study's output.dir). `study` is a study file path, or a dict (its relative
    paths resolve against `base_dir`, default the working directory). Returns study.json as a
    dict, with "exit_code" added (3 when a run failed; the other runs still ran). A bad study
    raises InputError naming its JSON path before anything runs. `progress(stage, fraction)`
    gets stages prefixed by "[i/n] run-name: "."""
    output = "" if output_dir is None else _os.fspath(output_dir)
    if isinstance(study, dict):
        base = _os.fspath(base_dir) if base_dir is not None else _os.getcwd()
        text, code = _curvefem.run_study(_json.dumps(study), _os.path.join(base, "study.json"),
                                         output, threads, progress)
    else:
        text, code = _curvefem.run_study("", _os.fspath(study), output, threads, progress)
    report = _json.loads(text)
    report["exit_code"] = code
    return report


def resolved(case):
    """The case as run, every default filled in (resolved_case.json), as a dict."""
    return _json.loads(read_case(case).resolved_json)


def check(path):
    """The `curvefem check` report of a surface file, as a dict ("acceptable", "defects", ...;
    "warnings" lists needle faces and near folds, which do not make the surface unacceptable but
    bound the elements of a mesh whose boundary keeps them)."""
    return _json.loads(_curvefem.check_surface(_os.fspath(path)))


def merge_short_edges(vertices, faces, length):
    """The repair of `curvefem check --merge-short-edges`: every edge shorter than `length` x the
    longest bounding-box edge is collapsed onto one of its ends (which keeps its position) where
    the surface stays a closed 2-manifold and no face turns by more than 30 degrees. Returns a dict:
    "vertices", "faces" (the repaired surface), "vertex_map" (per input vertex its repaired
    vertex), "face_origin" (per repaired face its input face), "merged" ([(removed, kept,
    length)]), "candidates", "left" (edges still shorter), "max_moved". The result is not checked
    for self-intersections here: write it and pass it to `check` before meshing it. A case's
    meshing.merge_short_edges does the same before `run` meshes."""
    v, f, vmap, origin, pairs, candidates, left, moved = _curvefem.merge_short_edges(
        _np.asarray(vertices, dtype=float), _np.asarray(faces, dtype=_np.int32), float(length))
    return {"vertices": v, "faces": f, "vertex_map": _np.asarray(vmap),
            "face_origin": _np.asarray(origin), "merged": pairs, "candidates": candidates,
            "left": left, "max_moved": moved}


def deform(vertices, faces, targets=None, grow=1.0, box=2.0, iterations=50, tolerance=1e-5,
           untangle=False, arap=0.0, way_back_targets=True, rebuild_quality=0.5,
           sliver_rests=False, threads=0):
    """Deforms a closed surface without self-intersection (SCAF with a tetrahedral scaffold, as
    `curvefem deform`): toward `targets` ({vertex: (x, y, z)}) and/or a rest shape `grow` times
    the input, inside the bounding box padded by (box - 1) / 2 x its longest extent. With
    `untangle=True` a self-intersecting genus-0 surface is flowed until embedded and pulled back
    toward itself. `arap` > 0 adds a surface ARAP term toward the input's shape; with
    `untangle=True, way_back_targets=False` it alone brings the surface back (the thesis' way,
    Fig. 3.9: the input's shape rather than its position). The scaffold is rebuilt only when its
    worst tet fell below `rebuild_quality` x that of the last rebuild (0: every iteration, as in
    the thesis). `sliver_rests=True`: a scaffold tet flatter than a small regular tet gets that
    tet as its rest, so the scaffold keeps sheets of the surface apart (thesis §3.2.2; report
    `max_slivers`). Returns (new vertices as an (n, 3)
    array, report dict); the report's
    `self_intersecting_pairs` and `non_positive_tets` come from exact checks independent of the
    solver, `valid` is true when both are 0."""
    targets = targets or {}
    ids = _np.array(sorted(targets), dtype=_np.int32)
    pos = _np.array([targets[i] for i in ids], dtype=float).reshape(-1, 3)
    V, text = _curvefem.deform(_np.asarray(vertices, dtype=float), _np.asarray(faces, dtype=_np.int32),
                               ids, pos, grow, box, iterations, tolerance, untangle, float(arap),
                               bool(way_back_targets), float(rebuild_quality),
                               bool(sliver_rests), threads)
    return V, _json.loads(text)


def load_surface(case):
    """Stage 1: the dense input of a curved | dense case, checked (a `Surface`)."""
    return _curvefem.load_surface(read_case(case))


def mesh(case, surface=None, threads=0, progress=None):
    """Stage 2: the mesh (a `Domain`): curved (validated), dense (tetfill) or given.

    `progress(stage, fraction)` is called as the work goes on (from worker threads too)."""
    c = read_case(case)
    if surface is None and c.method != "given":
        surface = _curvefem.load_surface(c)
    return _curvefem.mesh_domain(c, surface, threads, progress)


def load_mesh(path, validate=True, threads=0, progress=None):
    """Stage 2 without meshing: the curved `Domain` saved in the folder `path` (the output of
    `curvefem mesh` or of a curved `curvefem run` / `curvefem.run(..., output_dir=...)`: mesh.msh,
    boundary_map.json with phi and the shell fibers, report.json).

    The dense input is read from the path recorded in boundary_map.json and must still have the
    recorded checksum (InputError naming the file otherwise). With `validate` the independent
    validation runs again against the eps the mesh was made for (`Domain.valid`,
    `Domain.report["validation"]`). The result is what `mesh` would give for a case with
    `"geometry": {"mesh_dir": path}`: pass it to `discretize` / `solve` with any case of the same
    input (e.g. one with that geometry) to solve new boundary conditions on it."""
    return _curvefem.load_mesh_dir(_os.fspath(path), validate, threads, progress)


def discretize(case, domain):
    """Stage 3: the solve geometry and function space of a `Domain`."""
    return _curvefem.discretize(read_case(case), domain)


def solve(case, domain, discretization, load="", threads=0, progress=None):
    """Stages 4-5: the boundary conditions of a load case (by name; "" the first or only one)
    bound through φ⁻¹, then the solve (a `Solution`; .values is #nodes × components)."""
    return _curvefem.solve(read_case(case), domain, discretization, load, threads, progress)


def compute_errors(case, discretization, solution, load=""):
    """Stage 6: errors against the load case's exact solution, as a dict (empty without one)."""
    return _json.loads(_curvefem.compute_errors(read_case(case), discretization, solution,
                                                load).report_json)


def transfer_to_input(case, domain, discretization, solution, load=""):
    """Stage 7: (values, images): u_h(φ(v)) and φ(v) for every input vertex (NumPy)."""
    s = _curvefem.transfer_to_input(read_case(case), domain, discretization, solution, None, load)
    return s.values, s.images


# ---- meshio -------------------------------------------------------------------------------------

def _meshio_cells(nodes, cells, order, high_order):
    """(points, cell type, connectivity, used) of a tet mesh for meshio; `used` are the rows of
    `nodes` kept as points (None: all of them)."""
    nodes = _np.asarray(nodes, dtype=float)
    cells = _np.asarray(cells, dtype=_np.int64)
    if high_order not in ("auto", "corners", "lagrange"):
        raise ValueError("high_order: 'auto', 'corners' or 'lagrange', not %r" % (high_order,))
    if order == 1:
        return nodes, "tetra", cells[:, :4], None
    if order == 2 and high_order != "corners":
        # meshio's tetra10 is VTK's quadratic tetra (edges 01 12 02 03 13 23).
        return nodes, "tetra10", cells[:, _curvefem.vtk_node_permutation(2)], None
    if high_order == "lagrange":
        return (nodes, "VTK_LAGRANGE_TETRAHEDRON",
                cells[:, _curvefem.vtk_node_permutation(order)], None)
    used = _np.unique(cells[:, :4])
    index = _np.full(len(nodes), -1, dtype=_np.int64)
    index[used] = _np.arange(len(used))
    return nodes[used], "tetra", index[cells[:, :4]], used


def _to_meshio(nodes, cells, order, high_order, point_data=None, cell_data=None):
    import meshio  # Debian's python3-meshio; only needed here

    points, kind, conn, used = _meshio_cells(nodes, cells, order, high_order)
    pd = {}
    for name, values in (point_data or {}).items():
        values = _np.asarray(values, dtype=float)
        if values.ndim == 2 and values.shape[1] == 1:
            values = values[:, 0]
        pd[name] = values if used is None else values[used]
    cd = {name: [_np.asarray(values)] for name, values in (cell_data or {}).items()}
    return meshio.Mesh(points, [(kind, conn)], point_data=pd, cell_data=cd)


_HIGH_ORDER_DOC = """
    Cells by order: 1 "tetra", 2 "tetra10" (meshio's, i.e. VTK's quadratic tetra node order;
    XDMF, VTU, Gmsh, Exodus, ...). meshio's cubic and quartic tets ("tetra20", "tetra35") exist
    only for Gmsh files, in Gmsh's node order, and its VTU and XDMF writers do not know them
    (curvefem's own mesh.msh / volume.vtu hold them), so for order 3 and 4
    `high_order="auto"` (default) or "corners" gives straight
    "tetra" cells through the corner nodes only (points and point data restricted to the corners;
    the curved geometry and the higher-order values in between are dropped), and
    `high_order="lagrange"` gives meshio's "VTK_LAGRANGE_TETRAHEDRON" cells in VTK's node order
    with every node — written only by meshio's VTU / VTK writers. "corners" also turns order 2
    into straight tets. meshio's XDMF writer needs python3-h5py (tools/bootstrap installs it)."""


def _domain_to_meshio(self, high_order="auto"):
    cell_data = {}
    if len(self.cell_tags) == len(self.cells):
        cell_data["tag"] = _np.asarray(self.cell_tags)
    for name, components, values in self.cell_quality:
        if len(values) == components * len(self.cells):
            v = _np.asarray(values).reshape(-1, components)
            cell_data[name] = v[:, 0] if components == 1 else v
    return _to_meshio(self.nodes, self.cells, self.order, high_order, cell_data=cell_data)


_domain_to_meshio.__doc__ = """The mesh (order k, no solution) as a meshio.Mesh, with the cell
    data "tag" (region tags, when set) and, for curved meshes, the validator's per-tet quality
    fields of mesh.vtu.
""" + _HIGH_ORDER_DOC


def _disc_to_meshio(self, fields=None, high_order="auto", cell_data=None):
    point_data = {}
    for name, values in (fields or {}).items():
        values = getattr(values, "values", values)  # a Solution or an array
        values = _np.asarray(values)
        if len(values) != len(self.dof_points):
            raise ValueError("field %r: %d rows, the space has %d DOF points" % (
                name, len(values), len(self.dof_points)))
        point_data[name] = values
    return _to_meshio(self.dof_points, self.dof_cells, self.degree, high_order, point_data,
                      cell_data)


_disc_to_meshio.__doc__ = """The function space's Lagrange mesh (degree p: points are the DOF
    points) as a meshio.Mesh, with `fields` ({name: Solution or #DOFs x c array}) as point data.
""" + _HIGH_ORDER_DOC

Domain.report = property(lambda self: _json.loads(self.report_json),
                         doc="report.json's \"meshing\" section as a dict (quality, validation).")
Domain.corners = property(lambda self: self.cells[:, :4],
                          doc="#C x 4 corner node ids per tet (rows of nodes), positively "
                              "oriented: det(x1-x0, x2-x0, x3-x0) > 0.")
_domain_to_meshio.__name__ = _disc_to_meshio.__name__ = "to_meshio"
Domain.to_meshio = _domain_to_meshio
Discretization.to_meshio = _disc_to_meshio


class RunResult:
    """What `run` returns: the report (dict), exit code, stage times and the arrays. With
    load_cases: `solutions` and `surface_values_by_load` hold every case (in order, by name);
    `solution` / `surface_values` are the first one's."""

    def __init__(self, outcome):
        self._outcome = outcome
        self.report = _json.loads(outcome.report_json)
        self.exit_code = outcome.exit_code
        self.timings = dict(outcome.timings)
        self.domain = outcome.domain
        self.discretization = outcome.discretization
        self.load_names = list(outcome.load_names)
        self.solutions = [outcome.solution(i) for i in range(len(self.load_names))]
        self.solution = self.solutions[0]
        on_input = [outcome.on_input(i) for i in range(len(self.load_names))]
        self.surface_values_by_load = {
            name: (None if s is None else s.values) for name, s in zip(self.load_names, on_input)}
        self.surface_values = None if on_input[0] is None else on_input[0].values
        self.surface_images = None if on_input[0] is None else on_input[0].images

    def _field_name(self, i):
        base = "u" if self.solutions[i].components == 1 else "displacement"
        name = self.load_names[i]
        return base if name == "" else base + "_" + name

    def to_meshio(self, high_order="auto"):
        """The solution as a meshio.Mesh: the degree-p Lagrange mesh of the function space
        (points = DOF points) with every load case's solution as point data ("u" or
        "displacement", "_<name>" appended for named load cases, as in volume.vtu), and the
        curved mesh's per-tet quality fields as cell data.
        """
        d = self.discretization
        fields = {self._field_name(i): s for i, s in enumerate(self.solutions)}
        cell_data = {}
        for name, components, values in self.domain.cell_quality:
            if len(values) == components * len(d.dof_cells):
                v = _np.asarray(values).reshape(-1, components)
                cell_data[name] = v[:, 0] if components == 1 else v
        return d.to_meshio(fields, high_order=high_order, cell_data=cell_data)

    to_meshio.__doc__ += _HIGH_ORDER_DOC

    def surface_to_meshio(self):
        """The dense input surface (curved | dense runs) as a meshio.Mesh of "triangle" cells
        with u_h(phi(v)) of every load case as point data (named as in `to_meshio`)."""
        import meshio

        if self.surface_values is None:
            raise ValueError("a run on a given mesh has no input surface")
        point_data = {}
        for i, name in enumerate(self.load_names):
            values = self.surface_values_by_load[name]
            point_data[self._field_name(i)] = values[:, 0] if values.shape[1] == 1 else values
        return meshio.Mesh(self.domain.input_vertices,
                           [("triangle", _np.asarray(self.domain.input_faces))],
                           point_data=point_data)

    @property
    def valid(self):
        """False when the curved mesh failed its independent validation (exit code 3)."""
        return self.exit_code == 0

    def __repr__(self):
        return "RunResult(exit_code=%d, tets=%d, dofs=%d)" % (
            self.exit_code, self.report.get("tets", 0), self.report.get("dofs", 0))


def run(case, output_dir=None, threads=0, paraview=False, write=True, progress=None,
        base_dir=None):
    """The whole pipeline of `curvefem run`: mesh, solve, errors, transfer to the input and (with
    `write`) the output files of the CLI into output_dir (default: the case's output.dir)."""
    c = read_case(case, output_dir=output_dir, base_dir=base_dir)
    return RunResult(_curvefem.run_case(c, threads, paraview, write, progress))
