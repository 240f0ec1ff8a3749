"""Viscoelasticity ([material.viscoelastic] prony = [[g_i, tau_i], ...]) against closed forms of linear
viscoelasticity (e.g. Findley, Lai & Onaran, Creep and Relaxation of Nonlinear Viscoelastic Materials, 1976,
ch. 5), a bar in uniaxial stress on rollers, the static analysis's pseudo-time being time:
- stress relaxation: stretched by a ramp then held, the bar's force follows
  E eps / t_r [g_inf t_r + sum g_i tau_i (exp(-(t - t_r)/tau_i) - exp(-t/tau_i))] at every step (Simo's update
  is exact for a strain linear in time over each step, so to round-off);
- creep of a standard linear solid (one Prony term) under a load ramped then held: the strain follows the
  creep compliance J(t) = 1/E_inf - (1/E_inf - 1/E) exp(-t/tau_c), tau_c = tau / g_inf, convolved with the ramp;
- at a finite stretch (neo-Hookean, 50 %) the held force relaxes by the same function of time from the
  elastic force of that stretch (a run without viscoelasticity);
- in dynamics a suddenly loaded cantilever comes to rest at the deflection of its long-term modulus (beam
  theory), the energy account (with the work on the Prony branches) constant."""
import json
import math

import numpy as np
import pytest

import fem_forms as ff
from fem_forms.errors import InputError
from helpers import mpirun, run_scene, toml_dumps

E, NU = 1.0e6, 0.3
PRONY = [[0.3, 0.01], [0.2, 1.0]]
G_INF = 1 - sum(g for g, _ in PRONY)
AREA = 0.01                                                   # the bar's section, m^2


def bar(model="linear", prony=PRONY, fix_history=None, load=None, steps=20, **over) -> dict:
    """A 1 x 0.1 x 0.1 m bar on rollers at x = 0, y = 0, z = 0: uniaxial stress along x."""
    fix = [{"where": {"axis": a, "at": 0.0}, "components": [a]} for a in "xyz"]
    if fix_history is not None:
        stretch, history = fix_history
        fix.append({"name": "pull", "where": {"axis": "x", "at": 1.0}, "components": ["x"],
                    "value": [stretch, 0.0, 0.0]} | ({"history": history} if history else {}))
    material = {"model": model, "E": E, "nu": NU}
    if prony is not None:
        material["viscoelastic"] = {"prony": prony}
    d = {"mesh": {"size": [1.0, 0.1, 0.1], "cells": [2, 1, 1]}, "material": material,
         "discretization": {"degree": 1}, "fix": fix, "load": load or [], "solver": {"steps": steps},
         "output": {"picture": False, "fields": False, "probes": {"end": [1.0, 0.1, 0.1]}}}
    d.update(over)
    return d


def path(out) -> np.ndarray:
    return np.genfromtxt(out / "probes.csv", delimiter=",", names=True)


def relaxation(t: float, t_r: float) -> float:
    """Force over E eps A of a strain ramped over t_r, then held (linear viscoelasticity, the Prony series)."""
    if t <= t_r:
        return (G_INF * t + sum(g * tau * -math.expm1(-t / tau) for g, tau in PRONY)) / t_r
    return (G_INF * t_r + sum(g * tau * (math.exp(-(t - t_r) / tau) - math.exp(-t / tau)) for g, tau in PRONY)) / t_r


def test_stress_relaxation_at_constant_stretch_follows_the_prony_series(tmp_path):
    eps, t_r = 1e-4, 1e-3
    code, s, err, out = run_scene(tmp_path, bar(fix_history=(eps, [[0.0, 0.0], [t_r, 1.0], [3.0, 1.0]])))
    assert code == 0, err
    rows = path(out)
    assert rows["time"][-1] == pytest.approx(3.0) and len(rows) >= 5
    expected = [E * eps * AREA * relaxation(t, t_r) for t in rows["time"]]
    assert rows["pull_Fx"] == pytest.approx(expected, rel=1e-8, abs=1e-12)
    assert s["reactions"]["pull"][0] == pytest.approx(E * eps * AREA * relaxation(3.0, t_r), rel=1e-8)
    assert s["reactions"]["pull"][0] < 0.52 * E * eps * AREA                  # relaxed near g_inf = 0.5


