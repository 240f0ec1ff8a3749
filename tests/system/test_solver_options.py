"""Options from [solver] petsc reach every PETSc object they name, also those PETSc only reads at the first
solve (the factorisation's MUMPS controls), and two drivers' options never mix."""
import fem_forms as ff
from helpers import beam_scene
from fem_forms.model import build_model
from fem_forms.solvers import snes


def _driver(petsc: dict) -> snes.SNESDriver:
    scene = ff.Scene.from_dict(beam_scene(
        mesh={"generator": "box", "size": [1.0, 0.1, 0.1], "cells": [6, 1, 1]},
        material={"model": "neo-hookean", "E": 1e6, "nu": 0.3, "rho": 1000.0}))
    model = build_model(scene)
    problem = snes.NonlinearProblem(model.unknown, model.residual, model.jacobian, model.bcs, model.energy)
    options = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps", **petsc}
    return snes.SNESDriver(problem, options, linear_kind="direct")


def test_factor_options_are_read_at_the_first_solve():
    drv = _driver({"mat_mumps_icntl_14": 77})
    drv.solve_step()
    factor = drv.snes.getKSP().getPC().getFactorMatrix()
    assert factor.getMumpsIcntl(14) == 77


def test_two_drivers_keep_their_own_options():
    first = _driver({"mat_mumps_icntl_14": 61})
    second = _driver({"mat_mumps_icntl_14": 93})
    second.solve_step()
    first.solve_step()
    assert first.snes.getKSP().getPC().getFactorMatrix().getMumpsIcntl(14) == 61
    assert second.snes.getKSP().getPC().getFactorMatrix().getMumpsIcntl(14) == 93
