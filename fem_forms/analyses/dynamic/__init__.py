"""Transient dynamics: implicit Newmark / generalized-alpha and explicit central difference on the
hyperelastic terms, with damping, time-dependent loads, energy accounting, checkpoints and restart.

Modules: system (forms and state), implicit and explicit (the steps), energy (accounting), solve (the
run), output (files), checkpoint (--restart)."""
from __future__ import annotations

from pathlib import Path
import sys

from mpi4py import MPI

from fem_forms.analyses.dynamic import checkpoint
from fem_forms.analyses.dynamic.impact import ImpactRecorder, impact_entry
from fem_forms.analyses.dynamic.output import MotionWriter, write_csvs, write_gif, write_history_png
from fem_forms.analyses.dynamic.solve import DynamicResult, solve_dynamic
from fem_forms.errors import SolveError
from fem_forms.output import results
from fem_forms.output.guard import attempt
from fem_forms.output.interrupts import Interrupts
from fem_forms.output.pictures import scene_up
from fem_forms.output.report import write_model_report
from fem_forms.output.summary import header
from fem_forms.output.plastic import plastic_summary
from fem_forms.output.quantities import Quantities
from fem_forms.output.strength import summary_line
from fem_forms.scene import Scene
from fem_forms.solvers.thermal_step import max_value

__all__ = ["DynamicResult", "run", "solve_dynamic"]

REPORT_FRAMES = 50             # report.html shows about this many of the motion's frames (evenly in time)


def run(scene: Scene, out, echo: bool = False, restart: Path | None = None) -> dict:
    """CLI entry: march, write probes/energy CSVs, motion (XDMF, GIF), history PNG; results.json last."""
    out = Path(out)
    comm = MPI.COMM_WORLD
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    writer = None

    def frame(system, t, step):
        nonlocal writer
        if writer is None:
            writer = MotionWriter(out, system.model.mesh, restart is not None, scene.output.fields,
                                  scene.output.picture,
                                  scene.dynamic.duration / REPORT_FRAMES if scene.output.report else None)
        writer(system, t, step)

    recorder = ImpactRecorder(scene.sound) if scene.sound is not None else None   # [sound.impact]
    held: dict = {}
    with Interrupts(comm, lambda: interrupted_note(held.get("result"), scene, out, comm)) as interrupts:
        try:
            def started(r) -> None:                # what the start found is said before the march
                held.update(result=r)
                if echo and comm.rank == 0:
                    for w in r.system.start_warnings:
                        print(f"fem-forms: warning: {w}", file=sys.stderr)
            result = solve_dynamic(scene, out, Path(restart) if restart else None, on_frame=frame,
                                   on_step=recorder, interrupts=interrupts, on_result=started,
                                   keepers=(recorder,) if recorder is not None else ())
        except KeyboardInterrupt:
            if writer is not None:
                writer.close()
                writer = None
            keep_interrupted(held.get("result"), scene, out, comm)
            raise
        finally:
            if writer is not None:
                writer.close()
    write_csvs(out, result, comm)
    if result.failure is not None and result.last_accepted is not None:     # a failed run can be continued
        checkpoint.save(out / "checkpoint", result, *result.last_accepted)
    summary = end_state(result)
    warnings = summary["warnings"]
    files = {"probes": "probes.csv", "energy": "energy.csv"}
    if recorder is not None and recorder.times:
        impact = attempt(warnings, "impact sound", lambda: impact_entry(result, recorder, scene.sound, out))
        if impact is not None:
            summary["impact_sound"] = impact
            files["impact_sound"], files["impact_spectrogram"] = impact["wav"], impact["spectrogram"]
    if scene.output.fields:
        files["motion"] = "motion.xdmf"
    if scene.output.picture and comm.rank == 0:
        if writer is not None and len(writer.frames) > 1:
            write_gif(out / "motion.gif", writer.frames, scene.title)
            files["animation"] = "motion.gif"
        if attempt(warnings, "history.png", lambda: write_history_png(out / "history.png", result) or True):
            files["picture"] = "history.png"
    files = comm.bcast(files, root=0)
    if scene.output.report and writer is not None and attempt(
            warnings, "report.html", lambda: _report(result, writer.frames, summary, files, out)):
        files["report"] = "report.html"
    summary["files"] = files
    results.write_json_atomic(out / "results.json", summary, comm)
    if echo and comm.rank == 0:
        print(f"{scene.title}: {summary['dofs']} dofs, {scene.dynamic.scheme}, {summary['steps']} steps to "
              f"t = {summary['time_reached']:.6g} s, {summary['newton_iterations']} Newton iterations, "
              f"energy balance {_balance(summary)}, {summary['wall_time_s']:.2f} s -> {out}")
        if "impact_sound" in summary:
            print(_impact_line(summary["impact_sound"]))
        if line := summary_line(summary):
            print(line + (f" at t = {summary['strength']['time']:.6g} s" if summary["strength"].get("time") is
                          not None else ""))
    if result.failure is not None:
        raise SolveError(f"{scene.title}: {result.failure}")
    return summary


