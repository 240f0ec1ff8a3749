"""Nearly incompressible materials: the mixed (Taylor-Hood P2/P1) formulation neither locks nor fails;
the displacement formulation locks and warns."""
import numpy as np
from scipy.optimize import fsolve

import fem_forms as ff
from fem_forms.materials import lame_from_young_poisson
from helpers import incompressible_beam as beam


def euler_bernoulli_timoshenko(nu, E=1e9, rho=1000.0, L=1.0, h=0.05):
    A, I = h * h, h**4 / 12
    w = rho * 9.81 * A
    return w * L**4 / (8 * E * I) + w * L**2 / (2 * (5 / 6) * E / (2 * (1 + nu)) * A)


def test_mixed_cantilever_matches_beam_theory_without_locking():
    """nu = 0.4999: Taylor-Hood stays within 2.5 % of beam theory (the clamp restrains the Poisson
    contraction near the root, which stiffens the 3D beam a little); P2 displacement elements lose
    about 9 % to locking on the same mesh."""
    nu = 0.4999
    ref = euler_bernoulli_timoshenko(nu)
    mixed = ff.solve_static(beam(nu, "mixed", 2, cells=(30, 3, 3)))
    p2 = ff.solve_static(beam(nu, "displacement", 2, cells=(30, 3, 3)))
    assert mixed.report.converged and p2.report.converged
    err_mixed = abs(-mixed.probes["tip"][2] / ref - 1)
    err_p2 = abs(-p2.probes["tip"][2] / ref - 1)
    assert err_mixed < 0.025
    assert err_p2 > 2 * err_mixed


def test_displacement_p1_locks_and_warns():
    nu = 0.4999
    res = ff.solve_static(beam(nu, "displacement", 1))
    assert res.report.converged
    ref = euler_bernoulli_timoshenko(nu)
    assert -res.probes["tip"][2] < 0.5 * ref                    # locked: far too stiff
    assert any("formulation = \"mixed\"" in w for w in res.summary()["warnings"])


def test_mixed_uniaxial_tension_matches_analytic_nearly_incompressible():
    """Neo-Hookean at nu = 0.4999 stretched 1.3x: lateral stretch ~ 1/sqrt(1.3) (volume kept)."""
    E, nu = 1e6, 0.4999
    mu, lmbda = lame_from_young_poisson(E, nu)
    T = 0.4 * E

    def eqs(v):
        l1, l2 = v
        lnJ = np.log(l1 * l2**2)
        return [mu * (l1 - 1 / l1) + lmbda * lnJ / l1 - T, mu * (l2 - 1 / l2) + lmbda * lnJ / l2]
    l1, l2 = fsolve(eqs, [1.2, 0.9], xtol=1e-13)
    d = {"mesh": {"generator": "box", "size": [1.0, 1.0, 1.0], "cells": [2, 2, 2]},
         "material": {"model": "neo-hookean", "E": E, "nu": nu},
         "discretization": {"degree": 2, "formulation": "mixed"},
         "fix": [{"where": {"axis": a, "at": 0.0}, "components": [a]} for a in "xyz"],
         "load": [{"type": "traction", "where": {"axis": "x", "at": 1.0}, "value": [T, 0.0, 0.0]}],
         "solver": {"steps": 2},
         "output": {"probes": {"corner": [1.0, 1.0, 1.0]}}}
    res = ff.solve_static(ff.Scene.from_dict(d))
    assert res.report.converged
    assert abs(l1 * l2 * l2 - 1) < 1e-3
    np.testing.assert_allclose(res.probes["corner"], [l1 - 1, l2 - 1, l2 - 1], rtol=1e-7)
