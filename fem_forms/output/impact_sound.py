"""Impact sound: modal oscillators driven by a force history, integrated at the audio rate.

Each mode i (mass-normalised phi_i, omega_i, zeta_i) obeys q_i'' + 2 zeta_i omega_i q_i' + omega_i^2 q_i = g_i(t),
g_i = phi_i . f(t) the modal force of the contact forces f. The force is known at the run's accepted steps and
taken linear between them; on a uniform grid of `k` sub-steps per audio sample (k so that a sub-step is no
longer than the run's shortest step) the recursion x_{j+1} = Phi x_j + G0 g_j + G1 (g_{j+1} - g_j) / h with
Phi, G0, G1 from one matrix exponential per mode (the first-order hold) is exact for a force linear over each
sub-step. The run's step times are not on that grid: the force is resampled there linearly, which moves q by
up to a few 1e-4 of its size where the force kinks inside a sub-step (1.8e-3 for a force rising within one
5 us step, measured against a fine ODE solve): far below hearing, not exact. After the run the force is held at its last value (zero once the part has left the obstacle) and
each mode rings on in closed form. What is heard is linear in q and q' (output/sound.py says why a product of
two factors linear in phi_i is the same on any number of ranks).
"""
from __future__ import annotations

import math

import numpy as np

MAX_SUBSTEPS = 64           # sub-steps per audio sample at most (a run's step far below 1 / (64 fs) is averaged)


def first_order_hold(omega: np.ndarray, zeta: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per mode: Phi (m, 2, 2), G0 (m, 2), G1 (m, 2) of the exact step over h of x = (q, q') for a force linear
    in time: x(h) = Phi x(0) + G0 g(0) + G1 (g(h) - g(0)) / h."""
    from scipy.linalg import expm
    m = len(omega)
    Phi, G0, G1 = np.empty((m, 2, 2)), np.empty((m, 2)), np.empty((m, 2))
    for i, (w, z) in enumerate(zip(omega, zeta)):
        A = np.zeros((4, 4))              # d/dt (q, q', g, g') with g'' = 0
        A[0, 1], A[1, 0], A[1, 1], A[1, 2], A[2, 3] = 1.0, -w * w, -2.0 * z * w, 1.0, 1.0
        E = expm(A * h)
        Phi[i], G0[i], G1[i] = E[:2, :2], E[:2, 2], E[:2, 3]
    return Phi, G0, G1


def free_ring(q0: np.ndarray, v0: np.ndarray, omega: np.ndarray, zeta: np.ndarray, tau: np.ndarray):
    """q and q' (m, len(tau)) of damped free vibration from q0, v0 (underdamped modes)."""
    wd = omega * np.sqrt(1.0 - zeta**2)
    e = np.exp(-np.outer(zeta * omega, tau))
    c, s = np.cos(np.outer(wd, tau)), np.sin(np.outer(wd, tau))
    q = e * (q0[:, None] * c + ((v0 + zeta * omega * q0) / wd)[:, None] * s)
    v = e * (v0[:, None] * c - ((omega**2 * q0 + zeta * omega * v0) / wd)[:, None] * s)
    return q, v


def modal_response(times: np.ndarray, forces: np.ndarray, omega: np.ndarray, zeta: np.ndarray, duration: float,
                   sample_rate: int) -> tuple[np.ndarray, np.ndarray]:
    """q and q' (m, n) at the n = duration x sample_rate audio samples t = j / sample_rate of the oscillators
    at rest at t = times[0] = 0, driven by `forces` (steps, m), linear between the `times`, held after them.
    Only the span where a force acts is stepped (at rest before it, a closed-form ring after it): a long fall
    or flight costs nothing."""
    times, forces = np.asarray(times, float), np.asarray(forces, float).reshape(len(times), -1)
    n = int(round(duration * sample_rate))
    m = len(omega)
    q, v = np.zeros((m, n)), np.zeros((m, n))
    acting = np.flatnonzero(np.any(forces != 0.0, axis=1))
    if not len(acting):
        return q, v
    first, last = max(acting[0] - 1, 0), min(acting[-1] + 1, len(times) - 1)
    start = min(n, int(math.floor(times[first] * sample_rate)))      # the oscillators rest until this sample
    times, forces = times[first:last + 1], forces[first:last + 1]
    shortest = float(np.diff(times).min()) if len(times) > 1 else 1.0 / sample_rate
    k = int(min(MAX_SUBSTEPS, max(1, math.ceil(1.0 / (sample_rate * shortest) - 1e-9))))
    h = 1.0 / (sample_rate * k)
    forced = min(n, int(math.ceil(times[-1] * sample_rate)) + 1)     # samples until the force is held
    fine = start / sample_rate + np.arange(max(forced - 1 - start, 0) * k + 1) * h
    g = np.stack([np.interp(fine, times, forces[:, i], left=0.0) for i in range(m)], axis=1) if m \
        else np.zeros((len(fine), 0))
    Phi, G0, G1 = first_order_hold(omega, zeta, h)
    x = np.zeros((m, 2))
    for j in range(len(fine) - 1):
        x = np.einsum("mab,mb->ma", Phi, x) + G0 * g[j][:, None] + G1 * ((g[j + 1] - g[j]) / h)[:, None]
        if (j + 1) % k == 0:
            q[:, start + (j + 1) // k], v[:, start + (j + 1) // k] = x[:, 0], x[:, 1]
    end = max(forced, start + 1)
    if end < n:                          # held force g_end: a static offset g_end / omega^2 and a free ring
        g_end = g[-1] if len(g) else np.zeros(m)
        static = g_end / omega**2
        tau = np.arange(1, n - end + 1) / sample_rate
        ring_q, ring_v = free_ring(x[:, 0] - static, x[:, 1], omega, zeta, tau)
        q[:, end:], v[:, end:] = ring_q + static[:, None], ring_v
    return q, v


def heard(q: np.ndarray, v: np.ndarray, omega: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """sum_i Re(w_i) q_i + Im(w_i) q_i' / omega_i: with w_i the complex pressure per unit modal displacement at
    omega_i (time factor e^{i omega t}) the pressure of a harmonic q_i = Re(Q e^{i omega t}) exactly, of a lightly
    damped ring nearly; a real w_i (a point's motion along a direction) gives sum_i w_i q_i."""
    w = np.asarray(weights, dtype=complex)
    return w.real @ q + (w.imag / omega) @ v


def contact_history(times: np.ndarray, totals: np.ndarray) -> dict:
    """Contact start, end and time (first to last step with a force), the peak of |F| and the impulse's size,
    from the total force (steps, 3) on the part."""
    mag = np.linalg.norm(totals, axis=1)
    on = np.flatnonzero(mag > 0.0)
    impulse = np.trapz(totals, times, axis=0) if len(times) > 1 else np.zeros(3)
    if not len(on):
        return {"contact_start_s": None, "contact_end_s": None, "contact_time_s": 0.0, "peak_force_N": 0.0,
                "impulse_Ns": 0.0}
    return {"contact_start_s": float(times[on[0]]), "contact_end_s": float(times[on[-1]]),
            "contact_time_s": float(times[on[-1]] - times[on[0]]), "peak_force_N": float(mag.max()),
            "peak_force_time_s": float(times[int(np.argmax(mag))]), "impulse_Ns": float(np.linalg.norm(impulse))}
