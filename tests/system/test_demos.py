"""Demos cannot rot: every script in demos/*.py runs as a user runs it (`python demos/X.py OUT_DIR`, a
subprocess), must exit 0, and the key numbers it prints are checked against references that do not
come from the demo itself (never its own past output):

- sagging_beam: the tip displacement against an independent solve of the same continuum problem with
  another element, mesh, formulation and load path (see `sag_reference`); its output files as the
  first README command writes them.
- struck_bar: the first flexural frequencies of the free bar against Euler-Bernoulli theory.
- loaded_vs_unloaded_modes: the unloaded modes against Timoshenko beam theory, Saint-Venant torsion and
  longitudinal bar theory; the loaded state against the same independent static solve.
- heated_strip: the face temperatures against the steady heat balance (wall and film in series) and the
  tip rise against the thermal-gradient beam (a circular arc of curvature alpha dT / (h s^2)).
- silicone_swing: the swing's frequency against Timoshenko beam theory and its decay per cycle against
  the Rayleigh damping ratio of its losses.
- struck_bar_in_time: the spectrum peaks of the time-domain run against the modal analysis of the same
  bar (a separate eigen solve here), each mode mapped through Newmark's exact period elongation.
- bent_spoon: the loaded tip deflection and the springback against Euler-Bernoulli theory of an elastic-
  perfectly plastic cantilever, the permanent set against the same theory's residual curvature.
- inverse_design: the printed forward-check mismatch against the design tolerance, and the written rest
  shape solved forward here, through the public API, landing on the target.
- spinning_top, floating_boat, roly_poly, soft_figure: closed forms of their shapes (centres of mass,
  buoyancy, the rocking centre, the clamped sole as support) and each design's bound recomputed from the
  printed or written numbers.

The demos run two at a time in worker threads (the machines have 2 cores) while the references are
computed in this process.
"""
import json
import math
import re

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq

import fem_forms as ff
from system.demo_runs import CHECKS, DEMOS, NUMBER, demo, grab, scene_dict  # noqa: F401 (demo: fixture)


def test_every_demo_is_checked():
    assert sorted(p.stem for p in DEMOS.glob("*.py")) == sorted(CHECKS)


# --- the sagging soft beam (static) -------------------------------------------------------------
@pytest.fixture(scope="module")
def sag_reference(demo):
    """The demo's scene solved independently of the demo's discretisation: Taylor-Hood Q2/Q1 (mixed
    u-p) hexahedra 20x2x2 instead of P2 displacement tetrahedra 40x4x4, and 4 load steps instead of 1
    (a hyperelastic equilibrium does not depend on the load path). Only the continuum problem is
    shared, so agreement within 1 % checks that the demo's answer is converged in mesh and Newton
    (measured: tip within 0.2 %; a linear solve would sag 1.6 m; Q2 displacement hexes 20x2x2: 0.5 %)."""
    d = scene_dict("sagging_beam")
    d["mesh"] |= {"cells": [20, 2, 2], "cell": "hexahedron"}
    d["discretization"] = {"degree": 2, "formulation": "mixed"}
    d["solver"] = {"steps": 4}
    res = ff.solve_static(ff.Scene.from_dict(d))
    assert res.report.converged
    return res


def test_demo_scene_solves_and_writes_outputs(demo, sag_reference):
    """The main demo (the first README command) solves, writes every output file, and its printed tip
    displacement agrees with the independent solve to 1 % of its length."""
    stdout, out = demo("sagging_beam")
    tip = np.array(grab(rf"tip displacement u = \(({NUMBER}), ({NUMBER}), ({NUMBER})\) m", stdout))
    ref = np.array(sag_reference.probes["tip"])
    assert np.linalg.norm(tip - ref) <= 0.01 * np.linalg.norm(ref), (tip, ref)
    assert grab(rf"max \|u\| = ({NUMBER}) m", stdout)[0] == pytest.approx(sag_reference.max_displacement, rel=0.01)
    summary = json.loads((out / "results.json").read_text())        # what write_static_outputs returned
    assert summary["converged"]
    data = json.loads((out / "results.json").read_text())
    for key in ("analysis", "dofs", "converged", "newton_iterations", "load_steps", "energy",
                "max_displacement", "wall_time_s", "probes"):
        assert key in data
    assert data["probes"]["tip"]["displacement"][2] < -0.3     # a soft beam sags a lot
    for f in ("fields.xdmf", "fields.h5", "deformed.png", "newton_history.csv"):
        assert (out / f).stat().st_size > 0


