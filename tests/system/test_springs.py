"""[[spring]]: a stiff block hanging from a soft spring tied to its top face, a rigid body on a spring.

- Static: the block sags m g / k (plus its own elastic stretch, rho g H^2 / (2 E)); the spring carries m g.
- Modal: it bounces at sqrt(k / m) / (2 pi) and rocks about an axis in its top face at
  sqrt(k a^2 / (m (a^2 + 4 H^2))) / (2 pi) (the spring's pull spread over the top face, the top held sideways).
- Dynamic: released under gravity, it reaches 2 m g / k after half a period 2 pi sqrt(m / k); the energy
  account, with the spring's energy in its `support` column, balances.
"""
import math

import pytest

from helpers import run_scene, serial_and_two_ranks

A, H, RHO, E, K, G = 0.02, 0.05, 1000.0, 1.0e9, 20.0, 9.81
M = RHO * A * A * H
SAG = M * G / K


def hanging(**over) -> dict:
    d = {"title": "block on a spring",
         "mesh": {"size": [A, A, H], "cells": [2, 2, 5]},
         "material": {"model": "linear", "E": E, "nu": 0.0, "rho": RHO},
         "fix": [{"where": {"axis": "z", "at": H}, "components": ["x", "y"]}],
         "spring": [{"name": "hook", "where": {"axis": "z", "at": H}, "anchor": [A / 2, A / 2, H + 1.0],
                     "stiffness": K}],
         "load": [{"type": "gravity"}],
         "output": {"probes": {"top": [A / 2, A / 2, H], "bottom": [A / 2, A / 2, 0.0]}, "picture": False,
                    "fields": []}}
    d.update(over)
    return d


@pytest.mark.mpi
def test_block_hangs_m_g_over_k_below_its_anchor_on_one_and_two_ranks(tmp_path):
    one, two = serial_and_two_ranks(tmp_path, hanging())
    top = -one["probes"]["top"]["displacement"][2]
    bottom = -one["probes"]["bottom"]["displacement"][2]
    assert top == pytest.approx(SAG, rel=1e-3)                       # 7e-5 measured (the pull's fan of lines)
    assert bottom - top == pytest.approx(RHO * G * H**2 / (2 * E), rel=0.05)
    assert one["springs"]["hook"]["force"] == pytest.approx([0.0, 0.0, M * G], abs=1e-9 * M * G)
    assert one["springs"]["hook"]["tension"] == pytest.approx(M * G, rel=1e-3)
    assert one["equilibrium_error"] < 1e-8
    assert two["probes"]["top"]["displacement"][2] == pytest.approx(-top, rel=1e-8)
    assert two["springs"]["hook"]["force"][2] == pytest.approx(M * G, rel=1e-8)


def test_block_on_a_spring_bounces_and_rocks_as_a_rigid_body(tmp_path):
    d = hanging(analysis="modal", load=[], modal={"count": 3})
    code, res, _, _ = run_scene(tmp_path, d)
    assert code == 0
    bounce = math.sqrt(K / M) / (2 * math.pi)
    rock = math.sqrt(K * A**2 / (M * (A**2 + 4 * H**2))) / (2 * math.pi)
    assert res["frequencies_hz"] == pytest.approx([rock, rock, bounce], rel=2e-3)


def test_released_block_reaches_twice_its_sag_after_half_a_period(tmp_path):
    period = 2 * math.pi * math.sqrt(M / K)
    d = hanging(analysis="dynamic", dynamic={"duration": period / 2, "dt": period / 100})
    code, res, _, _ = run_scene(tmp_path, d)
    assert code == 0
    assert -res["probes"]["bottom"]["displacement"][2] == pytest.approx(2 * SAG, rel=2e-3)
    assert res["energy_final"]["support"] == pytest.approx(0.5 * K * (2 * SAG) ** 2, rel=5e-3)
    assert res["energy_balance_error"] < 1e-6


def test_bad_springs_are_refused_in_one_line(tmp_path, capsys):
    no_anchor = hanging(spring=[{"where": {"axis": "z", "at": H}, "stiffness": K}])
    code, _, err, _ = run_scene(tmp_path, no_anchor, capsys)
    assert code == 2 and "spring[0].anchor: missing" in err
    at_centroid = hanging(spring=[{"where": {"axis": "z", "at": H}, "anchor": [A / 2, A / 2, H], "stiffness": K}])
    code, _, err, _ = run_scene(tmp_path, at_centroid, capsys)
    assert code == 2 and "spring[0].anchor: at the centroid" in err
    twice = hanging(spring=[{"name": "s", "where": {"axis": "z", "at": H}, "anchor": [0, 0, 1], "stiffness": K}] * 2)
    code, _, err, _ = run_scene(tmp_path, twice, capsys)
    assert code == 2 and "given to two springs" in err
    for method in ("direct", "adjoint"):
        inverse = {**hanging(analysis="inverse", inverse={"method": method}),
                   "spring": [{"where": {"axis": "z", "at": H}, "anchor": [A / 2, A / 2, 1.0], "stiffness": K,
                               "length": 0.5}]}
        code, _, err, _ = run_scene(tmp_path, inverse, capsys)
        assert code == 2 and "spring[0]: not in inverse designs yet" in err, method


def test_a_shorter_rest_length_pulls_from_the_start_and_a_new_surface_needs_a_new_model(tmp_path):
    """With a rest length 5 mm below its length at the start the spring carries m g 5 mm closer to its anchor."""
    import fem_forms as ff
    from fem_forms.model import build_model
    from fem_forms.scene import Scene
    short = hanging()
    short["spring"][0]["length"] = 1.0 - 0.005
    code, res, _, _ = run_scene(tmp_path, short)
    assert code == 0
    assert -res["probes"]["top"]["displacement"][2] == pytest.approx(SAG - 0.005, rel=2e-3)
    model = build_model(Scene.from_dict(hanging()))
    moved = hanging()
    moved["spring"][0]["where"] = {"axis": "z", "at": 0.0}
    with pytest.raises(ff.InputError, match=r"spring\[0\].where: another surface needs a new model"):
        model.set_values(Scene.from_dict(moved))
