#!/usr/bin/python3
"""Whole-run elasticity peer of `curvefem run` in DOLFINx 0.5 (Debian python3-dolfinx): linear
elasticity P_p on a given Gmsh tetrahedral mesh of the beam [0, L] x [0, 1] x [0, 1], clamped at
x = 0, traction (0, 0, -1) on x = L, E = 1000, nu = 0.3; CG + GAMG (rtol 1e-10) with the six
rigid-body modes as near-nullspace (as in DOLFINx's elasticity demo), or CHOLMOD.

Prints one JSON line: DOFs (scalar unknowns), iterations, stage seconds, the compliance
(integral of t . u over the loaded face), the mean z-displacement of the loaded face and the
largest |u| over the DOF points (P_p nodes: the same points as curvefem's on the same mesh).
Usage: /usr/bin/python3 dolfinx_elasticity_msh.py MESH.msh P cg-gamg|direct
"""
import json
import sys
import time
from contextlib import ExitStack

t_start = time.perf_counter()
import meshio  # noqa: E402
import numpy as np  # noqa: E402
import ufl  # noqa: E402
from dolfinx import fem, la, mesh  # noqa: E402
from dolfinx.fem.petsc import (apply_lifting, assemble_matrix, assemble_vector,  # noqa: E402
                               set_bc)
from mpi4py import MPI  # noqa: E402
from petsc4py import PETSc  # noqa: E402

path, p, solver = sys.argv[1], int(sys.argv[2]), sys.argv[3]
E, nu = 1000.0, 0.3

t = time.perf_counter()
m = meshio.read(path)
cells = np.vstack([c.data for c in m.cells if c.type == "tetra"]).astype(np.int64)
domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.tetrahedron, 1))
msh = mesh.create_mesh(MPI.COMM_WORLD, cells, m.points[:, :3], domain)
length = float(m.points[:, 0].max())
t_mesh = time.perf_counter() - t

t = time.perf_counter()
V = fem.VectorFunctionSpace(msh, ("Lagrange", p))
mu, lmbda = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))


def sigma(w):
    return 2.0 * mu * ufl.sym(ufl.grad(w)) + lmbda * ufl.tr(ufl.sym(ufl.grad(w))) * ufl.Identity(3)


fdim = msh.topology.dim - 1
clamped = mesh.locate_entities_boundary(msh, fdim, lambda x: np.isclose(x[0], 0.0))
loaded = mesh.locate_entities_boundary(msh, fdim, lambda x: np.isclose(x[0], length))
tags = mesh.meshtags(msh, fdim, np.sort(loaded), np.full(len(loaded), 2, dtype=np.int32))
ds = ufl.Measure("ds", domain=msh, subdomain_data=tags)
traction = fem.Constant(msh, np.array([0.0, 0.0, -1.0]))
uu, v = ufl.TrialFunction(V), ufl.TestFunction(V)
a = fem.form(ufl.inner(sigma(uu), ufl.grad(v)) * ufl.dx)
L = fem.form(ufl.dot(traction, v) * ds(2))
zero = np.zeros(3, dtype=PETSc.ScalarType)
bc = fem.dirichletbc(zero, fem.locate_dofs_topological(V, fdim, clamped), V)
t_space = time.perf_counter() - t

t = time.perf_counter()
A = assemble_matrix(a, bcs=[bc])
A.assemble()
b = assemble_vector(L)
apply_lifting(b, [a], bcs=[[bc]])
b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
set_bc(b, [bc])
t_asm = time.perf_counter() - t


def rigid_body_modes(V):
    """The six rigid-body modes at the DOF points, orthonormalized (DOLFINx's demo)."""
    index_map, bs = V.dofmap.index_map, V.dofmap.index_map_bs
    ns = [la.create_petsc_vector(index_map, bs) for _ in range(6)]
    with ExitStack() as stack:
        local = [stack.enter_context(x.localForm()) for x in ns]
        basis = [np.asarray(x) for x in local]
        dofs = [V.sub(i).dofmap.list.array for i in range(3)]
        for i in range(3):
            basis[i][dofs[i]] = 1.0
        x = V.tabulate_dof_coordinates()
        block = V.dofmap.list.array
        x0, x1, x2 = x[block, 0], x[block, 1], x[block, 2]
        basis[3][dofs[0]] = -x1
        basis[3][dofs[1]] = x0
        basis[4][dofs[0]] = x2
        basis[4][dofs[2]] = -x0
        basis[5][dofs[2]] = x1
        basis[5][dofs[1]] = -x2
    la.orthonormalize(ns)
    return PETSc.NullSpace().create(vectors=ns)


t = time.perf_counter()
ksp = PETSc.KSP().create(msh.comm)
if solver == "direct":
    ksp.setOperators(A)
    ksp.setType("preonly")
    ksp.getPC().setType("cholesky")
    ksp.getPC().setFactorSolverType("cholmod")
else:
    A.setNearNullSpace(rigid_body_modes(V))
    ksp.setOperators(A)
    ksp.setType("cg")
    ksp.getPC().setType("gamg")
    ksp.setTolerances(rtol=1e-10)
uh = fem.Function(V)
ksp.solve(b, uh.vector)
uh.x.scatter_forward()
t_solve = time.perf_counter() - t

t = time.perf_counter()
compliance = msh.comm.allreduce(fem.assemble_scalar(fem.form(ufl.dot(traction, uh) * ds(2))),
                                op=MPI.SUM)
area = msh.comm.allreduce(fem.assemble_scalar(fem.form(1.0 * ds(2))), op=MPI.SUM)
t_qoi = time.perf_counter() - t

nodal = uh.x.array.reshape(-1, 3)
max_u = float(np.sqrt((nodal**2).sum(axis=1)).max())
print(json.dumps({
    "code": "dolfinx", "solver": solver, "dofs": V.dofmap.index_map.size_global * 3,
    "cells": msh.topology.index_map(3).size_global, "iterations": ksp.getIterationNumber(),
    "mesh": t_mesh, "space": t_space, "assembly": t_asm, "solve": t_solve, "qoi": t_qoi,
    "total_in_process": time.perf_counter() - t_start, "compliance": float(compliance),
    "mean_tip_uz": float(-compliance / area), "max_nodal_displacement": max_u}))
