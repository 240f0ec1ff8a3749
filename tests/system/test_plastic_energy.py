"""The plastic work in a dynamic run's energy account (analyses/dynamic/energy.py), von Mises:
- a hardening block in uniaxial tension loaded slowly past yield (rollers on three faces, traction on the
  fourth: a uniform uniaxial state): kinetic + elastic - external work + damping + plastic work stays
  constant (Newmark's identity, the reference), and the plastic work equals J2 theory's
  int (sigma_y a + H a^2 / 2) dV of the equivalent plastic strain a reached (sigma : d eps_p = (sigma_y + H a) da
  while it flows; the account sums trapezoidal stresses times plastic strain increments instead);
- a bar held between rollers, heated past yield, held hot and cooled back to T_ref (perfectly plastic, every
  node on a heated face): hot -sigma_y, after cooling the residual stress E alpha dT - sigma_y (1-D closed
  form, valid while E alpha dT < 2 sigma_y), plastic work sigma_y (alpha dT - sigma_y / E) V (to the few %
  that the ringing of the undamped lateral motion adds), and the balance with thermal and plastic work."""
import json

from dolfinx import fem
from mpi4py import MPI
import numpy as np
import pytest

import fem_forms as ff
from fem_forms.analyses.dynamic import solve_dynamic
from fem_forms.output.plastic import plastic_summary
from fem_forms.output.quantities import Quantities
from helpers import mpirun, rollered_block, tension_block, toml_dumps

T, H, SY, E = 300e6, 20e9, 250e6, 200e9


def test_plastic_work_closes_the_balance_of_a_bar_loaded_past_yield():
    d = tension_block()
    r = solve_dynamic(ff.Scene.from_dict(d))
    m, e = r.system.model, r.energy
    assert plastic_summary(m)["max_plastic_strain"] == pytest.approx((T - SY) / H, rel=0.05)   # dynamic overshoot
    a = m.solid.alpha                                  # committed equivalent plastic strain (quadrature points)
    j2 = MPI.COMM_WORLD.allreduce(fem.assemble_scalar(fem.form((SY * a + 0.5 * H * a**2) * m.dx)), op=MPI.SUM)
    assert e.now.plastic_work == pytest.approx(j2, rel=3e-4)     # -8e-5 (dt 5e-4 s), -1.4e-6 (dt 1e-4 s)
    assert e.now.plastic_work > 3 * e.now.elastic                      # most of the work is dissipated (3.1x)
    assert e.balance_error() < 1e-10                     # 2e-13; 0.72 without the plastic work
    assert "plastic_work" in r.summary()["energy_final"]


def test_finite_strain_plastic_work_and_balance():
    """The same block as a finite-strain (Simo) von Mises solid, model "neo-hookean". Its plastic work is
    int sigma_y da + H/2 d(a^2) per step, so the quasi-static closed form (sigma_y a* + H a*^2 / 2) V with
    a* = (T - sigma_y) / H is the reference (measured +3.8 %: the dynamic overshoot, largest a 4.9 % above a*).
    The balance is a real check here (the plastic work is not fitted to close it): 1.0e-3 at dt 0.5 ms,
    0.9e-3 at 0.1 ms, the closed-form return's own inconsistency (it lets det bbar_e drift from 1); it
    was 0.82 with psi at the committed C_p^-1 and -113 % plastic work against J2 theory's with psi at
    the returned bbar_e without unit determinant."""
    d = tension_block("neo-hookean")
    r = solve_dynamic(ff.Scene.from_dict(d))
    e = r.energy
    a = (T - SY) / H
    assert e.now.plastic_work == pytest.approx((SY * a + 0.5 * H * a**2) * 1.0, rel=0.1)
    assert e.now.plastic_work > 3 * e.now.elastic > 0
    assert e.balance_error() < 3e-3


