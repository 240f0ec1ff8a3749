"""A CAD file's faces, numbered, for picking one in a scene (`where = { face = N }`): a table (number, group,
area, centroid, normal of a flat face), faces.json, and faces.png, the part from two opposite sides with every face
in its own colour and its number on it. Written by `fem-forms faces FILE`."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np


def faces_text(faces: list[dict]) -> str:
    """The table a user picks a face from."""
    lines = [f"{'face':>5}  {'group':<20} {'area m^2':>10}  {'centroid m':<32} normal (flat faces), CAD name"]
    for f in faces:
        c = ", ".join(f"{v:.4g}" for v in f["centroid"])
        n = "[" + ", ".join(f"{v:.3g}" for v in f["normal"]) + "]" if "normal" in f else "(curved)"
        name = f"  {f['name']}" if "name" in f else ""
        lines.append(f"{f['face']:>5}  {f['group']:<20} {f['area']:>10.4g}  [{c}]".ljust(72) + f" {n}{name}")
    return "\n".join(lines)


def write_faces(faces: list[dict], triangles: dict, title: str, out: Path) -> None:
    """faces.json and faces.png in `out` (created)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    out.mkdir(parents=True, exist_ok=True)
    (out / "faces.json").write_text(json.dumps({"faces": faces}, indent=1) + "\n")
    colours = plt.get_cmap("tab20")
    every = np.array([p for tris in triangles.values() for tri in tris for p in tri] or [[0.0, 0.0, 0.0]])
    lo, hi = every.min(axis=0), every.max(axis=0)
    centre, half = (lo + hi) / 2, max(float((hi - lo).max()) / 2, 1e-12)
    fig = plt.figure(figsize=(12, 6))
    for k, azim in enumerate((-60, 120)):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        ax.computed_zorder = False                 # the numbers stay on top of the faces
        for i, f in enumerate(faces):
            tris = triangles.get(f["face"]) or []
            if tris:
                ax.add_collection3d(Poly3DCollection(tris, facecolor=colours(i % 20), edgecolor="none", alpha=0.85,
                                                     zorder=1))
            at = np.asarray(f["centroid"]) + 0.04 * half * np.asarray(f.get("normal", (0.0, 0.0, 0.0)))
            ax.text(*at, str(f["face"]), fontsize=9, weight="bold", ha="center", va="center", zorder=10,
                    bbox={"boxstyle": "round,pad=0.15", "fc": "white", "alpha": 0.85, "lw": 0})
        for set_lim, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), centre):
            set_lim(c - half, c + half)
        ax.set_box_aspect((1, 1, 1))
        ax.view_init(elev=25, azim=azim)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_zlabel("z (m)")
        ax.set_title("from the front" if k == 0 else "from the back")
    fig.suptitle(f"{title}: {len(faces)} faces (where = {{ face = N }})")
    fig.tight_layout()
    fig.savefig(out / "faces.png", dpi=110)
    plt.close(fig)
