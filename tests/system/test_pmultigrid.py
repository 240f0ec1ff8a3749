"""P2 -> P1 p-multigrid on the iterative path: the interpolation is exact on P1 fields, the driver really runs
PCMG with the P1 Galerkin coarse level, and the answer is the direct solver's (2 ranks: tests/system/test_mpi.py)."""
import numpy as np
import pytest
from dolfinx import fem, mesh as dmesh
from mpi4py import MPI

import fem_forms as ff
from fem_forms.solvers import linear, pmultigrid
from helpers import beam_scene


def test_interpolation_reproduces_a_linear_field_exactly():
    msh = dmesh.create_box(MPI.COMM_WORLD, [np.zeros(3), np.array([1.0, 0.1, 0.1])], [6, 2, 2],
                           dmesh.CellType.tetrahedron)
    V2 = fem.VectorFunctionSpace(msh, ("Lagrange", 2))
    pmg = pmultigrid.PMultigrid(V2)
    field = lambda x: np.stack([x[0] + 2 * x[1], 3 * x[2] - x[0], x[1] + 0.5])     # noqa: E731
    u1, u2 = fem.Function(pmg.V1), fem.Function(V2)
    u1.interpolate(field)
    u2.interpolate(field)
    y = u2.vector.duplicate()
    pmg.interpolation.mult(u1.vector, y)
    y.axpy(-1.0, u2.vector)
    assert y.norm() < 1e-12 * u2.vector.norm()
    assert pmg.interpolation.getBlockSizes() == (3, 3)
    pmg.destroy()


def test_options_choose_p_multigrid_from_degree_2_and_leave_gamg_whole():
    assert linear.options("iterative", degree=1)["pc_type"] == "gamg"
    p2 = linear.options("iterative", degree=2)
    assert p2["pc_type"] == "mg" and p2["mg_coarse_pc_type"] == "gamg"
    assert linear.options("direct", degree=2)["pc_type"] == "lu"
    # a scene asking for GAMG on P2 gets ITERATIVE's GAMG: no pc_mg_levels, mg_coarse_* (GAMG reads them too)
    merged = {**p2, "pc_type": "gamg"}
    pmultigrid.drop_unused(merged, {"pc_type": "gamg"})
    assert merged == linear.ITERATIVE


def _p2_beam(linear_kind: str, petsc: dict | None = None) -> ff.Scene:
    scene = ff.Scene.from_dict(beam_scene(
        mesh={"generator": "box", "size": [1.0, 0.1, 0.1], "cells": [20, 2, 2]},
        material={"model": "neo-hookean", "E": 1e7, "nu": 0.3, "rho": 1000.0},
        discretization={"degree": 2}, solver={"linear": linear_kind, "petsc": petsc or {}}))
    return scene


def test_p2_iterative_runs_pcmg_on_the_p1_coarse_level_and_gives_the_direct_answer(monkeypatch):
    coarse_sizes = []
    refresh = pmultigrid.PMultigrid.refresh

    def recording(self, ksp, P):
        refresh(self, ksp, P)
        coarse_sizes.append((ksp.getPC().getType(), self.coarse.getSize()[0], P.getSize()[0]))
    monkeypatch.setattr(pmultigrid.PMultigrid, "refresh", recording)
    direct = ff.solve_static(_p2_beam("direct"))
    iterative = ff.solve_static(_p2_beam("iterative"))
    assert direct.report.converged and iterative.report.converged
    assert iterative.report.linear_solver == "iterative"
    assert coarse_sizes and coarse_sizes[0] == ("mg", 3 * 21 * 3 * 3, iterative.model.dofs)   # P1 nodes x 3
    np.testing.assert_allclose(iterative.probes["tip"], direct.probes["tip"], rtol=1e-6)
    assert iterative.energy == pytest.approx(direct.energy, rel=1e-8)
    # the scene may still ask for GAMG on the P2 tangent itself: no p-multigrid then, the same answer
    coarse_sizes.clear()
    gamg = ff.solve_static(_p2_beam("iterative", {"pc_type": "gamg"}))
    assert gamg.report.converged and not coarse_sizes
    np.testing.assert_allclose(gamg.probes["tip"], direct.probes["tip"], rtol=1e-6)
