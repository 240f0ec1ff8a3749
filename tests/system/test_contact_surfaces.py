"""Contact between triangles (the IPC Toolkit's pairs): obstacles given as surface files and friction between
the part's own pieces, against the references the analytic obstacles meet: a block resting on a table file
carries its weight exactly, with no support; blocks slide on a slope with Coulomb's acceleration
g (sin theta - mu cos theta), down a slope file and down a second solid of the same mesh; one-line refusals."""
import math

import numpy as np
import pytest

from helpers import run_scene
from system.contact_meshes import box_surface, two_blocks
from system.test_contact import block_scene, run
from system.test_contact_dynamics import G, THETA, probe_history, slope_scene

GAP = 5e-4


def table(tmp_path, **keys) -> dict:
    path = box_surface(tmp_path / "table.stl", [-0.2, -0.2, -0.05], [0.3, 0.3, -GAP])
    return {"contact": {"distance": 1e-3, "obstacle": [{"name": "table", "shape": "file", "file": path, **keys}]}}


def test_a_block_rests_on_a_table_file_with_no_support_at_all(tmp_path):
    """The table is two big triangles under the block: its friction holds the sliding, its push the weight."""
    code, r, _, out = run_scene(tmp_path, block_scene(fix=[], **table(tmp_path, friction=0.5)))
    assert code == 0 and r["converged"] and r["intersection_free"]
    assert np.allclose(r["contact"]["table"]["force"], [0.0, 0.0, 9.81], rtol=0, atol=1e-6)   # measured 8e-8 N
    assert r["contact"]["table"]["active_points"] == 7 * 7 and 0 < r["min_distance"] < 1e-3
    assert r["reactions"] == {} and r["equilibrium_error"] < 1e-7        # measured 1e-8


def test_a_block_slides_down_a_slope_file_with_coulombs_acceleration(tmp_path):
    mu = 0.3
    scene = slope_scene(mu)
    path = box_surface(tmp_path / "slope.stl", [-0.2, -0.2, -0.05], [0.4, 0.3, -5e-5])
    scene["contact"]["obstacle"] = [{"name": "slope", "shape": "file", "file": path, "friction": mu}]
    code, r, _, out = run_scene(tmp_path, scene)
    assert code == 0 and r["converged"] and r["intersection_free"]
    h = probe_history(out)
    late = h["time"] > 0.02
    a = 2 * np.polyfit(h["time"][late], h["c_ux"][late], 2)[0]
    assert a == pytest.approx(G * (math.sin(THETA) - mu * math.cos(THETA)), rel=0.03)


@pytest.mark.parametrize("mu", [0.3, 0.7])
def test_a_block_slides_or_sticks_on_a_second_solid_of_the_same_mesh(tmp_path, mu):
    """Self-contact with friction: the cube on the slab (held at its bottom) slides at g (sin - mu cos) when
    tan 30 deg = 0.577 > mu and sticks otherwise."""
    scene = slope_scene(mu)
    scene["mesh"] = {"generator": "file", "file": two_blocks(tmp_path / "blocks.msh", 5e-5, 0.05)}
    scene["fix"] = [{"name": "slab", "where": {"axis": "z", "at": -0.05}}]
    scene["contact"] = {"self": True, "friction": mu, "distance": 1e-4}
    code, r, _, out = run_scene(tmp_path, scene)
    assert code == 0 and r["converged"] and r["intersection_free"]
    h = probe_history(out)
    late = h["time"] > 0.02
    if mu < math.tan(THETA):
        a = 2 * np.polyfit(h["time"][late], h["c_ux"][late], 2)[0]
        assert a == pytest.approx(G * (math.sin(THETA) - mu * math.cos(THETA)), rel=0.03)
    else:
        assert abs(h["c_ux"][-1] - h["c_ux"][late][0]) < 1e-4    # sliding would have moved 9 mm
        assert r["contact"]["self"]["active_points"] >= 9           # the cube still on the slab


def refused(tmp_path, capsys, scene, *fragments):
    code, err, wrote = run(tmp_path, scene, capsys)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and all(f in lines[0] for f in fragments), err
    assert not wrote


def test_an_obstacle_file_with_a_hole_is_refused(tmp_path, capsys):
    path = box_surface(tmp_path / "open.stl", [-0.2, -0.2, -0.05], [0.3, 0.3, -GAP], open_face=True)
    scene = block_scene(**{"contact": {"obstacle": [{"shape": "file", "file": path}]}})
    refused(tmp_path, capsys, scene, "contact.obstacle[0].file = ", "the surface is not closed: 4 open edges")


def test_an_obstacle_file_through_or_around_the_part_is_refused(tmp_path, capsys):
    through = box_surface(tmp_path / "through.stl", [-0.2, -0.2, -0.05], [0.3, 0.3, 0.02])
    refused(tmp_path, capsys, block_scene(**{"contact": {"obstacle": [{"shape": "file", "file": through}]}}),
            "an obstacle file intersects, touches or encloses the part")
    around = box_surface(tmp_path / "around.stl", [-1, -1, -1], [1, 1, 1])
    refused(tmp_path, capsys, block_scene(**{"contact": {"obstacle": [{"shape": "file", "file": around}]}}),
            "an obstacle file intersects, touches or encloses the part")


@pytest.mark.mpi
def test_a_table_file_gives_the_same_answer_on_two_ranks(tmp_path):
    import json
    from helpers import mpirun, toml_dumps
    scene = block_scene(fix=[], **table(tmp_path, friction=0.5))
    (tmp_path / "one").mkdir()
    code, serial, _, _ = run_scene(tmp_path / "one", scene)
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(scene))
    proc = mpirun(["-m", "fem_forms", "run", str(path), "--out", str(tmp_path / "two"), "-q"])
    assert proc.returncode == 0, proc.stderr
    two = json.loads((tmp_path / "two" / "results.json").read_text())
    assert two["mpi_ranks"] == 2 and two["intersection_free"]
    assert np.allclose(two["contact"]["table"]["force"], serial["contact"]["table"]["force"], rtol=0, atol=1e-6)
    assert two["min_distance"] == pytest.approx(serial["min_distance"], rel=1e-6)


def test_a_block_pressed_onto_a_table_file_by_its_top_pushes_back_what_the_press_exerts(tmp_path):
    """The top moved down (a support's increment: the residual's lifting takes the triangle pairs' Hessian): the
    table's force (from the barrier) balances the press's reaction (from the elastic residual)."""
    scene = block_scene(fix=[{"name": "press", "where": {"axis": "z", "at": 0.1}, "value": [0.0, 0.0, -0.002]}],
                        load=[], **table(tmp_path, friction=0.5))
    scene["solver"] = {"steps": 2}
    code, r, _, _ = run_scene(tmp_path, scene)
    assert code == 0 and r["converged"] and r["intersection_free"]
    force, press = np.array(r["contact"]["table"]["force"]), np.array(r["reactions"]["press"])
    assert np.allclose(force, -press, rtol=0, atol=1e-6 * abs(force[2])) and force[2] > 0
