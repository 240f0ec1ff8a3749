"""Real-world surfaces (issue 22, item 3): `[mesh] repair = true` closes a punched, dirty sphere whose
tetrahedral volume matches the closed sphere's; without it the open surface exits 2 suggesting repair;
`units`/`scale` turn a part drawn in mm into metres (volume x 1e-9, the same displacement in m);
a real scan (pymeshfix's Stanford bunny, shipped in its wheel) is repaired and meshed."""
import importlib.util
from pathlib import Path

import numpy as np
import pytest

import fem_forms as ff
from fem_forms.errors import InputError
from fem_forms.meshes import load_mesh
from helpers import beam_scene, mesh_volume, run_scene
from system.test_surface_meshes import box_surface, write

R = 0.05


def icosphere(r: float, levels: int = 3):
    """A closed, outward triangulated sphere: an icosahedron split `levels` times, points on radius r."""
    t = (1 + 5 ** 0.5) / 2
    p = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
         [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    f = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2],
         [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11],
         [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    pts = [np.array(q, float) / np.linalg.norm(q) for q in p]
    for _ in range(levels):
        mid, new = {}, []
        for a, b, c in f:
            m = []
            for i, j in ((a, b), (b, c), (c, a)):
                if (min(i, j), max(i, j)) not in mid:
                    q = pts[i] + pts[j]
                    pts.append(q / np.linalg.norm(q))
                    mid[(min(i, j), max(i, j))] = len(pts) - 1
                m.append(mid[(min(i, j), max(i, j))])
            new += [[a, m[0], m[2]], [b, m[1], m[0]], [c, m[2], m[1]], m]
        f = new
    return r * np.array(pts), np.array(f)


def polyhedron_volume(pts, tris):
    """Volume of a closed outward triangulation: tetrahedra from the origin (the reference)."""
    return sum(np.linalg.det(pts[t]) for t in tris) / 6.0


def dirty_sphere(tmp_path):
    """The sphere with three holes punched (faces removed), 8 duplicate faces (4 reversed) and 4
    collapsed faces (two equal corners): (STL path, closed volume, triangles in the file)."""
    pts, tris = icosphere(R)
    closed = polyhedron_volume(pts, tris)
    c = pts[tris].mean(axis=1) / R
    holes = np.zeros(len(tris), bool)
    for d in ([1, 0, 0], [0, -1, 0], [0, 0, 1]):
        holes |= c @ np.array(d, float) > 0.985
    kept = tris[~holes]
    dirty = np.vstack([kept, kept[:4], kept[4:8, ::-1], [[t[0], t[0], t[1]] for t in kept[8:12]]])
    with np.errstate(invalid="ignore"):                # meshio's normals of the collapsed faces
        stl = write(tmp_path / "scan.stl", pts, dirty)
    return stl, closed, len(dirty), int(holes.sum())


def sphere_scene(stl, **mesh):
    return beam_scene(mesh={"generator": "file", "file": str(stl), "h": R / 4, **mesh},
                      fix=[{"where": {"axis": "z", "at": -R}}], output={"picture": False, "fields": False})


def test_repair_closes_a_punched_dirty_sphere_to_its_volume(tmp_path):
    stl, closed, n_file, n_holes = dirty_sphere(tmp_path)
    assert n_holes >= 9                                           # three holes of several faces each
    loaded = load_mesh(ff.Scene.from_dict(sphere_scene(stl, repair=True)).mesh)
    assert mesh_volume(loaded.mesh) == pytest.approx(closed, rel=0.02)
    rep = loaded.info["repair"]
    assert rep["holes_filled"] == 3 and rep["faces_before"] == n_file
    assert rep["duplicate_faces"] == 8 and rep["collapsed_faces"] == 4
    assert rep["faces_removed"] >= 12 and rep["volume_before"] is None
    assert rep["volume_after"] == pytest.approx(closed, rel=0.02)
    assert "repaired surface" in loaded.info["source"]


def test_without_repair_the_open_surface_exits_2_suggesting_repair(tmp_path, capsys):
    stl, *_ = dirty_sphere(tmp_path)
    code, data, err, out = run_scene(tmp_path, sphere_scene(stl), capsys)
    assert code == 2 and data is None
    assert "the surface is not closed" in err
    assert "set [mesh] repair = true to fill holes and remove bad faces (help: fem-forms help mesh" in err, err
    assert err.strip().endswith("(help: fem-forms help mesh.file)") or err.strip().endswith("#key-mesh.file)"), err


def test_repair_is_refused_on_other_generators_and_on_volume_files(tmp_path):
    with pytest.raises(InputError, match=r"^mesh.repair: only for generator = 'file'"):
        ff.Scene.from_dict(beam_scene(mesh={"generator": "box", "repair": True}))
    import meshio
    pts, _ = box_surface(1, 1, 1)
    meshio.write(tmp_path / "t.vtu", meshio.Mesh(pts[:4], [("tetra", np.array([[0, 1, 2, 4]]))]))
    with pytest.raises(InputError, match=r"^mesh.repair: only for surface files"):
        ff.Scene.from_dict(beam_scene(mesh={"generator": "file", "file": str(tmp_path / "t.vtu"), "repair": True}))


def test_scale_and_units_together_are_refused(tmp_path):
    stl = write(tmp_path / "b.stl", *box_surface(1, 1, 1))
    with pytest.raises(InputError, match=r"^mesh.units: give scale or units, not both"):
        ff.Scene.from_dict(beam_scene(mesh={"generator": "file", "file": str(stl), "scale": 0.001, "units": "mm"}))
    with pytest.raises(InputError, match=r"^mesh.scale = -1"):
        ff.Scene.from_dict(beam_scene(mesh={"generator": "file", "file": str(stl), "scale": -1}))


def block(stl, **mesh):
    """A 100 x 20 x 20 mm block clamped at x = 0 under gravity, sizes in metres."""
    return beam_scene(mesh={"generator": "file", "file": str(stl), "h": 0.005, **mesh},
                      material={"model": "neo-hookean", "E": 1e6, "nu": 0.3, "rho": 1000.0},
                      output={"probes": {"tip": [0.1, 0.01, 0.01]}, "picture": False, "fields": False})


def test_a_block_in_mm_is_the_block_in_m(tmp_path, capsys):
    mm = write(tmp_path / "mm.stl", *box_surface(100.0, 20.0, 20.0))
    m = write(tmp_path / "m.stl", *box_surface(0.1, 0.02, 0.02))
    v_m = mesh_volume(load_mesh(ff.Scene.from_dict(block(m)).mesh).mesh)
    v_raw = mesh_volume(load_mesh(ff.Scene.from_dict(block(mm, h=5.0)).mesh).mesh)   # the file as it is, in mm
    v_mm = mesh_volume(load_mesh(ff.Scene.from_dict(block(mm, units="mm")).mesh).mesh)
    assert v_m == pytest.approx(0.1 * 0.02 * 0.02, rel=1e-9)
    assert v_mm == pytest.approx(v_raw * 1e-9, rel=1e-9) and v_mm == pytest.approx(v_m, rel=1e-9)
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    code_m, res_m, err, _ = run_scene(tmp_path / "a", block(m), capsys)
    code_mm, res_mm, err, _ = run_scene(tmp_path / "b", block(mm, scale=0.001), capsys)
    assert code_m == 0 and code_mm == 0, err
    u_m, u_mm = res_m["probes"]["tip"]["displacement"], res_mm["probes"]["tip"]["displacement"]
    assert abs(u_m[2]) > 1e-5 and u_mm == pytest.approx(u_m, rel=1e-6, abs=1e-12)
    assert res_mm["mesh"]["scale"] == 0.001


def test_a_volume_mesh_in_mm_is_scaled(tmp_path):
    import meshio
    pts, _ = box_surface(10.0, 10.0, 10.0)                         # a 10 mm cube of five tetrahedra
    tets = np.array([[0, 1, 3, 5], [0, 3, 2, 6], [0, 5, 4, 6], [3, 5, 6, 7], [0, 3, 6, 5]])
    p = pts[tets]
    flip = np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0])) < 0
    tets[flip] = tets[flip][:, [0, 2, 1, 3]]
    meshio.write(tmp_path / "cube.vtu", meshio.Mesh(pts, [("tetra", tets)]))
    loaded = load_mesh(ff.Scene.from_dict(beam_scene(mesh={"generator": "file", "file": str(tmp_path / "cube.vtu"),
                                                           "units": "mm"})).mesh)
    assert mesh_volume(loaded.mesh) == pytest.approx(1e-6, rel=1e-9)


