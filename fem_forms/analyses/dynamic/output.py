"""What a dynamic run writes: probes.csv and energy.csv (every step), the motion as an XDMF time series
(P1 displacement and velocity), an animated GIF of the boundary, and a PNG of probe histories and energies."""
from __future__ import annotations

from pathlib import Path

from dolfinx import io
import numpy as np

from fem_forms.output import fields, probes
from fem_forms.output.load_path import records
from fem_forms.output.plastic import plastic_fields
from fem_forms.scene.spec import fix_names

COMPONENTS = ("ux", "uy", "uz", "vx", "vy", "vz")


def write_csvs(out: Path, result, comm) -> None:
    """probes.csv (time, then NAME_ux .. NAME_vz per probe, NAME_T if heat, then the terms' records) and
    energy.csv, by the CSV writer the static load path shares (output/probes.write_table); a run appends each
    accepted step's rows to them as it goes (append_rows)."""
    head = probe_head(result)
    result.probe_rows = [padded(r, len(head)) for r in result.probe_rows]
    probes.write_table(out / "probes.csv", head, result.probe_rows, comm)
    cols = result.energy.columns()
    probes.write_table(out / "energy.csv", ["time", *cols],
                       [[t] + [e.value(c) for c in cols] for t, e in result.energy.history], comm)
    comm.barrier()


def append_rows(out: Path, result, comm) -> None:
    """The last accepted step's rows at the end of probes.csv and energy.csv (rank 0, flushed)."""
    probes.append_row(out / "probes.csv", padded(result.probe_rows[-1], len(probe_head(result))), comm)
    t, e = result.energy.history[-1]
    probes.append_row(out / "energy.csv", [t] + [e.value(c) for c in result.energy.columns()], comm)


def probe_head(result) -> list[str]:
    """probes.csv's columns (found once per run: the records' names cost their evaluation; collective)."""
    if result.probe_columns is None:
        names = list(result.system.scene.output.probes)
        head = ["time"] + probes.columns(names, COMPONENTS)
        if result.system.model.temperature is not None and names:
            head += [f"{n}_T" for n in names]
        head += probes.columns(fix_names(result.system.scene.fix), ("Fx", "Fy", "Fz"))   # each support's force
        result.probe_columns = head + list(records(result.system.model))
    return result.probe_columns


def padded(row: list, width: int) -> list:
    """A probes.csv row as wide as the header: rows a checkpoint of an older version carried lack the records."""
    return list(row) + [float("nan")] * (width - len(row))


class MotionWriter:
    """Frames every output_every steps: the XDMF time series and the GIF's boundary snapshots; for report.html
    alone, a snapshot only every `report_every` seconds of simulated time (each is a gather of the surface)."""

    def __init__(self, out: Path, mesh, append: bool, with_fields: bool, with_picture: bool,
                 report_every: float | None = None):
        self.mesh, self.frames = mesh, []
        self.with_picture = with_picture
        self.report_every, self._next_report = report_every, -float("inf")
        self.xdmf = None
        if with_fields:
            path = out / "motion.xdmf"
            self.xdmf = io.XDMFFile(mesh.comm, str(path), "a" if append and path.exists() else "w")
            if not (append and path.exists()):
                self.xdmf.write_mesh(mesh)
        self._p1 = None

    def __call__(self, system, t: float, step: int) -> None:
        if self.xdmf is not None:
            shown = (system.u, system.v) + ((system.model.temperature,) if system.model.temperature is not None else ())
            if self._p1 is None:
                self._p1 = tuple(fields.p1_interpolant(f, n) for f, n in zip(shown, ("displacement", "velocity",
                                                                                   "temperature")))
            for g, f in zip(self._p1, shown):
                g.interpolate(f)
                self.xdmf.write_function(g, t)
            for g in plastic_fields(system.model):       # committed plastic strain (cell averages), if plastic
                self.xdmf.write_function(g, t)
            for f in system.model.terms.output_fields():    # the terms' own (the damage, P1)
                self.xdmf.write_function(f, t)
        due = self.report_every is not None and t >= self._next_report - 1e-12 * abs(t)
        if self.with_picture or due:
            if due:
                self._next_report = t + self.report_every
            surf = fields.boundary_surface(system.u)       # collective; rank 0 keeps it
            if surf is not None:
                self.frames.append((t, surf))

    def close(self) -> None:
        if self.xdmf is not None:
            self.xdmf.close()


def write_gif(path: Path, frames: list, title: str, fps: int = 12, label: str = "t = {:.4g} s") -> None:
    """Animated GIF (matplotlib + pillow) of the deformed boundary, true scale; frames are (value, boundary
    surface) pairs, each frame titled `title: label.format(value)`. Each frame is rendered once (matplotlib's
    FuncAnimation renders every frame twice on Agg): the rocking toy's 51 frames 6.1 -> 4.0 s, the same bytes."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    from PIL import Image

    allx = np.vstack([X + d for _, (X, _, d) in frames])
    lo, hi = allx.min(axis=0), allx.max(axis=0)
    fig = plt.figure(figsize=(5, 4))
    ax = fig.add_subplot(projection="3d")
    images = []
    for t, (X, polys, d) in frames:
        ax.clear()
        ax.add_collection3d(Poly3DCollection((X + d)[polys], facecolor=(0.35, 0.55, 0.8),
                                             edgecolor=(0, 0, 0, 0.2), linewidths=0.2))
        ax.set_xlim(lo[0], hi[0]), ax.set_ylim(lo[1], hi[1]), ax.set_zlim(lo[2], hi[2])
        ax.set_box_aspect(np.maximum(hi - lo, 0.05 * (hi - lo).max()))
        ax.set_axis_off()
        ax.set_title(f"{title}: {label.format(t)}", fontsize=9)
        fig.canvas.draw()
        images.append(Image.fromarray(np.asarray(fig.canvas.buffer_rgba()).copy()))
    plt.close(fig)
    images[0].save(path, save_all=True, append_images=images[1:], duration=int(1000 / fps), loop=0)


def write_history_png(path: Path, result) -> None:
    """Probe displacement histories (top) and the energies with their balance (bottom)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = np.array(result.probe_rows)
    names = list(result.system.scene.output.probes)
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for i, n in enumerate(names):
        for c in range(3):
            col = rows[:, 1 + 6 * i + c]
            if np.abs(col).max() > 0:
                a1.plot(rows[:, 0], col, label=f"{n}_{COMPONENTS[c]}")
    a1.set_ylabel("displacement [m]")
    if names:
        a1.legend(fontsize=8)
    t = np.array([h[0] for h in result.energy.history])
    for name in result.energy.columns():
        a2.plot(t, [h[1].value(name) for h in result.energy.history], label=name.replace("_", " "))
    a2.plot(t, [h[1].balance() for h in result.energy.history], "k--",
            label="balance (kin + el - W + D ...)")
    a2.set_xlabel("time [s]")
    a2.set_ylabel("energy [J]")
    a2.legend(fontsize=8)
    fig.suptitle(result.system.scene.title)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
