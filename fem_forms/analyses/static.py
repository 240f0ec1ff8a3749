"""Static analysis: equilibrium under the scene's loads, then fields, picture and results.json."""
from __future__ import annotations

from pathlib import Path
import sys

from mpi4py import MPI

from fem_forms.equilibrium import StaticResult, solve_static
from fem_forms.errors import SolveError
from fem_forms.output import fields, pictures, results
from fem_forms.output.guard import attempt
from fem_forms.output.plastic import plastic_fields, plastic_summary, plastic_term
from fem_forms.output.quantities import output_fields
from fem_forms.scene import Scene


def write_static_outputs(result: StaticResult, out: "Path") -> dict:
    """Fields (XDMF), picture (PNG), Newton history (CSV), then results.json last and atomically."""

    out = Path(out)
    comm = result.model.mesh.comm
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    summary = result.summary()
    files = {}
    plastic = plastic_term(result.model) is not None
    if plastic and not result.report.converged:
        summary["collapse"] = {"load_factor": result.report.load_reached}
    if result.report.converged:
        scene, warnings = result.model.scene, summary["warnings"]
        summary.update(attempt(warnings, "plastic summary", lambda: plastic_summary(result.model), {}))
        if scene.output.fields:
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
                                                                     up=pictures.scene_up(scene)) or True):
            files["picture"] = "deformed.png"
    results.write_newton_history(out / "newton_history.csv", result.report.steps, comm)
    files["newton_history"] = "newton_history.csv"
    summary["files"] = files
    results.write_json_atomic(out / "results.json", summary, comm)
    return summary


def _write_fields(result: StaticResult, out: Path, names: list) -> bool:
    """fields.xdmf with the asked-for fields (the plastic ones and the temperature too, if any)."""
    written = output_fields(result.quantities, names) + plastic_fields(result.model)
    if result.model.temperature is not None:
        written.append(fields.p1_interpolant(result.model.temperature, "temperature"))
    fields.write_fields(out / "fields.xdmf", result.model.mesh, written)
    return True


def run(scene: Scene, out, echo: bool = False) -> dict:
    """CLI entry: solve, write outputs, print a summary; SolveError if not converged."""
    result = solve_static(scene)
    summary = write_static_outputs(result, out)
    if echo and result.model.mesh.comm.rank == 0:
        for w in summary["warnings"]:
            print(f"fem-forms: warning: {w}", file=sys.stderr)
    if echo and result.model.mesh.comm.rank == 0 and summary["converged"]:
        print(f"{scene.title}: {summary['dofs']} dofs, {summary['newton_iterations']} Newton iterations "
              f"in {summary['load_steps']} load steps, max |u| = {summary['max_displacement']:.6g} m, "
              f"{summary['wall_time_s']:.2f} s -> {out}")
        for name, pr in summary["probes"].items():
            print(f"  probe {name} {pr['point']}: u = [{', '.join(f'{v:.6g}' for v in pr['displacement'])}]")
    if "collapse" in summary:
        raise SolveError(f"{scene.title}: plastic collapse: no equilibrium beyond load factor "
                         f"{summary['collapse']['load_factor']:.6g} ({summary['message']})")
    if not summary["converged"]:
        raise SolveError(f"{scene.title}: did not converge: {summary['message']}")
    return summary