def obrien_block(dt: float):
    """A soft StVK block (E 10 MPa) on rollers pulled by 1.5x the traction at which O'Brien's deviatoric elastic
    strain reaches gamma1 = 1e-3: it flows until the plastic limit gamma2 = 0.02 caps |eps_p|."""
    e, nu, g1, g2 = 1e7, 0.3, 1e-3, 0.02
    flow = 2 * e / (2 * (1 + nu)) * g1 / np.sqrt(2 / 3)          # uniaxial S_xx with |dev S| = 2 mu gamma1
    d = rollered_block("stvk", 1.5 * flow, history=((0, 0), (2.0, 1)), E=e, rho=1000.0,
                       plasticity={"model": "obrien", "elastic_limit": g1, "plastic_limit": g2},
                       analysis="dynamic", dynamic={"duration": 3.0, "dt": dt},
                       damping={"rayleigh": {"alpha": 20.0, "beta": 0.0}}, output={"picture": False, "fields": []})
    return solve_dynamic(ff.Scene.from_dict(d)), 2 * e / (2 * (1 + nu)) * g1 * g2 * 1.0   # 2 mu g1 g2 V


def test_obrien_plastic_work_tends_to_the_flow_rule_as_dt_shrinks():
    """While it flows, O'Brien's plastic strain moves along its deviatoric elastic strain of norm gamma1, so
    the dissipation is 2 mu gamma1 |d eps_p|: 2 mu gamma1 gamma2 V once capped. The account counts the
    stored energy each update releases; the update comes one step late (the elastic strain overshoots
    gamma1 by a step's worth), so the plastic work tends to the reference with dt: +10.5 %, +3.3 %, +1.0 %
    at dt 5, 1, 0.2 ms, and so does the energy balance, the scheme's own error: 7.4 %, 2.3 %, 0.56 %
    (measured)."""
    errors, balances = [], []
    for dt in (5e-3, 1e-3):
        r, reference = obrien_block(dt)
        assert plastic_summary(r.system.model)["max_plastic_strain"] == pytest.approx(0.02, rel=1e-9)
        errors.append(r.energy.now.plastic_work / reference - 1)
        balances.append(r.energy.balance_error())
    assert 0 < errors[1] < 0.05 and errors[1] < errors[0] / 2
    assert balances[1] < 0.05 and balances[1] < balances[0] / 2



def test_a_restart_keeps_the_plastic_history(tmp_path):
    """The hardening block loaded past yield and unloaded, stopped after the unloading began (its last
    checkpoint) and continued with --restart, ends where the uninterrupted run ends: the checkpoint holds the
    plastic history (before it did not, and the restart rebuilt it by one return from zero at the saved
    displacement: the largest plastic strain came out 1.11e-3 instead of 1.63e-3, measured)."""
    d = tension_block(history=((0, 0), (0.01, 1), (0.02, 0)), duration=0.025, checkpoint_every=10,
                      output={"picture": False, "fields": [], "probes": {"c": [2.0, 1.0, 0.5]}})
    results = {}
    for name, duration in (("full", 0.025), ("half", 0.015)):
        path = tmp_path / f"{name}.toml"
        path.write_text(toml_dumps(dict(d, dynamic={**d["dynamic"], "duration": duration})))
        assert ff.cli.main(["run", str(path), "--out", str(tmp_path / name), "-q"]) == 0
    assert ff.cli.main(["run", str(tmp_path / "full.toml"), "--out", str(tmp_path / "half"),
                        "--restart", str(tmp_path / "half"), "-q"]) == 0
    for name in ("full", "half"):
        results[name] = json.loads((tmp_path / name / "results.json").read_text())
    full, cont = results["full"], results["half"]
    assert full["max_plastic_strain"] > 1e-3                          # it did flow (1.63e-3)
    assert cont["max_plastic_strain"] == pytest.approx(full["max_plastic_strain"], rel=1e-9)
    assert np.allclose(cont["probes"]["c"]["displacement"], full["probes"]["c"]["displacement"], rtol=1e-8)
    assert cont["energy_balance_error"] < 1e-9


EP, ALPHA, DT, L, A = 2.0e11, 1.2e-5, 100.0, 1.0, 0.01      # E alpha DT = 240 MPa: yields at 200 MPa


