"""Inverse rest-shape design analysis: run the scene's method, check the design, write outputs."""
from __future__ import annotations

from pathlib import Path
import sys
import time

from dolfinx import fem
import numpy as np

from fem_forms.analyses.inverse.carving import balance_line, check_stance, design_carved
from fem_forms.analyses.inverse.check import check_rest_shape, picture
from fem_forms.analyses.inverse.standing import standing_report
from fem_forms.design.direct import solve_direct
from fem_forms.design.fixed_point import solve_fixed_point
from fem_forms.design.optimizers import solve_adjoint
from fem_forms.design.parameters import InverseResult, target_scene
from fem_forms.analyses.static.solve import max_norm
from fem_forms.errors import SolveError
from fem_forms.meshes import load_mesh
from fem_forms.output import fields, pictures, probes, results
from fem_forms.output.quantities import Quantities
from fem_forms.output.strength import has_strength, summary_line
from fem_forms.output.summary import header
from fem_forms.scene import Scene


METHODS = {"direct": solve_direct, "adjoint": solve_adjoint, "fixed-point": solve_fixed_point}


def design_rest_shape(scene: Scene, material=None) -> InverseResult:
    """Run the scene's inverse method (mesh loading and compilation included in solve_time); with
    [balance], the carving first, on the target (res.carving), and the rest shape of the carved part."""
    t0 = time.perf_counter()
    loaded = load_mesh(target_scene(scene))
    V = fem.VectorFunctionSpace(loaded.mesh, ("Lagrange", scene.discretization.degree))
    probes.evaluate(fem.Function(V), scene.output.probes)       # a probe outside the target: bad input
    if scene.balance is not None:                               # direct only (the scene's rules)
        res = design_carved(scene, material, loaded, solve_direct)
    else:
        res = METHODS[scene.inverse.method](scene, material, loaded)
    res.solve_time = time.perf_counter() - t0
    return res


def run(scene: Scene, out: Path, echo: bool = False) -> dict:
    """CLI entry: design, check, write outputs; SolveError (exit 3) for any unusable design."""
    t0 = time.perf_counter()
    res = design_rest_shape(scene)
    comm = res.loaded.mesh.comm
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    summary = {**header("inverse", scene, comm, res.v.function_space.dofmap.index_map.size_global * 3),
               "method": res.method,
               "iterations": res.iterations, "converged": res.converged, "design_time_s": res.solve_time,
               "forward_solves": res.forward_solves,
               "physics": res.physics, "history": res.history,
               **({"cavities": res.cavities} if res.cavities else {})}
    problems = [] if res.converged else [f"the {res.method} method did not reach a rest shape: {res.message}"]
    check = None
    if res.converged:
        check = check_rest_shape(scene, res, out, res.carving)
        problems += check.problems
        if res.carving is not None:
            if not any("cannot write" in p for p in check.problems):
                problems += [p for p in [res.carving.write_void(out, res.v)] if p]
            summary["balance"], stance = check_stance(res.carving, check.static, out, scene.title,
                                                      scene.output.picture)
            problems += stance
        summary["target_mismatch_max"] = check.mismatch_max
        summary["design_gap_max"] = check.design_gap_max
        if check.solve is not None:
            summary["forward_check"] = check.solve.summary()
            if has_strength(scene) and check.static.report.converged:    # the rest shape under its loads
                summary["strength"] = Quantities(check.static.model).strength()
        if getattr(scene, "contact", None) is not None:
            standing, unusable = standing_report(scene, check, res.free_direction)
            summary.update(standing)
            problems += unusable
        if check.matched_mismatch_max is not None:
            summary["matched_mismatch_max"] = check.matched_mismatch_max
        summary["rest_mesh"] = str((out / "rest_shape.msh"))
        summary["rest_surface"] = str((out / "rest_shape.stl"))
        summary["max_rest_offset"] = max_norm(res.v)
        offsets = probes.evaluate(res.v, scene.output.probes)
        summary["probes"] = {n: {"point": p, "rest_position": (np.array(p) + offsets[n]).tolist()}
                             for n, p in scene.output.probes.items()}
        fields.write_fields(out / "fields.xdmf", res.loaded.mesh,
                            [fields.p1_interpolant(res.v, "rest_minus_target")])
        picture(out / "inverse.png", res, check, scene.title, up=pictures.scene_up(scene))
    summary["usable"] = not problems
    summary["problems"] = problems
    summary["wall_time_s"] = time.perf_counter() - t0
    results.write_json_atomic(out / "results.json", summary, comm)
    if echo and comm.rank == 0:
        for w in summary.get("warnings", []):
            print(f"fem-forms: warning: {w}", file=sys.stderr)
    if echo and comm.rank == 0 and not problems:
        print(f"{scene.title}: rest shape by the {res.method} method in {res.iterations} iterations, "
              f"{res.solve_time:.2f} s; largest rest offset {summary['max_rest_offset']:.4g} m; forward check "
              f"({check.solve.kind}, stable) lands within {check.mismatch_max:.3g} m of the target"
              + ("" if check.matched_mismatch_max is None else
                 f" ({check.matched_mismatch_max:.3g} m where matched)") + f" -> {out}")
        if line := summary_line(summary):
            print(line + " (the rest shape under its loads)")
        if "balance" in summary:
            print(balance_line(summary["balance"]))
        if "stance" in summary:
            st = summary["stance"]
            print(f"stands on its own: rests {1e3 * summary['resting_offset_m']:+.3g} mm from the target's height "
                  f"(the barrier's gap), shape within {summary['shape_mismatch_max']:.3g} m; centre of mass "
                  f"{1e3 * st['margin_m']:.3g} mm inside the contact patch (toppling angle "
                  f"{st['toppling_angle_deg']:.3g} deg)")
    if problems:
        raise SolveError(f"{scene.title}: no usable rest shape: {'; '.join(problems)}")
    return summary

