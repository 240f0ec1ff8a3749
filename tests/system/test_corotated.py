"""System tests of the corotated material: static solves of a clamped beam under gravity.

Small load: corotated and linear elasticity agree to O(strain). Large deflection (tip sag about half
the length): corotated agrees with neo-Hookean (both are exact for rigid rotations and differ only at
O(strain)), linear elasticity does not (it sees rotation as strain), and Newton converges quadratically."""
import numpy as np
import pytest

import fem_forms as ff
from helpers import beam_scene


def _solve(model: str, E: float) -> ff.StaticResult:
    d = beam_scene(material={"model": model, "E": E, "nu": 0.3, "rho": 1000.0})
    d["mesh"]["cells"] = [20, 2, 2]
    d["output"] = {"probes": {"tip": [1.0, 0.05, 0.05]}, "picture": False, "fields": False}
    result = ff.solve_static(ff.Scene.from_dict(d))
    assert result.report.converged, result.report.message
    return result


def test_small_load_agrees_with_linear_elasticity():
    """E 1e10 (largest displacement gradient about 1e-4): displacement fields agree to 1e-4 relative."""
    lin, cor = _solve("linear", 1e10), _solve("corotated", 1e10)
    ul, uc = lin.u.x.array, cor.u.x.array
    assert np.linalg.norm(uc - ul) < 1e-4 * np.linalg.norm(ul)
    tip_l, tip_c = np.array(lin.probes["tip"]), np.array(cor.probes["tip"])
    assert tip_c[2] == pytest.approx(tip_l[2], rel=1e-4)
    assert cor.report.load_steps == 1                    # no cut-back on a stiff, nearly linear problem


def test_large_deflection_follows_neo_hookean_where_linear_fails():
    """E 1e6: the tip sags about half the length and swings back. Corotated and neo-Hookean tips agree
    within 2 %; linear elasticity overshoots the sag by a third and misses the swing-back entirely."""
    nh, cor, lin = _solve("neo-hookean", 1e6), _solve("corotated", 1e6), _solve("linear", 1e6)
    t_nh, t_cor, t_lin = (np.array(r.probes["tip"]) for r in (nh, cor, lin))
    assert t_nh[2] < -0.4 and t_nh[0] < -0.1             # a large rotation
    assert t_cor[2] == pytest.approx(t_nh[2], rel=0.02)
    assert t_cor[0] == pytest.approx(t_nh[0], rel=0.02)
    assert abs(t_lin[2]) > 1.2 * abs(t_nh[2])            # linear: too much sag ...
    assert abs(t_lin[0]) < 0.05 * abs(t_nh[0])           # ... and no shortening of the span


def test_newton_converges_quadratically_on_the_large_deflection():
    """In the last accepted load step, once the relative residual is below 1e-2 and above round-off,
    each Newton step squares it (r_k+1 <= 10 r_k^2, residuals relative to the first)."""
    report = _solve("corotated", 1e6).report
    step = [s for s in report.steps if s.accepted][-1]
    r = np.array(step.residuals) / step.residuals[0]
    pairs = [(a, b) for a, b in zip(r[:-1], r[1:]) if a < 1e-2 and b > 1e-10]
    assert pairs, r
    for a, b in pairs:
        assert b <= 10 * a**2, r
    assert r[-1] < 1e-9, r