def test_a_standard_linear_solid_creeps_under_a_held_load(tmp_path):
    g, tau, sigma = 0.4, 0.5, 100.0
    e_inf, t_c = (1 - g) * E, tau / (1 - g)
    t_r, t_end = 1e-3 * t_c, 5 * t_c
    load = [{"type": "traction", "where": {"axis": "x", "at": 1.0}, "value": [sigma, 0.0, 0.0],
             "history": [[0.0, 0.0], [t_r, 1.0], [t_end, 1.0]]}]
    d = bar(prony=[[g, tau]], load=load, steps=100)
    d["solver"]["max_step"] = 0.01
    code, _, err, out = run_scene(tmp_path, d)
    assert code == 0, err
    rows = path(out)

    def strain(t):                                  # the creep compliance convolved with the ramp
        decay = (math.exp(-(t - t_r) / t_c) - math.exp(-t / t_c)) if t > t_r else -math.expm1(-t / t_c)
        return sigma / t_r * (min(t, t_r) / e_inf - (1 / e_inf - 1 / E) * t_c * decay)
    later = rows["time"] > t_r
    assert rows["end_ux"][later] == pytest.approx([strain(t) for t in rows["time"][later]], rel=1e-4)
    assert rows["end_ux"][-1] == pytest.approx(sigma / e_inf, rel=0.01)          # nearly crept out


def test_a_finite_stretch_relaxes_from_its_elastic_force(tmp_path):
    stretch, t_r = 0.5, 1e-6
    elastic = ff.solve_static(ff.Scene.from_dict(bar("neo-hookean", None, (stretch, None))))
    force = elastic.summary()["reactions"]["pull"][0]
    history = [[0.0, 0.0], [t_r, 1.0], [1.0, 1.0]]
    code, _, err, out = run_scene(tmp_path, bar("neo-hookean", fix_history=(stretch, history), steps=10))
    assert code == 0, err
    rows = path(out)
    held = rows["time"] > t_r
    expected = [force * (G_INF + sum(g * math.exp(-(t - t_r) / tau) for g, tau in PRONY))
                for t in rows["time"][held]]
    assert rows["pull_Fx"][held] == pytest.approx(expected, rel=1e-3)


@pytest.mark.mpi
def test_two_ranks_relax_as_one(tmp_path):
    d = bar(fix_history=(1e-4, [[0.0, 0.0], [1e-3, 1.0], [1.0, 1.0]]))
    d["mesh"]["cells"] = [6, 2, 2]
    (tmp_path / "scene.toml").write_text(toml_dumps(d))
    one = ff.solve_static(ff.Scene.from_dict(d)).summary()
    p = mpirun(["-m", "fem_forms", "run", str(tmp_path / "scene.toml"), "--out", str(tmp_path / "out")])
    assert p.returncode == 0, p.stderr[-2000:]
    two = json.loads((tmp_path / "out" / "results.json").read_text())
    assert two["reactions"]["pull"][0] == pytest.approx(one["reactions"]["pull"][0], rel=1e-9)


@pytest.mark.parametrize("change, message", [
    ({"prony": [[0.6, 1.0], [0.5, 2.0]]}, "sum to 1.1; they must sum below 1"),
    ({"prony": [[1.2, 1.0]]}, r"the relative modulus g must lie in \(0, 1\)"),
    ({"prony": [[0.2, 0.0]]}, "the relaxation time tau must be positive"),
    ({"fix_history": None}, "a static scene needs time"),
    ({"analysis": "modal"}, "for analysis = 'static' or 'dynamic' only"),
    ({"analysis": "dynamic", "dynamic": {"scheme": "central-difference", "mass": "lumped"}},
     "not with the explicit central-difference scheme"),
    ({"solver": {"control": "arc-length"}}, "not with solver.control = 'arc-length'"),
    ({"discretization": {"degree": 2, "formulation": "mixed"}}, "the mixed formulation is not implemented"),
])
def test_bad_viscoelastic_input_is_refused_in_one_line(change, message):
    args = {"fix_history": (1e-4, [[0.0, 0.0], [1.0, 1.0]])}
    over = dict(change)
    args["prony"] = over.pop("prony", PRONY)
    if "fix_history" in over:
        args["fix_history"] = over.pop("fix_history")
    d = bar(model="neo-hookean", **args, **over)
    if d.get("analysis") in ("modal", "dynamic"):
        d["material"]["rho"] = 1000.0
        d["fix"] = [f for f in d["fix"] if "history" not in f]       # a support history is static's
    with pytest.raises(InputError, match=message):
        ff.Scene.from_dict(d)


