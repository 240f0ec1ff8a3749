"""Modal analysis and modal sound against beam theory, and across MPI ranks.

References are independent of the code: Euler-Bernoulli cantilever and free-free frequencies and
effective masses, the exact frequency equation of a cantilever under axial tension, the FFT of the
written WAV computed here with numpy. Meshes are coarse (P2 tetrahedra on a 40:1 beam, where
shear and rotary inertia shift the second bending mode by only -0.25 %).
"""
import json
import math
import os
import subprocess
import wave

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from helpers import MODAL_E, MODAL_L, MODAL_RHO, MODAL_T, ROOT, run_ahead, to_toml
from helpers import modal_beam as beam
from fem_forms import Scene
from fem_forms.analyses.modal import write_modal_outputs
from fem_forms.analyses.modal import solve_modal

PYTHON = str(ROOT / ".venv" / "bin" / "python")
L, T, E, RHO = MODAL_L, MODAL_T, MODAL_E, MODAL_RHO          # slender square beam, nu = 0
EI, RHO_A = E * T**4 / 12, RHO * T * T


def eb_frequency(beta_l: float) -> float:
    """Euler-Bernoulli f = (beta L)^2 / (2 pi L^2) sqrt(E I / (rho A))."""
    return beta_l**2 / (2 * math.pi * L**2) * math.sqrt(EI / RHO_A)


def cantilever_roots(n: int) -> list:
    """beta L of the clamped-free beam: 1 + cos(x) cosh(x) = 0."""
    g = lambda x: 1 + math.cos(x) * math.cosh(x)                      # noqa: E731
    return [brentq(g, (k + 0.5) * math.pi - 0.5, (k + 0.5) * math.pi + 0.5) for k in range(n)]


def cantilever_effective_mass(bl: float) -> float:
    """(int phi)^2 / (L int phi^2) of the Euler-Bernoulli cantilever mode with root bl."""
    s = (math.cosh(bl) + math.cos(bl)) / (math.sinh(bl) + math.sin(bl))
    def phi(x):
        return math.cosh(bl * x) - math.cos(bl * x) - s * (math.sinh(bl * x) - math.sin(bl * x))
    return quad(phi, 0, 1)[0] ** 2 / quad(lambda x: phi(x) ** 2, 0, 1)[0]


def tensioned_cantilever_f1(N: float) -> float:
    """First bending frequency of EI w'''' - N w'' + rho A w_tt = 0, clamped at 0, free at L under
    a dead axial force N (EI w'' = 0, EI w''' - N w' = 0): the root of the 4x4 determinant."""
    def det(w):
        s = math.sqrt(N * N + 4 * EI * RHO_A * w * w)
        a, b = math.sqrt((N + s) / (2 * EI)), math.sqrt((s - N) / (2 * EI))
        ch, sh, c, sn = math.cosh(a * L), math.sinh(a * L), math.cos(b * L), math.sin(b * L)
        A = np.array([[1, 0, 1, 0], [0, a, 0, b],
                      [a * a * ch, a * a * sh, -b * b * c, -b * b * sn],
                      [(EI * a**3 - N * a) * sh, (EI * a**3 - N * a) * ch,
                       (EI * b**3 + N * b) * sn, -(EI * b**3 + N * b) * c]])
        return np.linalg.det(A / np.abs(A).max(axis=1, keepdims=True))
    w0 = 2 * math.pi * eb_frequency(1.8751)
    ws = np.linspace(0.5 * w0, 3 * w0, 200)
    d = [det(w) for w in ws]
    i = next(i for i in range(len(ws) - 1) if d[i] * d[i + 1] < 0)
    return brentq(det, ws[i], ws[i + 1]) / (2 * math.pi)


