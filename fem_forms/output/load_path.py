"""The load path of a static run that takes more than one load step, written as it is walked: after every
accepted step a row of probes.csv (load factor, pseudo-time, each probe's displacement, each support's
reaction, the scalars the terms record) and the fields at that step in fields.xdmf (ParaView plays the
path); at the end a load-displacement picture, load_path.png. Each step's files are complete on disk before the next step
starts, so a run stopped at a limit point or interrupted keeps its last converged state, and the
interrupted results.json is written from rank 0's copy of that step without any collective call.

A run whose first accepted step is already the full load (one load step, no cut-back) writes nothing
here: its outputs stay those of a single solve.
"""
from __future__ import annotations

import math
from pathlib import Path

from dolfinx import io
from mpi4py import MPI
import numpy as np

from fem_forms.output import fields, probes, results
from fem_forms.output.guard import attempt
from fem_forms.output.plastic import plastic_fields
from fem_forms.output.report import surface_frames
from fem_forms.output.quantities import Quantities, output_fields
from fem_forms.output.reactions import support_forces
from fem_forms.output.summary import header
from fem_forms.scene.spec import fix_names

REPORT_STEPS = 50              # report.html shows about this many of a stepped run's load steps, and the last


def field_functions(model, quantities: Quantities, names: list[str]) -> list:
    """The fields a static run writes: the asked-for ones, the plastic ones and the temperature, if any."""
    written = output_fields(quantities, names) + plastic_fields(model)
    if model.temperature is not None:
        written.append(fields.p1_interpolant(model.temperature, "temperature"))
    written += model.terms.output_fields()          # the terms' own (the damage, P1), a time series
    return written


def records(model) -> dict[str, float]:
    """Every term's `record()` (optional: Term's default gives {}), merged in term order."""
    out: dict[str, float] = {}
    for term in model.terms:
        out.update({str(k): float(v) for k, v in term.record().items()})
    return out


