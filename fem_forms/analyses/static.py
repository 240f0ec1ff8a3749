"""Static equilibrium: minimise the total potential energy with SNES under load continuation."""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from .. import newton, probes
from ..linear import rigid_body_modes
from ..model import Model, build_model
from ..scene import Scene


@dataclass
class StaticResult:
    """What a static solve found: the model (mesh, u) and the numbers results.json reports."""
    model: Model
    report: newton.SolveReport
    energy: float = float("nan")
    max_displacement: float = float("nan")
    probes: dict = field(default_factory=dict)
    wall_time_s: float = 0.0

    @property
    def u(self) -> fem.Function:
        return self.model.u

    def summary(self) -> dict:
        r = self.report
        return {
            "analysis": "static",
            "title": self.model.scene.title,
            "dofs": self.model.dofs,
            "converged": r.converged,
            "newton_iterations": r.newton_iterations,
            "load_steps": r.load_steps,
            "load_reached": r.load_reached,
            "residual_norm": r.residual_norm,
            "energy": self.energy,
            "max_displacement": self.max_displacement,
            "wall_time_s": self.wall_time_s,
            "assembly_time_s": r.assembly_time,
            "linear_solver": r.linear_solver,
            "krylov_iterations": r.krylov_iterations,
            "preconditioner_builds": r.preconditioner_builds,
            "element": ("P2-P1 (Taylor-Hood) " if self.model.scene.discretization.formulation == "mixed" else
                        f"P{self.model.scene.discretization.degree} ") + self.model.mesh.topology.cell_name(),
            "quadrature_degree": self.model.scene.discretization.quadrature,
            "mpi_ranks": self.model.mesh.comm.size,
            "formulation": self.model.scene.discretization.formulation,
            "peak_memory_mb": peak_memory_mb(self.model.mesh.comm),
            "warnings": self.model.warnings,
            "probes": {n: {"point": self.model.scene.output.probes[n], "displacement": v}
                       for n, v in self.probes.items()},
            "message": r.message,
        }


def peak_memory_mb(comm) -> float:
    """Peak resident memory of this process so far, summed over ranks (MB)."""
    import resource
    return comm.allreduce(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, op=MPI.SUM)


def max_norm(f: fem.Function) -> float:
    """Largest nodal vector length of f over all ranks."""
    bs = f.function_space.dofmap.index_map_bs
    n = f.function_space.dofmap.index_map.size_local
    vals = f.x.array[: n * bs].reshape(-1, bs)
    local = float(np.linalg.norm(vals, axis=1).max()) if len(vals) else 0.0
    return f.function_space.mesh.comm.allreduce(local, op=MPI.MAX)


def solve_static(scene: Scene, material=None, model: Model | None = None) -> StaticResult:
    """Solve the scene's equilibrium. `material` may be a Material or a user's psi(F) function.
    Raises InputError for bad input; a failed solve is returned with report.converged False."""
    t0 = time.perf_counter()
    model = model or build_model(scene, material)
    probes.evaluate(model.u, scene.output.probes)          # a probe outside the mesh is bad input
    problem = newton.NonlinearProblem(
        model.state, model.residual, model.jacobian, model.bcs,
        energy=model.energy if model.conservative else None,
        set_load=model.load.set, inadmissible=model.inadmissible)
    report = newton.solve(problem, scene.solver.petsc, steps=scene.solver.steps,
                          max_cutbacks=scene.solver.max_cutbacks,
                          linear_kind="direct" if scene.discretization.formulation == "mixed" else scene.solver.linear,
                          near_nullspace=lambda: rigid_body_modes(model.V))
    result = StaticResult(model, report)
    if report.converged:
        model.sync_displacement()
        result.energy = model.mesh.comm.allreduce(fem.assemble_scalar(fem.form(model.energy)), op=MPI.SUM)
        result.max_displacement = max_norm(model.u)
        result.probes = probes.evaluate(model.u, scene.output.probes)
    result.wall_time_s = time.perf_counter() - t0
    return result


def write_static_outputs(result: StaticResult, out: "Path") -> dict:
    """Fields (XDMF), picture (PNG), Newton history (CSV), then results.json last and atomically."""
    from pathlib import Path
    from .. import output
    from ..kinematics import deformation_gradient
    from ..materials import cauchy_stress, von_mises

    out = Path(out)
    comm = result.model.mesh.comm
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    summary = result.summary()
    files = {}
    if result.report.converged:
        scene = result.model.scene
        if scene.output.fields:
            F = deformation_gradient(result.u)
            sigma = cauchy_stress(result.model.material, F)
            vm = output.cellwise(von_mises(sigma), result.model.mesh, "von_mises")
            output.write_fields(out / "fields.xdmf", result.model.mesh,
                                [output.p1_interpolant(result.u, "displacement"), vm])
            summary["max_von_mises"] = comm.allreduce(
                float(vm.x.array.max()) if vm.x.array.size else 0.0, op=MPI.MAX)
            files["fields"] = "fields.xdmf"
        if scene.output.picture:
            output.picture(out / "deformed.png", result.u, scene.title)
            files["picture"] = "deformed.png"
    output.write_newton_history(out / "newton_history.csv", result.report.steps, comm)
    files["newton_history"] = "newton_history.csv"
    summary["files"] = files
    output.write_json_atomic(out / "results.json", summary, comm)
    return summary


def run(scene: Scene, out, echo: bool = False) -> dict:
    """CLI entry: solve, write outputs, print a summary; SolveError if not converged."""
    from ..errors import SolveError
    result = solve_static(scene)
    summary = write_static_outputs(result, out)
    if echo and result.model.mesh.comm.rank == 0:
        import sys
        for w in summary["warnings"]:
            print(f"fem-forms: warning: {w}", file=sys.stderr)
    if echo and result.model.mesh.comm.rank == 0 and summary["converged"]:
        print(f"{scene.title}: {summary['dofs']} dofs, {summary['newton_iterations']} Newton iterations "
              f"in {summary['load_steps']} load steps, max |u| = {summary['max_displacement']:.6g} m, "
              f"{summary['wall_time_s']:.2f} s -> {out}")
        for name, pr in summary["probes"].items():
            print(f"  probe {name} {pr['point']}: u = [{', '.join(f'{v:.6g}' for v in pr['displacement'])}]")
    if not summary["converged"]:
        raise SolveError(f"{scene.title}: did not converge: {summary['message']}")
    return summary
