"""Anisotropic materials against closed forms:
- small-strain orthotropic: a block in uniaxial tension along each material axis strains as the compliance
  matrix of the nine engineering constants says (E_k along, -nu_kj / E_k across), the axes turned so that
  each one in turn lies along the pull; constants that make the stiffness indefinite are refused;
- fibre reinforcement: a bar pulled along its fibres is E_m + E_f stiff, across them (fibres shortened:
  no compression stiffness) E_m; fibres on one layer only stiffen that layer (transformed section)."""
import math

import numpy as np
import pytest

import fem_forms as ff
from fem_forms.errors import InputError

SIGMA = 1.0e5                                                    # Pa
ORTHO = {"E1": 2.2e9, "E2": 1.5e9, "E3": 1.0e9, "G12": 0.8e9, "G13": 0.6e9, "G23": 0.5e9,
         "nu12": 0.35, "nu13": 0.3, "nu23": 0.4}


def pulled_block(material: dict, sigma=SIGMA) -> dict:
    """A 2 x 1 x 0.5 m block on rollers on three faces, pulled along x by sigma: uniaxial stress."""
    return {"mesh": {"size": [2.0, 1.0, 0.5], "cells": [2, 2, 2]}, "material": material,
            "discretization": {"degree": 1},
            "fix": [{"where": {"axis": a, "at": 0.0}, "components": [a]} for a in "xyz"],
            "load": [{"type": "traction", "where": {"axis": "x", "at": 2.0}, "value": [sigma, 0.0, 0.0]}],
            "output": {"picture": False, "probes": {"corner": [2.0, 1.0, 0.5]}}}


def strains(material: dict, sigma=SIGMA) -> np.ndarray:
    s = ff.solve_static(ff.Scene.from_dict(pulled_block(material, sigma))).summary()
    assert s["converged"]
    return np.array(s["probes"]["corner"]["displacement"]) / np.array([2.0, 1.0, 0.5])


def compliance() -> np.ndarray:
    """The 3 x 3 normal block of the compliance in the material axes (textbook form)."""
    E = [ORTHO["E1"], ORTHO["E2"], ORTHO["E3"]]
    nu = {(0, 1): ORTHO["nu12"], (0, 2): ORTHO["nu13"], (1, 2): ORTHO["nu23"]}
    S = np.diag([1 / e for e in E])
    for (i, j), v in nu.items():
        S[i, j] = S[j, i] = -v / E[i]
    return S


# (axis1, axis2) and the material axis that lies along x, then along y and z
TURNS = [(([1, 0, 0], [0, 1, 0]), (0, 1, 2)),
         (([0, 1, 0], [1, 0, 0]), (1, 0, 2)),
         (([0, 1, 0], [0, 0, 1]), (2, 0, 1))]


@pytest.mark.parametrize("axes, order", TURNS)
def test_orthotropic_uniaxial_tension_along_each_axis(axes, order):
    eps = strains({"model": "orthotropic", **ORTHO, "axis1": axes[0], "axis2": axes[1]})
    S = compliance()
    along = order[0]
    expected = [S[along, k] * SIGMA for k in order]             # global x, y, z strains
    assert eps == pytest.approx(expected, rel=1e-9)


MINIMAL = [{"where": {"axis": "x", "at": 0.0}, "components": ["x"]},
           {"where": {"point": [0.0, 0.0, 0.0]}, "components": ["y", "z"]},
           {"where": {"point": [0.0, 1.0, 0.0]}, "components": ["z"]}]


def test_orthotropic_axes_turned_30_degrees_couple_stretch_and_shear():
    """Uniaxial stress at 30 deg to the fibres (supports that leave the shear free): the stretch is the
    off-axis compliance 1/E_x = cos^4/E1 + (1/G12 - 2 nu12/E1) sin^2 cos^2 + sin^4/E2 (Jones, Mechanics of
    Composite Materials, 2nd ed., 1999, eq. 2.98), and the block shears."""
    c, s_ = math.cos(math.radians(30)), math.sin(math.radians(30))
    d = pulled_block({"model": "orthotropic", **ORTHO, "axis1": [c, s_, 0.0], "axis2": [-s_, c, 0.0]})
    d["fix"] = MINIMAL
    d["output"]["probes"] = {"corner": [2.0, 1.0, 0.5], "edge": [0.0, 1.0, 0.0]}
    r = ff.solve_static(ff.Scene.from_dict(d)).summary()
    compliance_x = c**4 / ORTHO["E1"] + (1 / ORTHO["G12"] - 2 * ORTHO["nu12"] / ORTHO["E1"]) * s_**2 * c**2 \
        + s_**4 / ORTHO["E2"]
    ux = r["probes"]["corner"]["displacement"][0] - r["probes"]["edge"]["displacement"][0]
    assert ux / 2.0 == pytest.approx(compliance_x * SIGMA, rel=1e-9)
    assert abs(r["probes"]["corner"]["displacement"][1]) > 0.1 * abs(ux)          # sheared, not only thinned


