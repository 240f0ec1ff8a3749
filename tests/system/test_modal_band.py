"""`[modal] up_to`: every mode below a frequency, certified by an inertia count.

References independent of the code's eigensolvers: a dense scipy.linalg.eigh of the same assembled
K and M (supported dofs removed), Euler-Bernoulli's cantilever list, a serial run against 2 ranks.
"""
import json
import math

import numpy as np
import pytest
import scipy.linalg

from helpers import MODAL_E, MODAL_L, MODAL_RHO, MODAL_T, modal_beam, mpirun, serial_and_two_ranks, to_toml
from fem_forms import Scene
from fem_forms.cli import main
from fem_forms.model import build_model
from fem_forms.analyses.modal import band as modal_band
from fem_forms.analyses.modal import assemble_operators, solve_modal


def bar(up_to=None, **over):
    """A free aluminium bar 60 x 12 x 8 mm, P2 on 6 x 2 x 1 cells (777 dofs): a dense solve is cheap."""
    d = {"title": "small free bar", "analysis": "modal",
         "mesh": {"size": [0.06, 0.012, 0.008], "cells": [6, 2, 1]},
         "material": {"model": "linear", "E": 70e9, "nu": 0.33, "rho": 2700.0},
         "discretization": {"degree": 2}, "modal": {"up_to": up_to} if up_to else {}}
    d.update(over)
    return d


def dense_frequencies(scene: Scene) -> np.ndarray:
    """Every eigenvalue of the assembled pencil by LAPACK, supported rows and columns removed (there K
    is 1 and M is 0), as signed frequencies [Hz]."""
    model = build_model(scene)
    model.load.set(0.0)
    ops = assemble_operators(model, "direct", mat_type="aij")
    K, M = (np.asarray(A.convert("dense").getDenseArray()) for A in (ops.K, ops.M))
    free = np.flatnonzero(np.diag(M) != 0)
    lam = scipy.linalg.eigh(K[np.ix_(free, free)], M[np.ix_(free, free)], eigvals_only=True)
    ops.destroy()
    return np.sign(lam) * np.sqrt(np.abs(lam)) / (2 * math.pi)


@pytest.mark.parametrize("slice_above", [modal_band.SLICE_ABOVE, 0], ids=["single shift", "spectrum slicing"])
def test_up_to_finds_exactly_the_modes_a_dense_solve_finds(monkeypatch, slice_above):
    monkeypatch.setattr(modal_band, "SLICE_ABOVE", slice_above)
    limit = 60_000.0
    ref = dense_frequencies(Scene.from_dict(bar(limit)))
    rigid = np.abs(ref) < 1.0                              # six rigid-body modes at ~0 Hz
    below = ref[~rigid & (ref < limit)]
    assert rigid.sum() == 6 and len(below) >= 8 and ref[ref >= limit].min() > 1.02 * limit   # no mode at the edge
    res = solve_modal(Scene.from_dict(bar(limit)))
    s = res.summary()
    assert s["band"]["method"] == ("spectrum slicing" if slice_above == 0 else "shift-and-invert")
    assert res.rigid_modes == 6
    assert s["modes_below_limit"] == len(below) == len(res.frequencies_hz)
    assert s["band"]["eigenvalues_below_limit"] == len(below) + 6 and s["band"]["certified"]
    assert res.frequencies_hz == pytest.approx(below, rel=1e-8)


def test_up_to_on_a_cantilever_gives_the_euler_bernoulli_list():
    """Below 30 Hz the 40:1 cantilever has its first three bending pairs (Euler-Bernoulli 1.28, 8.00,
    22.4 Hz; the fourth pair is at 43.9 Hz, torsion at 51 Hz, the axial mode at 79 Hz)."""
    d = modal_beam(cells=(30, 2, 2))
    d["modal"] = {"up_to": 30.0}
    res = solve_modal(Scene.from_dict(d))
    ei, rho_a = MODAL_E * MODAL_T**4 / 12, MODAL_RHO * MODAL_T**2
    roots = [1.87510407, 4.69409113, 7.85475744]
    eb = [bl**2 / (2 * math.pi * MODAL_L**2) * math.sqrt(ei / rho_a) for bl in roots]
    assert res.summary()["modes_below_limit"] == 6 and res.rigid_modes == 0
    assert res.frequencies_hz == pytest.approx(np.repeat(eb, 2), rel=0.015)


