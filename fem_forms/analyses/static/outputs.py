"""Static analysis: equilibrium under the scene's loads, then fields, pictures and results.json.

A run with more than one load step writes its load path as it goes (output/load_path.py: probes.csv and
fields.xdmf at every accepted step, then load_path.png). A continuation that stops because its cut-backs
reached their floor has found a limit point: exit 3, with the last accepted state written and reported
(results.json "limit point: ..."). An interrupt (Ctrl-C, SIGTERM) leaves the last accepted state too, and
results.json with "interrupted": true (output/interrupts.py says how, also under MPI)."""
from __future__ import annotations

from pathlib import Path
from typing import Callable
import sys

from mpi4py import MPI

from fem_forms.analyses.static.solve import (GAVE_UP, LIMIT, StaticResult, limit_point, load_span, solve_static,
                                             stability_checked)
from fem_forms.errors import SolveError
from fem_forms.model import Model, build_model
from fem_forms.output import pictures, results
from fem_forms.output.guard import attempt
from fem_forms.output.interrupts import Interrupts
from fem_forms.output.load_path import LoadPath, field_functions
from fem_forms.output.plastic import plastic_summary, plastic_term
from fem_forms.output.report import write_model_report
from fem_forms.output.stl import write_deformed_surface
from fem_forms.output.strength import summary_line
from fem_forms.output import fields
from fem_forms.scene import Scene

def write_static_outputs(result: StaticResult, out: "Path", path: LoadPath | None = None) -> dict:
    """Fields (XDMF), picture (PNG), Newton history (CSV), then results.json last and atomically. With the
    load path of a stepped run (`path`), its files and load_path.png; at a limit point, the last accepted
    state's answer numbers and outputs."""
    out = Path(out)
    comm = result.model.mesh.comm
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    limit = limit_point(result)               # solve_static post-processed its last accepted state
    summary = result.summary()
    files = {}
    if limit and result.report.message.startswith(GAVE_UP):
        summary["message"] = LIMIT + result.report.message[len(GAVE_UP):]
    if plastic_term(result.model) is not None and not result.report.converged:
        summary["collapse"] = {"load_factor": result.report.load_reached}
    stepped = path is not None and path.stepping
    if result.report.converged or limit:
        scene, warnings = result.model.scene, summary["warnings"]
        summary.update(attempt(warnings, "plastic summary", lambda: plastic_summary(result.model), {}))
        if stepped:
            files.update(path.files)                  # fields.xdmf holds every accepted step already
        elif scene.output.fields:
            if attempt(warnings, "fields.xdmf", lambda: _write_fields(result, out, scene.output.fields)):
                files["fields"] = "fields.xdmf"
            elif attempt(warnings, "fields.xdmf (displacement only)",
                         lambda: _write_fields(result, out, ["displacement"])):
                files["fields"] = "fields.xdmf"
        if "von_mises" in scene.output.fields:
            vm = attempt(warnings, "von Mises stress", lambda: result.quantities.field("von_mises"))
            if vm is not None:
                summary["max_von_mises"] = comm.allreduce(
                    float(vm.x.array.max()) if vm.x.array.size else 0.0, op=MPI.MAX)
        if scene.output.picture and attempt(warnings, "deformed.png",
                                            lambda: pictures.picture(out / "deformed.png", result.u, scene.title,
                                                                     up=pictures.scene_up(scene),
                                                                     model=result.model) or True):
            files["picture"] = "deformed.png"
        if attempt(warnings, "deformed.stl", lambda: write_deformed_surface(result.model, out / "deformed.stl")):
            files["surface"] = "deformed.stl"
    for h in result.histories:
        if h.rows:
            files.update(attempt(summary["warnings"], h.label,
                                 lambda: h.write(out, result.model.scene.title, result.model.scene.output.picture),
                                 {}))
    if stepped:
        files.update(path.finish(summary))
    results.write_newton_history(out / "newton_history.csv", result.report.steps, comm)
    files["newton_history"] = "newton_history.csv"
    if (result.report.converged or limit) and result.model.scene.output.report:
        vm = (attempt(summary["warnings"], "von Mises stress", lambda: result.quantities.field("von_mises"))
              if "von_mises" in (scene.output.fields or []) else None)
        subtitle = (f"static, {summary['dofs']:,} dofs, {summary['load_steps']} load steps, max |u| "
                    f"{summary['max_displacement']:.4g} m")
        reached = summary.get("load_reached", 1.0)
        span = path.span if path is not None else load_span(result.model)
        if attempt(summary["warnings"], "report.html", lambda: write_model_report(
                result.model, result.u, (path.shapes if path is not None else [])
                + [(f"load factor {reached:.4g}", None)], vm,
                out, {**summary, "files": files}, subtitle, pictures.scene_up(scene),
                times=(path.shape_times if path is not None else []) + [reached * span])):
            files["report"] = "report.html"
    summary["files"] = files
    if path is not None:
        path.finished = True                          # from here an interrupt leaves this results.json
    results.write_json_atomic(out / "results.json", summary, comm)
    return summary


