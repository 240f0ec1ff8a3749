"""STL and other surface meshes in: closed surfaces written here (a bar, a cylinder) are filled with
tetrahedra by gmsh and solved; the meshed STL bar sags as the natively meshed bar; open surfaces are
refused in one line; meshio's warnings stay off the terminal."""
import numpy as np
import pytest

import fem_forms as ff
from fem_forms.errors import InputError
from fem_forms.meshes import load_mesh
from helpers import beam_scene, mesh_volume, run_scene

L, H = 1.0, 0.1


def box_surface(lx, ly, lz):
    """The 12 outward triangles of a box [0, lx] x [0, ly] x [0, lz]."""
    p = np.array([[x, y, z] for z in (0, lz) for y in (0, ly) for x in (0, lx)], dtype=float)
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    return p, np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])


def cylinder_surface(r, height, n=48, layers=8):
    """A closed triangulated cylinder about the z axis, base at z = 0."""
    th = np.linspace(0, 2 * np.pi, n, endpoint=False)
    pts = [[r * np.cos(t), r * np.sin(t), height * k / layers] for k in range(layers + 1) for t in th]
    idx = lambda k, i: k * n + i % n   # noqa: E731
    tris = [tri for k in range(layers) for i in range(n)
            for tri in ((idx(k, i), idx(k, i + 1), idx(k + 1, i + 1)), (idx(k, i), idx(k + 1, i + 1), idx(k + 1, i)))]
    c0, c1 = len(pts), len(pts) + 1
    pts += [[0, 0, 0], [0, 0, height]]
    tris += [t for i in range(n) for t in ((c0, idx(0, i + 1), idx(0, i)), (c1, idx(layers, i), idx(layers, i + 1)))]
    return np.array(pts, dtype=float), np.array(tris)


def write(path, points, tris):
    import meshio
    meshio.write(path, meshio.Mesh(points, [("triangle", tris)]))
    return path


def bar(mesh) -> dict:
    return beam_scene(mesh=mesh, material={"model": "neo-hookean", "E": 1e8, "nu": 0.3, "rho": 1000.0},
                      discretization={"degree": 2}, output={"probes": {"tip": [L, H / 2, H / 2]},
                                                            "picture": False, "fields": False})


def test_an_stl_bar_sags_as_the_natively_meshed_bar(tmp_path, capsys):
    stl = write(tmp_path / "bar.stl", *box_surface(L, H, H))
    code, data, err, _ = run_scene(tmp_path, bar({"generator": "file", "file": str(stl), "h": 0.025}), capsys)
    assert code == 0, err
    native = ff.solve_static(ff.Scene.from_dict(bar({"generator": "box", "size": [L, H, H], "cells": [40, 4, 4]})))
    assert data["probes"]["tip"]["displacement"][2] == pytest.approx(native.probes["tip"][2], rel=0.03)
    info = data["mesh"]
    assert "bar.stl (surface, 12 triangles) meshed by gmsh" in info["source"]
    assert info["cells"] > 1000 and 0 < info["radius_ratio_min"] <= info["radius_ratio_mean"] < 1


def test_a_cylinder_from_stl_and_from_obj_fills_its_volume(tmp_path):
    r, height = 0.05, 0.5
    pts, tris = cylinder_surface(r, height)
    exact_polygon = 0.5 * 48 * r * r * np.sin(2 * np.pi / 48) * height     # the faceted cylinder
    for name in ("rod.stl", "rod.obj"):
        path = write(tmp_path / name, pts, tris)
        spec = ff.Scene.from_dict(bar({"generator": "file", "file": str(path), "h": 0.0125})).mesh
        loaded = load_mesh(spec)
        assert mesh_volume(loaded.mesh) == pytest.approx(exact_polygon, rel=0.01), name
        assert loaded.info["cells"] > 1000


def test_an_open_surface_is_refused_naming_its_open_edges(tmp_path):
    pts, tris = box_surface(L, H, H)
    stl = write(tmp_path / "open.stl", pts, tris[:-2])            # one face missing: 4 open edges
    with pytest.raises(InputError, match=r"mesh.file = '.*open.stl': the surface is not closed: 4 open edges"):
        load_mesh(ff.Scene.from_dict(bar({"generator": "file", "file": str(stl)})).mesh)


def test_h_is_only_for_surface_files(tmp_path):
    import meshio
    pts, _ = box_surface(1, 1, 1)
    meshio.write(tmp_path / "t.vtu", meshio.Mesh(pts[:4], [("tetra", np.array([[0, 1, 2, 4]]))]))
    with pytest.raises(InputError, match=r"mesh.h: only for surface and CAD files"):
        ff.Scene.from_dict(bar({"generator": "file", "file": str(tmp_path / "t.vtu"), "h": 0.1}))


def test_meshio_warnings_do_not_reach_the_terminal(tmp_path, capfd):
    """A gmsh 2.2 file without physical tags makes meshio warn ("Appending zeros ..."): silent here."""
    import meshio
    from fem_forms.meshes.surfaces import read_meshio
    pts, _ = box_surface(1, 1, 1)
    tets = np.array([[0, 1, 3, 5], [0, 3, 2, 6], [0, 5, 4, 6], [3, 5, 6, 7], [0, 3, 6, 5]])
    p = pts[tets]
    flip = np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0])) < 0
    tets[flip] = tets[flip][:, [0, 2, 1, 3]]
    meshio.write(tmp_path / "plain.msh", meshio.Mesh(pts, [("tetra", tets)]), file_format="gmsh22", binary=False)
    capfd.readouterr()
    m = read_meshio(tmp_path / "plain.msh")
    loaded = load_mesh(ff.Scene.from_dict(bar({"generator": "file", "file": str(tmp_path / "plain.msh")})).mesh)
    out, err = capfd.readouterr()
    assert len(m.cells[0].data) == 5 and mesh_volume(loaded.mesh) == pytest.approx(1.0)
    assert out == "" and err == ""
