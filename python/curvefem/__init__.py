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
"""

import json as _json
import os as _os

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
    "load_surface", "mesh", "read_case", "resolved", "run", "set_log_level", "solve",
    "transfer_to_input",
]

# A library should not chatter: warnings and errors only, until set_log_level says otherwise.
set_log_level("warn")


def case(**sections):
    """A case dict from keyword arguments, one per top-level section of a case file:
    case(geometry={...}, meshing={...}, physics={...}, boundary_conditions=[...], ...)."""
    return dict(sections)


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


def resolved(case):
    """The case as run, every default filled in (resolved_case.json), as a dict."""
    return _json.loads(read_case(case).resolved_json)


def check(path):
    """The `curvefem check` report of a surface file, as a dict ("acceptable", "defects", ...)."""
    return _json.loads(_curvefem.check_surface(_os.fspath(path)))


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
        self.load_names = list(outcome.load_names)
        self.solutions = [outcome.solution(i) for i in range(len(self.load_names))]
        self.solution = self.solutions[0]
        on_input = [outcome.on_input(i) for i in range(len(self.load_names))]
        self.surface_values_by_load = {
            name: (None if s is None else s.values) for name, s in zip(self.load_names, on_input)}
        self.surface_values = None if on_input[0] is None else on_input[0].values
        self.surface_images = None if on_input[0] is None else on_input[0].images

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
