"""Meshes of the contact tests, made with gmsh: a quarter of a hemisphere graded toward its lowest point."""
import gmsh


def quarter_hemisphere(path, R: float, fine: float, coarse: float, zone: float) -> str:
    """The quarter x >= 0, y >= 0 of the ball of radius R centred at (0, 0, R), below its equator: flat face
    (group "top") at z = R, lowest point at the origin; cells of size `fine` within `zone` of that point,
    growing to `coarse` at 10 x zone."""
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        occ = gmsh.model.occ
        ball = occ.addSphere(0, 0, R, R)
        occ.cut([(3, ball)], [(3, occ.addBox(-2 * R, -2 * R, R, 4 * R, 4 * R, 2 * R))])
        occ.cut([(3, ball)], [(3, occ.addBox(-2 * R, -2 * R, -R, 2 * R, 4 * R, 4 * R))])
        occ.cut([(3, ball)], [(3, occ.addBox(-2 * R, -2 * R, -R, 4 * R, 2 * R, 4 * R))])
        occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [v[1] for v in gmsh.model.getEntities(3)], 1)
        top = [s[1] for s in gmsh.model.getEntities(2) if abs(occ.getCenterOfMass(2, s[1])[2] - R) < 1e-9 * R]
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, top, 2), "top")
        lowest = occ.addPoint(0, 0, 0)
        occ.synchronize()
        f = gmsh.model.mesh.field
        f.add("Distance", 1)
        f.setNumbers(1, "PointsList", [lowest])
        f.add("Threshold", 2)
        f.setNumber(2, "InField", 1)
        for key, value in (("SizeMin", fine), ("SizeMax", coarse), ("DistMin", zone), ("DistMax", 10 * zone)):
            f.setNumber(2, key, value)
        f.setAsBackgroundMesh(2)
        for key in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints", "Mesh.MeshSizeFromCurvature"):
            gmsh.option.setNumber(key, 0)
        gmsh.model.mesh.generate(3)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return str(path)


def ring(path, outer: float, inner: float, length: float, h: float) -> str:
    """A thick-walled tube (radii outer > inner) of the given length along y, its axis through the origin."""
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        occ = gmsh.model.occ
        tube = occ.addCylinder(0, 0, 0, 0, length, 0, outer)
        occ.cut([(3, tube)], [(3, occ.addCylinder(0, 0, 0, 0, length, 0, inner))])
        occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [v[1] for v in gmsh.model.getEntities(3)], 1)
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.option.setNumber("Mesh.MeshSizeMin", h)
        gmsh.model.mesh.generate(3)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return str(path)
