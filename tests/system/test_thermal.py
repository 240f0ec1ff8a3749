"""Heat and thermoelasticity against closed forms:
- free thermal expansion of a bar on minimal supports: dL = alpha dT L, no stress;
- a bar held axially at both ends, laterally free: sigma_xx = -E alpha dT (linear; neo-Hookean to 0.5 %);
  held laterally, free axially: -E alpha dT / (1 - nu) across, (1 + nu) / (1 - nu) alpha dT L along;
- E(T): the held bar's stress with E + dE/dT (T - T_ref);
- steady conduction: a slab with a fixed end and a convecting end (exact for P1), a fin with convecting
  sides (cosh solution of fin theory), a radiating end (a scalar equation solved by brentq);
- transient conduction of a bar suddenly heated at one end, insulated at the other: the Fourier series;
- 1 and 2 MPI ranks agree on a transient run (probes.csv and results.json)."""
import json
import math

import numpy as np
import pytest
from scipy.optimize import brentq

import fem_forms as ff
from fem_forms.analyses.thermal import solve_thermal
from fem_forms.physics.thermal import STEFAN_BOLTZMANN
from helpers import mpirun, toml_dumps

E, NU, ALPHA, DT = 2.0e11, 0.3, 1.2e-5, 100.0


def bar(fix, model="linear", thermal=None, degree=1, cells=(10, 2, 2)) -> ff.Scene:
    """A 1 x 0.1 x 0.1 m steel bar at a uniform T = DT (both ends held at DT) above T_ref = 0."""
    th = {"conductivity": 35.0, "expansion": ALPHA, "boundary": [
        {"where": {"axis": "x", "at": 0.0}, "temperature": DT},
        {"where": {"axis": "x", "at": 1.0}, "temperature": DT}]}
    th.update(thermal or {})
    return ff.Scene.from_dict({
        "mesh": {"size": [1.0, 0.1, 0.1], "cells": list(cells)},
        "material": {"model": model, "E": E, "nu": NU}, "discretization": {"degree": degree},
        "thermal": th, "fix": fix, "output": {"probes": {"mid": [0.5, 0.05, 0.05], "tip": [1.0, 0.05, 0.05]}}})


MINIMAL = [{"where": {"axis": "x", "at": 0.0}, "components": ["x"]},
           {"where": {"point": [0.0, 0.0, 0.0]}, "components": ["y", "z"]},
           {"where": {"point": [0.0, 0.1, 0.0]}, "components": ["z"]}]
ROLLERS = [{"where": {"axis": "x", "at": 0.0}, "components": ["x"]},
           {"where": {"axis": "x", "at": 1.0}, "components": ["x"]},
           {"where": {"point": [0.0, 0.0, 0.0]}, "components": ["y", "z"]},
           {"where": {"point": [0.0, 0.1, 0.0]}, "components": ["z"]}]


def test_free_expansion_is_alpha_dT_L_without_stress():
    s = ff.solve_static(bar(MINIMAL)).summary()
    assert s["converged"] and s["probes"]["tip"]["temperature"] == pytest.approx(DT, rel=1e-12)
    assert s["probes"]["tip"]["displacement"][0] == pytest.approx(ALPHA * DT * 1.0, rel=1e-9)
    assert s["probes"]["tip"]["displacement"][1] == pytest.approx(ALPHA * DT * 0.05, rel=1e-6)
    assert abs(np.array(s["probes"]["mid"]["stress"])).max() < 1e-6 * E * ALPHA * DT
    assert any("thermal strain" in p for p in s["physics"])


@pytest.mark.parametrize("model, rel", [("linear", 1e-8), ("neo-hookean", 5e-3)])
def test_bar_held_axially_carries_minus_E_alpha_dT(model, rel):
    s = ff.solve_static(bar(ROLLERS, model)).summary()
    sigma = np.array(s["probes"]["mid"]["stress"])
    assert sigma[0, 0] == pytest.approx(-E * ALPHA * DT, rel=rel)
    assert abs(sigma[1, 1]) < rel * E * ALPHA * DT and abs(sigma[2, 2]) < rel * E * ALPHA * DT
    assert abs(s["probes"]["tip"]["displacement"][0]) < 1e-12


def test_laterally_confined_bar_free_axially():
    """Rollers on the four sides and at x = 0: sigma_yy = sigma_zz = -E alpha dT / (1 - nu), sigma_xx = 0,
    u_x(L) = (1 + nu) / (1 - nu) alpha dT L."""
    held = [{"where": {"axis": a, "at": at}, "components": [a]} for a in "yz" for at in (0.0, 0.1)]
    held.append({"where": {"axis": "x", "at": 0.0}, "components": ["x"]})
    s = ff.solve_static(bar(held)).summary()
    sigma = np.array(s["probes"]["mid"]["stress"])
    np.testing.assert_allclose(np.diag(sigma), [0.0] + 2 * [-E * ALPHA * DT / (1 - NU)], rtol=1e-8,
                               atol=1e-8 * E * ALPHA * DT)
    assert s["probes"]["tip"]["displacement"][0] == pytest.approx((1 + NU) / (1 - NU) * ALPHA * DT, rel=1e-8)


