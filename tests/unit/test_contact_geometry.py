"""The contact barrier and the analytic obstacles, against independent references: the IPC Toolkit's own
barrier functions, central differences of the signed distances, and exact times of impact."""
from types import SimpleNamespace

import ipctk
import numpy as np
import pytest

from fem_forms.physics.contact.barrier import barrier, barrier_first, barrier_second, psd_blocks
from fem_forms.physics.contact.obstacles import KEEP, make_obstacle


def test_barrier_and_its_derivatives_equal_the_ipc_toolkits():
    dhat = 1e-3
    d = np.array([1e-9, 1e-6, 2e-4, 5e-4, 9.99e-4, 1e-3, 2e-3])
    for ours, theirs in ((barrier, ipctk.barrier), (barrier_first, ipctk.barrier_first_derivative),
                         (barrier_second, ipctk.barrier_second_derivative)):
        ref = np.array([theirs(x, dhat) if x < dhat else 0.0 for x in d])
        assert np.allclose(ours(d, dhat), ref, rtol=1e-12, atol=0.0)
    assert barrier(np.array([0.0, -1e-6]), dhat).tolist() == [np.inf, np.inf]


SPECS = {
    "plane": dict(point=[0.1, 0.0, -0.2], normal=[0.3, -0.2, 1.0]),
    "sphere": dict(center=[0.0, 0.1, -1.0], radius=0.7),
    "cylinder": dict(point=[0.0, 0.0, -1.0], axis=[1.0, 0.5, 0.2], radius=0.6),
    "box": dict(min=[-0.5, -0.4, -1.5], max=[0.3, 0.2, -0.6]),
}


def obstacle(shape, motion=None):
    return make_obstacle(SimpleNamespace(name=shape, shape=shape, friction=0.0, motion=motion, **SPECS[shape]))


@pytest.mark.parametrize("shape", list(SPECS))
def test_gradient_and_hessian_of_each_distance_are_its_central_differences(shape):
    ob = obstacle(shape)
    rng = np.random.default_rng(3)
    p = rng.uniform(-0.3, 0.6, size=(40, 3))
    d, g, H = ob.derivatives(p)
    h = 1e-6
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        dp, gp, _ = ob.derivatives(p + e)
        dm, gm, _ = ob.derivatives(p - e)
        assert np.allclose((dp - dm) / (2 * h), g[:, k], atol=1e-7)
        assert np.allclose((gp - gm) / (2 * h), H[:, :, k], atol=1e-5)


@pytest.mark.parametrize("shape", list(SPECS))
def test_a_filtered_step_never_enters_the_obstacle(shape):
    """Points thrown straight through the obstacle: the safe fraction stops every one of them outside, with at
    least KEEP of its gap, and no further point on the capped segments is inside (sampled densely)."""
    ob = obstacle(shape)
    rng = np.random.default_rng(5)
    p0 = rng.uniform(-0.3, 0.6, size=(30, 3))
    p0 = p0[ob.distance(p0) > 1e-3]
    dp = np.array(SPECS.get(shape, {}).get("center", [0.0, 0.0, -1.2])) - p0
    s = ob.safe_fraction(p0, 2.5 * dp)
    assert 0.0 < s < 1.0
    for t in np.linspace(0.0, s, 400):
        assert np.all(ob.distance(p0 + t * 2.5 * dp) > 0.0)
    assert np.all(ob.distance(p0 + s * 2.5 * dp) >= KEEP * ob.distance(p0) * (1 - 1e-9))


def test_plane_step_filter_is_its_exact_time_of_impact_shortened_to_keep_a_gap():
    ob = obstacle("plane")
    n = ob.normal
    p0 = np.array([[0.1, 0.0, -0.2]]) + 0.01 * n
    s = ob.safe_fraction(p0, -0.04 * n[None])        # impact at a quarter of the step
    assert s == pytest.approx(0.25 * (1 - KEEP), rel=1e-12)


def test_motion_moves_the_obstacle_piecewise_linearly_and_holds_after_the_last_row():
    ob = obstacle("sphere", motion=[[0.0, 0.0, 0.0, 0.0], [2.0, 0.2, 0.0, -0.4]])
    p = np.array([[0.0, 0.1, 0.0]])
    d0 = ob.distance(p)[0]
    ob.move_to(1.0)
    assert ob.distance(p)[0] == pytest.approx(np.linalg.norm([0.1, 0.0, 1.2]) - 0.7, rel=1e-12)
    ob.move_to(5.0)
    assert np.allclose(ob.offset, [0.2, 0.0, -0.4])
    assert d0 == pytest.approx(0.3, rel=1e-12)


def test_psd_projection_keeps_positive_parts_and_drops_negative_eigenvalues():
    Q = np.linalg.qr(np.random.default_rng(1).normal(size=(3, 3)))[0]
    H = Q @ np.diag([2.0, -1.0, 0.5]) @ Q.T
    P = psd_blocks(H[None])[0]
    assert np.allclose(P, Q @ np.diag([2.0, 0.0, 0.5]) @ Q.T)


def plates(gap, n=3):
    from fem_forms.physics.contact.ipc_surfaces import _plates
    V, F, n, area = _plates(0.01, gap, n=n)
    edges = np.unique(np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1), axis=0)
    return SimpleNamespace(rest=V, faces=F, edges=lambda: edges, size=len(V)), n, area