def heated_and_cooled(t_end: float) -> dict:
    """A 1 x 0.1 x 0.1 m steel bar between rollers, 20 x 1 x 1 cells (every node on a face y = 0 or 0.1,
    both following the temperature history: T is uniform), heated to DT over 2 ms, held 0.5 ms (the march
    does not stop at the history's corners: a cut-back at the onset of yield shifts its steps), cooled back
    over 2 ms."""
    hist = {"history": [[0.0, 0.0], [2e-3, DT], [2.5e-3, DT], [4.5e-3, 0.0], [1.0, 0.0]]}
    return {
        "analysis": "dynamic", "mesh": {"size": [L, 0.1, 0.1], "cells": [20, 1, 1]},
        "material": {"model": "linear", "E": EP, "nu": 0.3, "rho": 7800.0,
                     "plasticity": {"model": "von-mises", "yield_stress": SY - 50e6}},
        "discretization": {"degree": 1, "quadrature_degree": 2},
        "fix": [{"where": {"axis": "x", "at": x}, "components": ["x"]} for x in (0.0, L)] +
               [{"where": {"point": [0.0, 0.0, 0.0]}, "components": ["y", "z"]},
                {"where": {"point": [0.0, 0.1, 0.0]}, "components": ["z"]}],
        "thermal": {"conductivity": 50.0, "specific_heat": 500.0, "expansion": ALPHA, "boundary": [
            {"where": {"axis": "y", "at": y}, "temperature": hist} for y in (0.0, 0.1)]},
        "dynamic": {"duration": t_end, "dt": 5e-5, "output_every": 1000, "checkpoint_every": 0},
        "output": {"picture": False, "fields": [], "probes": {"mid": [0.5, 0.05, 0.05]}}}


@pytest.mark.parametrize("t_end, sigma, rel", [(2.4e-3, -(SY - 50e6), 5e-3), (5e-3, EP * ALPHA * DT - (SY - 50e6), 0.05)])
def test_heated_past_yield_then_cooled_leaves_a_residual_tension(t_end, sigma, rel):
    """Hot: -sigma_y (measured -0.16 %); cooled: E alpha DT - sigma_y = 40 MPa (measured +2.7 %). The lateral
    expansion rings (undamped Newmark, kinetic energy 0.3 J when hot) and each ring flows a little at the
    yield surface: the equivalent plastic strain spreads over 1.8e-4 to 3.0e-4 along the bar (2.0e-4 in the
    quasi-static answer) and the plastic work exceeds sigma_y (alpha DT - sigma_y / E) V by 3.5 %."""
    sy = SY - 50e6
    r = solve_dynamic(ff.Scene.from_dict(heated_and_cooled(t_end)))
    s = np.array(Quantities(r.system.model).at_probes(r.system.model.probes)["mid"]["stress"])
    assert s[0, 0] == pytest.approx(sigma, rel=rel)
    e = r.energy
    assert e.now.plastic_work == pytest.approx(sy * (ALPHA * DT - sy / EP) * L * A, rel=0.05)
    assert e.balance_error() < 1e-10                            # 4.4e-13 with thermal and plastic work


@pytest.mark.mpi
def test_two_ranks_agree_on_the_thermal_and_plastic_work(tmp_path):
    """The heated, held and cooled bar through the CLI on 2 ranks: energy.csv (with thermal_work and
    plastic_work) as on 1 rank."""
    d = heated_and_cooled(5e-3)
    serial = solve_dynamic(ff.Scene.from_dict(d))
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(d))
    p = mpirun(["-m", "fem_forms", "run", str(path), "--out", str(tmp_path / "out")])
    assert p.returncode == 0, p.stderr
    lines = (tmp_path / "out" / "energy.csv").read_text().splitlines()
    assert lines[0] == "time,kinetic,elastic,external_work,dissipated,thermal_work,plastic_work"
    rows = np.loadtxt(lines[1:], delimiter=",")
    ref = np.array([[t] + [getattr(e, c) for c in serial.energy.columns()] for t, e in serial.energy.history])
    np.testing.assert_allclose(rows, ref, rtol=1e-8, atol=1e-8 * ref[:, 5].max())