class LoadPath:
    """The static analysis's `on_step(lam)` hook (see the module docstring). `span` is the pseudo-time at
    load factor 1 (equilibrium.load_span); `interrupts` (output.interrupts.Interrupts) is checked before
    and after each step's writing, which no signal cuts short."""

    def __init__(self, scene, out: Path, comm: MPI.Comm = MPI.COMM_WORLD):
        self.scene, self.out, self.comm = scene, Path(out), comm
        self.model, self.span, self.interrupts = None, 1.0, None
        self.rows: list[list[float]] = []
        self.record_names: list[str] = []
        self.stepping = False                  # more than one load step: the per-step files are written
        self.field_names = list(scene.output.fields) if scene.output.fields else []
        self.xdmf_steps = 0
        self.files: dict[str, str] = {}        # what is complete on disk
        self.last: dict | None = None          # the last accepted step as written (rank 0 answers from it)
        self.finished = False                  # the final results.json is being written: no interrupted one
        self.shapes: list = []                 # steps' surface displacements for report.html (rank 0), the
        self._next_shape = 0.0                 # final state's not among them (the report gathers it)
        self.shape_times: list = []            # their pseudo-times (load factor x span: obstacles move with it)

    def attach(self, model, span: float, interrupts=None) -> None:
        self.model, self.span, self.interrupts = model, span, interrupts

    def __call__(self, lam: float) -> None:
        if self.interrupts is None:
            self._step(lam)
            return
        self.interrupts.check()
        with self.interrupts.critical():
            self._step(lam)
        self.interrupts.check()

    def _step(self, lam: float) -> None:
        model = self.model
        model.sync_displacement()
        values = model.probes.evaluate(model.u)
        forces = support_forces(model) if self.scene.fix else np.zeros((0, 3))
        recorded = records(model)
        if not self.rows:
            self.record_names = list(recorded)
        self.rows.append([lam, lam * self.span] + [x for n in model.probes.names for x in values[n]]
                         + forces.ravel().tolist() + [recorded.get(k, math.nan) for k in self.record_names])
        if not self.stepping and lam < 1.0 - 1e-12:  # the first of several steps: the folder is needed now
            self.stepping = True
            if self.comm.rank == 0:
                self.out.mkdir(parents=True, exist_ok=True)
            self.comm.barrier()
        if self.stepping and self.scene.output.report and self._next_shape <= lam < 1.0 - 1e-12:
            self._next_shape = lam + 1.0 / REPORT_STEPS         # a gather of the surface: about 50 in a run
            self.shapes += surface_frames([(f"load factor {lam:.4g}", model.u)])
            self.shape_times.append(lam * self.span)
        if self.stepping:
            self._write_fields(lam * self.span)
            probes.write_table(self.out / "probes.csv", self.head(), self.rows, self.comm)
            self.files["probes"] = "probes.csv"
            self.comm.barrier()
        self.last = {"load_factor": lam, "time": lam * self.span, "steps": len(self.rows), "probes": values,
                     "reactions": dict(zip(fix_names(self.scene.fix), forces.tolist())),
                     "records": recorded, "files": dict(self.files)}

    def head(self) -> list[str]:
        """probes.csv's columns: load_factor, time, NAME_ux, NAME_uy, NAME_uz per probe, FIX_Fx, FIX_Fy, FIX_Fz
        per support (the force it exerts on the body, N: a displacement-driven run's load), then the records."""
        return (["load_factor", "time"] + probes.columns(self.model.probes.names)
                + probes.columns(fix_names(self.scene.fix), ("Fx", "Fy", "Fz")) + self.record_names)

    def _write_fields(self, t: float) -> None:
        """This step's fields appended to fields.xdmf (created with the mesh at the first step); a failure
        falls back to the displacement alone, then to no fields, with a warning."""
        while self.field_names:
            names = self.field_names
            if attempt(self.model.warnings, f"fields.xdmf ({', '.join(names)}) at time {t:.6g}",
                       lambda: self._append(t, names)):
                self.files["fields"] = "fields.xdmf"
                return
            self.field_names = ["displacement"] if names != ["displacement"] else []

    def _append(self, t: float, names: list[str]) -> bool:
        written = field_functions(self.model, Quantities(self.model), names)
        path = self.out / "fields.xdmf"
        with io.XDMFFile(self.comm, str(path), "a" if self.xdmf_steps else "w") as xdmf:
            if not self.xdmf_steps:
                xdmf.write_mesh(self.model.mesh)
            for f in written:
                xdmf.write_function(f, t)
        self.xdmf_steps += 1
        return True

    def finish(self, summary: dict) -> dict:
        """At the end of a run that stepped: load_path.png and the summary's additions (files, records)."""
        if not self.stepping:
            return {}
        files = dict(self.files)
        if self.scene.output.picture and attempt(summary["warnings"], "load_path.png",
                                                 lambda: self.picture(self.out / "load_path.png") or True):
            files["load_path_picture"] = "load_path.png"
        if self.last and self.last["records"]:
            summary["records"] = self.last["records"]
        return files

    def picture(self, path: Path) -> None:
        """Each probe's displacement magnitude against the load factor; below, each recorded scalar."""
        if self.comm.rank != 0:
            return
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        rows = np.array(self.rows)
        shown = self.record_names[:4]
        fig, axes = plt.subplots(1 + len(shown), 1, figsize=(7, 3.5 + 2.2 * len(shown)), sharex=True,
                                 squeeze=False)
        for i, name in enumerate(self.model.probes.names):
            axes[0, 0].plot(rows[:, 0], np.linalg.norm(rows[:, 2 + 3 * i: 5 + 3 * i], axis=1), "o-", ms=3,
                            label=name)
        axes[0, 0].set_ylabel("|u| at probe [m]")
        if self.model.probes.names:
            axes[0, 0].legend(fontsize=8)
        first = 2 + 3 * len(self.model.probes.names) + 3 * len(self.scene.fix)
        for k, name in enumerate(shown):
            ax = axes[1 + k, 0]
            ax.plot(rows[:, 0], rows[:, first + k], "o-", ms=3)
            ax.set_ylabel(name.replace("_", " "))
        axes[-1, 0].set_xlabel("load factor" + (f" (time = {self.span:g} x load factor)" if self.span != 1.0 else ""))
        fig.suptitle(f"{self.scene.title}: load path")
        fig.tight_layout()
        fig.savefig(path, dpi=100)
        plt.close(fig)

    def write_interrupted(self) -> None:
        """The interrupted results.json of the last accepted step, from rank 0's data, atomically and with
        no collective call (other ranks may have stopped anywhere); nothing once the final one is due."""
        if self.finished or self.comm.rank != 0:
            return
        last = self.last or {"load_factor": 0.0, "time": 0.0, "steps": 0, "probes": {}, "records": {},
                             "files": {}}
        model = self.model
        summary = {**header("static", self.scene, self.comm, None if model is None else model.dofs, memory=False),
                   "converged": False, "interrupted": True,
                   "load_reached": last["load_factor"], "time": last["time"], "load_steps": last["steps"],
                   **({} if model is None else {"mesh": model.loaded.info,
                                                "physics": model.physics, "warnings": model.warnings}),
                   "probes": {n: {"point": self.scene.output.probes[n], "displacement": v}
                              for n, v in last["probes"].items()},
                   **({"reactions": last["reactions"]} if last.get("reactions") else {}),
                   **({"records": last["records"]} if last["records"] else {}),
                   "message": f"interrupted: load factor {last['load_factor']:.6g} reached in {last['steps']} "
                              f"accepted load step{'' if last['steps'] == 1 else 's'}; the files hold that state",
                   "files": last["files"] if self.stepping else {}}
        results.write_json_atomic(self.out / "results.json", summary, MPI.COMM_SELF)
