"""Mass properties against closed forms: box (hexahedra and tetrahedra, P1 and P2 displacement spaces),
cylinder, cone, solid hemisphere and a hemisphere with a concentric hemispherical cavity; the support
polygon's margin and toppling angle; flotation of a box and a vertical cylinder against the metacentric
formulas (BM = I / V).

Curved solids are meshed by gmsh with straight-sided tetrahedra: the mesh is a polyhedron inscribed in
the true surface (chordal error), so those checks use a tolerance of 1.5 % (h = R/10; measured errors
0.1-0.8 %). Straight-sided shapes (boxes) are exact to round-off (1e-10)."""
import math

from dolfinx import fem, mesh as dmesh
from mpi4py import MPI
import numpy as np
import pytest

import balance_shapes
from fem_forms.design.floating import flotation, tetrahedra
from fem_forms.design.mass_properties import MassProperties, cell_moments, total_moments
from fem_forms.design.support import SupportPolygon, fit_sphere
from fem_forms.meshes import load_mesh
from fem_forms.scene import MeshSpec

CURVED = 0.015


def props(mesh, rho=1.0, u=None):
    D = cell_moments(mesh, u)
    return MassProperties.from_moments(total_moments(np.full(len(D), rho), D, mesh.comm))


def file_mesh(path):
    return load_mesh(MeshSpec(generator="file", file=path)).mesh


@pytest.mark.parametrize("cell", [dmesh.CellType.tetrahedron, dmesh.CellType.hexahedron])
def test_box(cell):
    a, b, c, rho = 0.3, 0.2, 0.5, 7.0
    m = dmesh.create_box(MPI.COMM_WORLD, [[0.1, 0.0, -0.2], [0.1 + a, b, -0.2 + c]], [3, 2, 4], cell)
    p = props(m, rho)
    M = rho * a * b * c
    assert p.mass == pytest.approx(M, rel=1e-12)
    assert np.allclose(p.center_of_mass, [0.1 + a / 2, b / 2, -0.2 + c / 2], atol=1e-12)
    assert np.allclose(p.inertia, np.diag([M * (b * b + c * c), M * (a * a + c * c), M * (a * a + b * b)]) / 12,
                       rtol=1e-10, atol=1e-14)


@pytest.mark.parametrize("degree", [1, 2])
def test_deformed_box_is_the_stretched_box(degree):
    """Moments on x = X + u with u a uniform stretch (P1 and P2 spaces): the stretched box's closed form,
    with the rest mass (a part keeps its mass as it deforms: rho dv = rho_0 dV)."""
    m = dmesh.create_box(MPI.COMM_WORLD, [[0, 0, 0], [1, 1, 1]], [2, 2, 2], dmesh.CellType.hexahedron)
    u = fem.Function(fem.VectorFunctionSpace(m, ("Lagrange", degree)))
    u.interpolate(lambda x: np.vstack([0.5 * x[0], 0 * x[1], -0.2 * x[2]]))
    p = props(m, 1.0, u)
    assert p.mass == pytest.approx(1.0, rel=1e-12)
    assert np.allclose(p.center_of_mass, [0.75, 0.5, 0.4], atol=1e-12)
    assert p.inertia[2, 2] == pytest.approx((1.5 ** 2 + 1) / 12, rel=1e-10)


def test_cylinder():
    R, H = 0.05, 0.12
    m = load_mesh(MeshSpec(generator="cylinder", radius=R, height=H, h=R / 10)).mesh
    p = props(m)
    M = math.pi * R * R * H
    assert p.mass == pytest.approx(M, rel=CURVED)
    assert p.center_of_mass[2] == pytest.approx(H / 2, rel=1e-4)
    assert p.inertia[2, 2] == pytest.approx(M * R * R / 2, rel=CURVED)
    assert p.inertia[0, 0] == pytest.approx(M * (3 * R * R + H * H) / 12, rel=CURVED)


def test_cone(tmp_path):
    R, H = 0.05, 0.1
    p = props(file_mesh(balance_shapes.cone(tmp_path / "cone.msh", R, H, R / 10)))
    M = math.pi * R * R * H / 3
    assert p.mass == pytest.approx(M, rel=CURVED)
    assert p.center_of_mass[2] == pytest.approx(H / 4, rel=CURVED)
    assert p.inertia[2, 2] == pytest.approx(0.3 * M * R * R, rel=CURVED)
    assert p.inertia[0, 0] == pytest.approx(3 / 80 * M * (4 * R * R + H * H), rel=CURVED)


