"""Strength ([material.strength]): the safety factor against independent references.
- a bar in uniform tension: tensile / (F/A) and yield / (F/A) (small strain: exact); a neo-Hookean bar at a
  finite stretch: strength / (F / a) with a the current section (from the measured lateral stretch);
- compression does not count against a tensile strength (no safety factor), but against a yield one;
- two materials in series carry one stress: the weaker one is named;
- a cantilever: tensile / (6 P L / h^3) of beam theory at the clamp's top edge (within 3 %);
- a suddenly applied load swings the cantilever: the lowest safety factor over the run comes at half the
  first bending period (Euler-Bernoulli), with a dynamic amplification between 2 and 2.5;
- an inverse design's rest shape under its loads: as a static run of the written rest mesh finds it;
- the utilization field is stress / strength cell by cell; 2 ranks agree; bad input refused in one line."""
import json
import math

import pytest

import fem_forms as ff
from fem_forms.analyses.dynamic import solve_dynamic
from fem_forms.errors import InputError
from helpers import inverse_beam, mpirun, run_scene, toml_dumps

TRACTION, TENSILE, YIELD = 1.0e5, 2.0e5, 1.5e5


def bar(model="linear", traction=TRACTION, strength=None, materials=None, **over) -> dict:
    """A 1 x 0.1 x 0.1 m bar on rollers at x = y = z = 0, pulled by a traction at x = 1: uniaxial stress."""
    d = {"title": "bar", "mesh": {"size": [1.0, 0.1, 0.1], "cells": [4, 2, 2]},
         "material": materials or {"model": model, "E": 1.0e7, "nu": 0.3,
                                   "strength": strength or {"tensile": TENSILE}},
         "discretization": {"degree": 1},
         "fix": [{"where": {"axis": a, "at": 0.0}, "components": [a]} for a in "xyz"],
         "load": [{"type": "traction", "where": {"axis": "x", "at": 1.0}, "value": [traction, 0.0, 0.0]}],
         "output": {"picture": False, "fields": False, "probes": {"corner": [1.0, 0.1, 0.1]}}}
    d.update(over)
    return d


@pytest.mark.parametrize("strength, expected, criterion", [
    ({"tensile": TENSILE}, TENSILE / TRACTION, "max principal stress"),
    ({"yield": YIELD}, YIELD / TRACTION, "von Mises"),
    ({"tensile": TENSILE, "yield": YIELD}, YIELD / TRACTION, "von Mises")])
def test_a_bar_in_tension_has_the_strength_over_its_stress(strength, expected, criterion):
    s = ff.solve_static(ff.Scene.from_dict(bar(strength=strength))).summary()
    assert s["strength"]["safety_factor"] == pytest.approx(expected, rel=1e-9)
    assert s["strength"]["criterion"] == criterion and s["strength"]["material"] == "material"


def test_a_finite_stretch_divides_the_force_by_the_current_section():
    s = ff.solve_static(ff.Scene.from_dict(bar("neo-hookean", traction=1.0e6, strength={"yield": 5e6}))).summary()
    lateral = 1 + s["probes"]["corner"]["displacement"][1] / 0.1           # the section's measured stretch
    assert lateral < 0.99                                                     # a finite stretch
    assert s["strength"]["safety_factor"] == pytest.approx(5e6 / (1.0e6 / lateral ** 2), rel=1e-6)


def test_compression_cracks_nothing_but_yields():
    s = ff.solve_static(ff.Scene.from_dict(bar(traction=-TRACTION))).summary()
    assert s["strength"]["safety_factor"] is None and "nothing is stressed" in s["strength"]["message"]
    s = ff.solve_static(ff.Scene.from_dict(bar(traction=-TRACTION, strength={"yield": YIELD}))).summary()
    assert s["strength"]["safety_factor"] == pytest.approx(YIELD / TRACTION, rel=1e-9)


def two_in_series() -> dict:
    half = {"box": [[0.0, 0.0, 0.0], [0.5, 0.1, 0.1]]}
    return bar(materials=[
        {"name": "tough", "model": "linear", "E": 1.0e7, "nu": 0.3, "strength": {"tensile": 4e5}},
        {"name": "brittle", "model": "linear", "E": 1.0e7, "nu": 0.3, "strength": {"tensile": TENSILE},
         "where": half}])


def test_of_two_materials_in_series_the_weaker_is_named(tmp_path):
    code, s, err, out = run_scene(tmp_path, two_in_series() | {"output": {"picture": False,
                                                                         "fields": ["displacement", "utilization"]}})
    assert code == 0, err
    assert s["strength"]["safety_factor"] == pytest.approx(TENSILE / TRACTION, rel=1e-9)
    assert s["strength"]["material"] == "brittle" and s["strength"]["where"][0] <= 0.5
    with open(out / "fields.xdmf") as f:
        assert 'Name="utilization"' in f.read()


