"""The inverse design demos under pressure against references independent of the finite elements: the balloon
segment's designed waist, inflated by the closed form of a long closed neo-Hookean tube (its cross-section far
from the ends in generalized plane strain: the radial equilibrium as an ODE in the rest radius, the axial stretch
from the end caps' force p pi a^2, scipy), lands on the target's radii."""
import math

from scipy.integrate import solve_ivp
from scipy.optimize import brentq, fsolve

from system.demo_runs import NUMBER, demo, grab  # noqa: F401 (demo: fixture)

E, NU, P = 1.0e6, 0.45, 3.0e4                   # demos/scenes/balloon_segment.toml
MU, LAMBDA = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))


def _nominal(stretch: float, J: float) -> float:
    """A principal nominal stress of psi = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2."""
    return MU * stretch - MU / stretch + LAMBDA * math.log(J) / stretch


def _tube(A: float, B: float, a: float, axial: float) -> tuple[float, float, float]:
    """The rest wall A..B inflated to inner radius a at axial stretch `axial`: (outer radius b, P_r at B, the axial
    force less the end caps' p pi a^2)."""
    def rhs(R, y):
        r, radial, force = y
        hoop = r / R
        lr = brentq(lambda s: _nominal(s, s * hoop * axial) - radial, 0.05, 20.0, xtol=1e-14)
        J = lr * hoop * axial
        return [lr, (_nominal(hoop, J) - radial) / R, _nominal(axial, J) * 2 * math.pi * R]
    y = solve_ivp(rhs, (A, B), [a, -P * (a / A) * axial, 0.0], rtol=1e-11, atol=1e-14).y[:, -1]
    return y[0], y[1], y[2] - P * math.pi * a * a


def inflated(A: float, B: float) -> tuple[float, float]:
    """(a, b): where P inflates the long closed tube of rest radii A, B (P_r = 0 at B, the axial force balanced)."""
    a, axial = fsolve(lambda v: [_tube(A, B, *v)[1] / P, _tube(A, B, *v)[2] / (P * A * A)], [1.1 * A, 1.0],
                      xtol=1e-12)
    return a, _tube(A, B, a, axial)[0]


def test_balloon_segment_demo(demo):
    """The designed rest waist (outer and inner radius at the segment's middle), inflated by the tube's closed form,
    lands on the target's 15 and 12 mm within 0.5 % (measured +0.12 % and +0.19 %: the ends 2 radii away, P2 on
    2 mm cells); the rest shape is smaller than the target (the cavity grows by the air), and the forward check lands
    within 1e-5 m."""
    text, out = demo("balloon_segment")
    (mismatch,) = grab(rf"lands within ({NUMBER}) m of the target, usable True", text)
    outer, inner, half = grab(rf"waist: outer radius ({NUMBER}) mm, inner ({NUMBER}) mm at rest \(inflated 15, 12 "
                              rf"mm\); half length ({NUMBER}) mm", text)
    a, b = inflated(inner / 1000, outer / 1000)
    assert abs(a / 0.012 - 1) < 5e-3 and abs(b / 0.015 - 1) < 5e-3, (a, b)
    rest, full = grab(rf"cavity \(one eighth\): ({NUMBER}) ml at rest, ({NUMBER}) ml at 30.0 kPa", text)
    assert rest < full and outer < 15 and inner < 12 and half < 45 and mismatch < 1e-5
    assert (out / "run" / "rest_shape.stl").stat().st_size > 0 and (out / "run" / "inverse.png").stat().st_size > 0
