"""The balance LPs solved by sifting (column generation on box-bounded columns), exact to HiGHS's
tolerances and much faster than handing HiGHS all cells at once.

A balance LP has ten or so rows and one [0, 1] column per carvable cell; its optimum has at most as many
fractional cells as rows and every other cell at the bound its reduced cost picks. HiGHS 1.2 pays for the
columns, not the rows (56k cells, 12 rows: 1-3 s for 3-13 simplex iterations), so:
1. solve the LP on groups of neighbouring cells (one column each: the sum of its cells' columns); its
   solution, spread over the cells, is feasible for the full LP;
2. price every cell with the restricted LP's row duals (rc = c + A^T y, numpy, ms) and re-solve over a
   working set that only grows: the cells whose bound contradicts their reduced cost, the fractional ones
   and the cells with the smallest |rc|; every other cell stays where it is (its column moves to the
   right-hand side); the objective never rises and a set that only grows cannot cycle;
3. repeat until no cell outside the set contradicts its reduced cost: then the duals prove the whole
   LP optimal (KKT), as a single HiGHS solve would.
When the grouped LP is infeasible (a tight requirement that groups cannot meet), the full LP is solved
directly: the result is the same, only slower.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import linprog

MIN_CELLS = 4000            # below this the full LP is solved directly (fast enough)
GROUP_CELLS = 12            # cells per group (voxels of the centroids' bounding box)
WORKING = 500               # cells in the working set besides the contradicting and fractional ones
MAX_ROUNDS = 30
RC_TOL = 1e-9               # x the largest |reduced cost|: a cell at a bound contradicts it beyond this
OPTIONS = {"dual_feasibility_tolerance": 1e-10, "primal_feasibility_tolerance": 1e-10}


def groups(centroids: np.ndarray, per_group: int = GROUP_CELLS) -> np.ndarray:
    """A group label per cell: the voxel of the centroids' bounding box it falls in (about `per_group`
    cells per non-empty voxel for a solid that fills its box)."""
    lo, hi = centroids.min(axis=0), centroids.max(axis=0)
    span = np.maximum(hi - lo, 1e-12 * max(float((hi - lo).max()), 1e-300))
    h = (np.prod(span) * per_group / max(len(centroids), 1)) ** (1 / 3)
    ijk = np.floor((centroids - lo) / h).astype(np.int64)
    dims = ijk.max(axis=0) + 1
    _, label = np.unique(ijk[:, 0] + dims[0] * (ijk[:, 1] + dims[1] * ijk[:, 2]), return_inverse=True)
    return label.ravel()


def _highs(c, A, b, bounds):
    r = linprog(c, A_ub=A, b_ub=b, bounds=bounds, method="highs", options=OPTIONS)
    if r.status != 0:
        return None, None
    return r.x, -r.ineqlin.marginals


def solve(c: np.ndarray, A: np.ndarray, b: np.ndarray, n: int, xb: list, labels: np.ndarray | None,
          stats: dict | None = None) -> np.ndarray | None:
    """Optimal v = (s, extra) of min c.v, A v <= b, 0 <= s <= 1 (the first n), extra within the bounds xb
    (None when infeasible). `labels` (a group per cell) enables sifting; None solves the full LP. Give it
    a well scaled problem (lp.scaled): the stopping test compares reduced costs. `stats` gets groups,
    rounds (restricted re-solves after the grouped LP), work (largest working set) and fallback (True when
    the full LP had to be solved after all)."""
    stats = stats if stats is not None else {}
    if labels is None or n < MIN_CELLS:
        x, _ = _highs(c, A, b, [(0.0, 1.0)] * n + xb)
        stats["rounds"] = 0
        return x
    Ac, cc = A[:, :n], c[:n]
    ng = int(labels.max()) + 1
    Ag = np.zeros((A.shape[0], ng))
    for i in range(A.shape[0]):
        Ag[i] = np.bincount(labels, weights=Ac[i], minlength=ng)
    cg = np.bincount(labels, weights=cc, minlength=ng)
    stats["groups"] = ng
    xg, y = _highs(np.concatenate([cg, c[n:]]), np.hstack([Ag, A[:, n:]]), b, [(0.0, 1.0)] * ng + xb)
    if xg is None:                                    # groups too coarse for the requirements
        stats.update(rounds=0, fallback=True)
        x, _ = _highs(c, A, b, [(0.0, 1.0)] * n + xb)
        return x
    s = xg[labels]
    extra = xg[ng:]
    work = np.zeros(n, dtype=bool)
    for k in range(MAX_ROUNDS):
        rc = cc + y @ Ac
        tol = RC_TOL * max(float(np.abs(rc).max()), 1e-300)
        wrong = ((s > 0) & (rc > tol)) | ((s < 1) & (rc < -tol))
        wrong &= ~work
        if k > 0 and not wrong.any():
            stats["rounds"] = k
            return np.concatenate([s, extra])
        frac = (s > 0) & (s < 1)
        near = np.argpartition(np.abs(rc), WORKING)[:WORKING] if n > WORKING else np.arange(n)
        work = work | wrong | frac                    # the set only grows: no cycling, at most n cells
        work[near] = True
        idx = np.flatnonzero(work)
        rhs = b - Ac @ np.where(work, 0.0, s)          # the cells outside the set stay where they are
        x, y_new = _highs(np.concatenate([cc[idx], c[n:]]), np.hstack([Ac[:, idx], A[:, n:]]), rhs,
                          [(0.0, 1.0)] * len(idx) + xb)
        stats["rounds"] = k + 1
        if x is None:                                 # cannot happen (the current point is feasible)
            break
        stats["work"] = max(stats.get("work", 0), len(idx))
        s[idx] = x[:len(idx)]
        extra = x[len(idx):]
        y = y_new
    stats["fallback"] = True                          # not settled in MAX_ROUNDS: the whole LP
    x, _ = _highs(c, A, b, [(0.0, 1.0)] * n + xb)
    return x