@pytest.mark.mpi
def test_two_ranks_find_the_serial_safety_factor(tmp_path):
    (tmp_path / "s.toml").write_text(toml_dumps(two_in_series()))
    r = mpirun(["-m", "fem_forms", "run", str(tmp_path / "s.toml"), "--out", str(tmp_path / "o")])
    assert r.returncode == 0, r.stderr[-2000:]
    s = json.loads((tmp_path / "o" / "results.json").read_text())
    assert s["mpi_ranks"] == 2 and s["strength"]["material"] == "brittle"
    assert s["strength"]["safety_factor"] == pytest.approx(TENSILE / TRACTION, rel=1e-9)
    assert "strength: safety factor 2 (holds; max principal stress in brittle" in r.stdout


# --- a cantilever, static and struck ----------------------------------------------------------------
P, L, H, E, RHO = 100.0, 1.0, 0.1, 1.0e9, 1000.0


def cantilever(analysis="static") -> dict:
    d = {"analysis": analysis, "mesh": {"size": [L, H, H], "cells": [20, 2, 2]},
         "material": {"model": "linear", "E": E, "nu": 0.0, "rho": RHO, "strength": {"tensile": 1e6}},
         "discretization": {"degree": 2}, "fix": [{"where": {"axis": "x", "at": 0.0}}],
         "load": [{"type": "traction", "where": {"axis": "x", "at": L}, "value": [0.0, 0.0, -P / H ** 2]}],
         "output": {"picture": False, "fields": False}}
    if analysis == "dynamic":
        d["dynamic"] = {"duration": 0.045, "dt": 3e-4}
    return d


def test_a_cantilever_is_weakest_at_the_top_of_its_clamp():
    s = ff.solve_static(ff.Scene.from_dict(cantilever())).summary()["strength"]
    assert s["safety_factor"] == pytest.approx(1e6 / (6 * P * L / H ** 3), rel=0.03)
    assert s["where"][0] == pytest.approx(0.0) and s["where"][2] == pytest.approx(H)


def test_a_suddenly_loaded_cantilever_is_weakest_at_half_its_period():
    static = ff.solve_static(ff.Scene.from_dict(cantilever())).summary()["strength"]["safety_factor"]
    struck = solve_dynamic(ff.Scene.from_dict(cantilever("dynamic"))).summary()["strength"]
    period = 2 * math.pi / (1.875 ** 2 * math.sqrt(E * H ** 4 / 12 / (RHO * H * H * L ** 4)))
    assert struck["time"] == pytest.approx(period / 2, rel=0.05)
    assert 2.0 <= static / struck["safety_factor"] <= 2.5


def test_the_rest_shape_of_an_inverse_design_is_checked_under_its_loads(tmp_path):
    """The design's forward check reports the safety factor of the rest shape under its weight; a static run
    of the written rest_shape.msh (what the user fabricates; ramped from rest) finds the same."""
    d = inverse_beam(E=1e6, cells=(10, 2, 2))
    d["material"]["strength"] = {"tensile": 1e5}
    code, s, err, out = run_scene(tmp_path, d)
    assert code == 0 and s["usable"], err
    static = {k: v for k, v in d.items() if k not in ("analysis", "inverse")}
    static["mesh"] = {"generator": "file", "file": str(out / "rest_shape.msh")}
    static["output"] = {"fields": [], "picture": False}
    (tmp_path / "static").mkdir()
    code, check, err, _ = run_scene(tmp_path / "static", static)
    assert code == 0, err
    assert s["strength"]["safety_factor"] < 10
    assert s["strength"]["safety_factor"] == pytest.approx(check["strength"]["safety_factor"], rel=1e-5)
    assert s["strength"]["where"] == pytest.approx(check["strength"]["where"], abs=1e-9)


@pytest.mark.parametrize("change, message", [
    ({"strength": {}}, "give tensile (largest principal stress, Pa) and/or yield"),
    ({"strength": {"tensile": -1.0}}, "material.strength.tensile"),
])
def test_bad_strength_is_refused_in_one_line(change, message):
    d = bar()
    d["material"].update(change)
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        ff.Scene.from_dict(d)


def test_the_utilization_field_needs_a_strength():
    d = bar(output={"fields": ["utilization"]})
    del d["material"]["strength"]
    with pytest.raises(InputError, match="'utilization' needs a \\[material.strength\\]"):
        ff.Scene.from_dict(d)


def test_a_plastic_bar_reports_its_yield_safety_factor():
    """With [material.plasticity] the yield strength defaults to its yield stress; the stress there lives on the
    quadrature points only (the strength check reads no corner values then)."""
    d = bar(strength={"tensile": 4e5})
    d["material"]["plasticity"] = {"model": "von-mises", "yield_stress": YIELD}
    s = ff.solve_static(ff.Scene.from_dict(d)).summary()
    assert s["strength"]["safety_factor"] == pytest.approx(YIELD / TRACTION, rel=1e-6)
    assert s["strength"]["criterion"] == "von Mises"
