"""Contact in time (implicit dynamics, [contact]): an undamped elastic ball bouncing on the floor keeps its
energy; a block on an inclined plane sticks when tan(theta) < mu and otherwise slides with the acceleration
g (sin theta - mu cos theta) of a rigid block with Coulomb friction (the slope is the floor, gravity tilted),
also released at rest in contact with the defaults (Newmark) and with backward Euler."""
import math

import numpy as np
import pytest

from helpers import run_scene

THETA = math.radians(30.0)
G = 9.81


def slope_scene(mu: float) -> dict:
    """A stiff 0.1 m cube (1 kg) at rest on the slope under the normal part of gravity (initial = static), the
    tangential part switched on at t = 0; generalized-alpha damps the barrier's stiff rocking."""
    return {"title": "block on a slope", "analysis": "dynamic",
            "mesh": {"generator": "box", "size": [0.1, 0.1, 0.1], "cells": [2, 2, 2]},
            "material": {"E": 1e7, "nu": 0.3, "rho": 1000.0}, "discretization": {"degree": 1},
            "load": [{"type": "gravity", "g": [0.0, 0.0, -G * math.cos(THETA)]},
                     {"type": "gravity", "g": [G * math.sin(THETA), 0.0, 0.0], "history": [[0.0, 0.0], [1e-6, 1.0]]}],
            "dynamic": {"duration": 0.1, "dt": 2e-3, "initial": "static", "scheme": "generalized-alpha",
                        "rho_inf": 0.5},
            "contact": {"distance": 1e-4, "obstacle": [{"name": "slope", "shape": "plane", "point": [0, 0, -5e-5],
                                                        "normal": [0, 0, 1], "friction": mu}]},
            "output": {"picture": False, "fields": False, "probes": {"c": [0.05, 0.05, 0.1]}}}


def probe_history(out):
    return np.genfromtxt(out / "probes.csv", delimiter=",", names=True)


def test_a_block_slides_down_a_slope_steeper_than_its_friction_angle(tmp_path):
    mu = 0.3
    code, r, _, out = run_scene(tmp_path, slope_scene(mu))
    assert code == 0 and r["converged"] and r["intersection_free"]
    h = probe_history(out)
    late = h["time"] > 0.02                          # after the switch-on transient
    a = 2 * np.polyfit(h["time"][late], h["c_ux"][late], 2)[0]
    assert a == pytest.approx(G * (math.sin(THETA) - mu * math.cos(THETA)), rel=0.03)   # measured 0.3 %
    assert abs(h["c_uy"]).max() < 1e-3
    # probes.csv carries the floor's force on the 1 kg block every step: its weight's normal part and, sliding,
    # mu times that against the motion; the active points and the smallest gap beside
    assert np.median(h["slope_Fz"][late]) == pytest.approx(G * math.cos(THETA), rel=0.01)
    assert np.median(h["slope_Fx"][late]) == pytest.approx(-mu * G * math.cos(THETA), rel=0.02)
    assert h["slope_active"][late].min() > 0 and h["min_distance"].min() > 0


def test_a_block_sticks_on_a_slope_flatter_than_its_friction_angle(tmp_path):
    mu = 0.7                                         # tan 30 deg = 0.577 < 0.7
    code, r, _, out = run_scene(tmp_path, slope_scene(mu))
    assert code == 0 and r["converged"]
    h = probe_history(out)
    creep = h["c_ux"][-1] - h["c_ux"][h["time"] > 0.02][0]
    assert abs(creep) < 1e-4                         # sliding would have moved 9 mm by then (measured 1e-5)
    force = r["contact"]["slope"]["force"]           # the slope holds the whole weight, friction included
    assert force[0] == pytest.approx(-G * math.sin(THETA), rel=0.02)
    assert force[2] == pytest.approx(G * math.cos(THETA), rel=0.02)


SLOPE_20 = math.radians(20.0)


