"""The quadrature rules (fem_forms/physics/quadrature.py): positive weights at every degree 1..8, the
Gauss-Jacobi rule really used by FFCx where basix's default is not positive, and the safe degrees
checked by counting the zero eigenvalues of the linear-elastic stiffness of a free 2x1x1 patch:
exactly the 6 rigid-body modes at and above the safe degree, more (hourglass modes) below."""
from dolfinx import fem, mesh
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
import numpy as np
import pytest
import ufl

from fem_forms.errors import InputError
from fem_forms import elements
from fem_forms.physics import quadrature
from fem_forms.scene import Scene

DEGREES = range(1, elements.MAX_DEGREE + 1)
ELEMENTS = [("tetrahedron", 1, False), ("tetrahedron", 2, False), ("tetrahedron", 2, True),
            ("hexahedron", 1, False), ("hexahedron", 2, False), ("hexahedron", 2, True), ("prism", 1, False)]


@pytest.mark.parametrize("cell", ["tetrahedron", "hexahedron", "prism"])
def test_rules_are_positive_at_every_degree(cell):
    for q in DEGREES:
        points, weights = quadrature.points(cell, q)
        assert np.all(weights > 0), (cell, q)
        assert weights.sum() == pytest.approx({"tetrahedron": 1 / 6, "hexahedron": 1.0, "prism": 0.5}[cell])
    assert [quadrature.rule_name("tetrahedron", q) for q in DEGREES].count("Gauss-Jacobi") == 3   # 3, 7, 8


@pytest.mark.parametrize("cell", ["hexahedron", "prism"])
def test_tensor_cells_name_each_rule_once(cell):
    """On hexahedra and prisms degrees 2k and 2k + 1 are one basix rule: the forms name it by one degree (one
    compile), and the points are basix's own rule of the degree asked for; simplices keep every degree."""
    import basix
    for q in range(0, 11):
        same = quadrature.metadata(cell, q) == quadrature.metadata(cell, q + 1)
        assert same == (q % 2 == 0), (cell, q)
        points, weights = quadrature.points(cell, q)
        asked = basix.make_quadrature(getattr(basix.CellType, cell), max(q, 1))
        assert np.array_equal(points, asked[0]) and np.array_equal(weights, asked[1]), (cell, q)
    assert [quadrature.metadata("tetrahedron", q)["quadrature_degree"] for q in (4, 5)] == [4, 5]


def test_ffcx_uses_the_positive_rule():
    """An integral FFCx's default degree-3 rule and Gauss-Jacobi give differently: the dx metadata
    selects Gauss-Jacobi, and the result is the integral over our own points and weights."""
    m = mesh.create_unit_cube(MPI.COMM_SELF, 1, 1, 1)
    x = ufl.SpatialCoordinate(m)
    f = ufl.exp(x[0]) * x[1] ** 2
    ours = fem.assemble_scalar(fem.form(f * ufl.dx(domain=m, metadata=quadrature.metadata("tetrahedron", 3))))
    default = fem.assemble_scalar(fem.form(f * ufl.dx(domain=m, metadata={"quadrature_degree": 3})))
    points, weights = quadrature.points("tetrahedron", 3)
    values = fem.Expression(f, points).eval(np.arange(6, dtype=np.int32))
    detJ = 1.0 / 6.0 / (1 / 6)          # six tetrahedra of volume 1/6 each in the unit cube: |det J| = 1
    assert ours == pytest.approx(float((values * weights).sum() * detJ), rel=1e-13)
    assert abs(ours - default) > 1e-6


def zero_modes(cell: str, degree: int, q: int, mixed: bool) -> int:
    """Zero eigenvalues of the linear-elastic stiffness (mixed: the u-p saddle matrix) of a free patch."""
    m = mesh.create_box(MPI.COMM_SELF, [np.zeros(3), np.array([2.0, 1.0, 1.0])], [2, 1, 1],
                        getattr(mesh.CellType, cell))
    dx = ufl.dx(domain=m, metadata=quadrature.metadata(cell, q))
    eps = lambda w: ufl.sym(ufl.grad(w))                       # noqa: E731
    if mixed:
        W = fem.FunctionSpace(m, ufl.MixedElement([ufl.VectorElement("Lagrange", m.ufl_cell(), 2),
                                                   ufl.FiniteElement("Lagrange", m.ufl_cell(), 1)]))
        (u, p), (v, r) = ufl.TrialFunctions(W), ufl.TestFunctions(W)
        dev = lambda e: e - ufl.tr(e) / 3 * ufl.Identity(3)   # noqa: E731
        a = (2 * ufl.inner(dev(eps(u)), dev(eps(v))) + p * ufl.div(v) + r * ufl.div(u) - p * r / 1.5) * dx
    else:
        V = fem.VectorFunctionSpace(m, ("Lagrange", degree))
        u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        a = (2 * ufl.inner(eps(u), eps(v)) + 1.5 * ufl.div(u) * ufl.div(v)) * dx
    A = fpetsc.assemble_matrix(fem.form(a))
    A.assemble()
    K = A.convert("dense").getDenseArray().copy()     # convert is in place: copy before destroy
    A.destroy()
    ev = np.abs(np.linalg.eigvalsh(0.5 * (K + K.T)))
    return int(np.sum(ev < 1e-9 * ev.max()))


@pytest.mark.parametrize("cell,degree,mixed", ELEMENTS)
def test_safe_degree_is_the_smallest_full_rank_rule(cell, degree, mixed):
    safe = elements.safe_degree(cell, degree)
    counts = {q: zero_modes(cell, degree, q, mixed) for q in DEGREES}
    assert all(counts[q] == 6 for q in DEGREES if q >= safe), counts
    assert all(counts[q] > 6 for q in DEGREES if q < safe), counts


def _scene(cell: str, degree: int, q: int) -> dict:
    return {"analysis": "static", "mesh": {"cell": cell, "cells": [3, 1, 1]},
            "discretization": {"degree": degree, "quadrature_degree": q},
            "material": {"model": "linear", "E": 1e6, "nu": 0.3, "rho": 1000.0},
            "fix": [{"where": {"axis": "x", "at": 0.0}}], "load": [{"type": "gravity", "g": [0, 0, -9.81]}]}


def test_under_integration_and_too_high_degrees_are_refused_when_read():
    with pytest.raises(InputError, match=r"discretization.quadrature_degree = 3: .*Q2 hexahedron.* use 4"):
        Scene.from_dict(_scene("hexahedron", 2, 3))
    with pytest.raises(InputError, match=r"quadrature_degree.*8"):
        Scene.from_dict(_scene("tetrahedron", 2, 9))
    Scene.from_dict(_scene("tetrahedron", 2, 3))            # fine: the positive rule


def test_q2_hexahedron_at_degree_3_exits_2_naming_degree_4(tmp_path, capsys):
    from fem_forms import cli
    d = _scene("hexahedron", 2, 3)
    path = tmp_path / "scene.toml"
    path.write_text('analysis = "static"\n[mesh]\ncell = "hexahedron"\ncells = [3, 1, 1]\n'
                    '[discretization]\ndegree = 2\nquadrature_degree = 3\n'
                    '[material]\nmodel = "linear"\nE = 1e6\nnu = 0.3\nrho = 1000.0\n'
                    '[[fix]]\nwhere = {axis = "x", at = 0.0}\n[[load]]\ntype = "gravity"\ng = [0, 0, -9.81]\n')
    assert d["discretization"]["quadrature_degree"] == 3
    assert cli.main(["run", str(path), "--out", str(tmp_path / "out"), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "quadrature_degree = 3" in err[0] and "use 4" in err[0], err
