"""Heat and motion together (analysis = "dynamic" with [thermal], staggered per time step):
- a free bar (nu = 0) suddenly at T0 above its stress-free temperature, insulated: the thermal strain
  eps0 = alpha (T0 - T_ref) launches an axial wave; 1-D theory gives the tip a triangle wave between 0 and
  2 eps0 L with period 4 L / c, c = sqrt(E / rho) (Newmark's dispersion rounds the corners);
- the same bar with strong viscous damping and damping_heat: the stored energy 3/2 E eps0^2 V (u = 0 with
  strain -eps0 I, nu = 0) is all dissipated and, the bar being insulated, heats it by 3/2 E eps0^2 / (rho c)
  on average (energy conservation: a closed form the solver never sees)."""
import math

from dolfinx import fem
from mpi4py import MPI
import numpy as np
import pytest
import ufl

import fem_forms as ff
from fem_forms.analyses.dynamic import solve_dynamic

E, RHO, ALPHA, T0, L = 1.0e6, 1000.0, 1e-4, 10.0, 1.0
EPS0 = ALPHA * T0
C = math.sqrt(E / RHO)
PERIOD = 4 * L / C


def heated_bar(duration, dt, damping=None, damping_heat=False) -> ff.Scene:
    d = {"analysis": "dynamic", "mesh": {"size": [L, 0.1, 0.1], "cells": [20, 2, 2]},
         "material": {"model": "linear", "E": E, "nu": 0.0, "rho": RHO}, "discretization": {"degree": 1},
         "fix": [{"where": {"axis": "x", "at": 0.0}, "components": ["x"]},
                 {"where": {"point": [0.0, 0.0, 0.0]}, "components": ["y", "z"]},
                 {"where": {"point": [0.0, 0.1, 0.0]}, "components": ["z"]}],
         "thermal": {"conductivity": 1.0, "specific_heat": 1.0, "expansion": ALPHA, "initial_temperature": T0,
                     "damping_heat": damping_heat},
         "dynamic": {"duration": duration, "dt": dt, "output_every": 1000, "checkpoint_every": 0},
         "output": {"probes": {"tip": [L, 0.05, 0.05]}}}
    if damping:
        d["damping"] = damping
    return ff.Scene.from_dict(d)


def test_suddenly_heated_free_bar_rings_between_0_and_2_eps0_L():
    r = solve_dynamic(heated_bar(PERIOD, PERIOD / 200))
    rows = np.array(r.probe_rows)
    t, tip, T = rows[:, 0], rows[:, 1], rows[:, -1]
    assert tip.max() == pytest.approx(2 * EPS0 * L, rel=0.05)
    assert t[np.argmax(tip)] == pytest.approx(PERIOD / 2, rel=0.05)
    assert np.trapz(tip, t) / PERIOD == pytest.approx(EPS0 * L, rel=0.02)     # the mean: free expansion
    np.testing.assert_allclose(T, T0, rtol=1e-12)                              # insulated, no damping heat
    assert r.summary()["physics"][-1] == "heat (backward Euler)"


def test_damping_heat_equals_the_stored_energy():
    sc = heated_bar(0.5, 0.0025, damping={"viscous": {"shear": 2e4, "bulk": 2e4}}, damping_heat=True)
    r = solve_dynamic(sc)
    rows = np.array(r.probe_rows)
    assert rows[-1, 1] == pytest.approx(EPS0 * L, rel=0.01)                    # settled, freely expanded
    T = r.system.model.temperature
    mean_rise = MPI.COMM_WORLD.allreduce(fem.assemble_scalar(fem.form((T - T0) * ufl.dx)), op=MPI.SUM) / (L * 0.01)
    assert mean_rise == pytest.approx(1.5 * E * EPS0**2 / (RHO * 1.0), rel=1e-3)        # measured +0.018 %
