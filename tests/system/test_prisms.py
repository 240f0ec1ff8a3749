"""System test of a prism mesh from a scene (`cell = "prism"`): a column hanging on its base under
gravity (nu = 0, rollers: a uniaxial stress state) against the closed form, outputs included."""
import json

import pytest

import fem_forms as ff


def test_prism_column_under_self_weight_matches_closed_form(tmp_path):
    """u_z(top) = -rho g H^2 / (2 E): P1 reproduces it at the nodes (exact nodal values of the
    one-dimensional problem); picture, fields and results.json are written from the prism mesh."""
    E, rho, g, H = 1.0e6, 1000.0, 9.81, 1.0
    scene = ff.Scene.from_dict({
        "title": "prism column",
        "mesh": {"generator": "box", "size": [0.2, 0.2, H], "cells": [2, 2, 8], "cell": "prism"},
        "material": {"model": "linear", "E": E, "nu": 0.0, "rho": rho},
        "discretization": {"degree": 1},
        "fix": [{"where": {"axis": a, "at": 0.0}, "components": [a]} for a in "xyz"],
        "load": [{"type": "gravity", "g": [0.0, 0.0, -g]}],
        "output": {"probes": {"top": [0.2, 0.2, H], "middle": [0.0, 0.0, H / 2]}},
    })
    result = ff.solve_static(scene)
    summary = ff.write_static_outputs(result, tmp_path)
    top = result.probes["top"]
    assert top[2] == pytest.approx(-rho * g * H**2 / (2 * E), rel=1e-10)
    assert result.probes["middle"][2] == pytest.approx(-rho * g * (H * H / 2 - H * H / 8) / E, rel=1e-10)
    assert abs(top[0]) < 1e-12 and abs(top[1]) < 1e-12
    assert summary["element"] == "P1 prism"
    assert json.loads((tmp_path / "results.json").read_text())["converged"]
    assert (tmp_path / "deformed.png").stat().st_size > 0 and (tmp_path / "fields.xdmf").exists()


def test_corotated_prism_column_agrees_with_linear_at_small_strain():
    """The nonlinear path on prisms (det F check, energy line search): corotated, strain 5e-4."""
    E, rho, g, H = 1.0e7, 1000.0, 9.81, 1.0
    scene = ff.Scene.from_dict({
        "mesh": {"generator": "box", "size": [0.2, 0.2, H], "cells": [2, 2, 8], "cell": "prism"},
        "material": {"model": "corotated", "E": E, "nu": 0.0, "rho": rho},
        "discretization": {"degree": 1},
        "fix": [{"where": {"axis": a, "at": 0.0}, "components": [a]} for a in "xyz"],
        "load": [{"type": "gravity", "g": [0.0, 0.0, -g]}],
        "output": {"probes": {"top": [0.2, 0.2, H]}},
    })
    result = ff.solve_static(scene)
    assert result.report.converged
    assert result.probes["top"][2] == pytest.approx(-rho * g * H**2 / (2 * E), rel=2e-3)