# --- the struck bar (modal + sound) -------------------------------------------------------------
def test_struck_bar_demo_scene(demo):
    """The demo's key number: the free bar's first flexural mode, against Euler-Bernoulli (free-free,
    (beta L)^2 = 22.373, within 1 %); the second flexural mode ((beta L)^2 = 61.673) is among the
    printed ones within 2 % (shear and rotary inertia lower it by about 1 % at L/t = 30)."""
    stdout, _ = demo("struck_bar")
    scene = ff.Scene.from_file(DEMOS / "scenes" / "struck_bar.toml")
    length, t = scene.mesh.size[0], scene.mesh.size[2]
    f_eb = 22.373 / (2 * math.pi * length**2) * math.sqrt(scene.material.E * t**2 / (12 * scene.material.rho))
    rigid_modes = int(grab(r"(\d+) rigid-body modes", stdout)[0])
    f1 = grab(rf"first flexural mode ({NUMBER}) Hz", stdout)[0]
    modes = [float(x) for x in re.search(r"modes \[Hz\]: (.*)", stdout).group(1).split(",")]
    peaks_hz = [float(x) for x in re.search(r"spectrum peaks \[Hz\] (.*)", stdout).group(1).split(",")]
    assert rigid_modes == 6
    assert f1 == pytest.approx(f_eb, rel=0.01)
    assert min(abs(p - f1) for p in peaks_hz) <= 2.0   # peaks printed to 1 Hz; the 2 s WAV resolves 0.5 Hz
    f2_eb = f_eb * 61.673 / 22.373
    assert min(abs(f / f2_eb - 1) for f in modes) < 0.02


# --- modes of the sagging beam, loaded and unloaded ---------------------------------------------
def timoshenko_cantilever(E, nu, rho, L, h, count):
    """Lowest bending frequencies [Hz] of a clamped-free Timoshenko beam of square section h x h
    (Cowper's shear coefficient 10 (1 + nu) / (12 + 11 nu)): roots of the 2x2 determinant of the
    free-end conditions, the ODE y' = M(omega) y (y = w, w', phi, phi') integrated exactly by expm."""
    A, I, G = h * h, h**4 / 12, E / (2 * (1 + nu))
    kGA = 10 * (1 + nu) / (12 + 11 * nu) * G * A

    def det(w):
        M = np.array([[0, 1, 0, 0], [-rho * A * w * w / kGA, 0, 0, 1], [0, 0, 0, 1],
                      [0, -kGA / (E * I), (kGA - rho * I * w * w) / (E * I), 0]])
        Y = expm(M * L)
        shear, moment = Y[1] - Y[2], Y[3]                  # w' - phi = 0 and phi' = 0 at x = L
        return shear[1] * moment[3] - shear[3] * moment[1]
    w_eb = 1.8751**2 / L**2 * math.sqrt(E * I / (rho * A))
    ws = np.linspace(0.2 * w_eb, 30 * w_eb, 3000)
    d = [det(w) for w in ws]
    roots = [brentq(det, ws[i], ws[i + 1]) for i in range(len(ws) - 1) if d[i] * d[i + 1] < 0]
    return [w / (2 * math.pi) for w in roots[:count]]