def test_a_model_solved_again_starts_again_from_rest():
    """Model reuse (set_values, then solve_static(model=...)): the second solve relaxes from t = 0 at rest as
    the first did (its time and history had stayed at the first run's end: exp(+300) and no convergence)."""
    from fem_forms.model import build_model
    scene = ff.Scene.from_dict(bar(fix_history=(1e-4, [[0.0, 0.0], [1e-3, 1.0], [3.0, 1.0]])))
    model = build_model(scene)
    first = ff.solve_static(scene, model=model).summary()["reactions"]["pull"][0]
    model.set_values(scene)
    again = ff.solve_static(scene, model=model)
    assert again.report.converged
    assert again.summary()["reactions"]["pull"][0] == pytest.approx(first, rel=1e-10)
    with pytest.raises(InputError, match="a new number of Prony terms needs a new model"):
        model.set_values(ff.Scene.from_dict(bar(prony=PRONY[:1], fix_history=(1e-4, [[0.0, 0.0], [1.0, 1.0]]))))


def cantilever(duration=3.0) -> dict:
    L, B, H, P = CANTILEVER
    return {"title": "viscoelastic cantilever", "analysis": "dynamic",
            "mesh": {"size": [L, B, H], "cells": [16, 1, 4], "cell": "hexahedron"},
            "material": {"model": "linear", "E": E * 10, "nu": 0.0, "rho": 1000.0,
                         "viscoelastic": {"prony": [[0.5, 0.08]]}},
            "discretization": {"degree": 2}, "fix": [{"where": {"axis": "x", "at": 0.0}}],
            "load": [{"type": "traction", "where": {"axis": "x", "at": L}, "value": [0.0, 0.0, -P / (B * H)]}],
            "dynamic": {"duration": duration, "dt": 0.0125, "checkpoint_every": 20},
            "output": {"picture": False, "fields": [], "probes": {"tip": [L, B / 2, H / 2]}}}


CANTILEVER = (0.4, 0.04, 0.02, 0.02)          # L, B, H (m), tip load P (N)


def test_a_viscoelastic_cantilever_swings_to_rest_at_its_relaxed_deflection():
    """Dynamics: a tip load applied at t = 0 sets a cantilever swinging; its Prony branch (g = 0.5, tau near
    1 / omega_1) damps the swing, and it comes to rest at the deflection of the long-term modulus g_inf E,
    P L^3 / (3 g_inf E I) (beam theory; another method than the motion). The energy account (kinetic +
    g_inf psi - external work + the branches' work) stays constant."""
    from fem_forms.analyses.dynamic import solve_dynamic
    L, B, H, P = CANTILEVER
    r = solve_dynamic(ff.Scene.from_dict(cantilever()))
    assert r.failure is None
    rows = np.array(r.probe_rows)
    relaxed = P * L**3 / (3 * 0.5 * E * 10 * B * H**3 / 12)
    assert -rows[-1, 3] == pytest.approx(relaxed, rel=0.02)
    assert np.ptp(rows[rows[:, 0] > 2.5, 3]) < 0.01 * relaxed             # at rest
    s = r.summary()
    assert s["energy_final"]["viscous_work"] > 0
    assert s["energy_balance_error"] < 0.01


def test_a_viscoelastic_run_continued_from_its_checkpoint_ends_where_the_whole_run_does(tmp_path):
    """--restart: the Prony stresses come back with the State and the branches' clock with the checkpoint's
    time (a clock left at 0 would step them by the whole elapsed time)."""
    from fem_forms.cli import main
    for name in ("whole", "half"):
        (tmp_path / name).mkdir()
    code, whole, err, _ = run_scene(tmp_path / "whole", cantilever(0.5))
    assert code == 0, err
    code, _, err, out = run_scene(tmp_path / "half", cantilever(0.25))
    assert code == 0, err
    assert main(["run", str(tmp_path / "whole" / "scene.toml"), "--out", str(out), "--restart", str(out), "-q"]) == 0
    cont = json.loads((out / "results.json").read_text())
    assert cont["probes"]["tip"]["displacement"] == pytest.approx(whole["probes"]["tip"]["displacement"],
                                                                 rel=1e-7, abs=1e-12)


def test_the_last_accepted_state_keeps_the_viscoelastic_state():
    """A run stopped at a limit point reports its last accepted state (solve_static sets the loads back through
    the load path, then post-processes): the solid's start belongs to the start of a solve, not to the load path
    (there it zeroed the displacement being reported)."""
    from fem_forms.analyses.static.solve import load_path, post_process
    r = ff.solve_static(ff.Scene.from_dict(bar(fix_history=(1e-4, [[0.0, 0.0], [1e-3, 1.0], [3.0, 1.0]]))))
    force, end = r.summary()["reactions"]["pull"][0], list(r.probes["end"])
    set_load, _ = load_path(r.model)                  # what solve_static does at a limit point
    set_load(r.report.load_reached)
    post_process(r)
    assert r.probes["end"] == pytest.approx(end, rel=1e-12)
    assert r.summary()["reactions"]["pull"][0] == pytest.approx(force, rel=1e-10)
