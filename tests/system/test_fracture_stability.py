"""Fracture on the stable path (issue 47 item 2), against Pham & Marigo's stability analysis of the homogeneous bar
(Pham, Amor, Marigo & Maurini 2011; Pham & Marigo 2013). AT1, a(d) = (1 - d)^2, uniaxial strain (nu = 0, rollers),
displacement control: the homogeneous state at damage d (E eps^2 = 3 Gc / (8 l (1 - d))) has the second variation
    P(v, b) = E eps^2 [int b^2 - 4 int (b - mean b)^2] + 3 Gc l / 4 int b'^2
once v is minimised out (int v' = 0), lowest for b = cos(pi x / L): it is a saddle as soon as
1 - d < 3/2 (L / (pi l))^2. A bar longer than pi l sqrt(2/3) = 2.565 l cracks at its elastic limit; a bar of
length 2 l stays homogeneous until 1 - d = 6 / pi^2, at eps_b = eps_c / sqrt(6 / pi^2) = 1.2826 eps_c. With
fracture.stable_path = true the run checks each converged state's Hessian and leaves a saddle along its unstable
mode: the bar cracks in one place, one end of a bar symmetric about its middle."""
import math

import numpy as np
import pytest

from helpers import mpirun, run_scene, toml_dumps

E, GC, ELL, A = 1.0, 1.0, 0.1, 0.01
EPS_C = math.sqrt(3 * GC / (8 * ELL * E))              # the elastic limit (AT1)


def bar(length: float, cells: int, eps_end: float, steps: int) -> dict:
    """A length x 0.1 x 0.1 bar on rollers at x = 0 (and y = 0, z = 0), pulled at x = length to strain eps_end."""
    return {"title": "bar", "mesh": {"size": [length, 0.1, 0.1], "cells": [cells, 1, 1]},
            "material": {"model": "linear", "E": E, "nu": 0.0}, "discretization": {"degree": 1},
            "fix": [{"name": "left", "where": {"axis": "x", "at": 0.0}, "components": ["x"]},
                    {"where": {"axis": "y", "at": 0.0}, "components": ["y"]},
                    {"where": {"axis": "z", "at": 0.0}, "components": ["z"]},
                    {"name": "pull", "where": {"axis": "x", "at": length}, "components": ["x"],
                     "value": [eps_end * length, 0.0, 0.0]}],
            "fracture": {"toughness": GC, "length": ELL, "model": "AT1", "stable_path": True},
            "solver": {"steps": steps, "max_step": 1.0 / steps},
            "output": {"picture": False, "fields": False}}


def curve(out) -> np.ndarray:
    return np.genfromtxt(out / "force_displacement.csv", delimiter=",", names=True)


def test_a_short_bar_stays_homogeneous_until_pham_and_marigos_bifurcation_strain(tmp_path):
    """L = 2 l: homogeneous and stable past the elastic limit (d = 1 - eps_c^2 / eps^2 at every step, the stress on
    the closed form) up to eps_b = 1.2826 eps_c; the first step beyond it is a saddle, left along its mode: the
    damage localises at one end (a crack) and the stress falls below the homogeneous curve's."""
    L, eps_end, steps = 2 * ELL, 1.55 * EPS_C, 62
    code, res, err, out = run_scene(tmp_path, bar(L, 40, eps_end, steps))
    assert code == 0, err
    rows = curve(out)
    eps = rows["pull_ux"] / L
    eps_b = EPS_C / math.sqrt(6 / math.pi ** 2)
    assert res["stable_path"] is True
    first = res["bifurcations"][0]
    at = first["load_factor"] * eps_end
    assert eps_b <= at <= eps_b + eps_end / steps + 1e-9, (at, eps_b)       # the first step past eps_b
    assert first["eigenvalue"] < 0 and min(first["at"][0], L - first["at"][0]) < 1e-9     # a crack at one end
    before = eps < at - 1e-9
    d = np.where(E * eps ** 2 > 3 * GC / (8 * ELL), 1 - EPS_C ** 2 / eps ** 2, 0.0)
    assert rows["damage_max"][before] == pytest.approx(d[before], abs=1e-5)          # homogeneous until then
    assert rows["pull_Fx"][before] / A == pytest.approx((1 - d[before]) ** 2 * E * eps[before], rel=1e-4)
    after = ~before
    homogeneous = (1 - d[after]) ** 2 * E * eps[after]
    assert np.all(rows["pull_Fx"][after] / A < homogeneous * (1 - 1e-3))
    assert rows["pull_Fx"][-1] / A < 0.05 * homogeneous[-1]                 # cracked through by the end
    assert res["damage_max"] >= 0.99


