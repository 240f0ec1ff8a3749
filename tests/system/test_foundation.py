"""[[load]] type = "foundation": an elastic (Winkler) foundation k/2 int (u . N)^2 dA, against closed forms.

- Static: Hetenyi's semi-infinite beam on an elastic foundation loaded by a force P at its free end,
  w(x) = 2 P beta / k_b exp(-beta x) cos(beta x), beta = (k_b / (4 E I))^(1/4), k_b = k b (per length). The
  beam is 8 / beta long (the far end moves e^-8 of the loaded end), its bottom face on the foundation.
- Modal: a stiff square plate on a soft foundation (rigid body on springs): bounce omega^2 = k a^2 / m, rocking
  about an axis in its base omega^2 = k a^4 / (m (a^2 + 4 h^2)).
- Dynamic: the beam loaded suddenly; the energy account (its `support` column) balances.
"""
import math

import numpy as np
import pytest

from helpers import run_scene, serial_and_two_ranks

E, B, L = 1.0e7, 0.01, 0.8
BETA = 10.0                                   # 1 / m
I = B * B**3 / 12
K_B = 4 * E * I * BETA**4                     # N/m^2
K = K_B / B                                   # Pa/m
W0 = 1e-4                                     # the end's deflection, m (small: linear theory)
P = W0 * K_B / (2 * BETA)                     # N


PROBES = {"end": 0.0, "near": 0.1, "far": 0.2}


def hetenyi(x: float) -> float:
    return 2 * P * BETA / K_B * math.exp(-BETA * x) * math.cos(BETA * x)


def beam(**over) -> dict:
    d = {"title": "beam on a foundation",
         "mesh": {"size": [L, B, B], "cells": [80, 1, 2], "cell": "hexahedron"},
         "material": {"E": E, "nu": 0.0, "rho": 1000.0},
         "fix": [{"where": {"axis": "x", "at": L}, "components": ["x", "y"]}],   # in-plane rigid motions only
         "load": [{"type": "foundation", "where": {"axis": "z", "at": 0.0}, "stiffness": K},
                  {"type": "traction", "where": {"axis": "x", "at": 0.0}, "value": [0.0, 0.0, -P / B**2]}],
         "output": {"probes": {name: [x, B / 2, B / 2] for name, x in PROBES.items()}, "picture": False,
                    "fields": []}}
    d.update(over)
    return d


@pytest.mark.mpi
def test_beam_on_foundation_matches_hetenyi_on_one_and_two_ranks(tmp_path):
    one, two = serial_and_two_ranks(tmp_path, beam())
    for name, x in PROBES.items():
        w = -one["probes"][name]["displacement"][2]
        assert w == pytest.approx(hetenyi(x), abs=0.005 * W0), name      # 0.1 % of W0 measured
        assert two["probes"][name]["displacement"][2] == pytest.approx(-w, rel=1e-8, abs=1e-12 * W0)
    force = one["foundations"]["load[0]"]["force"]
    assert force == pytest.approx([0.0, 0.0, P], abs=1e-9 * P)           # the foundation carries the end load
    assert one["equilibrium_error"] < 1e-8
    assert "elastic foundation (Winkler)" in one["physics"]


PLATE_A, PLATE_H, RHO_S, K_SOFT = 0.1, 0.01, 7800.0, 1.0e6


def test_plate_on_foundation_bounces_and_rocks_as_a_rigid_body(tmp_path):
    d = {"title": "plate on a foundation", "analysis": "modal",
         "mesh": {"size": [PLATE_A, PLATE_A, PLATE_H], "cells": [4, 4, 1], "cell": "hexahedron"},
         "material": {"model": "linear", "E": 200e9, "nu": 0.3, "rho": RHO_S},
         "fix": [{"where": {"axis": "z", "at": 0.0}, "components": ["x", "y"]}],
         "load": [{"type": "foundation", "where": {"axis": "z", "at": 0.0}, "stiffness": K_SOFT}],
         "modal": {"count": 3}, "output": {"picture": False, "fields": []}}
    code, res, _, _ = run_scene(tmp_path, d)
    assert code == 0
    m = RHO_S * PLATE_A**2 * PLATE_H
    rock = math.sqrt(K_SOFT * PLATE_A**4 / (m * (PLATE_A**2 + 4 * PLATE_H**2))) / (2 * math.pi)
    bounce = math.sqrt(K_SOFT * PLATE_A**2 / m) / (2 * math.pi)
    assert res["frequencies_hz"] == pytest.approx([rock, rock, bounce], rel=1e-3)


