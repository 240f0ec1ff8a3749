"""[sound.impact]: the sound of a dynamic run's contacts. An aluminium bar (200 x 20 x 10 mm, P2) thrown at a floor
tilted 3 degrees hits it with one end; the WAV's spectrum (the test's own FFT) peaks at the free-free
Euler-Bernoulli bending frequencies through the 10 mm thickness, (beta_n L)^2 / (2 pi L^2) sqrt(E t^2 / (12 rho)),
beta_n L = 4.730, 7.853, 10.996; 2 ranks write the same WAV; bad input is one line, exit status 2. The exact
oscillator recursion is checked against the closed form of a step force."""
import json
import math

import numpy as np
import pytest

from fem_forms.cli import main
from fem_forms.output.impact_sound import modal_response
from helpers import mpirun, run_scene, toml_dumps, with_

L, T, E, RHO = 0.2, 0.01, 70e9, 2700.0
BETA_L = (4.730, 7.853, 10.996)
SCENE = {"title": "dropped bar", "analysis": "dynamic",
         "mesh": {"generator": "box", "size": [L, 0.02, T], "cells": [10, 2, 1], "cell": "tetrahedron"},
         "material": {"model": "linear", "E": E, "nu": 0.33, "rho": RHO}, "discretization": {"degree": 2},
         "dynamic": {"duration": 3e-4, "dt": 5e-6, "initial_velocity": [0.0, 0.0, -1.0]},
         "contact": {"distance": 2e-5, "obstacle": [{"name": "floor", "shape": "plane", "point": [L, 0.0, -5e-5],
                                                     "normal": [-0.05, 0.0, 1.0]}]},
         "sound": {"duration": 0.5, "modal_damping": [[500.0, 0.002], [5000.0, 0.004]],
                   "impact": {"obstacle": "floor"}},
         "output": {"picture": False, "fields": False}}


def euler_bernoulli() -> list:
    return [b**2 / (2 * math.pi * L**2) * math.sqrt(E * T**2 / (12 * RHO)) for b in BETA_L]


def wav_peaks(path, seconds: float = 0.05) -> tuple:
    """Frequencies and levels (dB below the strongest) of the spectral peaks of the WAV's first `seconds` (Hann
    window, zero-padded 8x): the heard motion falls as 1 / f^2 and the higher modes die out fast, so a short
    window shows them."""
    from scipy.io import wavfile
    from scipy.signal import find_peaks
    rate, x = wavfile.read(str(path))
    x = x[: int(seconds * rate)].astype(float)
    spec = np.abs(np.fft.rfft(x * np.hanning(len(x)), 8 * len(x)))
    db = 20 * np.log10(spec / spec.max() + 1e-12)
    idx, _ = find_peaks(db, height=-70.0, prominence=10.0)
    return idx * rate / (8 * len(x)), db[idx]


def test_the_impact_rings_at_the_bending_modes(tmp_path):
    code, r, _, out = run_scene(tmp_path, SCENE)
    assert code == 0 and r["converged"] and r["intersection_free"]
    s = r["impact_sound"]
    assert s["rigid_modes"] == 6 and s["peak_force_N"] > 0 and 0 < s["contact_time_s"] < 3e-4
    peaks, level = wav_peaks(out / "impact.wav")
    for f in euler_bernoulli():                      # measured -0.4, -0.7, -1.1 %
        near = np.abs(peaks / f - 1)
        assert near.min() < 0.03, (f, peaks)
    assert peaks[np.argmax(level)] == pytest.approx(euler_bernoulli()[0], rel=0.03)   # the first one is loudest


@pytest.mark.mpi
def test_two_ranks_write_the_same_impact_wav(tmp_path):
    """The whole run on 2 ranks: the march with contact (it hung in the first tangent's assembly before the array
    terms allowed new nonzeros on every rank), the modes, the modal forces summed over each rank's surface nodes,
    the WAV on rank 0."""
    from scipy.io import wavfile
    code, r1, _, out = run_scene(tmp_path, SCENE)
    assert code == 0
    p = mpirun(["-m", "fem_forms", "run", str(tmp_path / "scene.toml"), "--out", str(tmp_path / "mpi"), "-q"])
    assert p.returncode == 0, p.stderr[-2000:]
    r2 = json.loads((tmp_path / "mpi" / "results.json").read_text())
    assert r2["mpi_ranks"] == 2
    e1, e2 = r1["impact_sound"], r2["impact_sound"]
    assert e2["peak_force_N"] == pytest.approx(e1["peak_force_N"], rel=1e-6) and e1["modes_used"] == e2["modes_used"]
    assert e2["peaks_hz"] == pytest.approx(e1["peaks_hz"], rel=1e-6) and len(e1["peaks_hz"]) >= 3
    w1 = wavfile.read(str(out / "impact.wav"))[1].astype(float)
    w2 = wavfile.read(str(tmp_path / "mpi" / "impact.wav"))[1].astype(float)
    assert len(w1) == len(w2) and np.abs(w1 - w2).max() <= 1.0          # 16-bit samples: at most one step apart


