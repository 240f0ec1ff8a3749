"""The Pillow pictures: the built-in viridis table matches matplotlib's, and a PNG comes out."""
import numpy as np

from fem_forms.output import pictures


def test_viridis_table_matches_matplotlib():
    from matplotlib import colormaps
    t = np.linspace(0.0, 1.0, 257)
    assert np.abs(pictures.viridis(t)[:, :3] - colormaps["viridis"](t)[:, :3]).max() < 0.02


def test_canvas_writes_a_png(tmp_path):
    from PIL import Image
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    tris = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    view = pictures.view_axes()
    canvas = pictures.Canvas(200, 120)
    canvas.surface(canvas.fit((0, 0, 150, 120), pts @ view[0].T), pts, tris,
                   pictures.shade(pts, tris, (0.2, 0.4, 0.8, 1.0), view[1]), (0, 0, 0, 0.3), view=view)
    canvas.colorbar((160, 20, 170, 100), 1.0, "|u| [m]")
    canvas.save(tmp_path / "p.png")
    img = np.asarray(Image.open(tmp_path / "p.png"))
    assert img.shape[:2] == (120, 200) and (img[:, :150] != 255).any()


def test_up_against_gravity_is_drawn_vertical():
    """The screen's up axis is the direction against gravity: +z by default (the view unchanged), +y when
    gravity points along -y (a part lying on its side was drawn so), and any tilted direction too."""
    default, _ = pictures.view_axes()
    np.testing.assert_allclose(pictures.view_axes(up=[0, 0, 1])[0], default, atol=1e-15)
    for up in ([0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.3, -0.4, 0.866]):
        up = np.asarray(up) / np.linalg.norm(up)
        screen, toward = pictures.view_axes(up=up)
        e1, e2, w = pictures.upright_frame(up)
        assert np.allclose(np.cross(e1, e2), w) and np.allclose(w, up)       # right-handed, up on top
        # projected on the screen, `up` points straight up (no sideways part), at the view's elevation
        assert abs(screen[0] @ up) < 1e-12
        assert abs(screen[1] @ up - np.cos(np.radians(pictures.VIEW[0]))) < 1e-12


def test_scene_up_is_against_the_gravity_loads():
    import fem_forms as ff
    from helpers import beam_scene
    scene = ff.Scene.from_dict(beam_scene(load=[{"type": "gravity", "g": [0.0, -9.81, 0.0]}]))
    np.testing.assert_allclose(pictures.scene_up(scene), [0.0, 1.0, 0.0])
    assert pictures.scene_up(ff.Scene.from_dict(beam_scene(load=[]))) is None
