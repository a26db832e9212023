#!/usr/bin/python3
"""Peer of benchmarks/bench_poisson_ball.cpp in DOLFINx 0.5: reads the same curved ball mesh
(MSH written by curvefem, geometric order K) through Gmsh's Python API and dolfinx.io.gmshio,
solves −Δu = f, u = (1 − r²) cos(x + 2y + 3z), u = 0 on the boundary, P_p; one JSON line.
Usage: /usr/bin/python3 dolfinx_poisson_ball.py MESH.msh P direct|cg
"""
import json
import resource
import sys
import time

import gmsh
import numpy as np
import ufl
from dolfinx import fem, mesh
from dolfinx.fem.petsc import apply_lifting, assemble_matrix, assemble_vector, set_bc
from dolfinx.io import gmshio
from mpi4py import MPI
from petsc4py import PETSc

path, p, solver = sys.argv[1], int(sys.argv[2]), sys.argv[3]
gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.open(path)
msh, _, _ = gmshio.model_to_mesh(gmsh.model, MPI.COMM_WORLD, 0, gdim=3)
gmsh.finalize()
t_total = time.perf_counter()
t = time.perf_counter()
V = fem.FunctionSpace(msh, ("Lagrange", p))
t_space = time.perf_counter() - t
x = ufl.SpatialCoordinate(msh)
s = x[0] + 2 * x[1] + 3 * x[2]
u_ex = (1 - ufl.dot(x, x)) * ufl.cos(s)
f = -ufl.div(ufl.grad(u_ex))
uu, v = ufl.TrialFunction(V), ufl.TestFunction(V)
a = fem.form(ufl.inner(ufl.grad(uu), ufl.grad(v)) * ufl.dx)
L = fem.form(f * v * ufl.dx)
msh.topology.create_connectivity(msh.topology.dim - 1, msh.topology.dim)
facets = mesh.exterior_facet_indices(msh.topology)
dofs = fem.locate_dofs_topological(V, msh.topology.dim - 1, facets)
bc = fem.dirichletbc(PETSc.ScalarType(0), dofs, V)
t = time.perf_counter()
A = assemble_matrix(a, bcs=[bc])
A.assemble()
b = assemble_vector(L)
apply_lifting(b, [a], bcs=[[bc]])
b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
set_bc(b, [bc])
t_asm = time.perf_counter() - t
ksp = PETSc.KSP().create(msh.comm)
ksp.setOperators(A)
if solver == "direct":
    ksp.setType("preonly")
    ksp.getPC().setType("cholesky")
    ksp.getPC().setFactorSolverType("cholmod")
else:
    ksp.setType("cg")
    ksp.getPC().setType("gamg")
    ksp.setTolerances(rtol=1e-10)
uh = fem.Function(V)
t = time.perf_counter()
ksp.setUp()
t_setup = time.perf_counter() - t
t = time.perf_counter()
ksp.solve(b, uh.vector)
uh.x.scatter_forward()
t_solve = time.perf_counter() - t
t = time.perf_counter()
dxe = ufl.dx(metadata={"quadrature_degree": 2 * p + 8})
e2 = fem.assemble_scalar(fem.form((uh - u_ex) ** 2 * dxe))
h2 = fem.assemble_scalar(fem.form(ufl.inner(ufl.grad(uh - u_ex), ufl.grad(uh - u_ex)) * dxe))
t_err = time.perf_counter() - t
print(json.dumps({
    "code": "dolfinx", "p": p, "k": msh.geometry.cmap.degree,
    "tets": msh.topology.index_map(3).size_global, "dofs": V.dofmap.index_map.size_global,
    "threads": MPI.COMM_WORLD.size, "solver": "cholmod" if solver == "direct" else "cg-gamg",
    "iterations": ksp.getIterationNumber(), "dofmap_s": t_space, "assembly_s": t_asm,
    "setup_s": t_setup, "solve_s": t_solve, "solve_total_s": t_setup + t_solve, "errors_s": t_err,
    "total_s": time.perf_counter() - t_total, "l2_error": float(np.sqrt(e2)),
    "h1_semi_error": float(np.sqrt(h2)),
    "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
}))