# ------------------------------------------------------------------------------------------------
def test_clamped_beam_matches_euler_bernoulli():
    res = solve_modal(Scene.from_dict(beam(cells=(30, 2, 2))))
    f = res.frequencies_hz
    roots = cantilever_roots(2)
    assert roots[0] == pytest.approx(1.8751, abs=1e-4) and roots[1] == pytest.approx(4.6941, abs=1e-4)
    for k, bl in enumerate(roots):                  # bending in y and in z: equal pairs
        ref = eb_frequency(bl)
        assert f[2 * k] == pytest.approx(ref, rel=0.01)
        assert f[2 * k + 1] == pytest.approx(ref, rel=0.01)
    assert res.rigid_modes == 0
    # each pair shares the Euler-Bernoulli effective mass of its mode in y and in z
    emf = np.asarray(res.effective_mass_fraction)
    for k, bl in enumerate(roots):
        pair = emf[2 * k] + emf[2 * k + 1]
        assert pair[0] < 1e-8
        assert pair[1:] == pytest.approx([cantilever_effective_mass(bl)] * 2, rel=0.01)


def test_free_free_part_has_six_rigid_body_modes():
    res = solve_modal(Scene.from_dict(beam(fix=False)))
    assert res.rigid_modes == 6
    assert res.effective_mass_fraction is None
    ref = eb_frequency(4.7300)                      # free-free: 1 - cos(x) cosh(x) = 0
    assert res.frequencies_hz[:2] == pytest.approx([ref, ref], rel=0.01)


def test_lumped_mass_lowers_frequencies():
    consistent = solve_modal(Scene.from_dict(beam())).frequencies_hz
    lumped_scene = beam()
    lumped_scene["modal"]["mass"] = "lumped"
    lumped = solve_modal(Scene.from_dict(lumped_scene)).frequencies_hz
    assert np.all(lumped < consistent)
    assert lumped == pytest.approx(consistent, rel=0.05)


def test_tension_stiffens_bending():
    rest = solve_modal(Scene.from_dict(beam())).frequencies_hz[0]
    sigma = 1e-4 * E                                  # axial tension: N L^2 / EI = 1.92
    scene = beam(load=[{"type": "traction", "where": {"axis": "x", "at": L}, "value": [sigma, 0.0, 0.0]}])
    scene["modal"]["prestress"] = True
    res = solve_modal(Scene.from_dict(scene))
    f = res.frequencies_hz[0]
    assert res.static is not None and res.static.report.converged
    assert f > 1.2 * rest
    assert f == pytest.approx(tensioned_cantilever_f1(sigma * T * T), rel=0.005)


def test_wav_spectrum_peaks_at_the_modal_frequencies(tmp_path):
    d = beam(count=6, material={"model": "neo-hookean", "E": 7e10, "nu": 0.0, "rho": 2700.0},
             sound={"strike": {"point": [L, T / 2, T], "direction": [0.0, 0.3, 1.0]},
                    "duration": 1.0, "sample_rate": 8000, "damping": {"alpha": 2.0, "beta": 2e-6}})
    res = solve_modal(Scene.from_dict(d))
    summary = write_modal_outputs(res, tmp_path)
    with wave.open(str(tmp_path / "sound.wav")) as w:
        assert (w.getnchannels(), w.getsampwidth(), w.getframerate()) == (1, 2, 8000)
        x = np.frombuffer(w.readframes(w.getnframes()), dtype="<i2").astype(float)
    assert len(x) == 8000 and 0.5 * 32767 < np.abs(x).max() < 32767   # normalised, not clipped
    spec = np.abs(np.fft.rfft(x * np.hanning(len(x))))
    df = 8000 / len(x)
    f = res.frequencies_hz
    amps = np.asarray(summary["sound"]["modal_amplitudes"])
    strong = [fi for fi, a in zip(f, amps) if a > 1e-2 * amps.max()]
    assert len(strong) >= 3
    for fi in strong:                               # a spectral maximum at each excited mode
        lo, hi = int(fi / df) - 3, int(fi / df) + 4
        peak = (lo + np.argmax(spec[lo:hi])) * df
        assert abs(peak - fi) <= df
    peaks = summary["sound"]["peaks_hz"]
    assert peaks and all(min(abs(p - f)) <= df for p in peaks)
    data = json.loads((tmp_path / "results.json").read_text())
    assert data["sound"]["wav"] == "sound.wav" and data["sound"]["peaks_hz"] == pytest.approx(peaks)
    for name in ("modes.xdmf", "modes.h5", "modes.png", "spectrogram.png"):
        assert (tmp_path / name).stat().st_size > 0
    import matplotlib.image                          # the mode shapes' colour bar: viridis, dark at 0, yellow at 1
    pixels = matplotlib.image.imread(tmp_path / "modes.png")[..., :3]
    strip = pixels[:, int(0.94 * pixels.shape[1]):int(0.96 * pixels.shape[1])]
    vivid = (strip.max(axis=2) - strip.min(axis=2)) > 0.3
    column = strip[:, int(np.argmax(vivid.sum(axis=0)))]                  # the bar's middle
    coloured = np.flatnonzero(vivid[:, int(np.argmax(vivid.sum(axis=0)))])
    top, bottom = column[coloured[3]], column[coloured[-4]]
    assert len(coloured) > 0.3 * pixels.shape[0] and top[1] > 0.7 and bottom[1] < 0.2      # yellow over purple


