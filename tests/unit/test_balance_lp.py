"""The balance LP machinery against independent references: sifting over cell groups reaches the
optimum HiGHS finds on the whole LP (a stand-like program and a spin-like one with an extra variable);
the shell test (cells farther than `shell` from the boundary) against brute-force distances."""
from dolfinx import cpp, mesh as dmesh
from mpi4py import MPI
import numpy as np
import pytest
from scipy.optimize import linprog
from scipy.spatial.distance import cdist

from fem_forms.design.balance import lp, rows, sifting
from fem_forms.design.balance.body import _beyond, _cell_nodes, surface_points


def cells(n, seed):
    """Moment columns (10, n) of n small cubes of random size at random points in a 0.2 x 0.1 x 0.1 box."""
    rng = np.random.default_rng(seed)
    x = rng.uniform([0, 0, 0], [0.2, 0.1, 0.1], size=(n, 3))
    V = rng.uniform(0.5, 1.5, n) * 1e-7
    a2 = (V ** (2 / 3)) / 12                      # a cube's int (x - c)^2 / V
    D = np.stack([V, V * x[:, 0], V * x[:, 1], V * x[:, 2], V * (x[:, 0] ** 2 + a2), V * (x[:, 1] ** 2 + a2),
                  V * (x[:, 2] ** 2 + a2), V * x[:, 0] * x[:, 1], V * x[:, 0] * x[:, 2], V * x[:, 1] * x[:, 2]])
    return D, x


def whole(p):
    """HiGHS on the whole LP as posed (no scaling, no groups): a reference optimum to HiGHS's default
    tolerances (its products-of-inertia rows are badly scaled: ~1e-7 relative)."""
    r = linprog(p.c, A_ub=p.A_ub, b_ub=p.b_ub, bounds=p.bounds(), method="highs")
    assert r.status == 0
    return r.x


def whole_scaled(p):
    """HiGHS on the whole LP after lp.scaled, tight tolerances, no groups: the reference for sifting."""
    c, A, b, xb, col = lp.scaled(p)
    r = linprog(c, A_ub=A, b_ub=b, bounds=[(0.0, 1.0)] * p.n_cells + xb, method="highs", options=sifting.OPTIONS)
    assert r.status == 0
    return r.x / col


def check(p, centroids, objective=None):
    """`objective(v)`: the LP's objective with its extra variables at their tightest feasible values
    (solvers meet the rows to ~1e-9 only, and an extra variable with a large cost turns that into
    objective differences of 1e-5 relative); default c . v."""
    objective = objective or (lambda v: p.c @ v)
    ref = objective(whole_scaled(p))
    loose = objective(whole(p))
    q = lp.Program(p.c, p.A_ub, p.b_ub, p.n_cells, p.extra_bounds, sifting.groups(centroids))
    t = lp.Timing()
    v = lp.solve(q, t)
    assert t.lps == t.sifted == 1 and t.rounds >= 1 and t.fallbacks == 0   # sifted, no fallback
    scale = np.abs(p.A_ub).max(axis=1)
    assert np.all((p.A_ub @ v - p.b_ub) / scale <= 1e-6)    # feasible
    assert np.all((v[:p.n_cells] >= -1e-9) & (v[:p.n_cells] <= 1 + 1e-9))
    assert objective(v) == pytest.approx(ref, rel=1e-9, abs=1e-12 * np.abs(p.c).sum())
    assert objective(v) == pytest.approx(loose, rel=1e-6, abs=1e-12 * np.abs(p.c).sum())
    frac = np.sum((v[:p.n_cells] > 1e-6) & (v[:p.n_cells] < 1 - 1e-6))
    assert frac <= len(p.b_ub)                              # a vertex: at most one fractional cell per row


@pytest.mark.parametrize("seed", [1, 2])
def test_sifting_reaches_the_whole_lp_optimum_stand_like(seed):
    """CoM moved into a band around a point (both sides of two directions), least mass removed."""
    D, x = cells(6000, seed)
    G = 600.0 * D
    M0 = 100.0 * D.sum(axis=1)
    p0 = np.array([0.12, 0.04, 0.03])
    W = np.array([rows.first(np.array([1.0, 0, 0]), p0), -rows.first(np.array([1.0, 0, 0]), p0),
                  rows.first(np.array([0, 1.0, 0]), p0), -rows.first(np.array([0, 1.0, 0]), p0)])
    W -= 0.01 * rows.mass()                                 # |m (c - p0)_i| <= 0.01 m
    p = lp.Program(-rows.mass() @ G, W @ G, -W @ M0, G.shape[1])
    check(p, x)


def test_sifting_reaches_the_whole_lp_optimum_spin_like():
    """Spin-It's LP at a fixed ratio: products of inertia bounded, max I_z - r w with w >= I_xx, I_yy."""
    D, x = cells(8000, 3)
    G = 900.0 * D
    M0 = 100.0 * D.sum(axis=1)
    p0 = np.array([0.1, 0.05, 0.0])
    ex, ey, ez = np.eye(3)
    Wp = np.array([rows.inertia(ez, ex, p0), rows.inertia(ez, ey, p0)])
    Ifull = rows.inertia(ez, ez, p0) @ (M0 + G.sum(axis=1))
    A1 = np.hstack([np.vstack([Wp, -Wp]) @ G, np.zeros((4, 1))])
    b1 = 1e-3 * Ifull - np.vstack([Wp, -Wp]) @ M0
    Ww = np.array([rows.inertia(ex, ex, p0), rows.inertia(ey, ey, p0)])
    A2 = np.hstack([Ww @ G, -np.ones((2, 1))])
    b2 = -Ww @ M0
    c = np.concatenate([-rows.inertia(ez, ez, p0) @ G, [0.9]])
    p = lp.Program(c, np.vstack([A1, A2]), np.concatenate([b1, b2]), G.shape[1], ((0.0, None),))
    n = G.shape[1]
    check(p, x, lambda v: c[:n] @ v[:n] + c[n] * max(Ww @ (M0 + G @ v[:n])))


def test_shell_cells_against_brute_force_distances():
    """Surface points: every boundary facet's corners, edge midpoints and centroid (from the facets' own
    corner coordinates); shell cells: brute-force distances to them."""
    m = dmesh.create_box(MPI.COMM_WORLD, [[0, 0, 0], [0.3, 0.2, 0.2]], [9, 6, 6], dmesh.CellType.tetrahedron)
    cn = _cell_nodes(m)
    surf = surface_points(m)
    m.topology.create_connectivity(2, 3)
    tri = m.geometry.x[cpp.mesh.entities_to_geometry(m._mesh, 2, dmesh.exterior_facet_indices(m.topology), False)]
    naive = np.vstack([tri.reshape(-1, 3), *[(tri[:, i] + tri[:, (i + 1) % 3]) / 2 for i in range(3)],
                       tri.mean(axis=1)])
    assert len(tri) == 2 * 2 * (9 * 6 + 9 * 6 + 6 * 6)            # two triangles per boundary square
    assert np.array_equal(np.unique(np.round(naive, 12), axis=0), np.unique(np.round(surf, 12), axis=0))
    for shell in (0.02, 0.035, 0.05):
        got = _beyond(m.geometry.x, cn, surf, shell)
        d = cdist(m.geometry.x[cn].reshape(-1, 3), surf).min(axis=1).reshape(len(cn), -1)
        ref = d.min(axis=1) > shell
        assert np.array_equal(got, ref) and 0 < ref.sum() < len(ref)