def test_self_contact_gradient_is_the_central_difference_of_its_energy():
    from fem_forms.physics.contact.ipc_surfaces import IpcSurfaces
    surface, n, _ = plates(0.003)
    p = surface.rest + np.random.default_rng(0).normal(scale=3e-4, size=surface.rest.shape)
    sc = IpcSurfaces(surface, 0.005)
    g = sc.gradient(p).ravel()
    fd = np.zeros_like(g)
    for k in range(len(g)):
        e = np.zeros(len(g))
        e[k] = 1e-7
        fd[k] = (sc.barrier_energy(p + e.reshape(-1, 3)) - sc.barrier_energy(p - e.reshape(-1, 3))) / 2e-7
    assert np.abs(fd - g).max() < 1e-6 * np.abs(g).max()
    assert np.linalg.eigvalsh(sc.hessian(p).toarray()).min() > -1e-12 * np.abs(g).max()   # projected: PSD


def test_self_contact_calibration_gives_the_asked_pressure_and_ccd_stops_before_crossing():
    from fem_forms.physics.contact.ipc_surfaces import SHORTEN, IpcSurfaces
    surface, n, area = plates(0.0025, n=6)                    # the calibration's own probe: patches of 6 x 6
    sc = IpcSurfaces(surface, 0.005)
    sc.calibrate(0.01, 1e3)
    force = -sc.gradient(surface.rest)[:n, 2].sum() / area    # on the lower patch: down, Pa
    assert force == pytest.approx(-1e3, rel=1e-9) and sc.stiffness > 0
    dp = np.zeros_like(surface.rest)
    x = surface.rest[n:, 0]
    dp[n:, 2] = -0.005 + 0.2 * (x - x.mean())                 # the top patch tilted through the bottom one
    first = 0.0025 / 0.011                                    # its corner at x = 0 meets the bottom patch first
    s = sc.safe_fraction(surface.rest, dp)
    assert SHORTEN * first * 0.85 < s < SHORTEN * first * 1.0001     # Tight Inclusion errs early (measured 5 %)
    assert not sc.intersects(surface.rest + s * dp) and sc.intersects(surface.rest + 0.75 * dp)


def test_winding_numbers_tell_inside_from_outside_of_a_closed_surface():
    from fem_forms.physics.contact.mesh_obstacle import winding_numbers
    import ipctk
    box = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], float)
    faces = np.array([[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4], [2, 6, 3], [3, 6, 7],
                      [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]])
    assert len(ipctk.edges(faces)) == 18                      # closed: every edge in two triangles
    w = winding_numbers(np.array([[0.5, 0.5, 0.5], [0.1, 0.9, 0.2], [1.5, 0.5, 0.5], [0.5, -2, 3]]), box, faces)
    assert np.allclose(np.abs(w), [1, 1, 0, 0], atol=1e-12)


def test_an_obstacle_file_sliding_over_the_part_drags_it_with_coulombs_force():
    """The lower patch is the part, the upper one a rigid obstacle moving 1 mm along x during the step: the
    friction on the part is mu times the normal force (slip >> the mollifier's eps), along the motion, and the
    gradient of the whole potential (barrier + friction) is the central difference of its energy."""
    from fem_forms.physics.contact.ipc_surfaces import IpcSurfaces
    surface, n, area = plates(0.0025, n=6)
    top = surface.rest[n:]
    ob = SimpleNamespace(name="tool", friction=0.4, points=top, triangles=surface.faces[len(surface.faces) // 2:] - n,
                         points_at=lambda t: top + [1e-3 * t, 0, 0], current_points=lambda: top)
    lower = surface.faces[:len(surface.faces) // 2]
    edges = np.unique(np.sort(np.concatenate([lower[:, [0, 1]], lower[:, [1, 2]], lower[:, [2, 0]]]), axis=1), axis=0)
    part = SimpleNamespace(rest=surface.rest[:n], faces=lower, size=n, edges=lambda: edges)
    c = IpcSurfaces(part, 0.005, [ob], self_pairs=False)
    c.calibrate(0.01, 1e3)
    c.lag_friction(part.rest, 0.0, 1.0, 1e-7, 0.0)
    normal = -(c.gradient(part.rest) + c.friction_forces(part.rest))[:, 2].sum()     # the obstacle pushes down
    drag = c.friction_forces(part.rest).sum(axis=0)
    assert normal == pytest.approx(-1e3 * area, rel=1e-9)     # the calibrated pressure at dhat / 2
    assert drag[0] == pytest.approx(0.4 * 1e3 * area, rel=1e-6) and abs(drag[1]) < 1e-9 * drag[0]
    p = part.rest + np.random.default_rng(2).normal(scale=2e-4, size=part.rest.shape)
    energy = lambda q: c.barrier_energy(q) + c.friction_energy(q)        # noqa: E731
    g = c.gradient(p).ravel()
    fd = np.array([(energy(p + e.reshape(-1, 3)) - energy(p - e.reshape(-1, 3))) / 2e-8
                   for e in np.eye(len(g)) * 1e-8])
    assert np.abs(fd - g).max() < 1e-5 * np.abs(g).max()
