"""Stresses and strains at probes (recovered fields) and fields on request:
- homogeneous uniaxial tension of a neo-Hookean block: Cauchy stress T / l2^2 and Green strain
  (l^2 - 1) / 2 at a surface corner, from an independent solve of the two stretches (helpers);
- a slender cantilever under a tip traction: the bending stress 6 T (L - x) / h on the top surface edge
  (beam theory, exact away from the ends for nu = 0) within 0.3 % with P2, where a single cell is off
  by 0.8 % (benchmarks/stress_recovery.md);
- [output] fields: the named fields are written, true/false keep their meaning, unknown names refused."""
import re

import numpy as np
import pytest

import fem_forms as ff
from fem_forms.errors import InputError
from fem_forms.scene.spec import FIELD_NAMES
from helpers import block_scene, uniaxial_stretches, run_scene, beam_scene

L, H, T = 1.0, 0.1, 1000.0


@pytest.mark.parametrize("cell, degree", [("tetrahedron", 1), ("hexahedron", 2)])
def test_uniaxial_tension_at_a_surface_corner(cell, degree):
    t = 2.0e5
    sc = block_scene(cell, degree, [{"type": "traction", "where": {"axis": "x", "at": 1.0},
                                     "value": [t, 0.0, 0.0]}])
    s = ff.solve_static(sc).summary()
    l1, l2 = uniaxial_stretches(t)
    probe = s["probes"]["corner"]
    sigma = np.zeros((3, 3))
    sigma[0, 0] = t / l2**2                          # Cauchy: force over the deformed area l2^2
    np.testing.assert_allclose(probe["stress"], sigma, atol=1e-6 * t)
    np.testing.assert_allclose(probe["strain"], np.diag([(l1**2 - 1) / 2, (l2**2 - 1) / 2, (l2**2 - 1) / 2]),
                               atol=1e-9)
    assert probe["von_mises"] == pytest.approx(t / l2**2, rel=1e-6)
    np.testing.assert_allclose(probe["displacement"], [l1 - 1, l2 - 1, l2 - 1], rtol=1e-7)
    # the x rollers carry the dead load: T times the reference area 1
    np.testing.assert_allclose(s["reactions"]["fix0"], [-t, 0.0, 0.0], atol=1e-8 * t)


def test_bending_stress_on_a_surface_edge_against_beam_theory():
    sc = ff.Scene.from_dict({
        "mesh": {"generator": "box", "size": [L, H, H], "cells": [20, 2, 2]},
        "material": {"model": "linear", "E": 1e9, "nu": 0.0},
        "discretization": {"degree": 2},
        "fix": [{"where": {"axis": "x", "at": 0.0}}],
        "load": [{"type": "traction", "where": {"axis": "x", "at": L}, "value": [0.0, 0.0, -T]}],
        "output": {"probes": {"edge": [0.5, 0.0, H], "quarter": [0.25, 0.0, H]}}})
    s = ff.solve_static(sc).summary()
    for name, x in (("edge", 0.5), ("quarter", 0.25)):
        assert s["probes"][name]["stress"][0][0] == pytest.approx(6 * T * (L - x) / H, rel=3e-3)


def run_in(folder, d):
    folder.mkdir()
    return run_scene(folder, d)


def attributes(path):
    return re.findall(r'Attribute Name="([a-z_0-9]+)"', path.read_text())


def test_fields_on_request(tmp_path):
    names = [n for n in FIELD_NAMES if n not in ("contact_pressure", "utilization")]   # [contact], a strength
    d = beam_scene(output={"fields": names, "picture": False})
    code, data, _, out = run_in(tmp_path / "all", d)
    assert code == 0 and attributes(out / "fields.xdmf") == names
    assert data["max_von_mises"] > 0
    d["output"]["fields"] = True
    code, data, _, out = run_in(tmp_path / "default", d)
    assert code == 0 and attributes(out / "fields.xdmf") == ["displacement", "von_mises"]
    d["output"]["fields"] = ["hencky_strain"]
    code, data, _, out = run_in(tmp_path / "one", d)
    assert code == 0 and attributes(out / "fields.xdmf") == ["hencky_strain"]
    assert "max_von_mises" not in data
    d["output"]["fields"] = False
    code, data, _, out = run_in(tmp_path / "none", d)
    assert code == 0 and not (out / "fields.xdmf").exists() and "fields" not in data["files"]


@pytest.mark.parametrize("value, message", [
    (["displacement", "stress"], "output.fields: unknown name 'stress' (known: displacement, von_mises, "),
    (["von_mises", "von_mises"], "output.fields: names must not repeat"),
    ("all", "output.fields: must be true, false or a list of names"),
    ([["x"]], "output.fields: must be true, false or a list of names"),
])
def test_bad_field_names_are_one_line(value, message):
    d = beam_scene(output={"fields": value})
    with pytest.raises(InputError) as e:
        ff.Scene.from_dict(d)
    assert str(e.value).startswith(message) and "\n" not in str(e.value)
