"""The numbers results.json reports for one carving on one shape, and the check that a design meets its
goal's requirements (computed from the binary carving's mass properties, never from the LP)."""
from __future__ import annotations

import math

from mpi4py import MPI
import numpy as np

from fem_forms.design.balance import goals
from fem_forms.design.balance.body import Body
from fem_forms.design.balance.design import Setting, rocking_center, tip
from fem_forms.design.floating import flotation, tetrahedra
from fem_forms.design.mass_properties import MassProperties, total_moments
from fem_forms.design.support import SupportPolygon

SLACK = 1.02        # requirements checked with 2 % slack on their tolerance bands (round-off)


def evaluate(body: Body, st: Setting, solid: np.ndarray, rest: Body | None = None) -> dict:
    """Mass properties, support, and the goal's numbers for solid fractions `solid` of the carvable cells."""
    b = st.spec
    comm = body.mesh.comm
    rest = rest or body
    dens = body.density(solid, st.rho, b.fill_density)
    mp = MassProperties.from_moments(total_moments(dens, body.moments, comm))
    c = mp.center_of_mass
    up, e1, e2 = st.frame
    out = mp.as_dict()
    poly = SupportPolygon.from_points(body.contact_points(up, b.contact_tolerance), st.gravity)
    out["support_polygon"] = poly.corners_3d().tolist()
    out["stability_margin"] = poly.margin(c)
    out["toppling_angle_deg"] = poly.toppling_angle_deg(c)
    vol = body.moments[:, 0]
    carved = comm.allreduce(float(vol[body.carvable] @ (1 - solid)), op=MPI.SUM)
    out["carved_fraction"] = carved / comm.allreduce(float(vol.sum()), op=MPI.SUM)
    if b.goal in ("stand", "check"):
        out["stands"] = bool(out["stability_margin"] > 0)
        out["meets_margin"] = bool(out["toppling_angle_deg"] >= b.margin_angle * (1 - 1e-9)
                                   and out["stability_margin"] > 0)
    axis = np.asarray(b.axis) if b.goal == "spin" else up
    out["spin_axis"] = axis.tolist()
    out["spin_ratio"] = spin_ratio(mp.inertia, axis)
    out["principal_axis_angle_deg"] = axis_angle(mp, axis)
    if b.goal == "spin":
        point = tip(body, axis, b.contact_tolerance) if b.kind == "top" else None
        ref = point if point is not None else c
        off = (c - ref) - ((c - ref) @ axis) * axis
        out["com_distance_from_axis"] = float(np.linalg.norm(off))
        if point is not None:
            out["tip"] = point.tolist()
            out["com_height_above_tip"] = float((c - point) @ axis)
    if b.goal == "swim" or (b.goal == "check" and b.waterline is not None):
        keel = body.lowest(up)
        f = flotation(tetrahedra(body.corners), up, e1, e2, keel, b.waterline, comm)
        out["waterline"] = b.waterline
        out["center_of_buoyancy"] = f.center_of_buoyancy.tolist()
        out["metacentric_height"] = f.metacentric_height(c)
        out["displaced_volume"] = f.volume
        out["displaced_mass"] = f.volume * b.water_density
        hoff = (c - f.center_of_buoyancy) - ((c - f.center_of_buoyancy) @ up) * up
        out["com_offset_from_buoyancy_vertical"] = float(np.linalg.norm(hoff))
    if b.goal == "swing":
        center, R = rocking_center(body, st)
        out["curvature_center"] = center.tolist()
        out["curvature_radius"] = R
        out["com_depth_below_center"] = float((center - c) @ up)
        hoff = (c - center) - ((c - center) @ up) * up
        out["com_offset_from_center_vertical"] = float(np.linalg.norm(hoff))
    return out


def spin_ratio(inertia: np.ndarray, axis: np.ndarray) -> float:
    """I about the axis over the larger principal moment of the perpendicular block."""
    a = axis / np.linalg.norm(axis)
    e1, e2 = goals.perpendicular(a)
    B = np.array([[e1 @ inertia @ e1, e1 @ inertia @ e2], [e2 @ inertia @ e1, e2 @ inertia @ e2]])
    return float(a @ inertia @ a / np.linalg.eigvalsh(B)[-1])


def axis_angle(mp: MassProperties, axis: np.ndarray) -> float:
    """Angle between the axis and the nearest principal axis (degrees)."""
    cos = np.abs(mp.principal_axes.T @ axis).max()
    return float(np.degrees(np.arccos(min(1.0, cos))))


def unmet(numbers: dict, st: Setting, mass_target: float | None = None) -> str | None:
    """Why a design's numbers miss the goal's requirements, or None."""
    b = st.spec
    size = st.size
    if b.goal == "stand" and not numbers["meets_margin"]:
        return (f"toppling angle {numbers['toppling_angle_deg']:.3g} deg below the margin angle "
                f"{b.margin_angle} deg")
    if b.goal == "spin":
        if numbers["com_distance_from_axis"] > math.sqrt(2) * SLACK * goals.CENTER_TOLERANCE * size:
            return f"CoM {numbers['com_distance_from_axis']:.3g} m off the spin axis"
        if b.kind == "yoyo" and numbers["spin_ratio"] <= 1:
            return f"spin ratio {numbers['spin_ratio']:.4g} <= 1: the axis is not the largest moment"
    if b.goal == "swim":
        if abs(numbers["mass"] - numbers["displaced_mass"]) > SLACK * goals.MASS_TOLERANCE * numbers["displaced_mass"]:
            return f"mass {numbers['mass']:.6g} kg differs from the displaced water {numbers['displaced_mass']:.6g} kg"
        if numbers["com_offset_from_buoyancy_vertical"] > math.sqrt(2) * SLACK * goals.CENTER_TOLERANCE * size:
            return f"CoM {numbers['com_offset_from_buoyancy_vertical']:.3g} m off the buoyancy vertical"
        if numbers["metacentric_height"] < st.min_metacentric_height() * (1 - 1e-6):
            return f"metacentric height {numbers['metacentric_height']:.3g} m below the minimum"
    if b.goal == "swing":
        depth = numbers["curvature_radius"] * math.sin(math.radians(b.margin_angle))
        if numbers["com_depth_below_center"] < depth * (1 - 1e-6):
            return f"CoM only {numbers['com_depth_below_center']:.3g} m below the rocking centre"
        if numbers["com_offset_from_center_vertical"] > math.sqrt(2) * SLACK * goals.CENTER_TOLERANCE * size:
            return f"CoM {numbers['com_offset_from_center_vertical']:.3g} m off the rocking centre's vertical"
    return None
