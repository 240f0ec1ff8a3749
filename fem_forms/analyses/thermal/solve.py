"""The heat run: steady (one solve) or transient (backward Euler marched by the shared time-stepping loop),
with probe temperatures every step and frames every output_every steps."""
from __future__ import annotations

from dataclasses import dataclass, field
import time
from typing import Callable

from dolfinx import fem
from mpi4py import MPI

from fem_forms.output.summary import header
from fem_forms.errors import SolveError
from fem_forms.meshes import LoadedMesh, load_mesh
from fem_forms.output import probes
from fem_forms.physics.thermal import HeatForms, temperature_space
from fem_forms.scene import Scene
from fem_forms.solvers.thermal_step import HeatSolver, max_value, min_value
from fem_forms.solvers.time_stepping import history_corners, march
from fem_forms.state import State


@dataclass
class ThermalResult:
    """The temperature and the numbers results.json reports."""
    scene: Scene
    loaded: LoadedMesh
    T: fem.Function
    physics: list
    steps: int = 0
    time_reached: float = 0.0
    iterations: int = 0
    probe_rows: list = field(default_factory=list)     # [t, T at each probe]
    wall_time_s: float = 0.0

    def summary(self) -> dict:
        space = self.T.function_space
        names = list(self.scene.output.probes)
        final = probes.evaluate(self.T, self.scene.output.probes)
        return {
            **header("thermal", self.scene, self.loaded.mesh.comm, space.dofmap.index_map.size_global,
                     self.wall_time_s),
            "mesh": self.loaded.info,
            "converged": True,
            "transient": self.scene.dynamic is not None,
            "steps": self.steps,
            "time_reached": self.time_reached,
            "newton_iterations": self.iterations,
            "max_temperature": max_value(self.T),
            "min_temperature": min_value(self.T),
            "element": f"P{self.scene.discretization.degree} {self.loaded.mesh.topology.cell_name()}",
            "physics": self.physics,
            "probes": {n: {"point": self.scene.output.probes[n], "temperature": final[n][0]} for n in names},
        }


def solve_thermal(scene: Scene, on_frame: Callable | None = None, comm: MPI.Comm = MPI.COMM_WORLD) -> ThermalResult:
    """Steady heat (no [dynamic]) or backward Euler from the initial temperature over [dynamic] duration.
    on_frame(T, t) runs at t = 0 and every output_every steps (and at the end)."""
    t0 = time.perf_counter()
    th, disc = scene.thermal, scene.discretization
    loaded = load_mesh(scene.mesh, comm, degree=disc.degree)
    T = fem.Function(temperature_space(loaded.mesh, disc.degree), name="temperature")
    T.x.array[:] = th.initial_temperature
    state = State({"temperature": T})
    transient = scene.dynamic is not None
    forms = HeatForms(th, scene.materials, loaded, T, state.old["temperature"], transient, disc.quadrature)
    solver = HeatSolver(forms, state, scene.solver.petsc, scene.solver.linear)
    probes.evaluate(T, scene.output.probes)                       # a probe outside the mesh is bad input
    result = ThermalResult(scene, loaded, T, forms.physics)

    def record(t: float) -> None:
        values = probes.evaluate(T, scene.output.probes)
        result.probe_rows.append([t] + [values[n][0] for n in scene.output.probes])

    if not transient:
        out = solver.solve()
        if not out.accepted:
            raise SolveError(f"{scene.title}: the steady heat problem did not converge ({out.why})")
        record(0.0)
        if on_frame:
            on_frame(T, 0.0)
    else:
        dyn = scene.dynamic
        forms.set_time(0.0)
        record(0.0)
        if on_frame:
            on_frame(T, 0.0)

        def accepted(t: float, dt: float, step: int) -> None:
            record(t)
            if on_frame and (step % dyn.output_every == 0 or t >= dyn.duration * (1 - 1e-12)):
                on_frame(T, t)

        rep = march(solver, 0.0, dyn.duration, dyn.dt, accepted, max_cutbacks=scene.solver.max_cutbacks,
                    stops=history_corners(*(b.history for b in scene.thermal.boundary)))
        result.steps, result.time_reached = rep.steps, rep.time_reached
    result.iterations = solver.iterations
    result.wall_time_s = time.perf_counter() - t0
    return result
