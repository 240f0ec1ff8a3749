"""Meshes through whole solves: gmsh groups as supports and loads against bar theory, a .msh file
with named groups round-tripped, a meshio hexahedral file against the built-in box."""
import numpy as np
import pytest
from mpi4py import MPI

import fem_forms as ff
from fem_forms.meshes import load_mesh
from helpers import beam_scene, mesh_volume as volume


def test_cylinder_groups_select_supports_and_a_gmsh_file_round_trips(tmp_path):
    """Clamp the cylinder's 'bottom' group, pull its 'top' group: axial stretch as in a bar."""
    scene = ff.Scene.from_dict(beam_scene(
        mesh={"generator": "cylinder", "radius": 0.05, "height": 0.5, "h": 0.025},
        material={"model": "neo-hookean", "E": 1e6, "nu": 0.0, "rho": 1000.0},
        discretization={"degree": 1},
        fix=[{"where": {"group": "bottom"}}],
        load=[{"type": "traction", "where": {"group": "top"}, "value": [0.0, 0.0, 1e3]}],
        output={"probes": {"top": [0.0, 0.0, 0.5]}}))
    res = ff.solve_static(scene)
    assert res.report.converged
    # neo-Hookean, nu = 0: lateral contraction free, small strain ~ T/E = 1e-3 over 0.5 m (clamped end
    # restrains contraction near the base, so allow 3 %)
    assert res.probes["top"][2] == pytest.approx(1e3 / 1e6 * 0.5, rel=0.03)

    # write the same geometry as a .msh with named groups and read it back through mesh.file
    import gmsh
    if MPI.COMM_WORLD.rank == 0:
        gmsh.initialize()
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.occ.addBox(0, 0, 0, 1, 0.2, 0.2)
        gmsh.model.occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [1], 1)
        left = [t for _, t in gmsh.model.getEntities(2) if gmsh.model.getBoundingBox(2, t)[3] < 1e-5]
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, left, 5), "wall")
        gmsh.option.setNumber("Mesh.CharacteristicLengthMax", 0.1)
        gmsh.model.mesh.generate(3)
        gmsh.write(str(tmp_path / "box.msh"))
        gmsh.finalize()
    scene2 = ff.Scene.from_dict(beam_scene(
        mesh={"generator": "file", "file": str(tmp_path / "box.msh")},
        fix=[{"where": {"group": "wall"}}], output={"probes": {}}))
    loaded = load_mesh(scene2.mesh)
    assert "wall" in loaded.groups
    assert volume(loaded.mesh) == pytest.approx(0.04, rel=1e-12)


def test_meshio_file_with_hexahedra_matches_the_built_in_box(tmp_path):
    """The same hexahedral beam from a .vtu file and from the built-in box gives the same tip sag."""
    import meshio
    nx, ny, nz, L, h = 8, 2, 2, 1.0, 0.1
    xs, ys, zs = np.linspace(0, L, nx + 1), np.linspace(0, h, ny + 1), np.linspace(0, h, nz + 1)
    pts = np.array([[x, y, z] for z in zs for y in ys for x in xs])
    idx = lambda i, j, k: i + (nx + 1) * (j + (ny + 1) * k)  # noqa: E731
    hexes = [[idx(i, j, k), idx(i + 1, j, k), idx(i + 1, j + 1, k), idx(i, j + 1, k),
              idx(i, j, k + 1), idx(i + 1, j, k + 1), idx(i + 1, j + 1, k + 1), idx(i, j + 1, k + 1)]
             for k in range(nz) for j in range(ny) for i in range(nx)]
    meshio.write(tmp_path / "beam.vtu", meshio.Mesh(pts, [("hexahedron", np.array(hexes))]))
    common = dict(material={"model": "neo-hookean", "E": 1e7, "nu": 0.3, "rho": 1000.0},
                  discretization={"degree": 2})
    a = ff.solve_static(ff.Scene.from_dict(beam_scene(
        mesh={"generator": "file", "file": str(tmp_path / "beam.vtu")}, **common)))
    b = ff.solve_static(ff.Scene.from_dict(beam_scene(
        mesh={"generator": "box", "size": [L, h, h], "cells": [nx, ny, nz], "cell": "hexahedron"}, **common)))
    assert a.report.converged and b.report.converged
    np.testing.assert_allclose(a.probes["tip"], b.probes["tip"], rtol=1e-9, atol=1e-12)
    assert a.probes["tip"][2] < -1e-3