def without(d: dict, *names) -> dict:
    return {k: v for k, v in d.items() if k not in names}


@pytest.mark.parametrize("scene, message", [
    (with_(SCENE, "sound.impact.obstacle", "table"),
     "sound.impact.obstacle = 'table': not an obstacle of [contact] (its obstacles: 'floor')"),
    (without(SCENE, "contact"), "sound.impact: needs a [contact] section"),
    (without(SCENE, "contact", "dynamic") | {"analysis": "modal"},
     "sound.impact: the sound of contacts is for analysis = 'dynamic' with [contact]"),
    (without(SCENE, "sound") | {"analysis": "static", "sound": {"impact": {"obstacle": "floor"}}},
     "sound: only for analysis = 'modal' or 'dynamic'"),
    (with_(SCENE, "sound.strike", {"point": [0.0, 0.0, 0.0], "direction": [0.0, 0.0, 1.0]}),
     "sound.strike: a struck part's ring is for analysis = 'modal'"),
    (with_(with_(SCENE, "sound.count", 4), "sound.up_to", 5000.0), "sound.up_to: give either count or up_to"),
    (with_(SCENE, "sound.listener", [0.1, 0.01, 0.005]),
     "sound.listener = [0.1, 0.01, 0.005]: lies in or on the part; it must be in the air"),
])
def test_bad_impact_input_is_one_line(tmp_path, capsys, scene, message):
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(scene))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err, err


def test_the_oscillator_recursion_is_exact_for_a_step_force():
    """q'' + 2 zeta w q' + w^2 q = F from rest: q = F / w^2 (1 - e^{-zeta w t} (cos w_d t + zeta w / w_d sin w_d t))."""
    w, z, F = np.array([2 * math.pi * 1000.0, 2 * math.pi * 7000.0]), np.array([0.01, 0.002]), 3.0
    times = np.array([0.0, 1e-4, 2e-4, 5e-3])
    q, v = modal_response(times, np.full((4, 2), F), w, z, 0.05, 44100)
    t = np.arange(q.shape[1]) / 44100
    for i in range(2):
        wd = w[i] * math.sqrt(1 - z[i] ** 2)
        e = np.exp(-z[i] * w[i] * t)
        ref = F / w[i] ** 2 * (1 - e * (np.cos(wd * t) + z[i] * w[i] / wd * np.sin(wd * t)))
        assert np.abs(q[i] - ref).max() < 1e-10 * np.abs(ref).max()      # across the held force too
        assert np.abs(v[i] - F / (w[i] * math.sqrt(1 - z[i] ** 2)) * e * np.sin(wd * t)).max() < 1e-9 * F / w[i]


def test_the_oscillators_follow_an_ode_solve_of_a_half_sine_pulse_off_the_audio_grid():
    """A contact-like pulse, sin(pi t / T) over T = 0.25 ms, known at 5 us steps (not on the 44.1 kHz grid: the
    sub-steps resample it), against scipy's DOP853 on the same piecewise-linear force: the first-order hold's
    ramp term and the sub-steps at work, within 2e-3 of the response's size (the resampling, not round-off)."""
    from scipy.integrate import solve_ivp
    w, z = np.array([2 * math.pi * 580.0, 2 * math.pi * 7600.0]), np.array([0.002, 0.004])
    times = np.arange(0.0, 0.4e-3 + 1e-12, 5e-6)
    pulse = np.where(times <= 0.25e-3, np.sin(math.pi * times / 0.25e-3), 0.0) * 1e3
    forces = np.column_stack([pulse, 0.5 * pulse])
    q, _ = modal_response(times, forces, w, z, 2e-3, 44100)
    t = np.arange(q.shape[1]) / 44100
    for i in range(2):
        f = lambda s, y, i=i: [y[1], np.interp(s, times, forces[:, i]) - 2 * z[i] * w[i] * y[1] - w[i] ** 2 * y[0]]  # noqa: E731
        ref = solve_ivp(f, (0.0, t[-1]), [0.0, 0.0], method="DOP853", t_eval=t, rtol=1e-11, atol=1e-16,
                        max_step=1e-6).y[0]
        assert np.abs(ref).max() > 0
        assert np.abs(q[i] - ref).max() < 2e-3 * np.abs(ref).max()           # measured 2e-4, 6e-4


