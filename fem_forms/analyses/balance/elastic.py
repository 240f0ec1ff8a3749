"""The sagging part: a static solve under gravity with the current carving, held by the scene's [[fix]].

Carved cells carry the fill density and a stiffness scaled by `fill_stiffness` = E_fill / E (a fill
material's own; for an empty fill an ersatz 1e-6): every material's psi(F) is multiplied by a DG0 factor
field (the Context's `stiffness_factor`). The factor and the density are fem.Functions, so a new carving
compiles nothing. (Removing carved cells from the mesh instead would build a
new mesh, spaces and solver per design and lose the cell correspondence the moments need.)

`sag_design` is the loop of `elastic = true`: solve the sag with the current carving, take the moments on
X + u (linear in the densities for that u), redesign, repeat until the redesign keeps the design (a fixed
point within FIXED_POINT_CELLS of the carvable cells) or MAX_STATIC_SOLVES solves. The reported design
is always one whose sag was solved: its deformed numbers are measured, never predicted by the LP.
"""
from __future__ import annotations

import dataclasses
from typing import Callable

from dolfinx import fem
from mpi4py import MPI
import numpy as np

from fem_forms.design.balance import stiffness_factors
from fem_forms.design.balance.body import Body
from fem_forms.design.balance.design import Setting, design
from fem_forms.design.balance.evaluate import evaluate, unmet
from fem_forms.analyses.static.solve import StaticResult, solve_static
from fem_forms.errors import SolveError
from fem_forms.meshes import load_mesh
from fem_forms.model import Model, build_model
from fem_forms.scene import Load, Scene
from fem_forms.scene.analyses.balance import fill_stiffness

MAX_STATIC_SOLVES = 4
FIXED_POINT_CELLS = 0.02        # a redesign changing at most this share of the carvable cells keeps the design


class SagModel:
    """The static model of the part under gravity, reused for every carving."""

    def __init__(self, scene: Scene, gravity: np.ndarray):
        if not any(ld.type == "gravity" for ld in scene.load):
            scene = dataclasses.replace(scene, load=list(scene.load) + [Load("gravity", g=list(gravity))])
        self.scene = scene
        loaded = load_mesh(scene.mesh, MPI.COMM_WORLD, degree=scene.discretization.degree)
        self.factor = fem.Function(fem.FunctionSpace(loaded.mesh, ("DG", 0)), name="stiffness_factor")
        self.factor.x.array[:] = 1.0
        self.model: Model = build_model(scene, loaded=loaded, extra={"stiffness_factor": self.factor})

    @property
    def mesh(self):
        return self.model.mesh

    def solve(self, density: np.ndarray, stiffness: np.ndarray) -> StaticResult:
        """Static sag with these cellwise densities and stiffness factors (owned cells), started from the
        last sag (a redesign changes it little: fewer Newton steps)."""
        self.model.parameters.set_density(density)
        n = len(stiffness)
        self.factor.x.array[self.factor.function_space.dofmap.list.array[:n]] = stiffness
        self.factor.x.scatter_forward()
        result = self._sag()
        if not result.report.converged:                  # retry from the rest shape before giving up
            self.model.u.x.array[:] = 0.0
            result = self._sag()
        if not result.report.converged:
            raise SolveError(f"balance: the sag under gravity did not converge: {result.report.message}")
        return result


    def _sag(self) -> StaticResult:
        """One static sag (each term starts again: contact's pseudo-time at 0, for friction's slip eps)."""
        return solve_static(self.scene, model=self.model)


def sag_design(scene: Scene, gravity: np.ndarray, setting: Callable[[object], Setting]) -> dict:
    """The elastic loop: the rigid numbers of the solid part, the design (or, for check, the solid part)
    and its numbers on the rest and on the sagged shape, and one history entry per static solve."""
    sag = SagModel(scene, gravity)
    st = setting(sag.model.loaded)
    b = st.spec
    rest = Body.rest(sag.mesh, b.shell)
    comm = sag.mesh.comm
    n_carvable = comm.allreduce(int(rest.carvable.sum()), op=MPI.SUM)
    solid = np.ones(int(rest.carvable.sum()))
    rigid_before = evaluate(rest, st, solid)
    timing = None                                          # the LPs' cost summed over the designs (rank 0)
    if b.goal != "check":
        solid, P = design(rest, st)                        # start from the rigid design
        timing = P.timing if P is not None else None
    history, met = [], None
    for k in range(MAX_STATIC_SOLVES):
        result = sag.solve(rest.density(solid, st.rho, b.fill_density),
                           stiffness_factors(rest, solid, fill_stiffness(b)))
        bent = rest.deformed(sag.model.u)
        numbers = evaluate(bent, st, solid, rest)
        numbers["max_displacement"] = result.max_displacement
        numbers.update(result.term_reports or {})              # resting on a [contact] floor: its force, the gap
        entry = {"static_solve": k + 1, "max_displacement": result.max_displacement,
                 "newton_iterations": result.report.newton_iterations,
                 "carved_fraction": numbers["carved_fraction"], "stability_margin": numbers["stability_margin"],
                 "toppling_angle_deg": numbers["toppling_angle_deg"]}
        history.append(entry)
        if b.goal == "check":
            break
        meets = unmet(numbers, st) is None
        entry["meets_goal"] = meets
        if meets:
            met = (solid, numbers, sag.model.u.x.array.copy())
        if k == MAX_STATIC_SOLVES - 1:
            break
        try:
            new, P = design(bent, st, rest, best_effort=True)
            timing = timing.add(P.timing) if P is not None else None
        except SolveError:
            if meets:                                      # no redesign on this shape, but this design holds
                break
            raise
        changed = comm.allreduce(int(np.sum(new != solid)), op=MPI.SUM)
        entry["cells_changed_by_redesign"] = changed
        if changed == 0 or (changed <= FIXED_POINT_CELLS * n_carvable and meets):
            break                                          # a fixed point: another solve would repeat this one
        solid = new
    if met is not None and not history[-1].get("meets_goal", True):
        solid, numbers, u = met                            # the last solved design that met the goal
        sag.model.u.x.array[:] = u
    after = evaluate(rest, st, solid)
    after["deformed"] = numbers
    return {"solid": solid, "before": rigid_before, "after": after, "mesh": sag.mesh, "rest": rest, "setting": st,
            "history": history, "u": sag.model.u, "timing": timing}
