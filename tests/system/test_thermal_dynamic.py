"""Heat and motion together (analysis = "dynamic" with [thermal], staggered per time step):
- a free bar (nu = 0) suddenly at T0 above its stress-free temperature, insulated: the thermal strain
  eps0 = alpha (T0 - T_ref) launches an axial wave; 1-D theory gives the tip a triangle wave between 0 and
  2 eps0 L with period 4 L / c, c = sqrt(E / rho) (Newmark's dispersion rounds the corners);
- the same bar with strong viscous damping and damping_heat: the stored energy 3/2 E eps0^2 V (u = 0 with
  strain -eps0 I, nu = 0) is all dissipated and, the bar being insulated, heats it by 3/2 E eps0^2 / (rho c)
  on average (energy conservation: a closed form the solver never sees);
- the energy account with the temperature changing (thermal work, energy.py): the same bar at T_ref heated
  to T0 within the first step (every node on a heated face), then kinetic + elastic = thermal work to
  round-off (Newmark conserves energy on a linear problem: the balance is the reference), also when the heat
  diffuses in from one end while the bar moves; held between rollers and heated slowly, the thermal work is
  the closed-form stored energy 1/2 E eps0^2 V. With damping heat the balance closes too (no double count)."""
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


def heated_bar(duration, dt, damping=None, damping_heat=False, heated=None, cells=(20, 2, 2),
               conductivity=1.0, held=False) -> ff.Scene:
    """The free bar; `heated`: [[thermal.boundary]] tables heating it from T_ref = 0 instead of starting at T0."""
    d = {"analysis": "dynamic", "mesh": {"size": [L, 0.1, 0.1], "cells": list(cells)},
         "material": {"model": "linear", "E": E, "nu": 0.0, "rho": RHO}, "discretization": {"degree": 1},
         "fix": [{"where": {"axis": "x", "at": 0.0}, "components": ["x"]},
                 {"where": {"point": [0.0, 0.0, 0.0]}, "components": ["y", "z"]},
                 {"where": {"point": [0.0, 0.1, 0.0]}, "components": ["z"]}],
         "thermal": {"conductivity": conductivity, "specific_heat": 1.0, "expansion": ALPHA, "initial_temperature": T0,
                     "damping_heat": damping_heat},
         "dynamic": {"duration": duration, "dt": dt, "output_every": 1000, "checkpoint_every": 0},
         "output": {"probes": {"tip": [L, 0.05, 0.05]}}}
    if damping:
        d["damping"] = damping
    if held:                                           # a roller at x = L too
        d["fix"].append({"where": {"axis": "x", "at": L}, "components": ["x"]})
    if heated:
        d["thermal"].update(initial_temperature=0.0, boundary=heated)
    return ff.Scene.from_dict(d)


def test_suddenly_heated_free_bar_rings_between_0_and_2_eps0_L():
    r = solve_dynamic(heated_bar(PERIOD, PERIOD / 200))
    rows = np.array(r.probe_rows)
    t, tip, T = rows[:, 0], rows[:, 1], rows[:, 7]             # time, tip_ux, ..., tip_T (then the supports' forces)
    assert tip.max() == pytest.approx(2 * EPS0 * L, rel=0.05)
    assert t[np.argmax(tip)] == pytest.approx(PERIOD / 2, rel=0.05)
    assert np.trapz(tip, t) / PERIOD == pytest.approx(EPS0 * L, rel=0.02)     # the mean: free expansion
    np.testing.assert_allclose(T, T0, rtol=1e-12)                              # insulated, no damping heat
    assert r.summary()["physics"][-1] == "heat (backward Euler)"
    assert r.energy.balance_error() < 1e-10 and r.energy.now.thermal_work == 0.0     # T never changes: 6.7e-13


def test_damping_heat_equals_the_stored_energy():
    sc = heated_bar(0.5, 0.0025, damping={"viscous": {"shear": 2e4, "bulk": 2e4}}, damping_heat=True)
    r = solve_dynamic(sc)
    rows = np.array(r.probe_rows)
    assert rows[-1, 1] == pytest.approx(EPS0 * L, rel=0.01)                    # settled, freely expanded
    T = r.system.model.temperature
    mean_rise = MPI.COMM_WORLD.allreduce(fem.assemble_scalar(fem.form((T - T0) * ufl.dx)), op=MPI.SUM) / (L * 0.01)
    assert mean_rise == pytest.approx(1.5 * E * EPS0**2 / (RHO * 1.0), rel=1e-3)        # measured +0.018 %
    # the heat is not in the mechanical account (no double count); the expansion it causes is thermal work
    assert abs(r.energy.now.thermal_work) < 1e-3 * r.energy.now.dissipated
    assert r.energy.balance_error() < 1e-10               # 1.9e-4 before thermal work was counted


def every_node_at(history) -> list:
    """[[thermal.boundary]] on the faces y = 0 and y = 0.1: with one cell across, every node lies on one."""
    return [{"where": {"axis": "y", "at": y}, "temperature": {"history": history}} for y in (0.0, 0.1)]


def test_thermal_work_closes_the_energy_balance():
    dt = PERIOD / 200
    jump = [[0.0, 0.0], [dt, T0], [1.0, T0]]
    r = solve_dynamic(heated_bar(PERIOD, dt, heated=every_node_at(jump), cells=(20, 1, 1)))
    e = r.energy
    assert e.history[0][1].elastic == 0.0 and e.now.thermal_work > 0.5 * 1.5 * E * EPS0**2 * L * 0.01
    assert e.now.thermal_work == pytest.approx(e.history[1][1].thermal_work, rel=1e-12)   # T constant after step 1
    assert e.now.kinetic + e.now.elastic == pytest.approx(e.now.thermal_work, rel=1e-10)
    assert e.balance_error() < 1e-10                 # 3e-13; without the thermal work 1.06 (measured)
    assert "thermal_work" in r.summary()["energy_final"]
    end = [{"where": {"axis": "x", "at": 0.0}, "temperature": {"history": jump}}]   # heat diffusing in
    r = solve_dynamic(heated_bar(PERIOD, dt, heated=end, conductivity=2e4))
    assert r.system.model.temperature.x.array.min() > 0.2 * T0           # the far end warmed during the run
    assert r.energy.now.thermal_work > 0.1 * e.now.thermal_work
    assert r.energy.balance_error() < 1e-10                                   # 4e-14; without: 1.20


def test_slowly_heated_held_bar_takes_the_stored_energy_as_thermal_work():
    """Held between rollers, heated over 4 periods: quasi-static, the thermal work is the stored energy
    1/2 E eps0^2 V of the axial stress -E eps0 (nu = 0: the sides expand freely)."""
    sc = heated_bar(5 * PERIOD, PERIOD / 40, heated=every_node_at([[0.0, 0.0], [4 * PERIOD, T0], [1.0, T0]]),
                    cells=(20, 1, 1), held=True)
    r = solve_dynamic(sc)
    assert r.energy.now.thermal_work == pytest.approx(0.5 * E * EPS0**2 * L * 0.01, rel=2e-4)   # +4.4e-5
    assert r.energy.balance_error() < 1e-10