def _report(result: DynamicResult, frames: list, summary: dict, files: dict, out: Path) -> bool:
    """report.html of the motion: about REPORT_FRAMES of its frames (rank 0's gathered surfaces), the end last."""
    scene, end = result.system.scene, summary["time_reached"]
    shown = frames[::-(-len(frames) // REPORT_FRAMES)] if frames else []
    subtitle = (f"dynamic ({scene.dynamic.scheme}), {summary['dofs']:,} dofs, {summary['steps']} steps to t = "
                f"{end:.4g} s")
    shapes = [(f"t = {t:.4g} s", surf[2]) for t, surf in shown if t < end] + [(f"t = {end:.4g} s", None)]
    times = [t for t, _ in shown if t < end] + [end]
    return write_model_report(result.system.model, result.system.u, shapes, None, out, {**summary, "files": files},
                              subtitle, scene_up(scene), times=times)


def end_state(result: DynamicResult) -> dict:
    """The run's summary with the last state's numbers: recovered stress and strain and the material at each
    probe (as the static analysis reports them), the temperature, the plastic and the terms' numbers."""
    summary = result.summary()
    warnings = summary.setdefault("warnings", [])
    warnings.extend(result.system.start_warnings)
    model = result.system.model
    stresses = attempt(warnings, "stress recovery at the probes",
                       lambda: Quantities(model).at_probes(model.probes), {})
    for name, values in stresses.items():
        summary["probes"].setdefault(name, {}).update(values)
    for name, material in model.probe_materials().items():      # the material each probe lies in
        summary["probes"].setdefault(name, {})["material"] = material
    T = model.temperature
    if T is not None:                              # [thermal]: the temperature at the end
        summary["max_temperature"] = max_value(T)
        for name, value in model.probes.evaluate(T).items():
            summary["probes"][name]["temperature"] = value[0]
    summary.update(plastic_summary(model))
    summary.update(model.terms.report(model.u.vector))         # each term's numbers at the end (contact, crack)
    if "max_plastic_strain" in summary and not result.energy.plastic_accounted:
        warnings.append("plasticity: the plastic work is not in the energy account; energy_balance_error "
                        "includes it")
    if model.scene.dynamic.scheme == "backward-euler":
        warnings.append("dynamic.scheme = 'backward-euler' damps every vibration (first order): "
                        "energy_balance_error includes the energy it took")
    return summary


def keep_interrupted(result, scene: Scene, out: Path, comm) -> None:
    """A run stopped by a signal (every rank here together): the step in progress undone, probes.csv, energy.csv
    and a checkpoint of the last accepted step, and results.json with "interrupted": true."""
    if result is None or result.last_accepted is None:
        return
    result.system.state.rollback()                         # the step in progress leaves no trace
    t, step, dt = result.last_accepted
    result.report.steps, result.report.time_reached = step, t
    if result.counts_accepted is not None:                 # nor do its attempts count
        result.report.rejected, result.report.refined, result.report.newton_iterations = result.counts_accepted
    write_csvs(out, result, comm)
    checkpoint.save(out / "checkpoint", result, t, step, dt)
    summary = result.summary()
    summary.update(converged=False, interrupted=True, files={"probes": "probes.csv", "energy": "energy.csv",
                                                             "checkpoint": "checkpoint"},
                   message=f"interrupted at t = {t:.6g} s after {step} steps; the files hold that step, and "
                           f"--restart {out} continues from it")
    results.write_json_atomic(out / "results.json", summary, comm)


def interrupted_note(result, scene: Scene, out: Path, comm) -> None:
    """Rank 0's results.json when a signal reaches several ranks (no collective call: the others may be anywhere);
    every rank then writes the whole account at its next accepted step."""
    if comm.rank != 0 or result is None or result.last_accepted is None:
        return
    t, step, _ = result.last_accepted
    summary = {**header("dynamic", scene, comm, memory=False), "converged": False, "interrupted": True,
               "time_reached": t, "steps": step, "message": f"interrupted at t = {t:.6g} s after {step} steps"}
    results.write_json_atomic(out / "results.json", summary, MPI.COMM_SELF)


def _balance(summary: dict) -> str:
    """The energy balance as the summary line says it: relative, or absolute when the energies are round-off."""
    rel = summary["energy_balance_error"]
    return f"error {rel:.2e}" if rel is not None else f"{summary['energy_imbalance']:.2e} J (energies at round-off)"


def _impact_line(s: dict) -> str:
    """The impact sound as the summary line says it: contact time, peak force, the WAV's strongest peaks."""
    peaks = ", ".join(f"{p:.0f}" for p in s["peaks_hz"][:8])
    return (f"  impact on {s['obstacle']!r}: contact {1e3 * s['contact_time_s']:.3g} ms, peak force "
            f"{s['peak_force_N']:.4g} N, {s['modes_used']} modes -> {s['wav']}, spectrum peaks [Hz]: {peaks}")
