#!/usr/bin/python3
"""Whole-run peer of `curvefem run` in DOLFINx 0.5 (Debian python3-dolfinx): P_p Poisson on a
given Gmsh tetrahedral mesh, u = cos πx cos πy cos πz, f = 3π² u, Dirichlet u on the whole
boundary, then the L2 and H1-semi errors against the exact u (a UFL expression of the
coordinates, so its gradient is exact), integrated with the given quadrature degree.

The mesh is read with meshio (Debian python3-meshio; Debian's DOLFINx has no gmsh module).
Prints one JSON line: dofs, iterations, stage seconds, errors. The caller times the process.

Usage: /usr/bin/python3 dolfinx_poisson_msh.py MESH.msh P cg-boomeramg|cg-gamg|direct QDEG
"""
import json
import sys
import time

t_start = time.perf_counter()
import meshio  # noqa: E402
import numpy as np  # noqa: E402
import ufl  # noqa: E402
from dolfinx import fem, mesh  # noqa: E402
from dolfinx.fem.petsc import (apply_lifting, assemble_matrix, assemble_vector,  # noqa: E402
                               set_bc)
from mpi4py import MPI  # noqa: E402
from petsc4py import PETSc  # noqa: E402

path, p, solver, qdeg = sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4])
t_import = time.perf_counter() - t_start

t = time.perf_counter()
m = meshio.read(path)
cells = np.vstack([c.data for c in m.cells if c.type == "tetra"]).astype(np.int64)
domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.tetrahedron, 1))
msh = mesh.create_mesh(MPI.COMM_WORLD, cells, m.points[:, :3], domain)
t_mesh = time.perf_counter() - t

t = time.perf_counter()
V = fem.FunctionSpace(msh, ("Lagrange", p))
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
t_space = time.perf_counter() - t

t = time.perf_counter()
A = assemble_matrix(a, bcs=[bc])
A.assemble()
b = assemble_vector(L)
apply_lifting(b, [a], bcs=[[bc]])
b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
set_bc(b, [bc])
t_asm = time.perf_counter() - t

t = time.perf_counter()
ksp = PETSc.KSP().create(msh.comm)
ksp.setOperators(A)
if solver == "direct":
    ksp.setType("preonly")
    ksp.getPC().setType("cholesky")
    ksp.getPC().setFactorSolverType("cholmod")
else:
    ksp.setType("cg")
    pc = ksp.getPC()
    if solver == "cg-boomeramg":
        pc.setType("hypre")
        pc.setHYPREType("boomeramg")
    else:
        pc.setType("gamg")
    ksp.setTolerances(rtol=1e-10)
uh = fem.Function(V)
ksp.solve(b, uh.vector)
uh.x.scatter_forward()
t_solve = time.perf_counter() - t

t = time.perf_counter()
dx = ufl.dx(metadata={"quadrature_degree": qdeg})
e = uh - u_ex
l2 = np.sqrt(msh.comm.allreduce(fem.assemble_scalar(fem.form(e * e * dx)), op=MPI.SUM))
h1 = np.sqrt(msh.comm.allreduce(
    fem.assemble_scalar(fem.form(ufl.inner(ufl.grad(e), ufl.grad(e)) * dx)), op=MPI.SUM))
t_err = time.perf_counter() - t

print(json.dumps({
    "code": "dolfinx", "solver": solver, "dofs": V.dofmap.index_map.size_global,
    "cells": msh.topology.index_map(3).size_global, "iterations": ksp.getIterationNumber(),
    "import": t_import, "mesh": t_mesh, "space": t_space, "assembly": t_asm, "solve": t_solve,
    "errors": t_err, "total_in_process": time.perf_counter() - t_start, "quadrature_degree": qdeg,
    "l2_error": float(l2), "h1_semi_error": float(h1)}))