def _write_fields(result: StaticResult, out: Path, names: list) -> bool:
    """fields.xdmf with the asked-for fields (the plastic ones and the temperature too, if any)."""
    fields.write_fields(out / "fields.xdmf", result.model.mesh, field_functions(result.model, result.quantities,
                                                                               names))
    return True


def solve_and_write(scene: Scene, out: Path, on_model: Callable[[Model], None] | None = None) -> dict:
    """Solve with the load path written step by step, then the outputs; an interrupt anywhere leaves the
    last accepted state and an interrupted results.json, then propagates (exit 130 / 143). `on_model(model)`
    runs once the model is built, before the solve (the CLI prints the warnings known by then)."""
    comm = MPI.COMM_WORLD                             # the folder is made when there is something to write:
    path = LoadPath(scene, out, comm)                 # bad input found while building leaves nothing
    with Interrupts(comm, path.write_interrupted) as interrupts:
        try:
            model = build_model(scene)
            path.attach(model, load_span(model), interrupts)
            if on_model is not None:
                stability_checked(model)
                on_model(model)
            result = solve_static(scene, model=model, on_step=path)
            interrupts.check()
            with interrupts.critical():
                summary = write_static_outputs(result, out, path)
            interrupts.check()
        except KeyboardInterrupt:
            path.write_interrupted()
            raise
    return summary


def run(scene: Scene, out, echo: bool = False) -> dict:
    """CLI entry: solve, write outputs, print a summary; SolveError (exit 3) if not converged."""
    said: list[str] = []

    def warn_early(model: Model) -> None:            # what is known before the solve is said before it
        if echo and MPI.COMM_WORLD.rank == 0:
            for w in model.warnings:
                print(f"fem-forms: warning: {w}", file=sys.stderr)
        said.extend(model.warnings)
    summary = solve_and_write(scene, Path(out), on_model=warn_early)
    if echo and MPI.COMM_WORLD.rank == 0:
        for w in summary["warnings"]:
            if w not in said:
                print(f"fem-forms: warning: {w}", file=sys.stderr)
    if echo and MPI.COMM_WORLD.rank == 0 and summary["converged"]:
        print(f"{scene.title}: {summary['dofs']} dofs, {summary['newton_iterations']} Newton iterations "
              f"in {summary['load_steps']} load steps, max |u| = {summary['max_displacement']:.6g} m, "
              f"{summary['wall_time_s']:.2f} s -> {out}")
        for name, pr in summary["probes"].items():
            print(f"  probe {name} {pr['point']}: u = [{', '.join(f'{v:.6g}' for v in pr['displacement'])}]")
        if line := summary_line(summary):
            print(line)
    if "collapse" in summary:
        raise SolveError(f"{scene.title}: plastic collapse: no equilibrium beyond load factor "
                         f"{summary['collapse']['load_factor']:.6g} ({summary['message']})")
    if not summary["converged"]:
        raise SolveError(f"{scene.title}: " + (summary["message"] if summary["message"].startswith("limit point")
                                               else f"did not converge: {summary['message']}"))
    return summary
