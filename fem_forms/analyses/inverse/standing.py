"""A rest shape designed to stand on obstacles ([contact], no glue): what its forward check says of it. How high
it rests (the barrier's gap, not the design's) and its shape's mismatch without that; each obstacle's force and
how much of Coulomb's cone the friction uses (a part that is to stand must not slide); and its stance: the centre
of mass of the sagged part over the polygon of the points touching the obstacles."""
from __future__ import annotations

from dolfinx import fem
from mpi4py import MPI
import numpy as np

from fem_forms.design.support import SupportPolygon


def centre_of_mass(model) -> np.ndarray:
    """The centre of mass of the part at its current state: each rest mass at its deformed place (all ranks)."""
    ctx, comm = model.context, model.mesh.comm
    rho = model.parameters.density
    mass = comm.allreduce(fem.assemble_scalar(fem.form(ctx.volume(rho))), op=MPI.SUM)
    return np.array([comm.allreduce(fem.assemble_scalar(fem.form(ctx.volume(rho * ctx.position[i]))), op=MPI.SUM)
                     for i in range(3)]) / mass


def standing_report(scene, check, up: np.ndarray) -> tuple[dict, list]:
    """results.json's numbers of a design standing on obstacles (resting_offset_m, shape_mismatch_max, contact,
    stance, and `warnings`: points sliding at Coulomb's limit, as a compressed block's sole edges do) and the problems
    that make it unusable (toppling, touching nothing). `up`: the table's normal (gravity's direction when the scene
    has no gravity load)."""
    static = check.static
    out = {"resting_offset_m": check.resting_offset, "shape_mismatch_max": check.shape_mismatch_max}
    if static is None or not static.report.converged:
        return out, []
    model = static.model
    term = next(t for t in model.terms.arrays if t.role == "contact")
    x = model.unknown.vector
    contact = term.report(x)
    out["contact"] = contact["contact"]
    out["min_distance"] = contact["min_distance"]
    slides = [f"{r['sliding_points']} contact points slip at Coulomb's limit on {name!r} (the rest shape is then "
              "path-dependent there: the forward check's load path is what it lands by)"
              for name, r in out["contact"].items() if r.get("sliding_points")]
    if slides:
        out["warnings"] = slides
    problems = []
    p = term.surface.positions(x)
    touching = p[np.any([ob.distance(p) < term.dhat for ob in term.obstacles], axis=0)]
    if not len(touching):
        return out, problems + ["the checked part touches no obstacle: nothing holds it"]
    com = centre_of_mass(model)
    if not np.all(np.isfinite(com)):
        return out, problems + ["the part has no mass (rho = 0): its stance is not defined"]
    gravity = next((ld.g for ld in scene.load if ld.type == "gravity"), None)
    polygon = SupportPolygon.from_points(touching, np.asarray(gravity, float) if gravity is not None else -up)
    margin = polygon.margin(com)
    out["stance"] = {"centre_of_mass": com.tolist(), "support_corners": len(polygon.vertices),
                     "margin_m": margin, "toppling_angle_deg": polygon.toppling_angle_deg(com), "stands": margin > 0}
    if margin <= 0:
        problems.append(f"it topples: its centre of mass lies {-margin:.3g} m outside the contact patch")
    return out, problems

