"""The balance picture marks what the goal means: a rocking (swing) design its rocking circle and centre,
never a support polygon or a toppling angle; a standing one its support polygon and toppling angle; a
floating one its centre of buoyancy, waterline and GM."""
from dolfinx import mesh as dmesh
from mpi4py import MPI
import numpy as np

from fem_forms.output.balance import overlays, panel_title, picture

SWING = {"mass": 0.512, "center_of_mass": [0.0, 0.0, -0.012], "support_polygon": [[0, 0, -0.05], [0.01, 0, -0.05]],
         "toppling_angle_deg": -3.0, "curvature_center": [0.0, 0.0, 0.0], "curvature_radius": 0.05,
         "com_depth_below_center": 0.012}
STAND = {"mass": 1.0, "center_of_mass": [0.5, 0.5, 0.5], "toppling_angle_deg": 45.0, "stands": True,
         "support_polygon": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]}


def test_swing_marks_the_rocking_circle_not_the_support():
    assert overlays(SWING) == ["CoM", "rocking circle", "rocking centre"]
    t = panel_title("carved", SWING)
    assert "R = 50 mm" in t and "CoM 12 mm below the centre" in t and "topple" not in t
    above = dict(SWING, com_depth_below_center=-0.004)
    assert "CoM 4 mm above the centre" in panel_title("solid", above)


def test_stand_marks_its_support_polygon_and_toppling_angle():
    assert overlays(STAND) == ["CoM", "support polygon"]
    assert panel_title("carved", STAND) == "carved: m = 1 kg, topple 45.0 deg"


def test_swim_marks_buoyancy_and_waterline_not_the_support():
    swim = dict(STAND, center_of_buoyancy=[0.5, 0.5, 0.1], waterline=0.2, metacentric_height=0.0128)
    del swim["stands"]                                     # evaluate reports stands for stand and check only
    assert overlays(swim) == ["CoM", "buoyancy", "waterline"]
    assert panel_title("carved", swim) == "carved: m = 1 kg, GM = 12.8 mm"


def test_swing_picture_is_written(tmp_path):
    m = dmesh.create_box(MPI.COMM_WORLD, [[-0.05, -0.05, -0.05], [0.05, 0.05, 0.05]], [2, 2, 2])
    n = m.topology.index_map(3).size_local
    carved = np.zeros(n, dtype=bool)
    carved[: n // 4] = True
    path = tmp_path / "balance.png"
    picture(path, m, carved, dict(SWING, com_depth_below_center=-0.004), SWING, "roly-poly", " (swing)")
    if MPI.COMM_WORLD.rank == 0:
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and path.stat().st_size > 10000
