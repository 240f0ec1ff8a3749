"""Balance outputs: the void and the outer surface as closed STL files, the density as a DG0 XDMF field,
and one picture of the part before and after carving (CoM, and support polygon, axis, centre of buoyancy
or rocking circle by goal)."""
from __future__ import annotations

from pathlib import Path

from mpi4py import MPI
import numpy as np

from fem_forms.frames import ground_frame
from fem_forms.meshes.cell_faces import surface_triangles
from fem_forms.output.fields import cell_function, gather_mesh, write_fields
from fem_forms.output.stl import write_stl

def write_outputs(out: Path, mesh, density: np.ndarray, carved: np.ndarray, shift=None) -> dict:
    """void.stl, outer.stl (rank 0, from the gathered mesh), density.xdmf, and when cells were carved
    solid.vtu (the cells left solid: the part as built, a mesh any analysis can load); their names."""
    write_fields(out / "density.xdmf", mesh, [cell_function(mesh, density, "density")])
    flags = mesh.comm.gather(carved, root=0)
    any_carved = mesh.comm.allreduce(bool(carved.any()), op=MPI.LOR)
    g = gather_mesh(mesh)
    if mesh.comm.rank == 0:
        points, cells, _ = g
        carved_all = np.concatenate(flags)
        write_stl(out / "outer.stl", points, surface_triangles(cells), "outer surface")
        void = surface_triangles(cells[carved_all]) if carved_all.any() else np.empty((0, 3), dtype=np.int64)
        # the void's faces, turned to point into the void (outward normals of the solid that remains)
        write_stl(out / "void.stl", points, void[:, ::-1], "carved void")
        if any_carved:
            import meshio
            kind = "tetra" if cells.shape[1] == 4 else "hexahedron"
            meshio.write(out / "solid.vtu", meshio.Mesh(points, [(kind, cells[~carved_all])]))
    mesh.comm.barrier()
    files = {"density": "density.xdmf", "outer_surface": "outer.stl", "void_surface": "void.stl"}
    return files | ({"solid_mesh": "solid.vtu"} if any_carved else {})


def overlays(nums: dict) -> list[str]:
    """What a panel marks besides the part, from its numbers: a rocking design (swing) its rocking circle
    and centre (a toppling angle and support polygon mean nothing for a toy that rolls on its dome); a
    standing one (stand, check) its support polygon; a floating one its centre of buoyancy and waterline;
    a top its spin axis."""
    marks = ["CoM"]
    if "curvature_center" in nums:
        return marks + ["rocking circle", "rocking centre"]
    if "stands" in nums and len(nums.get("support_polygon") or []) >= 2:
        marks.append("support polygon")
    if (nums.get("center_of_buoyancy") or [None])[0] is not None:
        marks += ["buoyancy", "waterline"]
    if "tip" in nums:
        marks.append("spin axis")
    return marks


def panel_title(label: str, nums: dict) -> str:
    """The panel's headline: mass and the goal's own measure of balance."""
    t = f"{label}: m = {nums['mass']:.4g} kg"
    if "curvature_center" in nums:
        d = nums["com_depth_below_center"]
        return t + (f", R = {1e3 * nums['curvature_radius']:.3g} mm, CoM {1e3 * abs(d):.3g} mm "
                    f"{'below' if d > 0 else 'above'} the centre")
    if "metacentric_height" in nums:
        return t + f", GM = {1e3 * nums['metacentric_height']:.3g} mm"
    ang = nums.get("toppling_angle_deg")
    return t + (f", topple {ang:.1f} deg" if ang is not None else "")