def test_temperature_dependent_modulus():
    slope = -1e8                                             # Pa/K: E(DT) = 0.95 E
    s = ff.solve_static(bar(ROLLERS, thermal={"modulus_slope": slope})).summary()
    sigma = np.array(s["probes"]["mid"]["stress"])
    assert sigma[0, 0] == pytest.approx(-(E + slope * DT) * ALPHA * DT, rel=1e-8)


def heat_scene(boundary, cells=(20, 1, 1), size=(1.0, 0.1, 0.1), degree=1, dynamic=None, k=2.0,
               probes=None) -> ff.Scene:
    d = {"analysis": "thermal", "mesh": {"size": list(size), "cells": list(cells)},
         "material": {"E": 1e9, "nu": 0.3, "rho": 1.0}, "discretization": {"degree": degree},
         "thermal": {"conductivity": k, "specific_heat": 1.0, "boundary": boundary},
         "output": {"probes": probes or {"mid": [0.5 * size[0], 0.05, 0.05], "end": [size[0], 0.05, 0.05]}}}
    if dynamic:
        d["dynamic"] = dynamic
    return ff.Scene.from_dict(d)


def test_slab_with_a_convecting_end():
    k, h, T0, Ta, L = 2.0, 10.0, 100.0, 20.0, 1.0
    sc = heat_scene([{"where": {"axis": "x", "at": 0.0}, "temperature": T0},
                     {"where": {"axis": "x", "at": L}, "convection": {"h": h, "ambient": Ta}}], k=k)
    s = solve_thermal(sc).summary()
    q = (T0 - Ta) / (L / k + 1 / h)                          # series resistances: wall then film
    assert s["probes"]["end"]["temperature"] == pytest.approx(Ta + q / h, rel=1e-10)
    assert s["probes"]["mid"]["temperature"] == pytest.approx(T0 - q * 0.5 * L / k, rel=1e-10)
    assert s["max_temperature"] == pytest.approx(T0, rel=1e-12)


def test_fin_with_convecting_sides():
    k, h, a, L, T0, Ta = 200.0, 25.0, 0.01, 0.5, 100.0, 20.0
    sides = [{"where": {"axis": ax, "at": at}, "convection": {"h": h, "ambient": Ta}}
             for ax in "yz" for at in (0.0, a)]
    sc = heat_scene([{"where": {"axis": "x", "at": 0.0}, "temperature": T0}] + sides, cells=(40, 2, 2),
                    size=(L, a, a), degree=2, k=k, probes={"mid": [L / 2, a / 2, a / 2], "end": [L, a / 2, a / 2]})
    s = solve_thermal(sc).summary()
    m = math.sqrt(h * 4 * a / (k * a * a))                   # fin theory, insulated tip (Biot h a / 2k = 6e-4)
    for name, x in (("mid", L / 2), ("end", L)):
        expected = Ta + (T0 - Ta) * math.cosh(m * (L - x)) / math.cosh(m * L)
        assert s["probes"][name]["temperature"] == pytest.approx(expected, rel=2e-3)


def test_radiating_end():
    k, eps, T0, Ta, L = 1.0, 0.8, 600.0, 300.0, 0.2        # kelvin
    sc = heat_scene([{"where": {"axis": "x", "at": 0.0}, "temperature": T0},
                     {"where": {"axis": "x", "at": L}, "radiation": {"emissivity": eps, "ambient": Ta}}],
                    size=(L, 0.1, 0.1), k=k)
    s = solve_thermal(sc).summary()
    TL = brentq(lambda T: k * (T0 - T) / L - eps * STEFAN_BOLTZMANN * (T**4 - Ta**4), Ta, T0)
    assert s["probes"]["end"]["temperature"] == pytest.approx(TL, rel=1e-8)
    assert s["newton_iterations"] > 1                        # radiation is nonlinear: Newton, not one solve


def series(x, t, L=1.0, kappa=1.0, terms=200):
    """T / T1 in a bar 0 < x < L at T = 0, its end x = 0 held at T1 from t = 0 on, x = L insulated."""
    n = np.arange(terms)
    lam = (2 * n + 1) * np.pi / (2 * L)
    return 1.0 - np.sum(4 / ((2 * n + 1) * np.pi) * np.sin(lam * x) * np.exp(-lam**2 * kappa * t))


