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