@pytest.mark.mpi
def test_two_ranks_give_the_same_frequencies(tmp_path):
    d = beam(count=6, cells=(30, 2, 2),
             sound={"strike": {"point": [0.8, T / 2, T], "direction": [0.0, 0.3, 1.0]},
                    "duration": 0.5, "sample_rate": 8000})
    (tmp_path / "scene.toml").write_text(to_toml(d))
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OPENBLAS_NUM_THREADS="1")
    runs = {}
    for n in (1, 2):
        cmd = ["mpirun", "-n", str(n), "--bind-to", "none"] if n > 1 else []
        cmd += [PYTHON, "-m", "fem_forms", "run", str(tmp_path / "scene.toml"),
                "--out", str(tmp_path / f"np{n}")]
        p = run_ahead(cmd, 300, env=env, cwd=ROOT) if n > 1 else \
            subprocess.run(cmd, env=env, cwd=ROOT, capture_output=True, text=True, timeout=300)
        assert p.returncode == 0, p.stderr
        runs[n] = json.loads((tmp_path / f"np{n}" / "results.json").read_text())
    assert runs[2]["mpi_ranks"] == 2 and runs[1]["dofs"] == runs[2]["dofs"]
    assert runs[2]["frequencies_hz"] == pytest.approx(runs[1]["frequencies_hz"], rel=1e-7)
    assert runs[2]["effective_mass_fraction_sum"] == pytest.approx(runs[1]["effective_mass_fraction_sum"],
                                                                   rel=1e-6)
    assert runs[2]["sound"]["peaks_hz"] == pytest.approx(runs[1]["sound"]["peaks_hz"], rel=1e-6)


def test_a_failing_picture_never_loses_the_frequencies(tmp_path, monkeypatch):
    """After the eigen solve an output that fails (here the picture) becomes one warning line; the
    frequencies and results.json are written, the same as without the failure."""
    import fem_forms.analyses.modal.outputs as modal

    def broken(*args, **kwargs):
        raise RuntimeError("no canvas")
    import fem_forms as ff
    scene = ff.Scene.from_dict(beam(count=2))
    good = modal.write_modal_outputs(solve_modal(scene), tmp_path / "good")
    monkeypatch.setattr(modal, "modes_picture", broken)
    bad = modal.write_modal_outputs(solve_modal(scene), tmp_path / "bad")
    assert bad["frequencies_hz"] == pytest.approx(good["frequencies_hz"], rel=1e-12)
    assert any("modes.png failed after the converged solve" in w for w in bad["warnings"])
    assert "picture" not in bad["files"] and (tmp_path / "bad" / "results.json").exists()