def test_beam_loaded_suddenly_keeps_its_energy_balance_with_the_foundation(tmp_path):
    d = beam(analysis="dynamic", dynamic={"duration": 0.02, "dt": 1e-3},
             mesh={"size": [L, B, B], "cells": [40, 1, 1], "cell": "hexahedron"})
    code, res, _, _ = run_scene(tmp_path, d)
    assert code == 0
    final = res["energy_final"]
    assert final["support"] > 0.0                      # the foundation stores energy as the beam moves
    assert res["energy_balance_error"] < 1e-6


def test_a_new_stiffness_compiles_nothing_and_history_is_refused(monkeypatch):
    """A stiffness never used before (a literal in a form would be a new signature, compiled on a cache miss)
    solves without compiling, and takes effect (the end sinks by the stiffness ratio's power 3/4)."""
    import ffcx.codegeneration.jit as ffcx_jit
    import fem_forms as ff
    from fem_forms.model import build_model
    from fem_forms.scene import Scene
    first = ff.solve_static(Scene.from_dict(beam()))
    compiled, original = [], ffcx_jit._compile_objects
    monkeypatch.setattr(ffcx_jit, "_compile_objects", lambda *a, **k: compiled.append(1) or original(*a, **k))
    ratio = 2.0 + np.random.default_rng().random()                 # a value no earlier run compiled
    stiffer = beam()
    stiffer["load"][0]["stiffness"] = ratio * K
    second = ff.solve_static(Scene.from_dict(stiffer))
    assert compiled == []
    end = lambda r: r.probes["end"][2]                               # noqa: E731
    assert end(second) / end(first) == pytest.approx(ratio ** -0.75, rel=0.01)
    bad = beam(load=[{"type": "foundation", "where": {"axis": "z", "at": 0.0}, "stiffness": K,
                      "history": [[0, 0], [1, 1]]}])
    with pytest.raises(ff.InputError, match=r"load\[0\].history: a foundation is a support"):
        build_model(Scene.from_dict(bad))
    with pytest.raises(ff.InputError, match="stiffness"):
        Scene.from_dict(beam(load=[{"type": "foundation", "where": {"axis": "z", "at": 0.0}}]))


@pytest.mark.parametrize("scheme", ["newmark", "backward-euler"])
def test_plate_bouncing_on_foundation_follows_its_schemes_closed_form(tmp_path, scheme):
    """The stiff plate on the soft foundation set moving at v0 (a rigid body on springs, omega^2 = k a^2 / m):
    each scheme's discrete solution is known in closed form, u_n = u_1 r^(n-1) sin(n theta) / sin(theta), from
    u_(n+1) and u_(n-1) in terms of u_n. Newmark average acceleration: u_1 = dt v0 / (1 + h^2/4), r = 1,
    theta = 2 atan(h/2); backward Euler: u_1 = dt v0 / (1 + h^2), r = (1 + h^2)^(-1/2), theta = atan(h)
    (h = omega dt): the amplitude decays 13 % a step here, the energy it loses is the scheme's damping."""
    v0, dt, steps = 0.01, 5e-3, 20
    d = {"title": "plate bouncing", "analysis": "dynamic",
         "mesh": {"size": [PLATE_A, PLATE_A, PLATE_H], "cells": [2, 2, 1], "cell": "hexahedron"},
         "material": {"model": "linear", "E": 200e9, "nu": 0.3, "rho": RHO_S},
         "fix": [{"where": {"axis": "z", "at": 0.0}, "components": ["x", "y"]}],
         "load": [{"type": "foundation", "where": {"axis": "z", "at": 0.0}, "stiffness": K_SOFT}],
         "dynamic": {"duration": steps * dt, "dt": dt, "scheme": scheme, "initial_velocity": [0.0, 0.0, v0]},
         "output": {"picture": False, "fields": [], "probes": {"c": [PLATE_A / 2, PLATE_A / 2, PLATE_H]}}}
    code, res, _, out = run_scene(tmp_path, d)
    assert code == 0 and res["steps"] == steps
    h = math.sqrt(K_SOFT * PLATE_A**2 / (RHO_S * PLATE_A**2 * PLATE_H)) * dt
    if scheme == "newmark":
        u1, r, theta = dt * v0 / (1 + h * h / 4), 1.0, 2 * math.atan(h / 2)
    else:
        u1, r, theta = dt * v0 / (1 + h * h), (1 + h * h) ** -0.5, math.atan(h)
    n = np.arange(steps + 1)
    expected = u1 * r ** (n - 1.0) * np.sin(n * theta) / math.sin(theta)
    uz = np.genfromtxt(out / "probes.csv", delimiter=",", names=True)["c_uz"]
    assert uz == pytest.approx(expected, abs=1e-5 * u1 / h)              # measured 8e-8 of the amplitude
    if scheme == "backward-euler":                                        # the energy it lost is in the imbalance
        assert res["energy_balance_error"] > 0.9           # measured 0.996 (Newmark: 7e-10), and it says why
        assert any("backward-euler" in w for w in res["warnings"])