def test_two_orthotropic_materials_in_series():
    """A long bar, its halves the same orthotropic material with the fibres along and across the pull: the
    halves stretch by sigma / E1 and sigma / E2 (their lateral mismatch at the joint is local: 1 %)."""
    d = pulled_block({}, SIGMA)
    d["mesh"] = {"size": [2.0, 0.1, 0.1], "cells": [40, 2, 2]}
    d["load"][0]["where"] = {"axis": "x", "at": 2.0}
    d["fix"] = [dict(MINIMAL[0]), {"where": {"point": [0.0, 0.0, 0.0]}, "components": ["y", "z"]},
                {"where": {"point": [0.0, 0.1, 0.0]}, "components": ["z"]}]
    d["material"] = [{"name": "along", "model": "orthotropic", **ORTHO, "axis1": [1, 0, 0], "axis2": [0, 1, 0]},
                     {"name": "across", "model": "orthotropic", **ORTHO, "axis1": [0, 1, 0], "axis2": [1, 0, 0],
                      "where": {"box": [[1.0, 0.0, 0.0], [2.0, 0.1, 0.1]]}}]
    d["output"]["probes"] = {"corner": [2.0, 0.1, 0.1]}
    r = ff.solve_static(ff.Scene.from_dict(d)).summary()
    ux = r["probes"]["corner"]["displacement"][0]
    assert ux == pytest.approx(SIGMA * (1 / ORTHO["E1"] + 1 / ORTHO["E2"]), rel=0.01)


@pytest.mark.parametrize("change, message", [
    ({"nu12": 1.3}, r"\|nu12\| must be below sqrt\(E1 / E2\)"),
    ({"E1": 1e9, "E2": 1e9, "E3": 1e9, "nu12": 0.7, "nu13": 0.7, "nu23": 0.7}, "indefinite"),
    ({"G13": 0.0}, "G13 = 0.0: must be positive"),
    ({"axis2": [1.0, 1.0, 0.0]}, "must be perpendicular to axis1"),
    ({"E": 1e9}, "not for model = 'orthotropic'"),
])
def test_orthotropic_constants_that_are_not_positive_definite_are_refused(change, message):
    material = {"model": "orthotropic", **ORTHO, "axis1": [1, 0, 0], "axis2": [0, 1, 0], **change}
    with pytest.raises(InputError, match=message):
        ff.solve_static(ff.Scene.from_dict(pulled_block(material)))


E_M, NU_M, E_F = 1.0e6, 0.3, 4.0e6


@pytest.mark.parametrize("kind", ["holzapfel", "quadratic"])
def test_a_bar_is_stiff_along_its_fibres_and_soft_across(kind):
    sigma = 50.0                                                   # strain 1e-5: small-strain closed forms
    along = strains({"model": "neo-hookean", "E": E_M, "nu": NU_M,
                     "fibers": {"direction": [1.0, 0.0, 0.0], "E": E_F, "model": kind}}, sigma)
    assert along[0] == pytest.approx(sigma / (E_M + E_F), rel=1e-4)
    assert along[1] == pytest.approx(-NU_M * sigma / (E_M + E_F), rel=1e-4)
    across = strains({"model": "neo-hookean", "E": E_M, "nu": NU_M,
                      "fibers": {"direction": [0.0, 1.0, 0.0], "E": E_F, "model": kind}}, sigma)
    assert across[0] == pytest.approx(sigma / E_M, rel=1e-4)       # fibres along y shorten: inactive


def test_fibres_stiffen_the_layers_they_reinforce_in_tension_only():
    """The cantilever of test_materials, all soft (nu = 0), with fibres along x in some layers:
    - a sandwich whose outer thirds are reinforced, stretched along x by its ends, pulls back with
      strain (E_soft + 2/3 E_f) B H (each layer carries its share);
    - fibres in the lower half, which the tip load shortens, carry nothing: the beam bends as a homogeneous
      soft one, P L^3 / (3 E_soft B H^3 / 12)."""
    from system import test_materials as tm
    fibers = {"direction": [1.0, 0.0, 0.0], "E": E_F}
    soft = {"model": "neo-hookean", "E": tm.E_SOFT, "nu": 0.0, "rho": 1000.0}
    d = tm.layered(cells=(8, 1, 6))
    d["material"] = [{"name": "core", **soft},
                     {"name": "skin_low", **soft, "fibers": fibers,
                      "where": {"box": [[0, 0, 0], [tm.L, tm.B, tm.H / 3]]}},
                     {"name": "skin_high", **soft, "fibers": fibers,
                      "where": {"box": [[0, 0, 2 * tm.H / 3], [tm.L, tm.B, tm.H]]}}]
    strain = 1e-4
    d["load"] = []
    d["fix"].append({"name": "pull", "where": {"axis": "x", "at": tm.L}, "value": [strain * tm.L, 0.0, 0.0]})
    s = ff.solve_static(ff.Scene.from_dict(d)).summary()
    force = strain * (tm.E_SOFT + 2 / 3 * E_F) * tm.B * tm.H           # plane sections: every layer at `strain`
    assert s["reactions"]["pull"][0] == pytest.approx(force, rel=1e-4)
    d = tm.layered("neo-hookean", "neo-hookean")
    d["material"][1].update({"E": tm.E_SOFT, "fibers": fibers})
    s = ff.solve_static(ff.Scene.from_dict(d)).summary()
    EI_soft = tm.E_SOFT * tm.B * tm.H ** 3 / 12
    assert -s["probes"]["tip"]["displacement"][2] == pytest.approx(tm.P * tm.L ** 3 / (3 * EI_soft), rel=0.01)


