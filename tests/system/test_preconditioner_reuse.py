"""Multigrid kept across Newton steps: the answer is the direct solver's, fewer hierarchies are built
than Newton steps (the rebuild rule itself: unit/test_preconditioner_reuse_rule.py)."""
import numpy as np
import pytest

import fem_forms as ff
from helpers import beam_scene
from fem_forms.solvers import preconditioner_reuse as pr


def _soft_beam(linear: str) -> ff.Scene:
    scene = ff.Scene.from_dict(beam_scene(
        mesh={"generator": "box", "size": [1.0, 0.1, 0.1], "cells": [20, 2, 2]},
        material={"model": "neo-hookean", "E": 3e5, "nu": 0.3, "rho": 1000.0},
        discretization={"degree": 2}))
    scene.solver.linear = linear
    return scene


def test_kept_multigrid_gives_the_direct_answer_with_fewer_builds_than_newton_steps():
    assert pr._SET_LAG is not None, "SNESSetLagPreconditioner must be reachable through petsc4py"
    direct = ff.solve_static(_soft_beam("direct"))
    iterative = ff.solve_static(_soft_beam("iterative"))
    assert direct.report.converged and iterative.report.converged
    rep = iterative.report
    assert rep.linear_solver == "iterative" and rep.newton_iterations >= 4     # a truly nonlinear solve
    assert 1 <= rep.preconditioner_builds < rep.newton_iterations
    assert type(rep.preconditioner_builds) is int          # a count, not a numpy scalar (JSON writers)
    assert iterative.summary()["preconditioner_builds"] == rep.preconditioner_builds
    np.testing.assert_allclose(iterative.probes["tip"], direct.probes["tip"], rtol=1e-6)
    assert iterative.energy == pytest.approx(direct.energy, rel=1e-8)
