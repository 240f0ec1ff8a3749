"""Every designed rest shape is checked before it is handed out: written, loaded as a mesh, solved forward."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from mpi4py import MPI
import numpy as np
from scipy.spatial import cKDTree

from fem_forms.analyses.inverse import forward
from fem_forms.design import rest_shape
from fem_forms.meshes import cell_faces
from fem_forms.design.parameters import InverseResult
from fem_forms.errors import InputError
from fem_forms.meshes import MeshArrays, check_cells, from_arrays, mesh_size
from fem_forms.output import fields, pictures
from fem_forms.output.stl import write_stl
from fem_forms.physics.regions import MaterialRegions
from fem_forms.scene import Scene


@dataclass
class ForwardCheck:
    mismatch_max: float             # largest distance of the forward-solved shape from the target
    static: object                  # the StaticResult of the forward solve on the rest shape
    problems: list
    design_gap_max: float = np.inf  # ... from the deformed shape the design predicted
    matched_mismatch_max: float | None = None   # ... from the target on the matched points/region
    solve: forward.ForwardSolve | None = None   # how the forward check solved, and its tangent's inertia
    # rank 0: (target points, rest points, boundary faces of both: the same cells) for the picture
    drawn: tuple | None = None
    resting_offset: float = 0.0     # standing on obstacles: how much higher than the target the part rests, and
    shape_mismatch_max: float | None = None     # ... the largest distance from the target raised by that much


def _stability_problems(solve: forward.ForwardSolve, predicted: str) -> list:
    """An equilibrium whose tangent is not positive definite is unstable (a buckled branch past a bifurcation, a
    balloon beyond its pressure maximum): the loads do not keep the part there; refused."""
    i = solve.inertia
    if i is None or i.stable:
        return []
    where = f"at {predicted}" if solve.kind == "equilibrium" else "at the forward solve's equilibrium"
    if i.error:
        return [f"the tangent {where} could not be checked for stability: {i.error}"]
    head = (f"has {i.negative} negative pivots where a stable state has {i.saddle} (its pressure dofs), {i.null} "
            f"null, of {i.dofs}" if i.saddle else
            f"is not positive definite ({i.negative} negative, {i.null} null pivots of {i.dofs})")
    return [f"the tangent {where} {head}: an unstable equilibrium (a buckled branch past a bifurcation, or past a "
            "limit point of the loads: a balloon beyond its pressure maximum), the loads do not keep the part "
            "there; the design is not usable"]


def _matched_vertices(spec, pts_target: np.ndarray, size: float) -> np.ndarray | None:
    """Mask of the target's vertices an adjoint objective matches (None: the whole body)."""
    if spec.method != "adjoint" or (spec.match_points is None and spec.match_region is None):
        return None
    mask = np.zeros(len(pts_target), dtype=bool)
    if spec.match_points is not None:
        mask[cKDTree(pts_target).query(np.asarray(spec.match_points, dtype=float))[1]] = True
    else:
        tol = 1e-9 * size
        lo, hi = np.asarray(spec.match_region.lo), np.asarray(spec.match_region.hi)
        mask = np.all((pts_target >= lo - tol) & (pts_target <= hi + tol), axis=1)
    return mask


def _material_groups(scene: Scene, loaded) -> dict | None:
    """On rank 0, the rows of the gathered cells of each material (several materials only): the rest
    mesh carries them as volume groups, so its cells keep the materials they had on the target."""
    if not scene.several_materials:
        return None
    index = fields.gather_cell_values(loaded.mesh, MaterialRegions(loaded, scene.materials).index)
    if index is None:
        return None
    return {m.name: np.flatnonzero(index == i) for i, m in enumerate(scene.materials)}


