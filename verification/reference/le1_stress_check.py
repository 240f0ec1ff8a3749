"""Side check of the LE1 geometry and mesh, independent of fem_forms: bare dolfinx 0.5.2 small-strain
elasticity on the same le1.msh (Q2, dead normal pressure on the outer edge, the same supports),
sigma_yy at D = (2, 0, 0) recovered by L2 projection onto the continuous Q2 space (and, for
comparison, the raw value of the cells that touch D). Target 92.7 MPa (NAFEMS LE1).

Until fem_forms reports probe stresses (results.json probes.D.stress), this is the only stress
number for LE1; run.py does NOT count it as the package's result.

    python verification/reference/le1_stress_check.py [--n-arc 24 --n-radial 8 --n-z 1]
"""
import argparse
import json
import logging
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import ufl
from dolfinx import fem, geometry
from dolfinx.fem.petsc import LinearProblem
from dolfinx.io import gmshio
from mpi4py import MPI
from petsc4py import PETSc

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "geometry"))
import le1  # noqa: E402

E, NU, P = 210e9, 0.3, 10e6
D = np.array([2.0, 0.0, 0.0])


def value_at(f, point):
    mesh = f.function_space.mesh
    tree = geometry.BoundingBoxTree(mesh, mesh.topology.dim)
    cand = geometry.compute_collisions(tree, point.reshape(1, 3))
    cells = geometry.compute_colliding_cells(mesh, cand, point.reshape(1, 3)).links(0)
    return [float(f.eval(point, np.array([c], dtype=np.int32))[0]) for c in cells]


def solve(msh: Path) -> dict:
    t0 = time.perf_counter()
    import gmsh
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.open(str(msh))
    groups = {gmsh.model.getPhysicalName(2, t): t for _, t in gmsh.model.getPhysicalGroups(2)}
    mesh, _, facet_tags = gmshio.model_to_mesh(gmsh.model, MPI.COMM_SELF, 0, gdim=3)
    gmsh.finalize()
    V = fem.VectorFunctionSpace(mesh, ("Lagrange", 2))
    mu, lmbda = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))                                   # noqa: E731
    sigma = lambda w: 2 * mu * eps(w) + lmbda * ufl.tr(eps(w)) * ufl.Identity(3)  # noqa: E731
    dx = ufl.dx(metadata={"quadrature_degree": 4})
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags, metadata={"quadrature_degree": 4})
    n = ufl.FacetNormal(mesh)
    a = ufl.inner(sigma(u), eps(v)) * dx
    L = P * ufl.dot(n, v) * ds(groups["outer"])          # outward pressure = tension P along n
    fdim = 2
    bcs = []
    for name, comp in (("x0", 0), ("y0", 1), ("bottom", 2)):
        dofs = fem.locate_dofs_topological(V.sub(comp), fdim, facet_tags.find(groups[name]))
        bcs.append(fem.dirichletbc(PETSc.ScalarType(0), dofs, V.sub(comp)))
    uh = LinearProblem(a, L, bcs=bcs, petsc_options={"ksp_type": "preonly", "pc_type": "lu",
                                                    "pc_factor_mat_solver_type": "mumps"}).solve()
    syy = sigma(uh)[1, 1]
    W = fem.FunctionSpace(mesh, ("Lagrange", 2))
    s, w = ufl.TrialFunction(W), ufl.TestFunction(W)
    proj = LinearProblem(s * w * dx, syy * w * dx, petsc_options={
        "ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}).solve()
    DG = fem.FunctionSpace(mesh, ("DG", 2))
    raw = fem.Function(DG)
    raw.interpolate(fem.Expression(syy, DG.element.interpolation_points()))
    return {"dofs": V.dofmap.index_map.size_global * 3,
            "sigma_yy_D_projected_MPa": value_at(proj, D)[0] / 1e6,
            "sigma_yy_D_cells_MPa": [x / 1e6 for x in value_at(raw, D)],
            "time_s": time.perf_counter() - t0}


if __name__ == "__main__":
    logging.getLogger().setLevel(logging.ERROR)           # FFCx compile log and UFL notes
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n-arc", type=int, nargs="+", default=[24])
    ap.add_argument("--n-radial", type=int, nargs="+", default=[8])
    ap.add_argument("--n-z", type=int, default=1)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for na, nr in zip(a.n_arc, a.n_radial):
            msh = le1.build(Path(tmp) / f"le1_{na}x{nr}.msh", na, nr, a.n_z)
            r = solve(msh)
            r.update(n_arc=na, n_radial=nr, n_z=a.n_z,
                     error_pct=100 * (r["sigma_yy_D_projected_MPa"] / 92.7 - 1))
            print(json.dumps(r))