@pytest.mark.parametrize("inner", [0.0, 0.03])
def test_hemisphere(tmp_path, inner):
    """Solid: CoM 3R/8 from the flat face, transverse inertia 83/320 m R^2 about the CoM, axial 2/5 m R^2.
    With a concentric cavity of radius r: the difference of two hemispheres."""
    R, rho = 0.05, 1000.0
    p = props(file_mesh(balance_shapes.hemisphere(tmp_path / "hemi.msh", R, R / 10, inner)), rho)
    r = inner
    M = rho * 2 / 3 * math.pi * (R ** 3 - r ** 3)
    zc = 3 / 8 * (R ** 4 - r ** 4) / (R ** 3 - r ** 3)
    axial = rho * 4 * math.pi / 15 * (R ** 5 - r ** 5)
    assert p.mass == pytest.approx(M, rel=CURVED)
    assert p.center_of_mass[2] == pytest.approx(zc, rel=CURVED)
    assert p.inertia[2, 2] == pytest.approx(axial, rel=CURVED)
    assert p.inertia[0, 0] == pytest.approx(axial - M * zc ** 2, rel=CURVED)
    if inner == 0:
        assert zc == pytest.approx(3 * R / 8)
        assert axial - M * zc ** 2 == pytest.approx(83 / 320 * M * R * R)


def test_support_polygon_margin_and_toppling_angle():
    pts = np.array([[0, 0, 0], [0.1, 0, 0], [0.1, 0.04, 0], [0, 0.04, 0], [0.05, 0.02, 0.0]])
    poly = SupportPolygon.from_points(pts, np.array([0, 0, -9.81]))
    assert poly.has_area and len(poly.vertices) == 4
    assert poly.margin(np.array([0.05, 0.02, 0.1])) == pytest.approx(0.02)
    assert poly.toppling_angle_deg(np.array([0.05, 0.02, 0.1])) == pytest.approx(math.degrees(math.atan(0.2)))
    assert poly.margin(np.array([0.13, 0.02, 0.1])) == pytest.approx(-0.03)
    assert not SupportPolygon.from_points(pts[:2], np.array([0, 0, -9.81])).has_area


def test_sphere_fit():
    rng = np.random.default_rng(1)
    d = rng.normal(size=(40, 3))
    d[:, 2] = -np.abs(d[:, 2]) - 2
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    c, R = fit_sphere(np.array([0.1, 0.2, 0.3]) + 0.07 * d)
    assert np.allclose(c, [0.1, 0.2, 0.3]) and R == pytest.approx(0.07)
    assert fit_sphere(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0.5, 0.5, 0]])) is None


def _float(mesh, waterline):
    x = mesh.geometry.x
    n = mesh.topology.index_map(3).size_local
    dofs = mesh.geometry.dofmap.array.reshape(n + mesh.topology.index_map(3).num_ghosts, -1)[:n]
    up, e1, e2 = np.array([0, 0, 1.0]), np.array([1.0, 0, 0]), np.array([0, 1.0, 0])
    keel = mesh.comm.allreduce(x[:, 2].min(), op=MPI.MIN)
    return flotation(tetrahedra(x[dofs]), up, e1, e2, keel, waterline, mesh.comm)


@pytest.mark.parametrize("cell", [dmesh.CellType.tetrahedron, dmesh.CellType.hexahedron])
def test_floating_box(cell):
    """Box L x B x H at draught T: V = L B T, KB = T/2, BM = B^2 / (12 T) (B < L), KG = H/2."""
    L, B, H, T = 0.4, 0.2, 0.1, 0.037
    m = dmesh.create_box(MPI.COMM_WORLD, [[0, 0, 0], [L, B, H]], [6, 4, 3], cell)
    f = _float(m, T)
    assert f.volume == pytest.approx(L * B * T, rel=1e-12)
    assert np.allclose(f.center_of_buoyancy, [L / 2, B / 2, T / 2], atol=1e-12)
    assert f.BM == pytest.approx(B * B / (12 * T), rel=1e-12)
    assert f.metacentric_height(np.array([L / 2, B / 2, H / 2])) == pytest.approx(
        T / 2 + B * B / (12 * T) - H / 2, rel=1e-12)


def test_floating_cylinder():
    """Vertical cylinder radius R at draught T: BM = R^2 / (4 T)."""
    R, H, T = 0.05, 0.1, 0.06
    m = load_mesh(MeshSpec(generator="cylinder", radius=R, height=H, h=R / 10)).mesh
    f = _float(m, T)
    assert f.volume == pytest.approx(math.pi * R * R * T, rel=CURVED)
    assert f.KB == pytest.approx(T / 2, rel=1e-4)
    assert f.BM == pytest.approx(R * R / (4 * T), rel=2 * CURVED)
