"""PNG pictures of the deformed part, drawn with Pillow (which matplotlib itself depends on).

Surfaces are drawn as polygons in an orthographic view (painter's order, Lambert shading) on a
canvas twice the output size, then halved (anti-aliasing). No matplotlib: its import and 3D drawing
cost 0.3-0.6 s per run, this picture 0.05-0.15 s (benchmarks/fixed_cost.md). Modal and study
pictures (plots with axes) still use matplotlib.
"""
from __future__ import annotations

from pathlib import Path

from dolfinx import fem
import numpy as np

from fem_forms.output.fields import boundary_surface
from fem_forms.output.marks import mark_rgb, marked_facets
from fem_forms.output.obstacle_shapes import obstacle_surfaces

VIEW = (15.0, -75.0)         # elevation, azimuth in degrees (mplot3d's view_init convention)
# matplotlib's viridis at 0, 1/16, ..., 1 (interpolated linearly: within 0.02 of the full table)
VIRIDIS = np.array([[0.267004, 0.004874, 0.329415], [0.282327, 0.094955, 0.417331], [0.278826, 0.17549, 0.483397],
                    [0.258965, 0.251537, 0.524736], [0.229739, 0.322361, 0.545706], [0.19943, 0.387607, 0.554642],
                    [0.172719, 0.448791, 0.557885], [0.149039, 0.508051, 0.55725], [0.127568, 0.566949, 0.550556],
                    [0.120638, 0.625828, 0.533488], [0.157851, 0.683765, 0.501686], [0.24607, 0.73891, 0.452024],
                    [0.369214, 0.788888, 0.382914], [0.515992, 0.831158, 0.294279], [0.678489, 0.863742, 0.189503],
                    [0.845561, 0.887322, 0.099702], [0.993248, 0.906157, 0.143936]])
SUPERSAMPLE = 2


def viridis(t: np.ndarray) -> np.ndarray:
    """RGBA (n, 4) in [0, 1] for values t in [0, 1]."""
    t = np.clip(np.asarray(t, dtype=float), 0.0, 1.0) * (len(VIRIDIS) - 1)
    rgb = np.stack([np.interp(t, np.arange(len(VIRIDIS)), VIRIDIS[:, c]) for c in range(3)], axis=-1)
    return np.concatenate([rgb, np.ones(rgb.shape[:-1] + (1,))], axis=-1)


def view_axes(elev: float = VIEW[0], azim: float = VIEW[1], up=None) -> tuple[np.ndarray, np.ndarray]:
    """(2, 3) screen axes (right, up) and the unit vector towards the viewer, as in mplot3d, with `up` (the
    direction against gravity; default +z) drawn vertical: elevation and azimuth are taken in the frame
    (e1, e2, up) of upright_frame, (x, y, z) itself for +z."""
    e1, e2, w = upright_frame(up)
    e, a = np.radians(elev), np.radians(azim)
    toward = np.cos(e) * np.cos(a) * e1 + np.cos(e) * np.sin(a) * e2 + np.sin(e) * w
    right = -np.sin(a) * e1 + np.cos(a) * e2
    return np.vstack([right, np.cross(toward, right)]), toward


def scene_up(scene) -> np.ndarray | None:
    """The direction against the scene's gravity (its gravity loads' g summed), or None without gravity."""
    g = sum((np.asarray(ld.g, dtype=float) for ld in scene.load if ld.type == "gravity"), np.zeros(3))
    return -g / np.linalg.norm(g) if np.linalg.norm(g) > 0 else None


