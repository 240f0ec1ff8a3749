"""analysis = "design": where to put the second material (the stiff one) so that the loaded part's probes reach
their targets. The layout is optimised as densities (fem_forms/design/layout.py: SIMP, filter, projection, adjoint
gradient; layout_optimizer.py: L-BFGS-B), then cast black and white (a cell is the placed material where its
density reaches the threshold whose cast reaches the targets with the least material, 1/2 first:
layout_optimizer.cast_layout) and solved once more as cast, from rest: the positions results.json reports are the
cast layout's, the files are what to make."""
from __future__ import annotations

import dataclasses
from pathlib import Path
import sys
import time

from dolfinx import fem, io
from mpi4py import MPI
import numpy as np

from fem_forms import progress
from fem_forms.analyses.static.solve import solve_static
from fem_forms.design.layout import CellVector, LayoutGradient, LayoutMaterial, PlacedDensity
from fem_forms.design.layout_optimizer import CAST_SLACK, cast_layout, optimize_layout
from fem_forms.design.layout_targets import TargetAngle, TargetPoints, part_length
from fem_forms.errors import InputError, SolveError
from fem_forms.materials.constants import bind_constants
from fem_forms.meshes import load_mesh
from fem_forms.model import build_model
from fem_forms.output import fields, results
from fem_forms.design.layout_files import VERTICES, write_layout_files
from fem_forms.output.probes import write_table
from fem_forms.output.summary import header
from fem_forms.scene import Scene


def _domain(model, cells: CellVector, placed_index: int) -> np.ndarray:
    """Where the placed material may go (design order): its `where`'s cells, else every cell."""
    spec = model.scene.materials[placed_index]
    if spec.where is None:
        return np.ones(cells.size, dtype=bool)
    regions = model.context.materials
    return cells.gather(regions.index[:cells.n_owned] == placed_index) > 0.5


def near_solver(scene: Scene):
    """The design's solve from a nearby layout's equilibrium: one step to full load (max_step 1), no cut-backs (a
    smaller load factor is farther from that state, not nearer); LayoutGradient.equilibrium approaches a far layout
    in steps. None where a load or support follows a history: its corners are steps of their own."""
    if any(getattr(ld, "history", None) for ld in scene.load) or any(f.history for f in scene.fix):
        return None
    near = dataclasses.replace(scene, solver=dataclasses.replace(scene.solver, steps=1, max_cutbacks=0,
                                                                 max_step=1.0))
    return lambda model: solve_static(near, model=model, answers=False).report


def build_design(scene: Scene, comm: MPI.Comm = MPI.COMM_WORLD) -> LayoutGradient:
    """The model of the scene with its two materials mixed per cell, and the design's gradient on it."""
    d = scene.design
    names = [m.name for m in scene.materials]
    body, placed = (scene.materials[names.index(n)] for n in d.materials)
    loaded = load_mesh(scene.mesh, comm, degree=scene.discretization.degree)
    if loaded.mesh.topology.cell_name() not in VERTICES:
        raise InputError(f"mesh: {loaded.mesh.topology.cell_name()} cells; a design writes its layout for "
                         "tetrahedra and hexahedra only")
    weight = fem.Function(fem.FunctionSpace(loaded.mesh, ("DG", 0)), name="placed_weight")
    mix = LayoutMaterial(bind_constants(body.material, loaded.mesh), bind_constants(placed.material, loaded.mesh),
                         weight)
    model = build_model(scene, mix, comm=comm, loaded=loaded)
    cells = CellVector(weight.function_space)
    targets = TargetPoints(model.V, *_target_rows(scene), part_length(model), *_counted_and_angles(scene))
    radius = d.filter_radius or 2.0 * float(np.mean(cells.volumes)) ** (1.0 / 3.0)
    return LayoutGradient(model, weight, cells, targets, radius, d.penalty, near=near_solver(scene),
                          solve=lambda model: solve_static(scene, model=model, answers=False).report,
                          domain=_domain(model, cells, names.index(d.materials[1])),
                          density=PlacedDensity(model.parameters.density, body.rho, placed.rho))


def _positions(d) -> list:
    """[design]'s target tables that place a probe (the others turn a segment: `angle`)."""
    return [t for t in d.target if t.get("position") is not None]