@pytest.mark.parametrize("scheme", [None, "backward-euler"])
def test_a_block_released_on_a_slope_slides_with_the_defaults(tmp_path, scheme):
    """As a user writes it: a stiff block at rest 0.1 mm above a 20 degree slope (inside the default barrier
    distance of 0.17 mm, so in contact from the start), gravity tilted, friction 0.2, dt 2 ms, the default scheme
    (Newmark) or backward Euler, no static start. The barrier is settled at t = 0 (its stiffness balancing the
    weight, as IPC's initial stiffness), so the block slides at g (sin - mu cos) instead of being launched (before:
    Newmark hopped off the slope, by 3 mm and 8 % too fast on a finer mesh)."""
    mu = 0.2
    g = [G * math.sin(SLOPE_20), 0.0, -G * math.cos(SLOPE_20)]
    scene = {"title": "block released on a slope", "analysis": "dynamic",
             "mesh": {"generator": "box", "size": [0.1, 0.1, 0.1], "cells": [2, 2, 2]},
             "material": {"E": 1e7, "nu": 0.3, "rho": 1000.0}, "discretization": {"degree": 1},
             "load": [{"type": "gravity", "g": g}],
             "dynamic": {"duration": 0.2, "dt": 2e-3, **({"scheme": scheme} if scheme else {})},
             "contact": {"obstacle": [{"name": "slope", "shape": "plane", "point": [0, 0, -1e-4], "normal": [0, 0, 1],
                                       "friction": mu}]},
             "output": {"picture": False, "fields": False, "probes": {"c": [0.05, 0.05, 0.1]}}}
    code, r, _, out = run_scene(tmp_path, scene)
    assert code == 0 and r["converged"] and r["intersection_free"] and r["rejected_steps"] == 0
    h = probe_history(out)
    late = h["time"] > 0.05
    a = 2 * np.polyfit(h["time"][late], h["c_ux"][late], 2)[0]
    assert a == pytest.approx(G * (math.sin(SLOPE_20) - mu * math.cos(SLOPE_20)), rel=0.02)   # measured 0.2 %
    # it stays on the slope, rocking at most 0.3 mm under Newmark (no numerical damping; measured: Newmark
    # 2.9e-4, backward Euler 6e-5; before: 1.1 mm, off the slope, 4 rejected steps, energy error 17 %)
    assert abs(h["c_uz"]).max() < 5e-4 and h["slope_active"].min() > 0
    assert r["energy_balance_error"] < 0.02            # measured 3e-3 (Newmark), 5e-3 (backward Euler)
    # it started in contact, undeformed: Newmark (no damping) is told what rings and what to do about it
    started = [w for w in r["warnings"] if "starts in contact" in w]
    assert len(started) == (0 if scheme == "backward-euler" else 1)
    # the slope carries the weight's normal part and friction mu times it, on average over the steps (Newmark's
    # rocking makes the force come in pulses: measured 9.52 and -1.848 N, backward Euler 9.218 and -1.844 N)
    assert np.mean(h["slope_Fz"][late]) == pytest.approx(G * math.cos(SLOPE_20), rel=0.05)
    assert np.mean(h["slope_Fx"][late]) == pytest.approx(-mu * G * math.cos(SLOPE_20), rel=0.05)


def test_an_undamped_ball_bounces_off_the_floor_and_keeps_its_energy(tmp_path):
    """A soft ball (R 5 cm) thrown down at 1 m/s, no gravity, Newmark average acceleration (no numerical
    damping): it touches the floor, comes to rest compressed and leaves it upward at nearly 1 m/s, its energy
    (kinetic + elastic + barrier) conserved to the scheme's accuracy."""
    scene = {"title": "bouncing ball", "analysis": "dynamic",
             "mesh": {"generator": "sphere", "origin": [0.0, 0.0, 0.0505], "radius": 0.05, "h": 0.02},
             "material": {"E": 1e5, "nu": 0.3, "rho": 1000.0}, "discretization": {"degree": 1},
             "dynamic": {"duration": 0.05, "dt": 1e-3, "initial_velocity": [0.0, 0.0, -1.0]},
             "contact": {"obstacle": [{"name": "floor", "shape": "plane", "point": [0, 0, 0], "normal": [0, 0, 1]}]},
             "output": {"picture": False, "fields": False, "probes": {"centre": [0.0, 0.0, 0.0505]}}}
    code, r, _, out = run_scene(tmp_path, scene)
    assert code == 0 and r["converged"] and r["intersection_free"]
    energy = np.genfromtxt(out / "energy.csv", delimiter=",", names=True)
    assert energy["contact"].max() > 0 and energy["elastic"].max() > 0.5 * energy["kinetic"][0]   # it hit
    assert r["energy_balance_error"] < 0.03                         # measured 0.8 %
    h = probe_history(out)
    assert h["centre_vz"][-1] > 0.8                                  # on its way up again


def test_a_restart_continues_the_stick_as_the_uninterrupted_run(tmp_path):
    """--restart from the checkpoint at t = 0.05 s of the sticking block: the step after it starts at the
    checkpoint's time (its friction's slip threshold is one step's, not 0.05 s worth), so the creep and the end
    state are the uninterrupted run's (kappa was never raised here, so nothing else differs)."""
    import json
    from fem_forms.cli import main
    d = slope_scene(0.7)
    d["dynamic"] = {**d["dynamic"], "checkpoint_every": 25}
    for sub in ("full", "half"):
        (tmp_path / sub).mkdir()
    code, full, _, _ = run_scene(tmp_path / "full", d)
    half = dict(d, dynamic={**d["dynamic"], "duration": 0.05})
    code, _, _, out2 = run_scene(tmp_path / "half", half)
    assert main(["run", str(tmp_path / "full" / "scene.toml"), "--out", str(out2), "--restart", str(out2), "-q"]) == 0
    cont = json.loads((out2 / "results.json").read_text())
    assert cont["time_reached"] == pytest.approx(0.1) and cont["intersection_free"]
    assert np.allclose(cont["probes"]["c"]["displacement"], full["probes"]["c"]["displacement"], rtol=1e-6,
                       atol=1e-9)              # without the restored step start: 4e-6 m more creep (measured)
