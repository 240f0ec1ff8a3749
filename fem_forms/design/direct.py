"""Inverse elastostatics: equilibrium written on the known target shape with the rest positions as unknowns."""
from __future__ import annotations

import time

import numpy as np
import ufl

from fem_forms.design.parameters import InverseResult, cellwise_exact, one_point_scene, target_scene
from fem_forms.meshes import LoadedMesh, load_mesh
from fem_forms.model import Model, build_model
from fem_forms.physics.admissibility import SmallestValue
from fem_forms.physics.cavities import cavity_report
from fem_forms.scene import Scene
from fem_forms.solvers import continuation, snes
from fem_forms.solvers.linear import rigid_body_modes


def solve_direct(scene: Scene, material=None, loaded: LoadedMesh | None = None, extra: dict | None = None,
                 density: np.ndarray | None = None) -> InverseResult:
    """Inverse elastostatics with load continuation (secant predictor, automatic cut-back). `extra` enters
    the Context (a carving's DG0 `stiffness_factor`), `density` (per owned cell of `loaded`) replaces the
    materials' (a carving's fill density in its carved cells)."""
    t0 = time.perf_counter()
    loaded = loaded or load_mesh(target_scene(scene))
    mesh = loaded.mesh

    def build(sc: Scene) -> Model:
        model = build_model(sc, material, loaded=loaded, extra=extra, rest="unknown")
        if density is not None:
            model.parameters.set_density(density)
        model.only_ufl_terms("inverse design")
        return model

    one = one_point_scene(scene, mesh)
    model = build(one or scene)
    if one is not None and not cellwise_exact(model.residual, model.unknown):   # a field that varies inside cells
        model = build(scene)
    v, V, G = model.unknown, model.V, model.context.rest_map
    load, bcs, terms = model.load, model.bcs, model.terms
    residual, jacobian = model.residual, model.jacobian
    degree = model.dx.metadata()["quadrature_degree"]
    rest_volume = SmallestValue(ufl.det(G), mesh, degree)

    def inadmissible():
        return rest_volume.positive_or("inverted rest-shape elements (min det = {value:.3g})")

    problem = snes.NonlinearProblem(v, residual, jacobian, bcs, energy=None, set_load=load.set,
                                    inadmissible=inadmissible, scalars=model.global_scalars())
    options = {"snes_linesearch_type": "basic", **scene.solver.petsc}
    mixed = scene.discretization.formulation == "mixed"       # (v, p): a saddle point, LU as in statics
    report = continuation.solve(problem, options, steps=scene.solver.steps,
                                max_cutbacks=scene.solver.max_cutbacks,
                                linear_kind="direct" if mixed else scene.solver.linear,
                                near_nullspace=None if mixed else lambda: rigid_body_modes(V),
                                prefix="fem_forms_inverse_",
                                reuse_factor=False if problem.scalars else "chord")   # bordered: fresh factors
    model.sync_displacement()                                  # mixed: the rest offset out of (v, p)
    res = InverseResult("direct", model.u, loaded, report.converged, report.newton_iterations, report.message,
                        history=[{"load": s.load, "iterations": s.iterations, "accepted": s.accepted,
                                  "reason": s.reason, "note": s.note} for s in report.steps],
                        physics=[t.name for t in terms], residual_scale=report.load_scale)
    res.cavities = cavity_report(terms)           # the pressure and the rest volume the design found
    res.solve_time = time.perf_counter() - t0
    return res

