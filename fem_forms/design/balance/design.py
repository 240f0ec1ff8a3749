"""From a Body to a binary carving: gather the carvable cells' moment columns on rank 0 (ordered by
global cell id, so any number of ranks poses the same LP), run the goal's program there, send the
carving back. Also the goal-independent geometry every goal needs (frame, support, tip, centres)."""
from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

from fem_forms.design.balance import goals
from fem_forms.design.balance.body import Body
from fem_forms.design.floating import flotation, tetrahedra
from fem_forms.design.mass_properties import total_moments
from fem_forms.design.support import SupportPolygon, fit_sphere
from fem_forms.frames import ground_frame
from fem_forms.errors import SolveError


@dataclass
class Setting:
    """What the goals need besides the cells: densities, gravity, the [balance] spec, the part's size."""
    spec: object                 # BalanceSpec
    rho: float | np.ndarray      # the solid's density: one, or one per owned cell (several materials)
    gravity: np.ndarray
    size: float

    @property
    def frame(self):
        return ground_frame(self.gravity)

    def min_metacentric_height(self) -> float:
        b = self.spec
        return b.min_metacentric_height if b.min_metacentric_height is not None else 0.01 * self.size


def fixed_moments(body: Body, st: Setting) -> np.ndarray:
    """M0: the wall at full density plus the carvable cells at the fill density (all ranks)."""
    dens = np.where(body.carvable, st.spec.fill_density, st.rho)
    return total_moments(dens, body.moments, body.mesh.comm)


def problem(body: Body, st: Setting) -> goals.Problem | None:
    """The LP data on rank 0 (None elsewhere)."""
    comm = body.mesh.comm
    M0 = fixed_moments(body, st)
    c = body.carvable
    rho = np.broadcast_to(st.rho, c.shape)[c]
    parts = comm.gather((body.ids[c], body.moments[c], body.centroids()[c], rho), root=0)
    if comm.rank != 0:
        return None
    ids = np.concatenate([p[0] for p in parts])
    order = np.argsort(ids)
    D = np.vstack([p[1] for p in parts])[order]
    cen = np.vstack([p[2] for p in parts])[order]
    rho = np.concatenate([p[3] for p in parts])[order]
    return goals.Problem((rho - st.spec.fill_density) * D.T, M0, cen, st.size)


def scatter(body: Body, s_root: np.ndarray | None) -> np.ndarray:
    """The solid fractions of this rank's carvable cells from rank 0's vector (ordered by global id)."""
    comm = body.mesh.comm
    ids = np.sort(np.concatenate(comm.allgather(body.ids[body.carvable])))
    s = comm.bcast(s_root, root=0)
    return s[np.searchsorted(ids, body.ids[body.carvable])]


def tip(body: Body, axis: np.ndarray, tolerance: float) -> np.ndarray:
    """A top's tip: the mean of the nodes lowest along the axis."""
    pts = body.contact_points(np.asarray(axis), tolerance)
    return pts.mean(axis=0)


def rocking_center(body: Body, st: Setting) -> tuple[np.ndarray, float]:
    up = st.frame[0]
    fit = fit_sphere(body.contact_points(up, st.spec.contact_tolerance))
    if fit is None:
        raise SolveError("balance: the contact region is flat or too small for a sphere fit (no rocking "
                         "surface): raise contact_tolerance or round the bottom")
    return fit


def full_moments(body: Body, st: Setting) -> np.ndarray:
    return total_moments(np.broadcast_to(st.rho, body.ids.shape).astype(float), body.moments, body.mesh.comm)


def design(body: Body, st: Setting, rest: Body | None = None,
           best_effort: bool = False) -> tuple[np.ndarray, goals.Problem | None]:
    """The goal's binary carving of this rank's carvable cells (solid fraction 0 or 1) on body's shape.
    `rest` (the undeformed body) fixes what a floating or spinning design refers to; `best_effort`
    (stand): the largest margin when the requested one is out of reach on this shape."""
    b = st.spec
    rest = rest or body
    up, e1, e2 = st.frame
    comm = body.mesh.comm
    if b.goal == "stand":
        poly = SupportPolygon.from_points(body.contact_points(up, b.contact_tolerance), st.gravity)
        if not poly.has_area:
            raise SolveError("balance: the support is a point or a line (no area to stand on): no design "
                             "can stand; raise contact_tolerance or give the part a foot")
        args = (poly.normals, poly.offsets, (up, e1, e2), poly.ground, math.tan(math.radians(b.margin_angle)))
        run = lambda P: goals.stand(P, *args, best_effort=best_effort)
    elif b.goal == "spin":
        axis = np.asarray(b.axis)
        if b.kind == "top":
            point = tip(body, axis, b.contact_tolerance)
        else:
            M = full_moments(rest, st)
            point = M[1:4] / M[0]
        run = lambda P: goals.spin(P, axis, point, along=b.kind == "yoyo")
    elif b.goal == "swim":
        keel = body.lowest(up)
        f = flotation(tetrahedra(body.corners), up, e1, e2, keel, b.waterline, comm)
        height = keel + f.KB + f.BM - st.min_metacentric_height()
        run = lambda P: goals.swim(P, (up, e1, e2), f.center_of_buoyancy, b.water_density * f.volume, height)
    elif b.goal == "swing":
        center, R = rocking_center(body, st)
        run = lambda P: goals.swing(P, (up, e1, e2), center, R * math.sin(math.radians(b.margin_angle)))
    else:
        raise ValueError(b.goal)
    P = problem(body, st)
    s_root, error = None, None
    if comm.rank == 0:
        try:
            s_root = run(P)
        except SolveError as e:
            error = str(e)
    error = comm.bcast(error, root=0)
    if error:
        raise SolveError(error)
    return scatter(body, s_root), P
