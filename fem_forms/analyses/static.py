"""Static analysis: equilibrium under the scene's loads, then fields, picture and results.json."""
from __future__ import annotations

from pathlib import Path
import sys

from mpi4py import MPI

from fem_forms.equilibrium import StaticResult, solve_static
from fem_forms.errors import SolveError
from fem_forms.output import fields, pictures, results
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
        scene = result.model.scene
        summary.update(plastic_summary(result.model))
        T = result.model.temperature
        if scene.output.fields:
            written = output_fields(result.quantities, scene.output.fields) + plastic_fields(result.model)
            if T is not None:
                written.append(fields.p1_interpolant(T, "temperature"))
            fields.write_fields(out / "fields.xdmf", result.model.mesh, written)
            files["fields"] = "fields.xdmf"
        if "von_mises" in scene.output.fields:
            vm = result.quantities.field("von_mises")
            summary["max_von_mises"] = comm.allreduce(
                float(vm.x.array.max()) if vm.x.array.size else 0.0, op=MPI.MAX)
        if scene.output.picture:
            pictures.picture(out / "deformed.png", result.u, scene.title, up=pictures.scene_up(scene))
            files["picture"] = "deformed.png"
    results.write_newton_history(out / "newton_history.csv", result.report.steps, comm)
    files["newton_history"] = "newton_history.csv"
    summary["files"] = files
    results.write_json_atomic(out / "results.json", summary, comm)
    return summary


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