@pytest.mark.mpi
def test_two_ranks_find_the_same_band_and_hear_the_same_sound(tmp_path):
    d = bar(40_000.0, output={"picture": False, "fields": False},
            sound={"strike": {"point": [0.01, 0.01, 0.008], "direction": [0.0, 0.3, -1.0]}, "duration": 0.2,
                   "sample_rate": 96000, "listener": [0.03, 0.006, 0.3],
                   "modal_damping": [[5000.0, 0.002], [50000.0, 0.004]]})
    runs = dict(zip((1, 2), serial_and_two_ranks(tmp_path, d)))
    assert runs[2]["modes_below_limit"] == runs[1]["modes_below_limit"] >= 4
    assert runs[2]["band"]["eigenvalues_below_limit"] == runs[1]["band"]["eigenvalues_below_limit"]
    assert runs[2]["frequencies_hz"] == pytest.approx(runs[1]["frequencies_hz"], rel=1e-8)
    heard = [r["sound"] for r in (runs[1], runs[2])]
    assert heard[0]["heard"] == "pressure at the listener [Pa]" and max(heard[0]["modal_amplitudes"]) > 0
    assert heard[1]["modal_amplitudes"] == pytest.approx(heard[0]["modal_amplitudes"], rel=1e-6, abs=1e-9)
    assert heard[1]["peaks_hz"] == pytest.approx(heard[0]["peaks_hz"], rel=1e-6)


REFUSED = [
    ("count and up_to", {"count": 4, "up_to": 1000.0}, "modal.up_to: give either count or up_to, not both"),
    ("zero", {"up_to": 0.0}, "modal.up_to = 0.0: must be positive"),
    ("negative", {"up_to": -5.0}, "modal.up_to = -5.0: must be positive"),
    ("not a number", {"up_to": "20 kHz"}, "modal.up_to = '20 kHz': must be a number"),
]


@pytest.mark.parametrize("name, modal, message", REFUSED, ids=[r[0] for r in REFUSED])
def test_bad_up_to_is_refused_in_one_line(tmp_path, capsys, name, modal, message):
    path = tmp_path / "scene.toml"
    path.write_text(to_toml(bar(modal=modal)))
    code = main(["run", str(path), "--out", str(tmp_path / "out"), "-q"])
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and message in lines[0], lines


SLICED_ON_TWO_RANKS = """
import json, sys
from mpi4py import MPI
import fem_forms as ff
from fem_forms.analyses.modal import band as modal_band
from fem_forms.analyses.modal import solve_modal
modal_band.SLICE_ABOVE = 0
res = solve_modal(ff.Scene.from_dict(json.loads(sys.argv[1])))
summary = res.summary()                      # collective
if MPI.COMM_WORLD.rank == 0:
    print(json.dumps([summary["band"]["method"], summary["frequencies_hz"]]))
"""


@pytest.mark.mpi
def test_spectrum_slicing_on_two_ranks_finds_the_dense_modes(tmp_path):
    limit = 60_000.0
    ref = dense_frequencies(Scene.from_dict(bar(limit)))
    below = ref[(np.abs(ref) >= 1.0) & (ref < limit)]
    p = mpirun(["-c", SLICED_ON_TWO_RANKS, json.dumps(bar(limit))], n=2)
    assert p.returncode == 0, p.stderr[-2000:]
    method, freqs = json.loads(p.stdout.strip().splitlines()[-1])
    assert method == "spectrum slicing"
    assert freqs == pytest.approx(below, rel=1e-8)
