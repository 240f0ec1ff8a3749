"""What a fracture run reports: after every accepted load step, each support's prescribed displacement and
force and the crack's numbers (force_displacement.csv); at the end the peak load, the crack's area and
volume, a picture of the crack (damage on the deformed surface) and the force-displacement curve."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from fem_forms.output import fields, pictures, probes
from fem_forms.output.reactions import support_forces
from fem_forms.physics.histories import piecewise_linear
from fem_forms.scene.spec import fix_names


class FractureHistory:
    """The static run's `on_step(lam)` for a term keeping a crack (its `record()`, `crack_center()` and damage
    field `d`), chained with the load path's: one row per step."""

    def __init__(self, model, span: float, term):
        self.model, self.span, self.term = model, span, term
        self.names = fix_names(model.scene.fix)
        self.rows: list[list[float]] = []
        self.records: list[dict] = []

    def prescribed(self, lam: float) -> np.ndarray:
        """(fixes, 3): each support's prescribed displacement at load factor lam (0 where it holds still)."""
        out = []
        for fix in self.model.scene.fix:
            factor = piecewise_linear(fix.history, lam * self.span) if fix.history else lam
            out.append(np.asarray(fix.value if fix.value is not None else [0.0] * 3, dtype=float) * factor)
        return np.array(out).reshape(-1, 3)

    def __call__(self, lam: float) -> None:
        forces = support_forces(self.model) if self.model.scene.fix else np.zeros((0, 3))
        record = self.term.record()
        self.records.append(record)
        self.rows.append([lam, lam * self.span] + np.column_stack([self.prescribed(lam), forces]).ravel().tolist()
                         + [record[k] for k in RECORDED])

    def head(self) -> list[str]:
        cols = ["load_factor", "time"]
        for name in self.names:
            cols += [f"{name}_{q}" for q in ("ux", "uy", "uz", "Fx", "Fy", "Fz")]
        return cols + list(RECORDED)

    def along(self) -> np.ndarray:
        """(steps, fixes): each support's force along its prescribed displacement's direction (the load it
        carries), 0 for supports that hold still."""
        rows = np.asarray(self.rows)[:, 2:2 + 6 * len(self.names)].reshape(len(self.rows), -1, 6)
        direction = np.array([np.asarray(f.value or [0.0] * 3, float) for f in self.model.scene.fix]).reshape(-1, 3)
        size = np.linalg.norm(direction, axis=1)
        unit = np.divide(direction, size[:, None], out=np.zeros_like(direction), where=size[:, None] > 0)
        return np.einsum("sfk,fk->sf", rows[:, :, 3:], unit)

    def summary(self) -> dict:
        """damage_max, cracked_volume, crack_area (the last step's), peak_load_factor and peak_force: the step
        where the pulling supports carry the most (with load control, where the load stopped growing)."""
        if not self.rows:
            return {}
        out = {k: self.records[-1][k] for k in ("damage_max", "cracked_volume", "crack_area", "surface_energy")}
        out["crack_center"] = self.term.crack_center()
        lams = np.asarray(self.rows)[:, 0]
        carried = self.along()
        moving = [i for i, f in enumerate(self.model.scene.fix) if any(f.value or [])]
        if moving:
            total = carried[:, moving].sum(axis=1)
            k = int(np.argmax(total))
            out["peak_force"] = {self.names[i]: float(carried[k, i]) for i in moving}
        else:
            k = len(lams) - 1
        out["peak_load_factor"] = float(lams[k])
        return out

    @property
    def label(self) -> str:
        return "force_displacement.csv and crack.png"

    def write(self, out: Path, title: str, picture: bool) -> dict:
        """force_displacement.csv, and with `picture` crack.png and force_displacement.png; the files' names."""
        comm = self.model.mesh.comm
        probes.write_table(out / "force_displacement.csv", self.head(), self.rows, comm)
        files = {"force_displacement": "force_displacement.csv"}
        if picture:
            crack_picture(out / "crack.png", self.model.u, self.term.d, title)
            files["crack_picture"] = "crack.png"
            if comm.rank == 0 and self.rows:
                curve_picture(out / "force_displacement.png", self, title)
            files["force_displacement_picture"] = "force_displacement.png"
        return files


RECORDED = ("damage_max", "crack_area", "surface_energy", "cracked_volume")


SHOWN_OPENING = 0.05           # the crack picture scales displacements to at most this share of the part's size


def crack_picture(path: Path, u, d, title: str) -> None:
    """The deformed boundary coloured by damage (0 intact, 1 cracked), the rest shape in grey; displacements
    scaled to at most SHOWN_OPENING of the part's size (a crack's opening would otherwise dwarf the part)."""
    surf = fields.boundary_surface(u, d)
    if surf is not None:
        X, polys, disp, damage = surf
        size = float(np.ptp(X, axis=0).max())
        largest = float(np.linalg.norm(disp, axis=1).max(initial=0.0))
        scale = min(1.0, SHOWN_OPENING * size / largest) if largest > 0 else 1.0
        x = X + scale * disp
        view = pictures.view_axes()
        canvas = pictures.Canvas(900, 500)
        to_px = canvas.fit((10, 40, 760, 480), np.vstack([X, x]) @ view[0].T)
        canvas.surface(to_px, X, polys, (0.6, 0.6, 0.6, 0.08), (0.4, 0.4, 0.4, 0.15), view=view)
        colors = pictures.shade(x, polys, pictures.viridis(np.clip(damage[polys].mean(axis=1), 0, 1)), view[1])
        canvas.surface(to_px, x, polys, colors, (0, 0, 0, 0.1), view=view)
        canvas.colorbar((775, 100, 795, 400), 1.0, "damage")
        canvas.triad((45, 455), view)
        shown = "" if scale == 1.0 else f", displacement x{scale:.3g}"
        canvas.text((450, 20), f"{title}: the crack (damage on the deformed surface{shown})", 14)
        canvas.save(path)
    u.function_space.mesh.comm.barrier()


def curve_picture(path: Path, history: FractureHistory, title: str) -> None:
    """Force against prescribed displacement for each pulling support (matplotlib, rank 0)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = np.asarray(history.rows)
    carried = history.along()
    fig, ax = plt.subplots(figsize=(6, 4))
    for i, (name, fix) in enumerate(zip(history.names, history.model.scene.fix)):
        if not any(fix.value or []):
            continue
        moved = rows[:, 2 + 6 * i: 5 + 6 * i]
        ax.plot(np.linalg.norm(moved, axis=1), carried[:, i], "o-", ms=3, label=name)
    ax.set_xlabel("prescribed displacement [m]")
    ax.set_ylabel("force [N]")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