def upright_frame(up=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A right-handed orthonormal (e1, e2, up): e1 the x axis made horizontal (the y axis if up is along x),
    so a part laid out along x is seen along its length whatever the gravity; (x, y, z) for up = +z."""
    w = np.array([0.0, 0.0, 1.0]) if up is None else np.asarray(up, dtype=float) / np.linalg.norm(up)
    axis = np.eye(3)[0] if abs(w[0]) < 0.9 else np.eye(3)[1]
    e1 = axis - (axis @ w) * w
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(w, e1), w


def shade(points: np.ndarray, polys: np.ndarray, rgba, toward: np.ndarray) -> np.ndarray:
    """Face colours (one RGBA, or one per face) darkened by the angle between face normal and view
    (Lambert, two-sided: surfaces here are not consistently oriented)."""
    p = points[polys[:, :3]]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    cos = np.abs(n @ toward) / np.maximum(np.linalg.norm(n, axis=1), 1e-300)
    c = np.array(np.broadcast_to(np.asarray(rgba, dtype=float), (len(polys), 4)))
    c[:, :3] *= (0.55 + 0.45 * cos)[:, None]
    return c


def _bytes(rgba) -> np.ndarray:
    return np.clip(np.round(np.atleast_2d(np.asarray(rgba, dtype=float)) * 255), 0, 255).astype(int)


class Canvas:
    """A white RGB picture of width x height pixels, drawn at SUPERSAMPLE times the size."""

    def __init__(self, width: int, height: int):
        from PIL import Image, ImageDraw
        self.s = SUPERSAMPLE
        self.image = Image.new("RGB", (width * self.s, height * self.s), "white")
        self.draw = ImageDraw.Draw(self.image, "RGBA")       # RGBA: fills blend by their alpha
        self._fonts = {}

    def font(self, size: float):
        from PIL import ImageFont
        px = int(round(size * self.s))
        if px not in self._fonts:
            try:
                self._fonts[px] = ImageFont.truetype("DejaVuSans.ttf", px)
            except OSError:
                self._fonts[px] = ImageFont.load_default()
        return self._fonts[px]

    def text(self, xy, s: str, size: float = 13, anchor: str = "mm", fill=(0, 0, 0)) -> None:
        self.draw.text((xy[0] * self.s, xy[1] * self.s), s, font=self.font(size), anchor=anchor, fill=fill)

    def fit(self, box, xy: np.ndarray, pad: float = 0.05):
        """Map 2D view coordinates (spanning the rows of xy) into box = (x0, y0, x1, y1) pixels with equal
        aspect, centred, y up."""
        lo, hi = xy.min(axis=0), xy.max(axis=0)
        span = np.maximum(hi - lo, 1e-300)
        w, h = box[2] - box[0], box[3] - box[1]
        k = (1 - 2 * pad) * min(w / span[0], h / span[1])
        centre = 0.5 * (lo + hi)
        cx, cy = 0.5 * (box[0] + box[2]), 0.5 * (box[1] + box[3])
        return lambda q: np.stack([cx + k * (q[..., 0] - centre[0]), cy - k * (q[..., 1] - centre[1])], axis=-1)

    def surface(self, to_px, points: np.ndarray, polys: np.ndarray, facecolors, outline=None,
                view=None, outward: bool = False) -> None:
        """Polygons of a surface seen from `view`, far ones first. facecolors: one RGBA or one per face
        (values in [0, 1]); outline: RGBA of the edges or None. `outward`: the polygons are a closed
        surface ordered with outward normals, so those facing away are hidden and not drawn (half the
        polygons: the inverse picture 0.12 -> 0.07 s)."""
        screen, toward = view or view_axes()
        if outward:
            p = points[polys[:, :3]]
            front = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]) @ toward > 0
            polys = polys[front]
            if np.ndim(facecolors) == 2 and len(facecolors) == len(front) and len(front) > 1:
                facecolors = np.asarray(facecolors)[front]
        order = np.argsort((points @ toward)[polys].mean(axis=1), kind="stable")
        px = (to_px(points @ screen.T)[polys[order]] * self.s).reshape(len(order), -1).tolist()
        fills = _bytes(facecolors)
        fills = [tuple(f) for f in (fills[order] if len(fills) == len(polys) and len(polys) > 1 else
                                    np.repeat(fills[:1], len(order), axis=0))]
        line = tuple(_bytes(outline)[0]) if outline is not None else None
        polygon = self.draw.polygon
        for q, f in zip(px, fills):
            polygon(q, fill=f, outline=line)

    def colorbar(self, box, vmax: float, label: str, ticks: int = 5) -> None:
        """A vertical viridis bar in box (pixels) from 0 (bottom) to vmax, with tick labels."""
        x0, y0, x1, y1 = box
        n = 64
        for i in range(n):
            c = tuple(_bytes(viridis((i + 0.5) / n))[0])
            ya, yb = y1 - (y1 - y0) * i / n, y1 - (y1 - y0) * (i + 1) / n
            self.draw.rectangle([x0 * self.s, yb * self.s, x1 * self.s, ya * self.s + 1], fill=c)
        self.draw.rectangle([x0 * self.s, y0 * self.s, x1 * self.s, y1 * self.s], outline=(0, 0, 0))
        for k in range(ticks):
            y = y1 - (y1 - y0) * k / (ticks - 1)
            self.draw.line([x1 * self.s, y * self.s, (x1 + 4) * self.s, y * self.s], fill=(0, 0, 0), width=self.s)
            self.text((x1 + 7, y), f"{vmax * k / (ticks - 1):.3g}", 11, anchor="lm")
        self.text((0.5 * (x0 + x1), y0 - 16), label, 12, anchor="mm")

    def triad(self, origin, view=None, length: float = 28) -> None:
        """Small x, y, z arrows of the view at origin (pixels)."""
        screen, _ = view or view_axes()
        for k, name in enumerate("xyz"):
            d = np.array([screen[0, k], -screen[1, k]]) * length
            end = np.asarray(origin) + d
            self.draw.line([*(np.asarray(origin) * self.s), *(end * self.s)], fill=(80, 80, 80), width=self.s)
            self.text(np.asarray(origin) + 1.3 * d, name, 10, fill=(80, 80, 80))

    def save(self, path: Path) -> None:
        self.image.reduce(self.s).save(path)


def picture(path: Path, u: fem.Function, title: str, scale: float = 1.0, up=None, model=None) -> None:
    """PNG of the deformed boundary coloured by displacement magnitude, undeformed outline in grey; `up`
    (against gravity, default +z) drawn vertical; with `model`, its contact obstacles where they are now, in
    translucent grey behind the part, and its supports and loads as translucent patches in report.html's colours
    over it (seen through the part where they face away), both named in the legend."""
    marked = marked_facets(model) if model is not None else []
    surf = boundary_surface(u, None, [facets for _, facets in marked]) if marked else boundary_surface(u)
    if surf is None:
        u.function_space.mesh.comm.barrier()
        return
    X, polys, d = surf[:3]
    x = X + scale * d
    mag = np.linalg.norm(d, axis=1)
    vmax = mag.max() if mag.max() > 0 else 1.0
    view = view_axes(up=up)
    canvas = Canvas(900, 500)
    to_px = canvas.fit((10, 40, 760, 480), np.vstack([X, x]) @ view[0].T)
    shown = obstacle_surfaces(model, x) if model is not None else []
    for name, points, triangles in shown:
        canvas.surface(to_px, points, triangles, (0.55, 0.57, 0.62, 0.35), (0.3, 0.3, 0.35, 0.3), view=view)
    if shown:
        canvas.text((20, 20), "obstacles (grey): " + ", ".join(name for name, _, _ in shown), 11, anchor="lm",
                    fill=(90, 90, 100))
    canvas.surface(to_px, X, polys, (0.6, 0.6, 0.6, 0.08), (0.4, 0.4, 0.4, 0.15), view=view)
    canvas.surface(to_px, x, polys, shade(x, polys, viridis(mag[polys].mean(axis=1) / vmax), view[1]),
                   (0, 0, 0, 0.15), view=view)
    _marks(canvas, to_px, x, polys, surf[3] if marked else None, [label for label, _ in marked], view)
    canvas.colorbar((775, 100, 795, 400), vmax, "|u| [m]")
    canvas.triad((45, 455), view)
    canvas.text((450, 20), title + ("" if scale == 1.0 else f" (displacement x{scale:g})"), 14)
    canvas.save(path)
    u.function_space.mesh.comm.barrier()


def _marks(canvas: Canvas, to_px, x: np.ndarray, polys: np.ndarray, bits, labels: list[str], view) -> None:
    """The supports' and loads' polygons (bit i of `bits` per polygon: labels[i]) as translucent patches in their
    mark colours, over the part, and a legend of coloured squares under the title (as many rows as it needs)."""
    at, row = 160.0, 38.0
    for i, label in enumerate(labels):
        rgb = mark_rgb(i)
        chosen = (bits >> i) & 1 == 1
        if chosen.any():
            canvas.surface(to_px, x, polys[chosen], (*rgb, 0.5), (*rgb, 0.9), view=view)
        width = 22 + 6.5 * len(label)
        if at + width > 760 and at > 160.0:
            at, row = 160.0, row + 15
        canvas.draw.rectangle([at * canvas.s, (row - 5) * canvas.s, (at + 9) * canvas.s, (row + 4) * canvas.s],
                              fill=tuple(int(round(255 * c)) for c in rgb))
        canvas.text((at + 13, row), label, 11, anchor="lm", fill=(60, 60, 60))
        at += width
