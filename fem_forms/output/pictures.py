"""PNG pictures with matplotlib: the deformed part coloured by displacement.

Static and inverse pictures are drawn as 2D polygons in an orthographic view (painter's order,
flat shading) on a bare matplotlib Figure with the Agg canvas: no pyplot and no mplot3d, whose
imports and 3D drawing cost 0.3-0.6 s per run (benchmarks/fixed_cost.md)."""
from __future__ import annotations

from pathlib import Path

from dolfinx import fem
import numpy as np

from fem_forms.output.fields import boundary_surface

VIEW = (15.0, -75.0)         # elevation, azimuth in degrees (mplot3d's view_init convention)


def style_axes(ax, lo: np.ndarray, hi: np.ndarray) -> None:
    """True-proportion 3D axes spanning [lo, hi], with few ticks on short axes, seen from the side."""
    import matplotlib.ticker
    ax.set_xlim(lo[0], hi[0]), ax.set_ylim(lo[1], hi[1]), ax.set_zlim(lo[2], hi[2])
    span = np.maximum(hi - lo, 1e-3 * (hi - lo).max())
    ax.set_box_aspect(span)
    for axis, s in zip((ax.xaxis, ax.yaxis, ax.zaxis), span):
        axis.set_major_locator(matplotlib.ticker.MaxNLocator(max(2, int(6 * s / span.max()))))
    ax.set_xlabel("x [m]"), ax.set_ylabel("y [m]"), ax.set_zlabel("z [m]")
    ax.view_init(elev=15, azim=-75)


def view_axes(elev: float = VIEW[0], azim: float = VIEW[1]) -> tuple[np.ndarray, np.ndarray]:
    """(2, 3) screen axes (right, up) and the unit vector towards the viewer, as in mplot3d."""
    e, a = np.radians(elev), np.radians(azim)
    toward = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    right = np.array([-np.sin(a), np.cos(a), 0.0])
    return np.vstack([right, np.cross(toward, right)]), toward


def figure(width: float, height: float):
    """A matplotlib Figure on the Agg canvas (no pyplot: no global state, cheaper import)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    fig = Figure(figsize=(width, height))
    FigureCanvasAgg(fig)
    return fig


def shade(points: np.ndarray, polys: np.ndarray, rgba, toward: np.ndarray) -> np.ndarray:
    """Face colours (one RGBA, or one per face) darkened by the angle between face normal and view
    (Lambert, two-sided: surfaces here are not consistently oriented)."""
    p = points[polys[:, :3]]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    cos = np.abs(n @ toward) / np.maximum(np.linalg.norm(n, axis=1), 1e-300)
    c = np.array(np.broadcast_to(np.asarray(rgba, dtype=float), (len(polys), 4)))
    c[:, :3] *= (0.55 + 0.45 * cos)[:, None]
    return c


def draw_surface(ax, points: np.ndarray, polys: np.ndarray, facecolors, edgecolor=(0, 0, 0, 0.2),
                 linewidth: float = 0.2, view=None) -> np.ndarray:
    """Polygons of a surface (points (n, 3), polys (m, k)) seen from `view` (screen axes, toward),
    far ones first; returns the 2D points drawn (for the limits)."""
    from matplotlib.collections import PolyCollection
    screen, toward = view or view_axes()
    xy = points @ screen.T
    order = np.argsort((points @ toward)[polys].mean(axis=1), kind="stable")
    fc = facecolors[order] if isinstance(facecolors, np.ndarray) and facecolors.ndim == 2 else facecolors
    ax.add_collection(PolyCollection(xy[polys[order]], facecolors=fc, edgecolors=edgecolor,
                                     linewidths=linewidth))
    return xy


def frame(ax, xy: np.ndarray, view=None) -> None:
    """Equal-aspect limits around the drawn points, no axes box, a small x-y-z triad in a corner."""
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    pad = 0.06 * max((hi - lo).max(), 1e-300)
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_axis_off()
    screen, _ = view or view_axes()
    box = ax.get_position()                       # the triad gets its own small equal-aspect axes
    tri = ax.figure.add_axes([box.x0, box.y0, 0.1 * box.width, 0.1 * box.width * ax.figure.get_figwidth()
                              / ax.figure.get_figheight()])
    tri.set_xlim(-0.3, 1.3), tri.set_ylim(-0.3, 1.3), tri.set_aspect("equal"), tri.set_axis_off()
    for k, name in enumerate("xyz"):
        tri.annotate("", xy=(0.4 + 0.6 * screen[0, k], 0.4 + 0.6 * screen[1, k]), xytext=(0.4, 0.4),
                     arrowprops={"arrowstyle": "->", "lw": 0.8, "color": "0.3"})
        tri.text(0.4 + 0.8 * screen[0, k], 0.4 + 0.8 * screen[1, k], name, fontsize=8, color="0.3",
                 ha="center", va="center")


def picture(path: Path, u: fem.Function, title: str, scale: float = 1.0) -> None:
    """PNG of the deformed boundary coloured by displacement magnitude, undeformed outline in grey."""
    surf = boundary_surface(u)
    if surf is None:
        u.function_space.mesh.comm.barrier()
        return
    from matplotlib import cm, colormaps, colors

    X, polys, d = surf
    x = X + scale * d
    mag = np.linalg.norm(d, axis=1)
    vmax = mag.max() if mag.max() > 0 else 1.0
    fig = figure(9, 5)
    ax = fig.add_axes([0.02, 0.02, 0.8, 0.86])
    view = view_axes()
    xy0 = draw_surface(ax, X, polys, (0.6, 0.6, 0.6, 0.08), (0.4, 0.4, 0.4, 0.15), view=view)
    cmap = colormaps["viridis"]
    rgba = shade(x, polys, cmap(mag[polys].mean(axis=1) / vmax), view[1])
    xy = draw_surface(ax, x, polys, rgba, (0, 0, 0, 0.15), view=view)
    frame(ax, np.vstack([xy0, xy]), view)
    cax = fig.add_axes([0.86, 0.2, 0.025, 0.6])
    fig.colorbar(cm.ScalarMappable(norm=colors.Normalize(0, vmax), cmap=cmap), cax=cax, label="|u| [m]")
    fig.suptitle(title + ("" if scale == 1.0 else f" (displacement x{scale:g})"))
    fig.savefig(path, dpi=100)
    u.function_space.mesh.comm.barrier()
