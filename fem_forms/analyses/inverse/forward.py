"""The forward check's solve on the written rest mesh, with the forward forms (not the inverse ones).

check = "equilibrium" (default): the design claims that the target is an equilibrium of the rest shape
under the loads. So start Newton from that claim, u = target - rest at every node, at full load: if the
forward residual there is at tolerance within EQUILIBRIUM_NEWTON_STEPS Newton steps, the claim holds
(degree 2: see CURVED_NEWTON_STEPS).
The tolerance is where a static solve of the rest shape from zero would stop: snes_rtol (1e-9) times
the residual at the rest shape under the full load, or the larger of where the direct design's own Newton
stops: snes_rtol times the same loads' residual on the target shape, or the round-off floor at the target
(eps |K|_inf |u|_inf sqrt(n), at most 1e-6 of the load's). results.json forward_check says which one.
check = "path": ramp the loads from the rest shape with Newton (load continuation), as a user's static
run of the rest mesh would; it costs about as much as the design itself.
Either way the tangent's inertia at the equilibrium found tells whether it is stable."""
from __future__ import annotations

import copy
from dataclasses import dataclass
from pathlib import Path

from dolfinx import fem
import numpy as np
from petsc4py import PETSc
from scipy.spatial import cKDTree

from fem_forms.analyses.inverse.stability import (Inertia, assemble_tangent, inertia_of, pressure_dofs,
                                                  tangent_inertia)
from fem_forms.analyses.static.solve import StaticResult, solve_static
from fem_forms.meshes import LoadedMesh
from fem_forms.model import build_model
from fem_forms.scene import MeshSpec, Scene, Selector
from fem_forms.solvers import acceptance, continuation, snes
from fem_forms.solvers.linear import rigid_body_modes

# The check's tangent is symmetric and (at the designed equilibrium) positive definite: with the scene's
# linear = "auto" it runs CG + GAMG (rigid-body near-nullspace) from this size on, and falls back to LU
# if a linear solve fails. Measured on the Chen-size arm (27,675 dofs, path check, 7 Newton steps): the
# solve 4.5 s CPU with LU, 1.3 s with CG + GAMG; at 10,527 dofs 0.7-1.0 s with LU, 0.5 s with CG + GAMG.
CHECK_ITERATIVE_ABOVE_DOFS = 10_000
# Newton steps the equilibrium check may take from the predicted equilibrium. Degree 1 designs are the
# exact discrete inverse of the forward problem on the written mesh: they start at the design's own
# tolerance and take 0 or 1. Degree 2 designs lose their mid-edge rest positions in the written
# (straight-edged) mesh, so the target is only near an equilibrium of it (measured on a 10x2x2 beam,
# E 10 MPa: residual 580x the load's at the target, the equilibrium 1e-4 m away): Newton takes up to
# CURVED_NEWTON_STEPS from there, and the distance to the target is checked as for the path check.
EQUILIBRIUM_NEWTON_STEPS = 2
CURVED_NEWTON_STEPS = 8


@dataclass
class ForwardSolve:
    """What the forward check solved and found; summary() is results.json's "forward_check"."""
    kind: str                   # "equilibrium" | "path"
    static: StaticResult        # the forward model (mesh, u) and its solve report
    inertia: Inertia | None     # of the tangent at the equilibrium found (None: the path solve failed)
    start_residual: float | None = None   # equilibrium check: |R(target)| / |R(rest shape)| at full load
    tolerance: float | None = None        # ... and what it was held to (same scale), set by:
    tolerance_from: str = ""              # "rest shape" | "design" | "round-off" | "snes_atol" (the user's)

    def summary(self) -> dict:
        r = self.static.report
        out = {"kind": self.kind, "newton_iterations": r.newton_iterations, "linear_solver": r.linear_solver,
               "krylov_iterations": r.krylov_iterations, "load_steps": r.load_steps}
        if self.start_residual is not None:
            out["start_residual_relative"] = self.start_residual
            out["tolerance_relative"] = self.tolerance
            out["tolerance_from"] = self.tolerance_from
        if self.inertia is not None:
            out["tangent"] = self.inertia.summary()
        return out


def forward_scene(scene: Scene, rest_mesh: Path, dofs: int, carved: bool = False) -> Scene:
    """The static scene of the rest shape written to `rest_mesh`, with the check's linear solver. A carved
    part (voids at 1e-6 of the stiffness) is solved with LU at any size: CG + GAMG failed its first linear
    solve on the carved sag-and-stand figure (P2, 119k dofs), and the equilibrium check has no retry."""
    fscene = copy.deepcopy(scene)
    fscene.analysis = "static"
    fscene.mesh = MeshSpec(generator="file", file=rest_mesh)
    fscene.output.probes = {}
    if fscene.several_materials:                # each material's cells, carried over as a volume group
        for m in fscene.materials:
            m.where = Selector("group", group=m.name, key=f"{m.key}.where")
    if fscene.discretization.formulation == "mixed":     # a saddle point: LU, as the static analysis's
        fscene.solver.linear = "direct"
    elif fscene.solver.linear == "auto" and carved:
        fscene.solver.linear = "direct"
    elif fscene.solver.linear == "auto" and dofs >= CHECK_ITERATIVE_ABOVE_DOFS:
        fscene.solver.linear = "iterative-then-direct"
        # GAMG graph squared on the finest level only, threshold 0.01: on the Chen arm 265 CG iterations
        # instead of 462 (7 Newton steps instead of 8), the path check's solve 2.0 -> 1.3 s CPU
        for k, v in {"pc_gamg_square_graph": 1, "pc_gamg_threshold": 0.01}.items():
            fscene.solver.petsc.setdefault(k, v)
    return fscene