def test_a_real_scan_the_stanford_bunny_is_repaired_and_meshed(tmp_path):
    """pymeshfix's wheel ships a Stanford bunny scan (50,000 points, holes in its base): in mm."""
    bunny = Path(importlib.util.find_spec("pymeshfix").submodule_search_locations[0]) / "examples" / "StanfordBunny.ply"
    assert bunny.exists()
    scene = beam_scene(mesh={"generator": "file", "file": str(bunny), "units": "mm", "h": 0.005},
                       fix=[{"where": {"axis": "z", "at": 0.0}}], output={"picture": False, "fields": False})
    with pytest.raises(InputError, match=r"the surface is not closed: 353 open edges.*repair = true"):
        load_mesh(ff.Scene.from_dict(scene).mesh)
    scene["mesh"]["repair"] = True
    loaded = load_mesh(ff.Scene.from_dict(scene).mesh)
    rep = loaded.info["repair"]
    assert rep["holes_filled"] == 71 and rep["faces_before"] == 99785 and rep["volume_before"] is None
    assert rep["faces_after"] > rep["faces_before"]                # holes patched with new triangles
    assert rep["volume_after"] == pytest.approx(2.4956e-5, rel=1e-3)
    # h = 5 mm on a 50 mm bunny: straight chords cut its curved surface (4 % measured)
    assert mesh_volume(loaded.mesh) == pytest.approx(rep["volume_after"], rel=0.06)
