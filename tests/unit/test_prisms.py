"""Unit tests of prism (wedge) meshes: the patch test on distorted prisms (a uniform strain is
reproduced exactly), a homogeneous large deformation is in equilibrium, and what dolfinx 0.5.2 cannot
do on prisms is refused when the scene is read."""
import numpy as np
import pytest
import ufl
from dolfinx import fem, mesh as dmesh
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
from petsc4py import PETSc

import fem_forms as ff
from fem_forms.kinematics import deformation_gradient
from fem_forms.meshes.prisms import create_prism_mesh, prism_box_arrays

G = np.array([[1.0e-3, 2.0e-3, -1.0e-3], [0.5e-3, -2.0e-3, 1.5e-3], [-1.0e-3, 0.0, 3.0e-3]])


@pytest.fixture(scope="module")
def distorted():
    """A 3 x 2 x 2 box of prisms with its interior nodes moved at random (by up to 15 % of a cell)."""
    comm = MPI.COMM_WORLD
    if comm.rank == 0:
        points, cells = prism_box_arrays([0, 0, 0], [3.0, 2.0, 2.0], [3, 2, 2])
        inner = np.all((points > 1e-9) & (points < np.array([3.0, 2.0, 2.0]) - 1e-9), axis=1)
        rng = np.random.default_rng(7)
        points[inner] += rng.uniform(-0.15, 0.15, (inner.sum(), 3))
    else:
        points, cells = np.empty((0, 3)), np.empty((0, 6), dtype=np.int64)
    return create_prism_mesh(comm, cells, points)


def _boundary_dofs(V):
    mesh = V.mesh
    mesh.topology.create_connectivity(2, 3)
    facets = dmesh.exterior_facet_indices(mesh.topology)
    return fem.locate_dofs_topological(V, 2, facets)


def test_volume_and_cell_count(distorted):
    vol = distorted.comm.allreduce(fem.assemble_scalar(fem.form(fem.Constant(distorted, 1.0) * ufl.dx)),
                                   op=MPI.SUM)
    assert vol == pytest.approx(12.0, rel=1e-12)          # interior moves keep the volume
    assert distorted.topology.index_map(3).size_global == 24
    assert distorted.topology.cell_name() == "prism"


def test_patch_test_reproduces_a_uniform_strain_exactly(distorted):
    """Linear elasticity, u = G X on the boundary: the interior nodes take u = G X to round-off."""
    V = fem.VectorFunctionSpace(distorted, ("Lagrange", 1))
    exact = fem.Function(V)
    exact.interpolate(lambda X: G @ X)
    u = fem.Function(V)
    mat = ff.LinearElastic(1.0, 1.5)
    dx = ufl.dx(metadata={"quadrature_degree": 2})
    residual = ufl.derivative(mat.psi(deformation_gradient(u)) * dx, u, ufl.TestFunction(V))
    a = fem.form(ufl.derivative(residual, u, ufl.TrialFunction(V)))
    bc = fem.dirichletbc(exact, _boundary_dofs(V))
    A = fpetsc.assemble_matrix(a, bcs=[bc])
    A.assemble()
    b = fpetsc.create_vector(fem.form(residual))
    with b.localForm() as loc:
        loc.set(0.0)
    fpetsc.apply_lifting(b, [a], bcs=[[bc]])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    fpetsc.set_bc(b, [bc])
    ksp = PETSc.KSP().create(distorted.comm)
    ksp.setOperators(A)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.solve(b, u.vector)
    u.x.scatter_forward()
    assert np.abs(u.x.array - exact.x.array).max() < 1e-13


def test_homogeneous_large_deformation_is_in_equilibrium(distorted):
    """u = (F0 - I) X with a finite F0 (rotation and stretch): the corotated residual vanishes at
    every interior dof (any material is in equilibrium under a homogeneous deformation)."""
    F0 = np.array([[0.9, -0.5, 0.1], [0.45, 0.95, 0.0], [0.05, 0.1, 1.1]])
    V = fem.VectorFunctionSpace(distorted, ("Lagrange", 1))
    u = fem.Function(V)
    u.interpolate(lambda X: (F0 - np.eye(3)) @ X)
    mat = ff.Corotated(1.0, 1.5)
    dx = ufl.dx(metadata={"quadrature_degree": 2})
    r = fpetsc.assemble_vector(fem.form(ufl.derivative(mat.psi(deformation_gradient(u)) * dx, u,
                                                       ufl.TestFunction(V))))
    r.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    values = r.array.reshape(-1, 3)
    interior = np.setdiff1d(np.arange(len(values)), _boundary_dofs(V))
    assert np.abs(values).max() > 0.01                     # boundary nodes carry the tractions
    assert np.abs(values[interior]).max() < 1e-12


def _scene(**mesh_over):
    d = {"mesh": {"generator": "box", "size": [1, 1, 1], "cells": [1, 1, 1], "cell": "prism", **mesh_over},
         "material": {"model": "linear", "E": 1e6, "nu": 0.3, "rho": 1000.0},
         "discretization": {"degree": 1},
         "fix": [{"where": {"axis": "z", "at": 0.0}}],
         "load": [{"type": "gravity", "g": [0.0, 0.0, -9.81]}]}
    return d


@pytest.mark.parametrize("change, fragment", [
    (lambda d: d["discretization"].update(degree=2), "prisms take degree 1 only"),
    (lambda d: d["load"].append({"type": "traction", "where": {"axis": "z", "at": 1.0},
                                 "value": [0, 0, 1.0]}), r"load\[1\]: surface loads"),
    (lambda d: d["load"].append({"type": "pressure", "where": {"axis": "z", "at": 1.0}, "value": 1.0}),
     "cannot integrate over prism facets"),
    (lambda d: d.update(mesh={"generator": "sphere", "radius": 1.0, "cell": "prism"}),
     "only the box generator makes prisms"),
    (lambda d: d.update(analysis="inverse"), "not on prism meshes"),
])
def test_what_prisms_cannot_do_is_refused_in_one_line(change, fragment):
    d = _scene()
    ff.Scene.from_dict(d)                                  # the base scene is valid
    change(d)
    with pytest.raises(ff.InputError, match=fragment):
        ff.Scene.from_dict(d)
