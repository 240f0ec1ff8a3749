"""A solid built with gmsh's OpenCASCADE kernel, meshed into a .msh file the mesh loader reads: demos,
benchmarks and users' scripts make parts this way (boxes, cylinders, cones, spheres fused or cut)."""
from __future__ import annotations

from pathlib import Path
from typing import Callable


def mesh_part(path: Path | None, build: Callable, h: float, h_min: float | None = None,
              name_of: Callable | None = None) -> int:
    """Mesh the volumes `build(gmsh.model.occ)` returns (gmsh dim-tags) with tetrahedra of size h down to
    h_min (default h/3) as one physical volume, their boundary's groups named by `name_of` (name_boundary), write
    them to `path` (None: only count) and return the tetrahedra's number."""
    import gmsh                                      # 0.2-0.5 s to import: only when a part is built
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("part")
        volumes = [t for d, t in build(gmsh.model.occ) if d == 3]
        gmsh.model.occ.synchronize()
        gmsh.model.addPhysicalGroup(3, volumes, 1)
        if name_of is not None:
            name_boundary(gmsh, volumes, name_of)
        gmsh.option.setNumber("Mesh.CharacteristicLengthMax", h)
        gmsh.option.setNumber("Mesh.CharacteristicLengthMin", h / 3 if h_min is None else h_min)
        gmsh.model.mesh.generate(3)
        if path is not None:
            gmsh.write(str(path))
        return sum(len(t) for t in gmsh.model.mesh.getElements(3)[1])
    finally:
        gmsh.finalize()


def write_part(path: Path, build: Callable, h: float, h_min: float | None = None,
               name_of: Callable | None = None) -> Path:
    """mesh_part written to `path`; the path (for a scene's mesh.file)."""
    mesh_part(path, build, h, h_min, name_of)
    return path


def fine_in_box(gmsh, bounds: dict, h_in: float, h_out: float) -> None:
    """Cells of size h_in inside a box (gmsh Box field keys: XMin, XMax, YMin, YMax, ZMin, ZMax, Thickness of the
    transition), h_out elsewhere, and only there: sizes from points and boundaries off (a crack's band, a notch)."""
    field = gmsh.model.mesh.field
    box = field.add("Box")
    field.setNumber(box, "VIn", h_in)
    field.setNumber(box, "VOut", h_out)
    for key, value in bounds.items():
        field.setNumber(box, key, value)
    field.setAsBackgroundMesh(box)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)


def symmetry_plane(box: tuple, tol: float = 1e-6) -> str | None:
    """'x0', 'y0' or 'z0' for a surface whose gmsh bounding box (x0, y0, z0, x1, y1, z1) lies in that coordinate
    plane (within tol: OpenCASCADE pads its boxes), else None."""
    return next((name for name, top in zip(("x0", "y0", "z0"), box[3:]) if top < tol), None)


def name_boundary(gmsh, volumes: list, name_of: Callable) -> None:
    """Physical surface groups of the volumes' boundary, each surface named by name_of(its bounding box), numbered
    from 10 in the names' sorted order."""
    names = {s: name_of(gmsh.model.getBoundingBox(2, s))
             for _, s in gmsh.model.getBoundary([(3, v) for v in volumes], oriented=False)}
    for i, name in enumerate(sorted(set(names.values()))):
        tag = gmsh.model.addPhysicalGroup(2, [s for s, n in names.items() if n == name], 10 + i)
        gmsh.model.setPhysicalName(2, tag, name)
