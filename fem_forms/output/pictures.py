"""PNG pictures with matplotlib: the deformed part coloured by displacement."""
from __future__ import annotations

from pathlib import Path

from dolfinx import fem
import numpy as np

from fem_forms.output.fields import boundary_surface


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


def picture(path: Path, u: fem.Function, title: str, scale: float = 1.0) -> None:
    """PNG of the deformed boundary coloured by displacement magnitude, undeformed outline in grey."""
    surf = boundary_surface(u)
    if surf is None:
        u.function_space.mesh.comm.barrier()
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    X, polys, d = surf
    x = X + scale * d
    mag = np.linalg.norm(d, axis=1)
    fig = plt.figure(figsize=(9, 6))
    ax = fig.add_subplot(projection="3d")
    ax.add_collection3d(Poly3DCollection(X[polys], facecolor=(0.6, 0.6, 0.6, 0.08),
                                         edgecolor=(0.4, 0.4, 0.4, 0.15), linewidths=0.2))
    cmap = plt.get_cmap("viridis")
    vmax = mag.max() if mag.max() > 0 else 1.0
    faces = Poly3DCollection(x[polys], facecolors=cmap(mag[polys].mean(axis=1) / vmax),
                             edgecolor=(0, 0, 0, 0.15), linewidths=0.2)
    ax.add_collection3d(faces)
    allp = np.vstack([X, x])
    style_axes(ax, allp.min(axis=0), allp.max(axis=0))
    sm = plt.cm.ScalarMappable(cmap=cmap, norm=plt.Normalize(0, vmax))
    fig.colorbar(sm, ax=ax, shrink=0.6, label="|u| [m]")
    ax.set_title(title + ("" if scale == 1.0 else f" (displacement x{scale:g})"))
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    u.function_space.mesh.comm.barrier()

