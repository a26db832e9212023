#!/usr/bin/python3
"""Peer of benchmarks/bench_poisson.cpp in DOLFINx 0.5 (Debian python3-dolfinx).

-Δu = f on the unit cube, u = cos πx cos πy cos πz, Dirichlet u on the boundary, P_p on 6n³
tetrahedra. Prints one JSON line with the same keys as curvefem_bench_poisson.
Usage: /usr/bin/python3 dolfinx_poisson.py N P direct|cg
"""
import json
import resource
import sys
import time

import numpy as np
import ufl
from dolfinx import fem, mesh
from dolfinx.fem.petsc import apply_lifting, assemble_matrix, assemble_vector, set_bc
from mpi4py import MPI
from petsc4py import PETSc

n, p, solver = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
t_total = time.perf_counter()
t = time.perf_counter()
msh = mesh.create_unit_cube(MPI.COMM_WORLD, n, n, n, mesh.CellType.tetrahedron)
t_mesh = time.perf_counter() - t
t = time.perf_counter()
V = fem.FunctionSpace(msh, ("Lagrange", p))
t_space = time.perf_counter() - t

x = ufl.SpatialCoordinate(msh)
u_ex = ufl.cos(ufl.pi * x[0]) * ufl.cos(ufl.pi * x[1]) * ufl.cos(ufl.pi * x[2])
f = 3 * ufl.pi**2 * u_ex
uu, v = ufl.TrialFunction(V), ufl.TestFunction(V)
a = fem.form(ufl.inner(ufl.grad(uu), ufl.grad(v)) * ufl.dx)
L = fem.form(f * v * ufl.dx)
msh.topology.create_connectivity(msh.topology.dim - 1, msh.topology.dim)
facets = mesh.exterior_facet_indices(msh.topology)
dofs = fem.locate_dofs_topological(V, msh.topology.dim - 1, facets)
uD = fem.Function(V)
uD.interpolate(lambda X: np.cos(np.pi * X[0]) * np.cos(np.pi * X[1]) * np.cos(np.pi * X[2]))
bc = fem.dirichletbc(uD, dofs)

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
deg = 2 * p + 4
dxe = ufl.dx(metadata={"quadrature_degree": deg})
e2 = fem.assemble_scalar(fem.form((uh - u_ex) ** 2 * dxe))
h2 = fem.assemble_scalar(fem.form(ufl.inner(ufl.grad(uh - u_ex), ufl.grad(uh - u_ex)) * dxe))
t_err = time.perf_counter() - t
print(json.dumps({
    "code": "dolfinx", "n": n, "p": p, "tets": msh.topology.index_map(3).size_global,
    "dofs": V.dofmap.index_map.size_global, "threads": MPI.COMM_WORLD.size,
    "solver": "cholmod" if solver == "direct" else "cg-gamg", "iterations": ksp.getIterationNumber(),
    "mesh_s": t_mesh, "dofmap_s": t_space, "assembly_s": t_asm, "setup_s": t_setup,
    "solve_s": t_solve, "solve_total_s": t_setup + t_solve, "errors_s": t_err,
    "total_s": time.perf_counter() - t_total, "l2_error": float(np.sqrt(e2)),
    "h1_semi_error": float(np.sqrt(h2)),
    "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
}))