def _write_and_inspect(scene: Scene, out: Path, gathered, target, groups, size: float,
                       cell_groups: dict | None = None) -> tuple[list, tuple]:
    """On rank 0: write the rest shape (volume .msh and STL) and look at it as built: does it cross a support
    plane or intersect itself? Returns (problems, what the picture draws)."""
    problems = []
    points, cells, ctype = gathered
    faces = cell_faces.boundary_faces(cells, ctype)
    drawn = (target[0], points, faces)
    write_ok = True
    try:
        rest_shape.write_volume_mesh(out / "rest_shape.msh", points, cells, ctype, groups, cell_groups)
        tris = cell_faces.triangles(faces)
        write_stl(out / "rest_shape.stl", points, tris, "rest_shape", ascii=True)
    except OSError as e:
        write_ok = False
        problems.append(f"cannot write the rest shape: {e}")
    if write_ok:
        for f in scene.fix:
            if f.where.kind == "plane":
                depth = rest_shape.crosses_support_plane(points, target[0], f.where.axis, f.where.at,
                                                         1e-6 * size)
                if depth > 0:
                    problems.append(f"the rest shape crosses the support plane {'xyz'[f.where.axis]} = "
                                    f"{f.where.at} by {depth:.3g} m")
        hits = rest_shape.self_intersections(points, tris)
        if hits:
            problems.append(f"the rest shape's surface intersects itself ({hits} crossing triangle pairs)")
    return problems, drawn


def check_rest_shape(scene: Scene, res: InverseResult, out: Path, carving=None) -> ForwardCheck:
    """Write the rest shape (volume .msh + STL), check it crosses no support plane and does not
    intersect itself, then load the written arrays as a mesh, solve the forward problem on it (from the
    target, or along the load path: scene.inverse.check), check the equilibrium is stable and measure
    the largest distance of the deformed shape from the target. `carving` (carving.Carving): its volume
    groups written, and read back from the loaded mesh into the forward model's stiffness and density."""
    mesh = res.loaded.mesh
    comm = mesh.comm
    size = mesh_size(mesh)
    shift = fields.node_values(res.v)
    gathered = fields.gather_mesh(mesh, shift)
    target = fields.gather_mesh(mesh)
    designed = fields.gather_mesh(mesh, fields.node_values(res.deformed_offset)) \
        if res.deformed_offset is not None else target
    groups = fields.gather_facet_groups(res.loaded)
    cell_groups = _material_groups(scene, res.loaded) if carving is None else carving.cell_groups()
    problems, drawn = _write_and_inspect(scene, out, gathered, target, groups, size, cell_groups) \
        if comm.rank == 0 else ([], None)
    problems = comm.bcast(problems, root=0)
    pts_rest = comm.bcast(gathered[0] if comm.rank == 0 else None, root=0)
    pts_target = comm.bcast(target[0] if comm.rank == 0 else None, root=0)
    pts_design = comm.bcast(designed[0] if comm.rank == 0 else None, root=0)
    if problems and any("cannot write" in p for p in problems):
        return ForwardCheck(np.inf, None, problems, drawn=drawn)
    # independent forward check: the mesh just written (its very arrays, loaded as any file mesh is:
    # checked, distributed) and the forward problem's forms on it
    vmap = res.v.function_space.dofmap
    fscene = forward.forward_scene(scene, out / "rest_shape.msh", vmap.index_map.size_global * vmap.index_map_bs,
                                   carved=carving is not None and carving.any_carved)

    def written():                               # called on rank 0, where the gathered arrays are
        points, cells, ctype = gathered
        arrays = MeshArrays(points, cells, ctype, groups or {}, cell_groups or {},
                            info={"source": "rest_shape.msh"})
        check_cells(arrays, "rest_shape.msh")
        return arrays
    try:
        loaded = from_arrays(comm, written)
        carved = carving.on_mesh(loaded) if carving is not None else None
        solve = (forward.solve_at_target(fscene, loaded, pts_rest, pts_design, res.residual_scale, carved)
                 if scene.inverse.check == "equilibrium" and getattr(scene, "contact", None) is None
                 else forward.solve_along_path(fscene, loaded, carved))     # friction depends on the path
    except InputError as e:
        return ForwardCheck(np.inf, None, problems + [f"the rest shape is not a valid mesh: {e}"], drawn=drawn)
    static = solve.static
    predicted = "the target" if res.deformed_offset is None else "the shape the design predicted"
    problems += _stability_problems(solve, predicted)
    if not static.report.converged:
        what = (f"{predicted} is not an equilibrium of the rest shape" if solve.kind == "equilibrium"
                else "the forward solve from the rest shape failed")
        return ForwardCheck(np.inf, static, problems + [f"{what}: {static.report.message}"], solve=solve,
                            drawn=drawn)
    fmesh = static.model.mesh
    X = fmesh.geometry.x
    dist, idx = cKDTree(pts_rest).query(X)
    deformed = X + fields.node_values(static.u)
    def largest(dist, where=None):
        dist = dist if where is None else dist[where]
        return comm.allreduce(float(dist.max()) if len(dist) else 0.0, op=MPI.MAX)

    to_target = np.linalg.norm(deformed - pts_target[idx], axis=1)
    mismatch = largest(to_target)
    offset, shape_max = 0.0, None
    if res.free_direction is not None:          # standing on a table: how high it rests is the barrier's
        n = res.free_direction
        owned = np.arange(len(X)) < fmesh.geometry.index_map().size_local
        rise = (deformed - pts_target[idx])[owned] @ n
        offset = comm.allreduce(float(rise.sum()), op=MPI.SUM) / comm.allreduce(int(owned.sum()), op=MPI.SUM)
        shape_max = largest(np.linalg.norm(deformed - pts_target[idx] - offset * n, axis=1))
    gap = largest(np.linalg.norm(deformed - pts_design[idx], axis=1))
    matched = _matched_vertices(scene.inverse, pts_target, size)
    matched_max = None if matched is None else largest(to_target, matched[idx])
    tol = scene.inverse.check_tolerance or 1e-3 * size
    if gap > tol:
        problems.append(f"the forward solve on the rest shape lands {gap:.3g} m from {predicted} "
                        f"(tolerance {tol:.3g} m): another equilibrium, the design is not usable")
    return ForwardCheck(mismatch, static, problems, gap, matched_max, solve, drawn, offset, shape_max)