def test_loaded_vs_unloaded_modes_demo(demo, sag_reference):
    """Unloaded (E 1 MPa, nu 0.45, 1 x 0.1 x 0.1 m, clamped): bending pairs 1-2 and 3-4 against
    Timoshenko beam theory within 2 % (the 3D clamp, which also holds the cross-section, stiffens them
    by about 1.3 %), mode 5 against Saint-Venant torsion (torsion constant 0.1406 h^4) and mode 6
    against the longitudinal bar, (1 / 4L) sqrt(E / rho), within 1.5 %; the loaded state's max |u|
    against the independent static solve of the sagging demo within 1 %."""
    stdout, out = demo("loaded_vs_unloaded_modes")
    d = scene_dict("sagging_beam")
    m = d["material"]
    E, nu, rho = m["E"], m["nu"], m["rho"]
    L, h = d["mesh"]["size"][0], d["mesh"]["size"][1]
    rows = re.findall(rf"^\s+(\d+)\s+({NUMBER})\s+({NUMBER})\s+{NUMBER} %$", stdout, re.M)
    assert [int(r[0]) for r in rows] == [1, 2, 3, 4, 5, 6], stdout
    unloaded = [float(r[1]) for r in rows]
    b1, b2 = timoshenko_cantilever(E, nu, rho, L, h, 2)
    assert unloaded[0:2] == pytest.approx([b1, b1], rel=0.02)
    assert unloaded[2:4] == pytest.approx([b2, b2], rel=0.02)
    G = E / (2 * (1 + nu))
    torsion = 1 / (4 * L) * math.sqrt(G * 0.1406 * h**4 / (rho * h**4 / 6))
    axial = 1 / (4 * L) * math.sqrt(E / rho)
    assert unloaded[4] == pytest.approx(torsion, rel=0.015)
    assert unloaded[5] == pytest.approx(axial, rel=0.015)
    # the axial mode carries the longitudinal bar's effective mass 8 / pi^2 along x
    emf = json.loads((out / "unloaded" / "results.json").read_text())["effective_mass_fraction"]
    assert emf[5][0] == pytest.approx(8 / math.pi**2, rel=0.02)
    loaded_max_u = grab(rf"loaded state: max \|u\| = ({NUMBER}) m", stdout)[0]
    assert loaded_max_u == pytest.approx(sag_reference.max_displacement, rel=0.01)


# --- inverse design -----------------------------------------------------------------------------
def test_inverse_design_demo(demo):
    """Both designs: the printed forward-check mismatch is within the design tolerance (1e-8 of the
    largest rest offset, as in test_inverse.py). The soft beam's written rest mesh, solved forward here
    through the public API (mesh file, 4 load steps), carries the target point onto the target."""
    stdout, out = demo("inverse_design")
    offsets = [float(x) / 1000 for x in re.findall(rf"largest rest offset ({NUMBER}) mm", stdout)]
    mismatches = [float(x) for x in re.findall(rf"lands within ({NUMBER}) m of the target", stdout)]
    assert len(offsets) == len(mismatches) == 2, stdout
    for offset, mismatch in zip(offsets, mismatches):
        assert mismatch <= 1e-8 * offset
    assert offsets[0] > 0.5                                  # the beam's rest shape curls up a lot
    design = json.loads((out / "straight_beam_inverse" / "results.json").read_text())
    target = np.array(design["probes"]["tip"]["point"])
    rest = np.array(design["probes"]["tip"]["rest_position"])
    forward = scene_dict("straight_beam_inverse")
    forward.pop("inverse")
    forward["analysis"] = "static"
    forward["mesh"] = {"generator": "file", "file": str(out / "straight_beam_inverse" / "rest_shape.msh")}
    forward["output"] = {"probes": {"tip": rest.tolist()}}
    res = ff.solve_static(ff.Scene.from_dict(forward))
    assert res.report.converged
    np.testing.assert_allclose(rest + np.array(res.probes["tip"]), target, rtol=0, atol=1e-6)