def test_a_long_flight_around_the_contact_only_delays_the_ring():
    """The same pulse after 50 ms of flight (coarse steps, no force) and before 30 ms more: the response is the
    undelayed one (checked against DOP853 above) moved by the delay, exactly 2205 samples at 44.1 kHz."""
    w, z = np.array([2 * math.pi * 580.0, 2 * math.pi * 7600.0]), np.array([0.002, 0.004])
    times = np.arange(0.0, 0.4e-3 + 1e-12, 5e-6)
    pulse = np.where(times <= 0.25e-3, np.sin(math.pi * times / 0.25e-3), 0.0) * 1e3
    q, v = modal_response(times, np.column_stack([pulse, pulse]), w, z, 0.1, 44100)
    delay = 2205 / 44100
    flight = np.concatenate([np.arange(0.0, delay - 1e-9, 1e-3), times + delay, delay + 0.4e-3 + np.arange(1, 31) * 1e-3])
    force = np.concatenate([np.zeros(len(flight) - len(times) - 30), pulse, np.zeros(30)])
    qd, vd = modal_response(flight, np.column_stack([force, force]), w, z, 0.1, 44100)
    assert np.all(qd[:, :2205] == 0.0)
    assert np.abs(qd[:, 2205:] - q[:, :-2205]).max() < 1e-9 * np.abs(q).max()
    assert np.abs(vd[:, 2205:] - v[:, :-2205]).max() < 1e-9 * np.abs(v).max()


def test_a_restarted_run_hears_the_whole_impact(tmp_path):
    """Stopped halfway through the impact (a checkpoint at step 30 of 60) and continued with --restart: the impact
    sound's contact history, and the wall time, cover the run from t = 0, as the uninterrupted run's do (issue 48
    item 3; before: only the restarted part's contact was heard); the barrier's stiffness continues from the
    checkpoint's (a raised one stays raised)."""
    whole_dir, half_dir = tmp_path / "whole", tmp_path / "half"
    whole_dir.mkdir()
    half_dir.mkdir()
    code, whole, _, _ = run_scene(whole_dir, SCENE)
    assert code == 0
    half = with_(with_(SCENE, "dynamic.duration", 1.5e-4), "dynamic.checkpoint_every", 30)
    code, first, _, out = run_scene(half_dir, half)
    assert code == 0 and first["steps"] == 30 and first["impact_sound"]["contact_time_s"] > 0   # mid-contact
    assert main(["run", str(whole_dir / "scene.toml"), "--out", str(out), "--restart", str(out), "-q"]) == 0
    cont = json.loads((out / "results.json").read_text())
    assert cont["steps"] == whole["steps"] == 60
    for key in ("contact_start_s", "contact_end_s", "contact_time_s", "peak_force_N", "impulse_Ns"):
        assert cont["impact_sound"][key] == pytest.approx(whole["impact_sound"][key], rel=1e-6), key
    assert cont["impact_sound"]["peaks_hz"] == pytest.approx(whole["impact_sound"]["peaks_hz"], rel=1e-6)
    assert cont["wall_time_s"] > first["wall_time_s"]           # the first part's time counted too
    assert cont["barrier_stiffness"] == pytest.approx(whole["barrier_stiffness"], rel=1e-12)
    # the barrier's stiffness is the checkpoint's (Term.saved / restore), not the one a fresh start settles on
    meta_path = out / "checkpoint" / "meta.json"
    meta = json.loads(meta_path.read_text())
    kept = next(t for t in meta["terms"] if "kappa" in t)
    kept["kappa"] *= 4.0
    meta_path.write_text(json.dumps(meta))
    assert main(["run", str(whole_dir / "scene.toml"), "--out", str(out), "--restart", str(out), "-q"]) == 0
    raised = json.loads((out / "results.json").read_text())
    assert raised["barrier_stiffness"] >= 4.0 * whole["barrier_stiffness"] * (1 - 1e-12)
