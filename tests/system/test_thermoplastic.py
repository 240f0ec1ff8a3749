"""Plasticity with a coupled temperature ([material.plasticity] with [thermal]), against 1-D closed forms on
a bar held axially between rollers, laterally free (a uniaxial stress state), at a uniform steady T = DT:
- E(T) (modulus_slope != 0) in the elastic range: sigma_xx = -E(T) alpha DT with E(T) = E + slope DT, for
  every plastic model (the plastic term scales its elastic constants by E(T) / E; the yield stress stays);
- thermal strain past yield (E alpha DT > sigma_y, perfectly plastic, the load factor ramping the thermal
  strain): sigma_xx = -sigma_y and the axial plastic strain -(alpha DT - sigma_y / E), with E(T) too."""
import numpy as np
import pytest

import fem_forms as ff
from fem_forms.output.plastic import plastic_summary

E, NU, ALPHA, DT, SY = 2.0e11, 0.3, 1.2e-5, 100.0, 200e6        # E alpha DT = 240 MPa > sigma_y
ROLLERS = [{"where": {"axis": "x", "at": 0.0}, "components": ["x"]},
           {"where": {"axis": "x", "at": 1.0}, "components": ["x"]},
           {"where": {"point": [0.0, 0.0, 0.0]}, "components": ["y", "z"]},
           {"where": {"point": [0.0, 0.1, 0.0]}, "components": ["z"]}]


def solve(scene: ff.Scene) -> dict:
    r = ff.solve_static(scene)
    return {**r.summary(), **plastic_summary(r.model)}


def held_bar(model: str, plasticity: dict, slope: float = 0.0) -> ff.Scene:
    th = {"conductivity": 35.0, "expansion": ALPHA, "modulus_slope": slope, "boundary": [
        {"where": {"axis": "x", "at": x}, "temperature": DT} for x in (0.0, 1.0)]}
    return ff.Scene.from_dict({
        "mesh": {"size": [1.0, 0.1, 0.1], "cells": [10, 2, 2]},
        "material": {"model": model, "E": E, "nu": NU, "plasticity": plasticity},
        "discretization": {"degree": 1, "quadrature_degree": 2}, "thermal": th, "fix": ROLLERS,
        "output": {"probes": {"mid": [0.5, 0.05, 0.05]}}})


@pytest.mark.parametrize("model, plasticity, rel", [
    ("linear", {"model": "von-mises", "yield_stress": 1e9}, 1e-8),
    ("neo-hookean", {"model": "von-mises", "yield_stress": 1e9}, 5e-3),
    ("linear", {"model": "obrien", "elastic_limit": 0.1, "plastic_limit": 0.2}, 1e-8),
    ("stvk", {"model": "obrien", "elastic_limit": 0.1, "plastic_limit": 0.2}, 5e-3)])
def test_temperature_dependent_modulus_in_the_plastic_term(model, plasticity, rel):
    slope = -1e8                                             # Pa/K: E(DT) = 0.95 E
    s = solve(held_bar(model, plasticity, slope))
    sigma = np.array(s["probes"]["mid"]["stress"])
    assert s["converged"] and s["max_plastic_strain"] == 0.0
    assert sigma[0, 0] == pytest.approx(-(E + slope * DT) * ALPHA * DT, rel=rel)
    assert abs(sigma[1, 1]) < rel * E * ALPHA * DT


@pytest.mark.parametrize("slope", [0.0, -1e8])
def test_thermal_strain_past_yield_holds_the_bar_at_minus_sigma_y(slope):
    Et = E + slope * DT
    s = solve(held_bar("linear", {"model": "von-mises", "yield_stress": SY}, slope))
    sigma = np.array(s["probes"]["mid"]["stress"])
    assert s["converged"] and sigma[0, 0] == pytest.approx(-SY, rel=1e-8)
    assert abs(sigma[1, 1]) < 1e-8 * SY and abs(sigma[2, 2]) < 1e-8 * SY
    # uniaxial, plastically incompressible: the equivalent plastic strain is |eps_p_xx|
    assert s["max_plastic_strain"] == pytest.approx(ALPHA * DT - SY / Et, rel=1e-8)
    assert s["yielded_fraction"] == pytest.approx(1.0)
