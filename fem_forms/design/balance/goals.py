"""The four designs as linear programs in the solid fractions s of the carvable cells (rank 0).

The body's moments are M(s) = M0 + G s (G: the moment columns of the carvable cells times the density
they can lose). Every requirement is a row w with w . M(s) <= b; each goal adds an objective:
- stand: the CoM inside the support polygon shrunk by h tan(margin angle): for each edge k,
  A_k = m (d_k - h tan a) >= 0 (d_k the distance inside edge k, h the CoM height). Largest margin
  (maximise min_k A_k, in kg m), then least carved mass keeping 98 % of that margin.
- spin: the CoM on the axis (within 2e-4 of the part's size), the axis principal (products of inertia
  with the axis within 1e-4 of the spin moment), then Spin-It's objective, the spin moment over the
  largest other moment, by Dinkelbach steps (maximise I_a - r w, w >= I_11 + |I_12|, I_22 + |I_12|, a
  bound on the other principal moments). A top's moments are taken about its tip, so the objective
  also lowers its CoM; a yo-yo's about its centre, where its CoM must lie.
- swim: mass = displaced water (within 1e-3), CoM on the buoyancy vertical, GM >= the minimum; CoM low.
- swing: the CoM on the vertical through the rocking surface's sphere centre and at least
  R sin(margin angle) below it; CoM low.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
import time

import numpy as np

from fem_forms.design.balance import lp, rows, sifting
from fem_forms.errors import SolveError

CENTER_TOLERANCE = 2e-4      # x the part's size: CoM off the axis / vertical
PRODUCT_TOLERANCE = 1e-4     # x the spin moment: products of inertia with the axis
MASS_TOLERANCE = 1e-3        # relative: mass against the displaced water
KEEP_MARGIN = 0.98           # stand: stage 2 keeps this share of the largest margin
DINKELBACH_STEPS = 4


@dataclass
class Problem:
    """The LP data on rank 0: moments as M0 + G s, cell centroids, the part's size."""
    G: np.ndarray                 # (10, n)
    M0: np.ndarray                # (10,)
    centroids: np.ndarray         # (n, 3)
    size: float
    timing: lp.Timing = field(default_factory=lp.Timing)

    @property
    def n(self) -> int:
        return self.G.shape[1]

    @cached_property
    def groups(self) -> np.ndarray:
        """Neighbouring cells grouped for the LP's sifting (lp.solve)."""
        return sifting.groups(self.centroids)

    def constraint(self, W: np.ndarray, b: np.ndarray, extra: np.ndarray | None = None) -> tuple:
        """Rows W . M(s) (+ extra . y) <= b as (A over (s, y), b - W M0)."""
        A = W @ self.G
        if extra is not None:
            A = np.hstack([A, extra])
        return A, b - W @ self.M0

    def moments(self, s: np.ndarray) -> np.ndarray:
        return self.M0 + self.G @ s