def predicted_displacement(u: fem.Function, pts_rest: np.ndarray, pts_target: np.ndarray) -> None:
    """u = target - rest position at every node of the written rest mesh (its points matched to the
    written ones by position); P2 spaces take the P1 interpolant."""
    V = u.function_space
    nodal = u if V.ufl_element().degree() == 1 else fem.Function(fem.VectorFunctionSpace(V.mesh, ("Lagrange", 1)))
    X = nodal.function_space.tabulate_dof_coordinates()
    idx = cKDTree(pts_rest).query(X)[1]
    nodal.x.array[:] = (pts_target[idx] - X).ravel()
    if nodal is not u:
        u.interpolate(nodal)
    u.x.scatter_forward()


def forward_model(fscene: Scene, loaded: LoadedMesh, carved: dict | None = None):
    """The forward model on the rest mesh; `carved` ({"extra": .., "density": ..}, a carving's fields on
    `loaded`) puts its stiffness factor in the forms and its density in the density field."""
    carved = carved or {}
    model = build_model(fscene, loaded=loaded, extra=carved.get("extra"))
    if carved.get("density") is not None:
        model.parameters.set_density(carved["density"])
    return model


def solve_at_target(fscene: Scene, loaded: LoadedMesh, pts_rest: np.ndarray, pts_target: np.ndarray,
                    design_scale: float = 0.0, carved: dict | None = None) -> ForwardSolve:
    """Newton from the predicted equilibrium at full load, at most EQUILIBRIUM_NEWTON_STEPS steps
    (CURVED_NEWTON_STEPS for degree 2). `design_scale`: the design's own residual scale (the loads on the
    target shape), whose snes_rtol its Newton stopped at; the check accepts that too."""
    model = forward_model(fscene, loaded, carved)
    steps = EQUILIBRIUM_NEWTON_STEPS if fscene.discretization.degree == 1 else CURVED_NEWTON_STEPS
    predicted_displacement(model.u, pts_rest, pts_target)
    model.start_from_displacement()
    model.load.set(1.0)
    problem = model.problem()
    # full Newton steps: at an equilibrium the energy's changes are round-off, an energy line search sees
    # no decrease and wastes a step (measured on the soft beam: 2 steps with it, 1 without)
    options = {"snes_linesearch_type": "basic", **fscene.solver.petsc, "snes_max_it": steps}
    driver = snes.SNESDriver(problem, options, fscene.solver.linear, "fem_forms_check_",
                             near_nullspace=None if model.unknown is not model.u else lambda: rigid_body_modes(model.V))
    K = assemble_tangent(model.compiled("jacobian"), model.bcs)      # at the target
    try:
        scale = driver.load_scale()              # the residual at the rest shape (u = 0) under full load
        start = driver.residual_norm() / max(scale, 1e-300)
        # at tolerance: where a static solve of the rest shape would stop (snes_rtol of that residual), or
        # of the same loads on the target shape, where the design stopped, or at the round-off floor at
        # the target (the design's Newton stops there too; on the Chen arm 1.05e-9 of the load's: without
        # the floor this check took one more Newton step, 0.35 s, to move 2e-15 m), the floor capped at
        # the 1e-6 of the load a load step's acceptance allows
        rtol = driver.options["snes_rtol"]
        bounds = {"rest shape": rtol * scale, "design": rtol * design_scale,
                  "round-off": min(snes.roundoff_floor(K.norm(PETSc.NormType.INFINITY), model.u.vector),
                                   acceptance.ACCEPTED * scale)}
        driver.user_options.setdefault("snes_atol", max(bounds.values()))
        tolerance = float(driver.user_options["snes_atol"])
        set_by = max(bounds, key=bounds.get) if tolerance == max(bounds.values()) else "snes_atol"
        report = continuation.solve(problem, driver=driver, max_cutbacks=0)
    finally:
        driver.snes.destroy()
    if not report.converged:
        step = report.steps[-1] if report.steps else None
        last = step.residuals[-1] / max(scale, 1e-300) if step and step.residuals else float("nan")
        report.message = (f"its residual there is {start:.2e} of the load's (tolerance "
                          f"{tolerance / max(scale, 1e-300):.2g}), {last:.2e} after {steps} "
                          f"Newton steps ({step.note if step else report.message})")
    model.sync_displacement()                               # mixed: the displacement out of (u, p)
    if report.converged and report.newton_iterations:      # the tangent where Newton ended (a failed solve
        K.destroy()                                         # is rolled back to the target)
        K = assemble_tangent(model.compiled("jacobian"), model.bcs)
    inertia = inertia_of(K, pressure_dofs(model.unknown))
    K.destroy()
    return ForwardSolve("equilibrium", StaticResult(model, report), inertia, start,
                        tolerance / max(scale, 1e-300), set_by)


def solve_along_path(fscene: Scene, loaded: LoadedMesh, carved: dict | None = None) -> ForwardSolve:
    """Load continuation from the rest shape (the scene's steps and cut-backs), as `fem-forms run` would."""
    static = solve_static(fscene, model=forward_model(fscene, loaded, carved))
    converged = static.report.converged
    m = static.model
    inertia = (tangent_inertia(m.compiled("jacobian"), m.bcs, pressure_dofs(m.unknown), (m.terms.arrays, m.unknown))
               if converged else None)
    return ForwardSolve("path", static, inertia)