def test_transient_bar_against_the_fourier_series():
    sc = heat_scene([{"where": {"axis": "x", "at": 0.0}, "temperature": 1.0}], cells=(40, 1, 1), degree=2,
                    k=1.0, dynamic={"duration": 0.1, "dt": 0.0005, "output_every": 50})
    r = solve_thermal(sc)
    rows = np.array(r.probe_rows)
    assert r.steps == 200 and rows[-1, 0] == pytest.approx(0.1)
    for row in rows[[40, 100, 200]]:
        assert row[1] == pytest.approx(series(0.5, row[0]), abs=2e-3)
        assert row[2] == pytest.approx(series(1.0, row[0]), abs=2e-3)


def test_a_transient_run_at_steady_state_steps_through():
    """Initial temperature equal to the held one: every step's residual is round-off, none is rejected."""
    d = {"analysis": "thermal", "mesh": {"size": [1.0, 0.1, 0.1], "cells": [20, 1, 1]},
         "material": {"E": 1e9, "nu": 0.3, "rho": 1.0}, "dynamic": {"duration": 0.05, "dt": 0.01},
         "thermal": {"conductivity": 1.3, "specific_heat": 1.0, "initial_temperature": 293.15, "boundary": [
             {"where": {"axis": "x", "at": 0.0}, "temperature": 293.15},
             {"where": {"axis": "x", "at": 1.0}, "convection": {"h": 7.0, "ambient": 293.15}}]}}
    r = solve_thermal(ff.Scene.from_dict(d))
    assert r.steps == 5 and r.summary()["max_temperature"] == pytest.approx(293.15, rel=1e-13)


@pytest.mark.mpi
def test_two_ranks_agree_on_a_transient_run(tmp_path):
    d = {"title": "t", "analysis": "thermal", "mesh": {"size": [1.0, 0.2, 0.1], "cells": [20, 4, 2]},
         "material": {"E": 1e9, "nu": 0.3, "rho": 1.0}, "discretization": {"degree": 1},
         "thermal": {"conductivity": 1.0, "specific_heat": 1.0, "boundary": [
             {"where": {"axis": "x", "at": 0.0}, "temperature": {"history": [[0.0, 0.0], [0.05, 1.0]]}},
             {"where": {"axis": "y", "at": 0.2}, "convection": {"h": 5.0, "ambient": 0.5}}]},
         "dynamic": {"duration": 0.1, "dt": 0.01, "output_every": 5},
         "output": {"probes": {"a": [0.3, 0.1, 0.05], "b": [0.9, 0.15, 0.0]}}}
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(d))
    serial = solve_thermal(ff.Scene.from_file(path))
    p = mpirun(["-m", "fem_forms", "run", str(path), "--out", str(tmp_path / "out")])
    assert p.returncode == 0, p.stderr
    par = json.loads((tmp_path / "out" / "results.json").read_text())
    assert par["mpi_ranks"] == 2 and par["steps"] == serial.steps == 10
    rows = np.loadtxt(tmp_path / "out" / "probes.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(rows, np.array(serial.probe_rows), rtol=1e-9, atol=1e-12)
    assert (tmp_path / "out" / "probes.csv").read_text().splitlines()[0] == "time,a_T,b_T"
    assert par["max_temperature"] == pytest.approx(serial.summary()["max_temperature"], rel=1e-12)


@pytest.mark.mpi
def test_two_ranks_agree_on_a_coupled_static_run(tmp_path):
    """Steady heat with convection, then the neo-Hookean bar's thermal bending, on 1 and 2 ranks."""
    d = {"title": "t", "mesh": {"size": [1.0, 0.1, 0.05], "cells": [16, 2, 2]},
         "material": {"model": "neo-hookean", "E": 1e6, "nu": 0.3}, "discretization": {"degree": 2},
         "thermal": {"conductivity": 0.5, "expansion": 1e-3, "modulus_slope": -2e3, "boundary": [
             {"where": {"axis": "z", "at": 0.0}, "temperature": 40.0},
             {"where": {"axis": "z", "at": 0.05}, "convection": {"h": 20.0, "ambient": 0.0}}]},
         "fix": [{"where": {"axis": "x", "at": 0.0}}],
         "output": {"probes": {"tip": [1.0, 0.05, 0.025]}, "picture": False}}
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(d))
    serial = ff.solve_static(ff.Scene.from_file(path)).summary()
    assert serial["converged"] and abs(serial["probes"]["tip"]["displacement"][2]) > 1e-3
    assert serial["max_temperature"] == pytest.approx(40.0, rel=1e-12)
    p = mpirun(["-m", "fem_forms", "run", str(path), "--out", str(tmp_path / "out")])
    assert p.returncode == 0, p.stderr
    par = json.loads((tmp_path / "out" / "results.json").read_text())
    assert par["mpi_ranks"] == 2
    np.testing.assert_allclose(par["probes"]["tip"]["displacement"], serial["probes"]["tip"]["displacement"],
                               rtol=1e-8, atol=1e-12)
    assert par["probes"]["tip"]["temperature"] == pytest.approx(serial["probes"]["tip"]["temperature"], rel=1e-10)
    assert par["max_temperature"] == pytest.approx(40.0, rel=1e-12)
