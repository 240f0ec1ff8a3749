"""gmsh models to MeshArrays: the solids gmsh generates from a scene (cylinder, sphere, an r-z profile
revolved about z) with their named surfaces (bottom, top, side; surface), and the arrays of any gmsh
model (linear tetrahedra or hexahedra and its physical groups of every dimension), which is also how
a .msh file is read (files.py). gmsh is imported only when a session opens.
"""
from __future__ import annotations

import math

import numpy as np

from fem_forms.errors import InputError
from fem_forms.meshes.groups import cell_groups, curve_and_point_groups
from fem_forms.meshes.arrays import MeshArrays, compact
from fem_forms.scene import MeshSpec


def gmsh_session():
    """gmsh initialised, quiet, with an empty model (the caller finalizes it)."""
    import gmsh
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("fem_forms")
    return gmsh


def gmsh_arrays(gmsh) -> MeshArrays:
    """Linear tetrahedra or hexahedra of the current gmsh model, with its named surface groups."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    order = np.argsort(tags)
    tags, points = tags[order], coords.reshape(-1, 3)[order]
    index = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    index[tags] = np.arange(len(tags))
    types, element_tags, nodes = gmsh.model.mesh.getElements(3)
    kinds = {4: ("tetrahedron", 4), 5: ("hexahedron", 8), 11: ("tetrahedron", 4), 12: ("hexahedron", 8)}
    found = [gmsh.model.mesh.getElementProperties(t)[0] for t in types]
    usable = [(t, n) for t, n in zip(types, nodes) if t in kinds]
    if not usable or len({kinds[t][0] for t, _ in usable}) != 1 or len(usable) != len(types):
        raise InputError(f"mesh: needs volume cells all tetrahedra or all hexahedra (found: "
                         f"{', '.join(found) or 'no volume cells'})")
    cell_type = kinds[usable[0][0]][0]
    nv = kinds[usable[0][0]][1]
    per = [gmsh.model.mesh.getElementProperties(t)[3] for t, _ in usable]
    cells = np.vstack([index[n.reshape(-1, k)[:, :nv]] for (t, n), k in zip(usable, per)])
    volumes = cell_groups(gmsh, np.concatenate([np.asarray(t) for t in element_tags]))
    curves, points_named = curve_and_point_groups(gmsh, points, index)
    groups = {}
    for dim, tag in gmsh.model.getPhysicalGroups(2):
        name = gmsh.model.getPhysicalName(dim, tag) or str(tag)
        facets = []
        for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
            ftypes, _, fnodes = gmsh.model.mesh.getElements(2, ent)
            for ft, fn in zip(ftypes, fnodes):
                k = gmsh.model.mesh.getElementProperties(ft)[3]
                corner = 3 if cell_type == "tetrahedron" else 4
                facets.append(index[fn.reshape(-1, k)[:, :corner]])
        if facets:
            groups[name] = np.vstack(facets)
    return compact(MeshArrays(points, cells, cell_type, groups, volumes, curves, points_named))


def generate_solid(spec: MeshSpec) -> MeshArrays:
    """The cylinder, sphere or revolved profile of `spec` meshed with tetrahedra of size spec.h."""
    gmsh = gmsh_session()
    try:
        occ = gmsh.model.occ
        ox, oy, oz = spec.origin
        if spec.generator == "cylinder":
            vol = occ.addCylinder(ox, oy, oz, 0, 0, spec.height, spec.radius)
        elif spec.generator == "sphere":
            vol = occ.addSphere(ox, oy, oz, spec.radius)
        else:
            vol = _revolved_profile(occ, spec)
        occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [vol], 1)
        _name_surfaces(gmsh, spec)
        gmsh.option.setNumber("Mesh.CharacteristicLengthMax", spec.h)
        gmsh.option.setNumber("Mesh.CharacteristicLengthMin", spec.h / 4)
        gmsh.option.setNumber("Mesh.Optimize", 1)
        gmsh.model.mesh.generate(3)
        return gmsh_arrays(gmsh)
    finally:
        gmsh.finalize()


def _revolved_profile(occ, spec: MeshSpec) -> int:
    """Revolve a closed r-z outline about the z axis through the origin into a solid."""
    pts = spec.profile
    if pts[0] == pts[-1]:
        pts = pts[:-1]
    ox, oy, oz = spec.origin
    tags = [occ.addPoint(ox + r, oy, oz + z) for r, z in pts]
    lines = [occ.addLine(tags[i], tags[(i + 1) % len(tags)]) for i in range(len(tags))]
    surf = occ.addPlaneSurface([occ.addCurveLoop(lines)])
    out = occ.revolve([(2, surf)], ox, oy, oz, 0, 0, 1, 2 * math.pi)
    vols = [t for d, t in out if d == 3]
    if len(vols) != 1:
        raise InputError("mesh.profile: revolving the outline did not give one solid")
    return vols[0]


def _name_surfaces(gmsh, spec: MeshSpec) -> None:
    """Physical groups for generated surfaces: flat horizontal faces at the lowest/highest z are
    'bottom'/'top' and the rest 'side' (cylinder, revolve); a sphere has one group 'surface'."""
    surfaces = [t for _, t in gmsh.model.getEntities(2)]
    if spec.generator == "sphere":
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, surfaces, 10), "surface")
        return
    boxes = {s: gmsh.model.getBoundingBox(2, s) for s in surfaces}
    zlo = min(b[2] for b in boxes.values())
    zhi = max(b[5] for b in boxes.values())
    tol = 1e-4 * (zhi - zlo)              # OCC pads bounding boxes by its tolerance
    named = {"bottom": [], "top": [], "side": []}
    for s, b in boxes.items():
        flat = b[5] - b[2] < tol
        if flat and abs(b[2] - zlo) < tol:
            named["bottom"].append(s)
        elif flat and abs(b[5] - zhi) < tol:
            named["top"].append(s)
        else:
            named["side"].append(s)
    for i, (n, ss) in enumerate(named.items()):
        if ss:
            gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, ss, 10 + i), n)
