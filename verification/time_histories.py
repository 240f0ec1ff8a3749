"""Closed forms and curve fits of the dynamic verification cases: the tip load cantilever's static
deflection and first-mode share, Rayleigh damping's ratio and decay per cycle, and least-squares fits of
a probe's time history (an undamped and a damped swing) that give its mean, amplitude, frequency and
decay per cycle. Used by verification/run.py on the probes.csv a `fem-forms run` wrote."""
from __future__ import annotations

import math


def cantilever_beta_l(mode: int) -> float:
    """beta L of the clamped-free Euler-Bernoulli mode 1, 2, ...: the roots of 1 + cos x cosh x = 0."""
    from scipy.optimize import brentq
    k = mode - 1
    return brentq(lambda x: 1 + math.cos(x) * math.cosh(x), (k + 0.5) * math.pi - 0.5, (k + 0.5) * math.pi + 0.5)


def cantilever_tip_static(traction=1000.0, L=1.0, t=0.025, E=1e8) -> float:
    """Tip deflection under an end traction on the t x t section (nu = 0, G = E / 2): Euler-Bernoulli
    F L^3 / (3 E I) plus the Timoshenko shear term F L / (kappa G A), kappa 5/6."""
    A, I = t * t, t**4 / 12
    F = traction * A
    return F * L**3 / (3 * E * I) + F * L / ((5 / 6) * (E / 2) * A)


def first_mode_share() -> float:
    """Share of the clamped-free beam's static tip deflection under a tip load carried by its first mode:
    modal superposition with phi_i(L)^2 = 4 (unit mean-square modes) gives 12 / (beta_1 L)^4 (0.9707)."""
    return 12 / cantilever_beta_l(1)**4


def rayleigh_zeta(alpha: float, beta: float, omega: float) -> float:
    """Damping ratio of a mode of circular frequency omega under C = alpha M + beta K."""
    return alpha / (2 * omega) + beta * omega / 2


def rayleigh_decay_per_cycle(alpha: float, beta: float, omega: float) -> float:
    """Free-vibration amplitude ratio per cycle, exp(-2 pi zeta / sqrt(1 - zeta^2))."""
    zeta = rayleigh_zeta(alpha, beta, omega)
    return math.exp(-2 * math.pi * zeta / math.sqrt(1 - zeta * zeta))


def peak_period(t, x) -> float:
    """Mean spacing of the local maxima of x: a first guess of the period for the fits."""
    i = [k for k in range(1, len(x) - 1) if x[k] > x[k - 1] and x[k] >= x[k + 1]]
    if len(i) < 2:
        raise ValueError("fewer than two maxima in the history: no period to measure")
    return (t[i[-1]] - t[i[0]]) / (len(i) - 1)


def harmonic_fit(t, x) -> tuple[float, float, float]:
    """(center, amplitude, omega) of the least-squares fit x ~ c + a cos(omega t) + b sin(omega t):
    omega by a bounded 1-D search within 30 % of the peak spacing's, (c, a, b) linear. Higher modes,
    which ride on the swing, are nearly orthogonal to it over the record and barely move the fit."""
    import numpy as np
    from scipy.optimize import minimize_scalar

    def lsq(w):
        A = np.column_stack([np.ones_like(t), np.cos(w * t), np.sin(w * t)])
        c = np.linalg.lstsq(A, x, rcond=None)[0]
        return float(np.sum((A @ c - x) ** 2)), c
    w0 = 2 * math.pi / peak_period(t, x)
    w = minimize_scalar(lambda w: lsq(w)[0], bounds=(0.7 * w0, 1.3 * w0), method="bounded",
                        options={"xatol": 1e-12 * w0}).x
    c = lsq(w)[1]
    return float(c[0]), float(math.hypot(c[1], c[2])), float(w)


def damped_fit(t, x) -> tuple[float, float]:
    """(s, omega_d) of the least-squares fit x ~ c + exp(-s t) (a cos(omega_d t) + b sin(omega_d t))
    (s and omega_d nonlinear, c, a, b linear); the decay per cycle is exp(-2 pi s / omega_d)."""
    import numpy as np
    from scipy.optimize import least_squares

    def residual(p):
        e = np.exp(-p[0] * t)
        A = np.column_stack([np.ones_like(t), e * np.cos(p[1] * t), e * np.sin(p[1] * t)])
        return A @ np.linalg.lstsq(A, x, rcond=None)[0] - x
    w0 = 2 * math.pi / peak_period(t, x)
    s, w = least_squares(residual, [0.01 * w0, w0], xtol=1e-14, ftol=1e-14).x
    return float(s), float(w)
