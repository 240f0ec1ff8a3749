"""A fill material in the carved cells (`[balance] fill_density` > 0, elastic = true) keeps its own stiffness:
`fill_stiffness` = E_fill / E is then required (refused in one line without it), and a cantilever whose core
is all fill sags as the composite section of Euler-Bernoulli-Timoshenko beam theory says."""
import math

import numpy as np
import pytest

import fem_forms as ff
from fem_forms.analyses.balance.elastic import SagModel
from fem_forms.design.balance import stiffness_factors
from fem_forms.design.balance.body import Body
from fem_forms.output.fields import node_values
from fem_forms.scene.analyses.balance import EMPTY_FILL_STIFFNESS, fill_stiffness
from helpers import run_scene

G = 9.81
L, H, E, RHO = 1.0, 0.06, 1e9, 1000.0
CORE = 2 * H / 3                    # the middle 4 x 4 of the 6 x 6 cells across


def cantilever(**balance) -> dict:
    return {"title": "composite cantilever", "analysis": "balance",
            "mesh": {"generator": "box", "size": [L, H, H], "cells": [20, 6, 6], "cell": "hexahedron"},
            "material": {"model": "neo-hookean", "E": E, "nu": 0.0, "rho": RHO},
            "discretization": {"degree": 2}, "fix": [{"where": {"axis": "x", "at": 0.0}}],
            "balance": {"goal": "check", "elastic": True, **balance}}


def composite_tip_sag(s: float, rho_f: float) -> float:
    """Tip deflection of a cantilever under its own weight, square section H with a square core CORE of
    density rho_f and modulus s E (nu = 0): q L^4 / (8 EI) + q L^2 / (2 kappa G A), transformed section
    EI = E (I_o - I_c) + s E I_c, weight q = g (rho (A_o - A_c) + rho_f A_c), shear kappa = 5/6 on the
    stiffness-weighted area (the shear term is 0.3 % of the sag)."""
    A_o, A_c, I_o, I_c = H * H, CORE * CORE, H**4 / 12, CORE**4 / 12
    q = G * (RHO * (A_o - A_c) + rho_f * A_c)
    EI = E * (I_o - I_c + s * I_c)
    kGA = 5 / 6 * (E / 2) * (A_o - A_c + s * A_c)
    return q * L**4 / (8 * EI) + q * L**2 / (2 * kGA)


def test_an_elastic_fill_material_needs_its_stiffness(tmp_path, capsys):
    code, data, err, _ = run_scene(tmp_path, cantilever(fill_density=400.0), capsys)
    lines = err.strip().splitlines()
    assert code == 2 and data is None and len(lines) == 1, err
    assert "balance.fill_stiffness: missing" in lines[0] and "E_fill / E" in lines[0]
    empty = ff.Scene.from_dict(cantilever()).balance                  # an empty fill keeps the ersatz
    assert fill_stiffness(empty) == EMPTY_FILL_STIFFNESS == 1e-6


def test_core_of_fill_sags_as_the_composite_section(tmp_path):
    s, rho_f = 0.5, 400.0
    scene = ff.Scene.from_dict(cantilever(fill_density=rho_f, fill_stiffness=s))
    b = scene.balance
    assert fill_stiffness(b) == s
    sag = SagModel(scene, np.array([0.0, 0.0, -G]))
    body = Body.rest(sag.mesh, b.shell)
    c = body.centroids()
    body.carvable = (np.abs(c[:, 1] - H / 2) < H / 3) & (np.abs(c[:, 2] - H / 2) < H / 3)   # the core, all along
    assert body.carvable.sum() == 20 * 4 * 4
    carved = np.zeros(int(body.carvable.sum()))
    sag.solve(body.density(carved, RHO, rho_f), stiffness_factors(body, carved, fill_stiffness(b)))
    x, u = sag.mesh.geometry.x, node_values(sag.model.u)
    tip = np.isclose(x[:, 0], L)
    w = -u[tip, 2].mean()                             # the end face's mean: the section's rotation cancels
    target = composite_tip_sag(s, rho_f)
    assert w == pytest.approx(target, rel=0.01)
    # the ersatz (fill_stiffness 1e-6) would have sagged clearly more: the fill's stiffness is what is seen
    assert composite_tip_sag(1e-6, rho_f) > 1.1 * target
    assert math.isfinite(w)