def _angles(d) -> list:
    return [t for t in d.target if t.get("angle") is not None]


def _target_rows(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """The targets' probe points and positions: one row per position target, then two per angle target (its
    segment's ends, `from` then `probe`, at their own rest points: not counted)."""
    probes = scene.output.probes
    rows = [(probes[t["probe"]], t["position"]) for t in _positions(scene.design)] + \
        [(probes[n], probes[n]) for t in _angles(scene.design) for n in (t["from"], t["probe"])]
    return np.array([r[0] for r in rows], dtype=float), np.array([r[1] for r in rows], dtype=float)


def _counted_and_angles(scene: Scene) -> tuple[np.ndarray, tuple]:
    """The position rows' counted coordinates (none on an angle's rows) and the TargetAngles on those rows."""
    placed, angles = _positions(scene.design), _angles(scene.design)
    counted = np.array([[float(i in t["axes"]) for i in range(3)] for t in placed] +
                       [[0.0] * 3] * (2 * len(angles))).reshape(-1, 3)
    return counted, tuple(TargetAngle(len(placed) + 2 * k, len(placed) + 2 * k + 1, float(np.radians(t["angle"])),
                                      np.asarray(t["about"], dtype=float) / np.linalg.norm(t["about"]))
                          for k, t in enumerate(angles))


def run(scene: Scene, out, echo: bool = False) -> dict:
    """Optimise, cast, solve the cast layout, write the files, then results.json last."""
    t0 = time.perf_counter()
    out = Path(out)
    comm = MPI.COMM_WORLD
    d = scene.design
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    design = build_design(scene, comm)
    history = []

    def said(k, J, fraction):
        history.append([k, J, fraction, design.beta])
        if echo and comm.rank == 0 and progress.reporter() is not None:       # shown as progress (not with -q)
            print(f"  layout {k}: mismatch J = {J:.4e}, placed fraction {fraction:.3f}, projection beta "
                  f"{design.beta:g}", file=sys.stderr, flush=True)

    result = optimize_layout(design, d.stiff_fraction, d.iterations, d.reach, on_iteration=said,
                             reach_angle=np.radians(d.reach_angle))
    allowed = design.targets.allowed(d.reach, np.radians(d.reach_angle))
    cast, level, _ = cast_layout(design, result.rho_bar, d.stiff_fraction, allowed)
    # along the load path from rest, as the part is loaded: measured on the PneuNet, the same cast layout reached
    # from the optimizer's last layout rests in another stable equilibrium (119.27 instead of 119.23 degrees)
    report = design.from_rest(cast.astype(float))
    if not report.converged:
        raise SolveError(f"design: the cast layout has no equilibrium under the loads ({report.message})")
    boundaries = fields.gather_facet_groups(design.model.loaded)         # the supports' and loads' groups
    files = write_layout_files(out, design.model.mesh, design.cells.order, cast, tuple(d.materials),
                               picture=scene.output.picture, facet_groups=boundaries)
    write_table(out / "design_history.csv", ["layout", "mismatch", "placed_fraction", "beta"], history, comm)
    files["history"] = "design_history.csv"
    if scene.output.fields:
        _write_fields(out / "layout.xdmf", design, result.rho_bar)
        files["fields"] = "layout.xdmf"
    summary = {**header("design", scene, comm, design.model.dofs, time.perf_counter() - t0),
               "converged": True, "design": {**_design_summary(design, result, cast, d), "cast_threshold": level},
               "files": files}
    summary["design"]["targets_reached"] = bool(summary["design"]["mismatch_cast"] <= allowed)
    said_warnings = _warnings(summary["design"], d)
    summary["warnings"] = list(design.model.warnings) + said_warnings
    results.write_json_atomic(out / "results.json", summary, comm)
    if echo and comm.rank == 0:
        s = summary["design"]
        print(f"{scene.title}: {result.iterations} layouts tried, {d.materials[1]} in "
              f"{s['placed_fraction_cast']:.1%} of its domain (bound {d.stiff_fraction:.0%}), "
              f"{summary['wall_time_s']:.1f} s -> {out}")
        for name, t in s["targets"].items():
            print(f"  {name}: reached {np.round(t['reached'], 6).tolist()} m, {t['distance_m'] * 1e3:.3g} mm from "
                  f"the target")
        for name, t in s["angles"].items():
            print(f"  {name}: turned {t['reached_deg']:.2f} deg (target {t['target_deg']:g} deg)")
        for line in said_warnings:
            print(f"fem-forms: warning: {line}", file=sys.stderr)
    return summary


def _warnings(s: dict, d) -> list[str]:
    """What results.json `warnings` and the run's stderr say of a design: targets out of reach, a cast over the
    bound."""
    out = []
    if not s["targets_reached"]:
        out.append(f"the cast layout misses the targets by more than their reach (design.targets and design.angles "
                   f"in results.json): {d.materials[1]} in {s['placed_fraction_cast']:.1%} of its domain (bound "
                   f"{d.stiff_fraction:.0%}), the optimizer "
                   f"{'converged' if s['optimizer_converged'] else 'stopped'} after {s['layouts_tried']} layouts, "
                   f"{s['gray_fraction']:.0%} of the domain gray before casting")
    if not s["within_bound"]:
        out.append(f"the cast layout holds more {d.materials[1]} than design.stiff_fraction = {d.stiff_fraction} "
                   f"allows ({s['placed_fraction_cast']:.1%}: the optimum at its bound rounded up)")
    return out


def _design_summary(design: LayoutGradient, result, cast: np.ndarray, d) -> dict:
    """results.json `design`: the optimum's and the cast layout's numbers, where the targets' probes landed."""
    volumes, domain = design.cells.volumes, design.domain > 0
    reached = design.targets.positions(design.model.u)
    misses = design.targets.misses(design.model.u)          # in the counted coordinates
    turned, angle_misses = design.targets.turned(design.model.u), design.targets.angle_misses(design.model.u)
    placed, angles = _positions(d), _angles(d)
    domain_volume = float(volumes @ domain)
    fraction_cast = float(volumes @ cast) / domain_volume
    gray = (result.rho_bar > 0.1) & (result.rho_bar < 0.9) & domain
    return {"materials": {"body": d.materials[0], "placed": d.materials[1]},
            "layouts_tried": result.iterations, "optimizer_converged": bool(result.converged),
            "mismatch_start": result.history[0] if result.history else None,
            "mismatch_optimized": result.objective, "mismatch_cast": design.targets.mismatch(design.model.u),
            "placed_fraction_bound": d.stiff_fraction, "placed_fraction_optimized": result.stiff_fraction,
            "placed_fraction_cast": fraction_cast,
            "within_bound": bool(fraction_cast <= d.stiff_fraction + CAST_SLACK),
            "placed_volume_m3": float(volumes @ cast), "domain_volume_m3": domain_volume,
            "gray_fraction": float(volumes @ gray) / domain_volume,
            "filter_radius_m": float(design.radius), "penalty": d.penalty,
            "targets": {t["probe"]: {"target": t["position"], "axes": ["xyz"[a] for a in t["axes"]],
                                     "node": design.targets.at[i].tolist(), "reached": reached[i].tolist(),
                                     "distance_m": float(np.linalg.norm(misses[i]))}
                        for i, t in enumerate(placed)},
            "angles": {f"{t['from']}->{t['probe']}": {"target_deg": t["angle"], "about": list(t["about"]),
                                                      "reached_deg": float(np.degrees(turned[k])),
                                                      "miss_deg": float(np.degrees(angle_misses[k]))}
                       for k, t in enumerate(angles)},
            "evaluations": design.evaluations}


def _write_fields(path: Path, design: LayoutGradient, rho_bar: np.ndarray) -> None:
    """layout.xdmf: the optimised densities (placed fraction per cell) and the cast layout's displacement."""
    model = design.model
    density = fem.Function(design.weight.function_space, name="placed_density")
    design.cells.fill(density, rho_bar)
    with io.XDMFFile(model.mesh.comm, str(path), "w") as xdmf:
        xdmf.write_mesh(model.mesh)
        xdmf.write_function(density)
        xdmf.write_function(fields.p1_interpolant(model.u, "displacement"))