def fibre_field_bar(path, direction_of) -> str:
    """A 2 x 0.1 x 0.1 m bar of tetrahedra as VTU with a cell field "fibers": direction_of(centroid x)."""
    import meshio
    from dolfinx import mesh as dmesh
    from mpi4py import MPI
    m = dmesh.create_box(MPI.COMM_SELF, [[0.0, 0.0, 0.0], [2.0, 0.1, 0.1]], [40, 2, 2])
    cells = m.geometry.dofmap.array.reshape(-1, 4)
    x = m.geometry.x
    fibers = np.array([direction_of(x[c].mean(axis=0)[0]) for c in cells], dtype=float)
    meshio.write(str(path), meshio.Mesh(x, [("tetra", cells)], cell_data={"fibers": [fibers]}))
    return str(path)


def test_fibre_directions_read_from_a_cell_field_of_the_mesh_file(tmp_path):
    """fibers.group_field: each cell's direction from the mesh file (VTU cell data). The bar's left half has
    its fibres along the pull, its right half across: the halves stretch by sigma / (E_m + E_f) and sigma / E_m
    (the joint's lateral mismatch is local: 1 %); the field all along x gives the constant direction's answer."""
    sigma = 50.0
    def run(direction_of, name):
        d = pulled_block({"model": "neo-hookean", "E": E_M, "nu": NU_M,
                          "fibers": {"group_field": "fibers", "E": E_F}}, sigma)
        d["mesh"] = {"generator": "file", "file": fibre_field_bar(tmp_path / name, direction_of)}
        d["load"][0]["where"] = {"axis": "x", "at": 2.0}
        d["fix"] = [dict(MINIMAL[0]), {"where": {"point": [0.0, 0.0, 0.0]}, "components": ["y", "z"]},
                    {"where": {"point": [0.0, 0.1, 0.0]}, "components": ["z"]}]
        d["output"]["probes"] = {"corner": [2.0, 0.1, 0.1]}
        return ff.solve_static(ff.Scene.from_dict(d)).summary()["probes"]["corner"]["displacement"][0]
    halves = run(lambda x: [1.0, 0.0, 0.0] if x < 1.0 else [0.0, 1.0, 0.0], "halves.vtu")
    assert halves == pytest.approx(sigma * (1 / (E_M + E_F) + 1 / E_M), rel=0.01)
    along = run(lambda x: [2.0, 0.0, 0.0], "along.vtu")                    # any length: made a unit vector
    assert along == pytest.approx(2 * sigma / (E_M + E_F), rel=1e-4)


def test_a_missing_cell_field_is_refused_in_one_line():
    d = pulled_block({"model": "neo-hookean", "E": E_M, "nu": NU_M, "fibers": {"group_field": "fibers", "E": E_F}})
    with pytest.raises(InputError, match="fibers.group_field = 'fibers': the mesh file has no such cell field"):
        ff.solve_static(ff.Scene.from_dict(d))


@pytest.mark.mpi
def test_a_fibre_cell_field_gives_the_serial_answer_on_two_ranks(tmp_path):
    """Each rank's cells take their rows of the file's field (by the cells' original index)."""
    import json
    from helpers import mpirun, toml_dumps
    d = pulled_block({"model": "neo-hookean", "E": E_M, "nu": NU_M, "fibers": {"group_field": "fibers", "E": E_F}},
                     50.0)
    d["mesh"] = {"generator": "file", "file": fibre_field_bar(
        tmp_path / "bar.vtu", lambda x: [1.0, 0.0, 0.0] if x < 1.0 else [0.0, 1.0, 0.0])}
    d["load"][0]["where"] = {"axis": "x", "at": 2.0}
    d["fix"] = [dict(MINIMAL[0]), {"where": {"point": [0.0, 0.0, 0.0]}, "components": ["y", "z"]},
                {"where": {"point": [0.0, 0.1, 0.0]}, "components": ["z"]}]
    d["output"]["probes"] = {"corner": [2.0, 0.1, 0.1]}
    serial = ff.solve_static(ff.Scene.from_dict(d)).summary()
    (tmp_path / "scene.toml").write_text(toml_dumps(d))
    p = mpirun(["-m", "fem_forms", "run", str(tmp_path / "scene.toml"), "--out", str(tmp_path / "out"), "-q"])
    assert p.returncode == 0, p.stderr[-2000:]
    two = json.loads((tmp_path / "out" / "results.json").read_text())
    assert two["probes"]["corner"]["displacement"] == pytest.approx(serial["probes"]["corner"]["displacement"],
                                                                    rel=1e-8)