def _band(W: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """|W . M| <= tol m as rows (W - tol mass) . M <= 0 and (-W - tol mass) . M <= 0."""
    m = rows.mass()
    return np.vstack([W - tol * m, -W - tol * m]), np.zeros(2 * len(W))


def _program(P: Problem, objective_rows: np.ndarray | None, W: np.ndarray, b: np.ndarray,
             objective: np.ndarray | None = None) -> lp.Program:
    """min (objective_rows . M(s)) (or objective . s) subject to W . M(s) <= b."""
    t0 = time.perf_counter()
    A, bb = P.constraint(W, b)
    p = lp.Program(objective_rows @ P.G if objective is None else objective, A, bb, P.n, groups=P.groups)
    P.timing.setup_s += time.perf_counter() - t0
    return p


def _finish(P: Problem, p: lp.Program, v: np.ndarray | None, why: str) -> np.ndarray:
    if v is None:
        raise SolveError(why)
    s = lp.binarise(p, v, P.centroids, P.timing)
    if s is None:
        raise SolveError(f"{why.split(':')[0]}: the LP design has no binary carving that meets the "
                         f"constraints ({P.timing.fractional} fractional cells); refine the mesh")
    return s


# ----------------------------------------------------------------------------- stand
def stand(P: Problem, normals: np.ndarray, offsets: np.ndarray, frame: tuple, ground: float,
          tan_margin: float, best_effort: bool = False) -> np.ndarray:
    """Largest margin, then least carved mass (binary s). With `best_effort`, a margin out of reach
    returns the largest-margin carving instead of failing (a step of the elastic loop: carving lightens
    the part, so it sags less than the shape this program was posed on)."""
    up, e1, e2 = frame
    W = np.array([rows.first(-(n[0] * e1 + n[1] * e2) - tan_margin * up) for n in normals])
    W[:, 0] = -offsets + tan_margin * ground
    t0 = time.perf_counter()
    A, b = P.constraint(-W, np.zeros(len(W)), extra=np.ones((len(W), 1)))      # z - A_k <= 0
    c = np.zeros(P.n + 1)
    c[-1] = -1.0
    p1 = lp.Program(c, A, b, P.n, ((None, None),), P.groups)
    P.timing.setup_s += time.perf_counter() - t0
    v = lp.solve(p1, P.timing)
    if best_effort and v is not None and v[-1] < 0:
        return _finish(P, p1, v, "balance: the largest-margin design failed")
    if v is None or v[-1] < 0:
        best = "none" if v is None else f"{v[-1]:.3g} kg m"
        raise SolveError("balance: no carving makes the part stand with the requested margin (best "
                         f"margin x mass {best} < 0): lower margin_angle or shell, or widen the foot")
    z = v[-1]
    # least mass moved: the carved (hollow or light fill) or ballasted cells' |rho - fill| V, least
    p2 = _program(P, None, -W, -KEEP_MARGIN * z * np.ones(len(W)), objective=-np.abs(P.G[0]))
    v2 = lp.solve(p2, P.timing)
    return _finish(P, p2, v2, "balance: the least-carved stand design failed")


# ----------------------------------------------------------------------------- spin
def perpendicular(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    h = np.eye(3)[np.argmin(np.abs(a))]
    e1 = np.cross(a, h)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(a, e1)


def spin(P: Problem, axis: np.ndarray, point: np.ndarray, along: bool) -> np.ndarray:
    """CoM on the axis through `point` (and at `point` when `along`), axis principal, Spin-It objective."""
    a = np.asarray(axis, float)
    e1, e2 = perpendicular(a)
    tol_c = CENTER_TOLERANCE * P.size
    I_full = rows.inertia(a, a, point) @ P.moments(np.ones(P.n))
    bands = [rows.first(e, point) for e in ((e1, e2, a) if along else (e1, e2))]
    Wc, bc = _band(np.array(bands), tol_c)
    Wp = np.array([rows.inertia(a, e1, point), rows.inertia(a, e2, point)])
    Wp = np.vstack([Wp, -Wp])
    bp = np.full(4, PRODUCT_TOLERANCE * I_full)
    I11, I22, I12 = rows.inertia(e1, e1, point), rows.inertia(e2, e2, point), rows.inertia(e1, e2, point)
    Ww = np.array([I11 + I12, I11 - I12, I22 + I12, I22 - I12])         # each <= w
    t0 = time.perf_counter()
    A1, b1 = P.constraint(np.vstack([Wc, Wp]), np.concatenate([bc, bp]), extra=np.zeros((len(bc) + 4, 1)))
    A2, b2 = P.constraint(Ww, np.zeros(4), extra=-np.ones((4, 1)))
    A, b = np.vstack([A1, A2]), np.concatenate([b1, b2])
    Ia = rows.inertia(a, a, point) @ P.G
    P.timing.setup_s += time.perf_counter() - t0
    M1 = P.moments(np.ones(P.n))
    r = (rows.inertia(a, a, point) @ M1) / max(Ww @ M1)
    v = None
    for _ in range(DINKELBACH_STEPS):
        p = lp.Program(np.concatenate([-Ia, [r]]), A, b, P.n, ((0.0, None),), P.groups)
        v = lp.solve(p, P.timing)
        if v is None:
            raise SolveError("balance: no carving puts the CoM on the spin axis with the axis principal "
                             "(the wall is too heavy or the shape too lopsided): lower shell")
        M = P.moments(v[:P.n])
        r_new = (rows.inertia(a, a, point) @ M) / v[-1]
        if abs(r_new - r) <= 1e-6 * abs(r):
            break
        r = r_new
    return _finish(P, p, v, "balance: the spin design failed")


# ----------------------------------------------------------------------------- swim and swing
def swim(P: Problem, frame: tuple, buoyancy: np.ndarray, target_mass: float, max_KG_height: float) -> np.ndarray:
    """Mass = displaced water, CoM on the buoyancy vertical, CoM below the height that gives GM_min."""
    up, e1, e2 = frame
    # the lightest and heaviest designs (each cell solid or carved: a fill lighter or heavier than the solid)
    lo = P.M0[0] + np.minimum(P.G[0], 0.0).sum()
    hi = P.M0[0] + np.maximum(P.G[0], 0.0).sum()
    if target_mass > hi * (1 + MASS_TOLERANCE):
        raise SolveError(f"balance: too light to float at this waterline (the heaviest design: {hi:.6g} kg < "
                         f"displaced water {target_mass:.6g} kg)")
    if target_mass < lo * (1 - MASS_TOLERANCE):
        raise SolveError(f"balance: too heavy to float at this waterline (the lightest design: {lo:.6g} kg > "
                         f"displaced water {target_mass:.6g} kg): lower shell or raise the waterline")
    tol_c = CENTER_TOLERANCE * P.size
    m = rows.mass()
    W = [m, -m]
    b = [target_mass * (1 + MASS_TOLERANCE), -target_mass * (1 - MASS_TOLERANCE)]
    for e in (e1, e2):
        w = rows.first(e, buoyancy)
        W += [w, -w]
        b += [tol_c * target_mass, tol_c * target_mass]
    W.append(rows.first(up, up * max_KG_height))       # m (up . c - height) <= 0
    b.append(0.0)
    p = _program(P, rows.first(up), np.array(W), np.array(b))
    return _finish(P, p, lp.solve(p, P.timing),
                   "balance: no carving floats upright at this waterline with the required metacentric "
                   "height: raise the waterline or lower min_metacentric_height or shell")


def swing(P: Problem, frame: tuple, center: np.ndarray, depth: float) -> np.ndarray:
    """CoM on the vertical through the rocking centre, at least `depth` below it; CoM low."""
    up, e1, e2 = frame
    Wc, bc = _band(np.array([rows.first(e1, center), rows.first(e2, center)]), CENTER_TOLERANCE * P.size)
    Wh = rows.first(up, center - depth * up)
    p = _program(P, rows.first(up, center), np.vstack([Wc, Wh]), np.concatenate([bc, [0.0]]))
    return _finish(P, p, lp.solve(p, P.timing),
                   "balance: no carving brings the CoM below the rocking surface's centre with the margin: "
                   "lower margin_angle or shell")
