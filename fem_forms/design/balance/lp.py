"""Linear programs over the carvable cells, solved by HiGHS (scipy) after scaling, by sifting over groups of
neighbouring cells (sifting.py), and their binarisation.

Variables: s (one per carvable cell, the solid fraction in [0, 1]) followed by a few continuous extra
variables a goal needs (a margin, a bound on the other moments). An LP's optimal vertex is 0/1 except in
at most as many cells as there are constraints: binarise fixes every cell the LP left at 0 or 1 and solves
the same problem as a small mixed-integer program (HiGHS milp) over the fractional cells and their nearest
neighbours, so the binary design meets the constraints exactly rather than approximately.
Speed (benchmarks/balance_scaling.md): 200k tetrahedra, a spin design's 4 LPs in about 1 s on this machine
(one HiGHS call on all cells: 1.5-3 s per LP at 56k cells).
"""
from __future__ import annotations

from dataclasses import astuple, dataclass
import time

import numpy as np
from scipy.optimize import Bounds, LinearConstraint, milp
from scipy.spatial import cKDTree

from fem_forms.design.balance import sifting

INTEGRAL = 1e-6          # an LP value this close to 0 or 1 counts as integral
MIP_GAP = 1e-2           # binarise's MILP stops within 1 % of the free cells' share of the objective (a few
                         # dozen cells of tens of thousands); proving optimality took 0.7-17 s (96k-tet boat)


@dataclass
class Program:
    """min c . v subject to A_ub v <= b_ub, lo <= v <= hi, v = (s, extra)."""
    c: np.ndarray
    A_ub: np.ndarray
    b_ub: np.ndarray
    n_cells: int
    extra_bounds: tuple = ()        # (lo, hi) per extra variable (None: unbounded)
    groups: np.ndarray | None = None    # a group of neighbouring cells per cell: solve by sifting

    def bounds(self) -> list:
        return [(0.0, 1.0)] * self.n_cells + list(self.extra_bounds)


@dataclass
class Timing:
    """What a design's LPs cost: wall seconds, LPs solved, how many by sifting and in how many rounds."""
    setup_s: float = 0.0
    solve_s: float = 0.0
    lps: int = 0
    sifted: int = 0                 # LPs solved by sifting (the others are small: one HiGHS call on all cells)
    rounds: int = 0                 # sifting rounds over those LPs
    fallbacks: int = 0              # sifted LPs finally solved whole (groups too coarse, or MAX_ROUNDS reached)
    binarise_s: float = 0.0
    fractional: int = 0

    def add(self, other: "Timing") -> "Timing":
        """Sums of both (fractional: the last design's), e.g. over the redesigns of the elastic loop."""
        return Timing(*(a + b for a, b in zip(astuple(self)[:-1], astuple(other)[:-1])), other.fractional)


def scaled(p: Program) -> tuple:
    """(c, A, b, extra bounds, column scale) of p with rows scaled to max |a| = 1 over the cells (HiGHS
    drops matrix entries below 1e-9 in absolute value: products-of-inertia rows have entries of 1e-7),
    extra columns to max |a| = 1 and the objective to max |c| = 1 over the cells (HiGHS's dual
    feasibility tolerance is absolute, 1e-7: a spin objective of 1e-7 per cell would be noise).
    Solve for x, then v = x / column scale."""
    n = p.n_cells
    A = np.array(p.A_ub, dtype=float)
    r = np.abs(A[:, :n]).max(axis=1) if n else np.zeros(len(A))      # by the cells: an extra column's -1
    r = np.where(r > 0, r, np.abs(A).max(axis=1))                     # next to cell entries of 1e-9 would
    r[r == 0] = 1.0                                                   # leave those rows unscaled
    A /= r[:, None]
    col = np.ones(A.shape[1])
    if A.shape[1] > n:
        ce = np.abs(A[:, n:]).max(axis=0)
        col[n:] = np.where(ce > 0, ce, 1.0)
    A /= col
    xb = [tuple(None if v is None else v * col[n + k] for v in bb) for k, bb in enumerate(p.extra_bounds)]
    c = p.c / col
    top = float(np.abs(c[:n]).max()) if n else 0.0
    c = c / (top if top > 0 else max(float(np.abs(c).max()), 1e-300))
    return c, A, p.b_ub / r, xb, col


def solve(p: Program, timing: Timing | None = None) -> np.ndarray | None:
    """The LP's optimal v, or None when infeasible (by sifting when p has cell groups)."""
    t0 = time.perf_counter()
    c, A, b, xb, col = scaled(p)
    stats = {}
    x = sifting.solve(c, A, b, p.n_cells, xb, p.groups, stats)
    if timing is not None:
        timing.solve_s += time.perf_counter() - t0
        timing.lps += 1
        if "groups" in stats:                       # sifting was tried (enough cells, groups given)
            timing.sifted += 1
            timing.rounds += stats.get("rounds", 0)
            timing.fallbacks += bool(stats.get("fallback"))
    return None if x is None else x / col


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
    """The program with cells outside `free` fixed at `fixed`, the free ones binary (scaled as for the LP)."""
    n = p.n_cells
    keep = np.ones(n, dtype=bool)
    keep[free] = False
    c_s, A_s, b_s, xb, col = scaled(p)
    b = b_s - A_s[:, :n][:, keep] @ fixed[keep]
    cols = np.concatenate([free, np.arange(n, A_s.shape[1])]).astype(np.int64)
    if not len(cols):                          # nothing left free: the rounded design must hold as it is
        return fixed.copy() if np.all(b >= -1e-12 * (1 + np.abs(b_s))) else None
    ne = A_s.shape[1] - n
    lo = np.concatenate([np.zeros(len(free)), [(-np.inf if b_[0] is None else b_[0]) for b_ in xb]])
    hi = np.concatenate([np.ones(len(free)), [(np.inf if b_[1] is None else b_[1]) for b_ in xb]])
    integrality = np.concatenate([np.ones(len(free)), np.zeros(ne)])
    r = milp(c_s[cols], constraints=LinearConstraint(A_s[:, cols], -np.inf, b), integrality=integrality,
             bounds=Bounds(lo, hi), options={"time_limit": 30.0, "mip_rel_gap": MIP_GAP})
    if r.x is None or r.status not in (0, 1):
        return None
    s = fixed.copy()
    s[free] = np.round(r.x[:len(free)])
    return s


