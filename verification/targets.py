"""Closed-form targets of the verification manual: each a function of the case's parameters, independent of
the package (scipy solves the implicit ones)."""
from __future__ import annotations

import math

from time_histories import cantilever_beta_l

def lame(E: float, nu: float) -> tuple[float, float]:
    return E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))


def uniaxial_neo_hookean(T: float, E: float = 1e6, nu: float = 0.3) -> tuple[float, float]:
    """Stretches (l1, l2) of the compressible neo-Hookean bar under dead traction T, lateral P = 0:
    mu (l1 - 1/l1) + lambda ln J / l1 = T and mu (l2 - 1/l2) + lambda ln J / l2 = 0, J = l1 l2^2."""
    from scipy.optimize import fsolve
    mu, lm = lame(E, nu)

    def eqs(v):
        l1, l2 = v
        lnJ = math.log(l1 * l2 * l2)
        return [mu * (l1 - 1 / l1) + lm * lnJ / l1 - T, mu * (l2 - 1 / l2) + lm * lnJ / l2]
    l1, l2 = fsolve(eqs, [1.1, 0.95], xtol=1e-14)
    return float(l1), float(l2)


def hydrostatic_neo_hookean(p: float, E: float = 1e6, nu: float = 0.3) -> float:
    """Stretch l of F = l I under follower pressure p: (mu (l^2 - 1) + 3 lambda ln l) / l^3 = -p."""
    from scipy.optimize import brentq
    mu, lm = lame(E, nu)
    return float(brentq(lambda s: (mu * (s * s - 1) + 3 * lm * math.log(s)) / s**3 + p, 0.3, 1.0, xtol=1e-15))


def cantilever_gravity_sag(L=1.0, h=0.05, E=1e9, rho=1000.0, g=9.81) -> float:
    """Euler-Bernoulli w L^4 / (8 E I) + Timoshenko shear w L^2 / (2 kappa G A), kappa 5/6, nu = 0."""
    A, I = h * h, h**4 / 12
    w = rho * g * A
    return w * L**4 / (8 * E * I) + w * L**2 / (2 * (5 / 6) * (E / 2) * A)


def bimetal_curvature(h1: float, h2: float, E1: float, E2: float, a1: float, a2: float, dT: float) -> float:
    """Timoshenko (1925), Analysis of bi-metal thermostats, J. Opt. Soc. Am. 11, 233: curvature of a strip
    of layer 1 (thickness h1, below) on layer 2 (h2) heated uniformly by dT."""
    m, n, h = h1 / h2, E1 / E2, h1 + h2
    return 6 * (a2 - a1) * dT * (1 + m)**2 / (h * (3 * (1 + m)**2 + (1 + m * n) * (m**2 + 1 / (m * n))))


def prony_relaxation(t: float, t_r: float, prony: list) -> float:
    """Relaxation of a strain ramped over t_r then held, over its instantaneous elastic value (linear
    viscoelasticity with the Prony series [[g_i, tau_i], ...]: W. N. Findley, J. S. Lai, K. Onaran, Creep and
    Relaxation of Nonlinear Viscoelastic Materials, North-Holland, 1976, ch. 5)."""
    g_inf = 1 - sum(g for g, _ in prony)
    return (g_inf * t_r + sum(g * tau * (math.exp(-(t - t_r) / tau) - math.exp(-t / tau)) for g, tau in prony)) / t_r


def cantilever_frequency(mode: int, L=1.0, t=0.025, E=1e8, rho=1000.0) -> float:
    """Euler-Bernoulli clamped-free bending frequency of mode 1, 2, ... (square section t x t)."""
    return cantilever_beta_l(mode)**2 / (2 * math.pi * L**2) * math.sqrt(E * t**2 / 12 / rho)


def bar_conduction(x: float, t: float, L: float = 1.0, kappa: float = 1.0, terms: int = 400) -> float:
    """T / T1 in a bar 0 < x < L initially at 0, x = 0 held at T1 from t = 0, x = L insulated (Fourier series)."""
    total = 0.0
    for n in range(terms):
        b = (2 * n + 1) * math.pi / (2 * L)
        total += 4 / ((2 * n + 1) * math.pi) * math.sin(b * x) * math.exp(-b * b * kappa * t)
    return 1.0 - total


def thick_sphere_outer_displacement(P: float, E=210e9, nu=0.3, sy=240e6, a=1.0, b=2.0) -> float:
    """u(b) of the perfectly plastic thick sphere: Lame below first yield, (1 - nu) sy c^3 / (E b^2) with the
    plastic front c from P = 2 sy ln(c/a) + (2 sy / 3)(1 - c^3/b^3) while yielding (Hill 1950, ch. V)."""
    from scipy.optimize import brentq
    if P <= 2 * sy / 3 * (1 - a**3 / b**3):
        return 1.5 * (1 - nu) * P * a**3 * b / (E * (b**3 - a**3))
    c = brentq(lambda c: 2 * sy * math.log(c / a) + 2 * sy / 3 * (1 - c**3 / b**3) - P, a, b, xtol=1e-14)
    return (1 - nu) * sy * c**3 / (E * b**2)