def picture(path: Path, res: InverseResult, check: ForwardCheck, title: str, up=None) -> None:
    """Three panels: the target, the designed rest shape, the forward check (rest shape under load), the
    first two from the arrays the check gathered (the rest shape has the target's cells and faces)."""
    fwd = None
    if check.static is not None:
        fm = check.static.model.mesh
        fwd = fields.gather_mesh(fm, fields.node_values(check.static.u))
    if res.loaded.mesh.comm.rank != 0:
        return
    target_points, rest_points, target_faces = check.drawn
    panels = [("target", target_points, target_faces, (0.12, 0.47, 0.71, 0.75)),
              ("rest shape to fabricate", rest_points, target_faces, (1.0, 0.5, 0.05, 0.75))]
    if fwd is not None:
        kind = check.solve.kind if check.solve is not None else ""
        panels.append((f"forward check, {kind} (mismatch {check.mismatch_max:.2g} m)", fwd[0],
                       cell_faces.boundary_faces(fwd[1], fwd[2]), (0.17, 0.63, 0.17, 0.75)))
    view = pictures.view_axes(up=up)                 # up: against gravity, drawn vertical
    everything = np.vstack([pts for _, pts, _, _ in panels]) @ view[0].T
    canvas = pictures.Canvas(500 * len(panels), 320)
    for k, (name, pts, faces, colour) in enumerate(panels):
        box = (500 * k + 10, 50, 500 * k + 490, 310)
        to_px = canvas.fit(box, everything)
        if k > 0:                                    # the target as a faint ghost behind the other panels
            canvas.surface(to_px, target_points, target_faces, (0.5, 0.5, 0.5, 0.08), view=view, outward=True)
        canvas.surface(to_px, pts, faces, pictures.shade(pts, faces, colour, view[1]), (0, 0, 0, 0.2), view=view,
                       outward=True)
        canvas.text((500 * k + 250, 45), name, 13)
        canvas.triad((500 * k + 40, 290), view)
    canvas.text((250 * len(panels), 15), title, 14)
    canvas.save(path)