def test_a_long_bar_cracks_once_at_its_elastic_limit_at_one_end(tmp_path):
    """L = 20 l: a saddle as soon as damage starts, so the bar cracks at the first step past the elastic limit:
    the force drops from the peak sigma_c A to the residual stiffness's, damage 1 in one band at one end (the
    bar is symmetric about its middle; the other end stays intact), a crack area of half the section (a band
    at a free end is half a band, as its surface energy says)."""
    L, eps_end, steps = 20 * ELL, 1.5 * EPS_C, 30
    code, res, err, out = run_scene(tmp_path, bar(L, 80, eps_end, steps))
    assert code == 0, err
    rows = curve(out)
    eps = rows["pull_ux"] / L
    first = res["bifurcations"][0]
    assert EPS_C <= first["load_factor"] * eps_end <= EPS_C + eps_end / steps
    k = int(np.argmax(rows["pull_Fx"]))
    assert rows["pull_Fx"][k] / A == pytest.approx(EPS_C, rel=eps_end / steps / EPS_C)   # the peak: sigma_c
    assert np.all(rows["pull_Fx"][k + 1:] / A < 0.01 * EPS_C)                             # cracked through
    assert res["damage_max"] == pytest.approx(1.0, abs=1e-6)
    end = first["at"][0]
    assert min(end, L - end) < 1e-9 and abs(res["crack_center"][0] - end) < 2 * ELL
    assert res["crack_area"] == pytest.approx(A / 2, rel=0.25)


def test_two_ranks_take_the_same_stable_path(tmp_path):
    """The short bar on 2 ranks: the same bifurcation step, the same crack."""
    d = bar(2 * ELL, 40, 1.45 * EPS_C, 29)
    code, one, err, _ = run_scene(tmp_path, d)
    assert code == 0, err
    (tmp_path / "two.toml").write_text(toml_dumps(d))
    p = mpirun(["-m", "fem_forms", "run", str(tmp_path / "two.toml"), "--out", str(tmp_path / "two"), "-q"])
    assert p.returncode == 0, p.stderr[-2000:]
    import json
    two = json.loads((tmp_path / "two" / "results.json").read_text())
    assert two["mpi_ranks"] == 2 and two["stable_path"] is True
    assert two["bifurcations"][0]["load_factor"] == pytest.approx(one["bifurcations"][0]["load_factor"])
    assert two["bifurcations"][0]["at"] == pytest.approx(one["bifurcations"][0]["at"], abs=1e-9)
    for key in ("damage_max", "crack_area"):
        assert two[key] == pytest.approx(one[key], rel=1e-5), key


def test_an_iterative_solver_leaves_the_check_out_and_says_so(tmp_path):
    """The check factorizes the energy's Hessian, which a run on an iterative solver cannot afford: not checked,
    stable_path false and a warning saying why."""
    d = bar(2 * ELL, 20, 1.1 * EPS_C, 4)
    d["solver"]["linear"] = "iterative"
    code, res, err, _ = run_scene(tmp_path, d)
    assert code == 0, err
    assert res["stable_path"] is False and "bifurcations" not in res
    assert any(w.startswith("fracture.stable_path: not checked, the run's linear solver is iterative")
               for w in res["warnings"])
