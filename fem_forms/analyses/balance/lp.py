"""Linear programs over the carvable cells, solved by HiGHS (scipy), and their binarisation.

Variables: s (one per carvable cell, the solid fraction in [0, 1]) followed by a few continuous extra
variables a goal needs (a margin, a bound on the other moments). An LP's optimal vertex is 0/1 except in
at most as many cells as there are constraints: binarise fixes every cell the LP left at 0 or 1 and solves
the same problem as a small mixed-integer program (HiGHS milp) over the fractional cells and their nearest
neighbours, so the binary design meets the constraints exactly rather than approximately.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
import time

import numpy as np
from scipy.optimize import Bounds, LinearConstraint, linprog, milp
from scipy.spatial import cKDTree

INTEGRAL = 1e-6          # an LP value this close to 0 or 1 counts as integral


@dataclass
class Program:
    """min c . v subject to A_ub v <= b_ub, lo <= v <= hi, v = (s, extra)."""
    c: np.ndarray
    A_ub: np.ndarray
    b_ub: np.ndarray
    n_cells: int
    extra_bounds: tuple = ()        # (lo, hi) per extra variable (None: unbounded)

    def bounds(self) -> list:
        return [(0.0, 1.0)] * self.n_cells + list(self.extra_bounds)


@dataclass
class Timing:
    setup_s: float = 0.0
    solve_s: float = 0.0
    lps: int = 0
    binarise_s: float = 0.0
    fractional: int = 0


def scaled(c: np.ndarray, A: np.ndarray, b: np.ndarray) -> tuple:
    """c, and each row of A v <= b, divided by its largest |coefficient|: HiGHS's feasibility and
    optimality tolerances are absolute (about 1e-7), and rows of moments in kg m^2 are smaller than that
    (a spin design's product-of-inertia rows were ignored: 14x over their bound)."""
    r = np.abs(A).max(axis=1) if A.size else np.ones(len(b))
    r[r == 0] = 1.0
    cmax = np.abs(c).max() if c.size else 1.0
    return c / (cmax if cmax > 0 else 1.0), A / r[:, None], b / r


def solve(p: Program, timing: Timing | None = None) -> np.ndarray | None:
    """The LP's optimal v, or None when infeasible."""
    t0 = time.perf_counter()
    c, A, b = scaled(p.c, p.A_ub, p.b_ub)
    r = linprog(c, A_ub=A, b_ub=b, bounds=p.bounds(), method="highs")
    if timing is not None:
        timing.solve_s += time.perf_counter() - t0
        timing.lps += 1
    return r.x if r.status == 0 else None


def binarise(p: Program, v: np.ndarray, centroids: np.ndarray, timing: Timing | None = None,
             neighbours: int = 64) -> np.ndarray | None:
    """A 0/1 cell vector meeting p's constraints, close to the LP solution v (None if none was found by
    freeing the fractional cells and up to a few hundred of their nearest neighbours)."""
    t0 = time.perf_counter()
    n = p.n_cells
    s = v[:n]
    frac = np.flatnonzero((s > INTEGRAL) & (s < 1 - INTEGRAL))
    if timing is not None:
        timing.fractional = int(len(frac))
    fixed = np.round(s)
    tree = cKDTree(centroids)
    result = None
    for k in (neighbours, 4 * neighbours, 16 * neighbours):
        seeds = centroids[frac] if len(frac) else centroids[:0]
        free = set(frac.tolist())
        if len(seeds):
            _, idx = tree.query(seeds, k=min(k // max(len(frac), 1) + 1, n))
            free.update(np.atleast_1d(idx).ravel().tolist())
        free = np.array(sorted(free), dtype=np.int64)
        result = _milp_on(p, fixed, free)
        if result is not None or len(free) == n:
            break
        if not len(frac):
            frac = np.arange(min(n, 8))
    if timing is not None:
        timing.binarise_s += time.perf_counter() - t0
    return result


def _milp_on(p: Program, fixed: np.ndarray, free: np.ndarray) -> np.ndarray | None:
    """The program with cells outside `free` fixed at `fixed`, the free ones binary."""
    n = p.n_cells
    keep = np.ones(n, dtype=bool)
    keep[free] = False
    A_cells = p.A_ub[:, :n]
    b = p.b_ub - A_cells[:, keep] @ fixed[keep]
    cols = np.concatenate([free, np.arange(n, p.A_ub.shape[1])]).astype(np.int64)
    if not len(cols):                          # nothing left free: the rounded design must hold as it is
        return fixed.copy() if np.all(b >= -1e-12 * (1 + np.abs(p.b_ub))) else None
    A = p.A_ub[:, cols]
    c = p.c[cols]
    ne = p.A_ub.shape[1] - n
    lo = np.concatenate([np.zeros(len(free)), [(-np.inf if b_[0] is None else b_[0]) for b_ in p.extra_bounds]])
    hi = np.concatenate([np.ones(len(free)), [(np.inf if b_[1] is None else b_[1]) for b_ in p.extra_bounds]])
    integrality = np.concatenate([np.ones(len(free)), np.zeros(ne)])
    c, A, b = scaled(c, A, b)
    r = milp(c, constraints=LinearConstraint(A, -np.inf, b), integrality=integrality, bounds=Bounds(lo, hi),
             options={"time_limit": 30.0})
    if r.x is None or r.status not in (0, 1):
        return None
    s = fixed.copy()
    s[free] = np.round(r.x[:len(free)])
    return s


def with_rhs(p: Program, b_ub: np.ndarray) -> Program:
    return replace(p, b_ub=b_ub)