def _rocking(ax, nums: dict, up: np.ndarray) -> None:
    """The rocking circle (the fitted sphere's section in a vertical plane, its lower half: the surface
    the part rolls on), its centre, and the vertical from the centre to the ground."""
    c, R = np.asarray(nums["curvature_center"]), nums["curvature_radius"]
    side = np.cross(up, [0.0, 1.0, 0.0] if abs(up[1]) < 0.9 else [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    t = np.linspace(-np.pi / 2, np.pi / 2, 61)
    arc = c + R * (np.sin(t)[:, None] * side - np.cos(t)[:, None] * up)
    ax.plot(*arc.T, color="tab:green", lw=1.5, label="rocking circle")
    ax.plot(*np.stack([c, c - R * up]).T, color="tab:green", lw=0.8, ls=":")
    ax.scatter(*c, color="tab:green", s=40, depthshade=False, label="rocking centre")


def picture(path: Path, mesh, carved: np.ndarray, before: dict, after: dict, title: str,
            extra: str = "", sag: np.ndarray | None = None, up: np.ndarray | None = None,
            check: bool = False, labels: tuple = ("rigid", "sagged")) -> None:
    """Two panels, each with the marks `overlays` names (CoM, support polygon, axis, buoyancy and waterline,
    or rocking circle): the part solid and carved; or, given the sag (displacement per local geometry node,
    elastic = true), the design rigid and sagged; one panel for a `check` (nothing carved). `up`: against
    gravity (default +z), drawn vertical. `labels`: the two panels' names with a sag."""
    flags = mesh.comm.gather(carved, root=0)
    g = gather_mesh(mesh)
    gs = gather_mesh(mesh, sag) if sag is not None else None
    if mesh.comm.rank != 0:
        mesh.comm.barrier()
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    up = np.array([0.0, 0.0, 1.0]) if up is None else np.asarray(up, dtype=float)
    points, cells, _ = g
    outer = surface_triangles(cells)
    carved_all = np.concatenate(flags)
    void = surface_triangles(cells[carved_all]) if carved_all.any() else None
    panels = [("solid", before, False, points), ("carved", after, True, points)]
    if gs is not None:
        panels = [(labels[0], after, True, points), (labels[1], after["deformed"], True, gs[0])]
    elif check:                                    # goal "check": nothing carved, one panel says it all
        panels = [("as it is", after, False, points)]
    fig = plt.figure(figsize=(11 if len(panels) == 2 else 6, 5.5))
    lo = np.min([p[3].min(axis=0) for p in panels], axis=0)
    hi = np.max([p[3].max(axis=0) for p in panels], axis=0)
    for k, (label, nums, show_void, points) in enumerate(panels):
        ax = fig.add_subplot(1, len(panels), k + 1, projection="3d")
        ax.computed_zorder = False                  # the marks drawn over the surfaces, never hidden in the void
        ax.plot_trisurf(points[:, 0], points[:, 1], points[:, 2], triangles=outer, color=(0.7, 0.7, 0.75, 0.15),
                        edgecolor=(0.3, 0.3, 0.3, 0.05), linewidth=0.1)
        if show_void and void is not None and len(void):
            ax.plot_trisurf(points[:, 0], points[:, 1], points[:, 2], triangles=void, color=(0.9, 0.4, 0.2, 0.5),
                            linewidth=0)
        c = np.asarray(nums["center_of_mass"])
        ax.scatter(*c, color="k", s=40, depthshade=False, label="CoM")
        marks = overlays(nums)
        if "rocking circle" in marks:
            _rocking(ax, nums, up)
        if "support polygon" in marks:
            poly = np.asarray(nums["support_polygon"])
            loop = np.vstack([poly, poly[:1]])
            ax.plot(loop[:, 0], loop[:, 1], loop[:, 2], color="tab:blue", lw=2, label="support polygon")
            down = c - float((c - poly.mean(axis=0)) @ up) * up      # the plumb line from the CoM
            ax.plot(*np.stack([c, down]).T, "k--", lw=1)
        if "buoyancy" in marks:
            ax.scatter(*nums["center_of_buoyancy"], color="tab:cyan", s=40, label="buoyancy")
            _waterline(ax, points, up, nums["waterline"])
        if "spin axis" in marks:
            a = np.asarray(nums["spin_axis"])
            t = np.asarray(nums["tip"])
            L = np.ptp(points, axis=0).max()
            ax.plot(*np.stack([t, t + L * a]).T, color="tab:red", lw=1.5, label="spin axis")
        marked = _marked_points(nums)
        _style_axes(ax, np.minimum(lo, marked.min(axis=0)), np.maximum(hi, marked.max(axis=0)), up)
        ax.set_title(panel_title(label, nums), fontsize=9)
        ax.legend(loc="upper left", fontsize=7)
    fig.suptitle(title + extra)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    mesh.comm.barrier()


def _waterline(ax, points: np.ndarray, up: np.ndarray, waterline: float) -> None:
    """The water surface: the part's horizontal bounding rectangle at `waterline` above its lowest point."""
    _, e1, e2 = ground_frame(-up)
    h = points @ up
    a, b = points @ e1, points @ e2
    level = h.min() + waterline
    box = [(a.min(), b.min()), (a.max(), b.min()), (a.max(), b.max()), (a.min(), b.max()), (a.min(), b.min())]
    loop = np.array([level * up + u * e1 + v * e2 for u, v in box])
    ax.plot(*loop.T, color="tab:cyan", lw=1.5, label="waterline")


def _marked_points(nums: dict) -> np.ndarray:
    """The points the marks must show besides the part (the rocking centre may lie above a squat toy)."""
    return np.array([nums["center_of_mass"]] + ([nums["curvature_center"]] if "curvature_center" in nums else []),
                    dtype=float)


def _style_axes(ax, lo: np.ndarray, hi: np.ndarray, up: np.ndarray) -> None:
    """True-proportion 3D matplotlib axes spanning [lo, hi], few ticks on short axes, seen from the side with
    the coordinate axis closest to `up` (against gravity) drawn vertical and pointing up."""
    import matplotlib.ticker
    ax.set_xlim(lo[0], hi[0]), ax.set_ylim(lo[1], hi[1]), ax.set_zlim(lo[2], hi[2])
    span = np.maximum(hi - lo, 1e-3 * (hi - lo).max())
    k = int(np.argmax(np.abs(up)))
    # matplotlib 3.6 rolls the box aspect by (vertical axis - 2) before use: roll it back so x, y, z keep
    # their true proportions whichever axis is vertical
    ax.set_box_aspect(np.roll(span, 2 - k))
    for axis, s in zip((ax.xaxis, ax.yaxis, ax.zaxis), span):
        axis.set_major_locator(matplotlib.ticker.MaxNLocator(max(2, int(6 * s / span.max()))))
    ax.set_xlabel("x [m]"), ax.set_ylabel("y [m]"), ax.set_zlabel("z [m]")
    ax.view_init(elev=15, azim=-75, vertical_axis="xyz"[k])
    if up[k] < 0:                                    # gravity along +axis: that axis points down
        (ax.invert_xaxis, ax.invert_yaxis, ax.invert_zaxis)[k]()
