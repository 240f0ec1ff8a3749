"""Modal analysis outputs: the scene's modes (solve.py: K phi = omega^2 M phi at rest or prestressed, by count or
every one below `up_to`), written as results.json, modes.xdmf and a picture, and with [sound] the ring of the
struck part as a WAV."""
from __future__ import annotations

from pathlib import Path

from dolfinx import fem
from mpi4py import MPI
import numpy as np

from fem_forms.analyses.static.solve import max_norm
from fem_forms.analyses.modal.solve import ModalResult, solve_modal
from fem_forms.output import fields, results, sound
from fem_forms.output.guard import attempt
from fem_forms.output.pictures import scene_up
from fem_forms.output.report import surface_frames, write_model_report
from fem_forms.scene import Scene


def modes_picture(path: Path, result: ModalResult, count: int = 6) -> None:
    """PNG: small multiples of the first modes, each boundary deformed by its scaled mode shape and coloured by its
    displacement relative to its largest (one colour bar, 0 to 1, for all)."""
    surfaces = [fields.boundary_surface(f) for f in result.modes[:count]]   # collective
    # about a loaded equilibrium the modes are drawn on the deformed shape
    base = fields.boundary_surface(result.model.u) if result.static is not None else None
    comm = result.model.mesh.comm
    if comm.rank == 0:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection

        n = len(surfaces)
        cols = min(n, 3)
        rows = -(-n // cols)
        fig = plt.figure(figsize=(4.2 * cols, 3.6 * rows))
        freqs = result.frequencies_hz
        for k, (X, polys, d) in enumerate(surfaces):
            ax = fig.add_subplot(rows, cols, k + 1, projection="3d")
            if base is not None:
                X = X + base[2]
            mag = np.linalg.norm(d, axis=1)
            span = (X.max(axis=0) - X.min(axis=0)).max()
            x = X + (0.1 * span / mag.max() if mag.max() > 0 else 0.0) * d
            colors = plt.get_cmap("viridis")(mag[polys].mean(axis=1) / max(mag.max(), 1e-300))
            ax.add_collection3d(Poly3DCollection(x[polys], facecolors=colors,
                                                 edgecolor=(0, 0, 0, 0.1), linewidths=0.1))
            lo, hi = np.vstack([X, x]).min(axis=0), np.vstack([X, x]).max(axis=0)
            ax.set_xlim(lo[0], hi[0]), ax.set_ylim(lo[1], hi[1]), ax.set_zlim(lo[2], hi[2])
            ax.set_box_aspect(np.maximum(hi - lo, 0.05 * (hi - lo).max()))
            ax.set_axis_off()
            ax.view_init(elev=20, azim=-60)
            ax.set_title(f"mode {k + 1}: {freqs[k]:.4g} Hz", fontsize=10)
        fig.suptitle(f"{result.model.scene.title}: mode shapes (scaled)")
        fig.tight_layout(rect=(0, 0, 0.93, 1))
        bar = fig.add_axes((0.945, 0.25, 0.012, 0.5))
        fig.colorbar(plt.cm.ScalarMappable(plt.Normalize(0.0, 1.0), "viridis"), cax=bar,
                     label="|mode| / its largest")
        fig.savefig(path, dpi=100)
        plt.close(fig)
    comm.barrier()


def _unit_shape(mode: fem.Function) -> fem.Function:
    """A copy of a mode shape scaled to a largest displacement of 1."""
    shape = fem.Function(mode.function_space, name=mode.name)
    shape.x.array[:] = mode.x.array / max(max_norm(mode), 1e-300)
    return shape


def write_modal_outputs(result: ModalResult, out: Path) -> dict:
    """Mode shapes (XDMF, P1, unit largest displacement), picture, sound; results.json last."""

    out = Path(out)
    comm = result.model.mesh.comm
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    scene = result.model.scene
    summary = result.summary()
    warnings = summary.setdefault("warnings", [])   # an output that fails must not lose the frequencies
    files = {}
    if scene.output.fields and result.modes:
        shapes = []
        for f in result.modes:
            g = fields.p1_interpolant(f, f.name)
            g.x.array[:] /= max(max_norm(f), 1e-300)
            shapes.append(g)
        if attempt(warnings, "modes.xdmf", lambda: fields.write_fields(out / "modes.xdmf", result.model.mesh,
                                                                         shapes) or True):
            files["modes"] = "modes.xdmf"
    if scene.output.picture and result.modes and attempt(
            warnings, "modes.png", lambda: modes_picture(out / "modes.png", result) or True):
        files["picture"] = "modes.png"
    if scene.sound is not None:
        heard = attempt(warnings, "sound", lambda: sound.modal_sound(result, scene.sound, out))
        if heard is not None:
            summary["sound"] = heard
            files["sound"], files["spectrogram"] = heard["wav"], heard["spectrogram"]
    if scene.output.report and result.modes:
        frames = [(f"mode {k + 1}: {hz:.4g} Hz", _unit_shape(f)) for k, (f, hz) in enumerate(
            zip(result.modes, result.frequencies_hz))]
        subtitle = f"modal, {summary['dofs']:,} dofs, {len(frames)} modes (shapes scaled: pick a mode with frame)"
        if attempt(warnings, "report.html", lambda: write_model_report(
                result.model, frames[0][1], surface_frames(frames), None, out, {**summary, "files": files},
                subtitle, scene_up(scene), "auto", ("|mode shape|", "largest 1"))):
            files["report"] = "report.html"
    summary["files"] = files
    results.write_json_atomic(out / "results.json", summary, comm)
    return summary


def run(scene: Scene, out, echo: bool = False) -> dict:
    """CLI entry: solve, write outputs, print the frequencies on rank 0."""
    result = solve_modal(scene)
    summary = write_modal_outputs(result, Path(out))
    if echo and MPI.COMM_WORLD.rank == 0:
        freqs = ", ".join(f"{f:.6g}" for f in summary["frequencies_hz"])
        rigid = f", {summary['rigid_modes']} rigid-body modes" if summary["rigid_modes"] else ""
        if "band" in summary:
            rigid += f", all below {summary['band']['up_to_hz']:g} Hz by an inertia count"
        print(f"{scene.title}: {summary['dofs']} dofs, {len(summary['frequencies_hz'])} modes{rigid}, "
              f"{summary['wall_time_s']:.2f} s -> {out}")
        print(f"  frequencies [Hz]: {freqs}")
        if "sound" in summary:
            print(f"  sound: {summary['sound']['wav']}, spectrum peaks [Hz]: "
                  f"{', '.join(f'{p:.1f}' for p in summary['sound']['peaks_hz'])}")
    return summary