# --- mass properties of homogeneous solids (Meriam & Kraige, Engineering Mechanics: Dynamics, table D/4;
# composite bodies by difference and the parallel-axis theorem). Each: mass, CoM height above the base
# (z), inertia about the CoM along the symmetry axis z and across it (x).
def block(a: float, b: float, c: float, rho: float) -> dict:
    """Rectangular block a x b x c (x, y, z)."""
    m = rho * a * b * c
    return {"mass": m, "z": c / 2, "axial": m * (a * a + b * b) / 12, "transverse": m * (b * b + c * c) / 12}


def cylinder(R: float, H: float, rho: float) -> dict:
    """Solid circular cylinder standing on its base."""
    m = rho * math.pi * R * R * H
    return {"mass": m, "z": H / 2, "axial": m * R * R / 2, "transverse": m * (3 * R * R + H * H) / 12}


def cone(R: float, H: float, rho: float) -> dict:
    """Solid right circular cone standing on its base."""
    m = rho * math.pi * R * R * H / 3
    return {"mass": m, "z": H / 4, "axial": 0.3 * m * R * R, "transverse": 3 / 80 * m * (4 * R * R + H * H)}


def hollow_hemisphere(R: float, r: float, rho: float) -> dict:
    """Solid hemisphere of radius R (flat face down) minus a concentric one of radius r. About the centre
    of the flat face a half ball has I_x = I_z = 4/15 pi rho R^5 (half of the ball's 2/5 m R^2)."""
    m = rho * 2 / 3 * math.pi * (R**3 - r**3)
    z = 3 / 8 * (R**4 - r**4) / (R**3 - r**3)
    axial = rho * 4 / 15 * math.pi * (R**5 - r**5)
    return {"mass": m, "z": z, "axial": axial, "transverse": axial - m * z * z}


def floating_cylinder(R: float, H: float, T: float) -> dict:
    """Vertical cylinder (uniform, KG = H/2) floating at draught T: V = pi R^2 T, KB = T/2,
    BM = I / V = (pi R^4 / 4) / V = R^2 / (4 T), GM = KB + BM - KG (Rawson & Tupper, Basic Ship Theory)."""
    return {"volume": math.pi * R * R * T, "KB": T / 2, "GM": T / 2 + R * R / (4 * T) - H / 2}


def ogden_sphere_pressure(stretch: float, mu: float, ratio: float = 2.0) -> float:
    """Internal pressure of the incompressible neo-Hookean thick sphere (outer / inner radius `ratio`) at inner hoop
    stretch `stretch` (Ogden, Non-linear Elastic Deformations, 1984, 5.2.6):
    p / mu = (2 / l_b + 1 / (2 l_b^4)) - (2 / l_a + 1 / (2 l_a^4)), l_b^3 = 1 + (l_a^3 - 1) / ratio^3."""
    outer = (1 + (stretch**3 - 1) / ratio**3) ** (1 / 3)
    return mu * ((2 / outer + 1 / (2 * outer**4)) - (2 / stretch + 1 / (2 * stretch**4)))


def ogden_sphere_maximum(mu: float, ratio: float = 2.0) -> float:
    """The largest pressure the sphere carries (0.8164 mu for ratio 2)."""
    from scipy.optimize import minimize_scalar
    return float(-minimize_scalar(lambda s: -ogden_sphere_pressure(s, mu, ratio), bounds=(1, 5), method="bounded").fun)


def centre_crack_stress(a: float, W: float, E: float, Gc: float, h: float, ell: float) -> float:
    """The remote stress at which a centre crack of half-length a in a plate of width W runs (LEFM, plane
    stress with nu = 0): sigma sqrt(pi a sec(pi a / W)) = sqrt(E Gc_eff), Gc_eff = Gc (1 + 3 h / (8 ell)) the
    AT1 phase field's toughness on a mesh of size h (Bourdin, Francfort & Marigo 2008)."""
    return math.sqrt(E * Gc * (1 + 3 * h / (8 * ell)) / (math.pi * a / math.cos(math.pi * a / W)))


def ogden_balloon_pair(total: float, ratio: float = 2.0) -> tuple[float, float]:
    """Two joined thick spheres past their maximum, one pressure, l_a^3 + l_b^3 = `total` (their mean stretch
    cubed, times two, past l = 1.83): the stable state has one on the falling branch and one on the rising
    branch at the same Ogden pressure. Returns (l_large, l_small)."""
    from scipy.optimize import brentq
    other = lambda s: (total - s**3) ** (1 / 3)                      # noqa: E731
    g = lambda s: ogden_sphere_pressure(s, 1.0, ratio) - ogden_sphere_pressure(other(s), 1.0, ratio)  # noqa: E731
    top = total ** (1 / 3)
    large = brentq(g, 0.9 * top, top * (1 - 1e-3))
    return large, other(large)
