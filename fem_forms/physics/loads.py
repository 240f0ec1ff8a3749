"""External loads as UFL terms."""
from __future__ import annotations

from dolfinx import fem
from petsc4py import PETSc
import ufl

from fem_forms.meshes import LoadedMesh
from fem_forms.physics.supports import LoadFactor, load_regions
from fem_forms.scene import Load


def external_work(u, loaded: LoadedMesh, loads: list[Load], rho: float, load: LoadFactor,
                  dx: ufl.Measure) -> tuple:
    """(W, pressure_residual): the work of conservative loads (gravity, dead traction) as an energy
    term, and the virtual work of follower pressure, which has no energy, as a residual term."""
    mesh = loaded.mesh
    tags, ids = load_regions(loaded, loads)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags, metadata=dx.metadata())
    W = 0
    pressure_terms = []
    for i, spec in enumerate(loads):
        if spec.type == "gravity":
            W = W + rho * ufl.dot(fem.Constant(mesh, PETSc.ScalarType(spec.g)), u) * dx
        elif spec.type == "traction":
            t = fem.Constant(mesh, PETSc.ScalarType(spec.value))
            W = W + sum(ufl.dot(t, u) * ds(k) for k in ids[i])
        else:
            pressure_terms.append((spec.pressure, ids[i]))
    W = load.constant * W if not isinstance(W, int) else None

    def pressure_residual(v, F):
        """Virtual work of pressure p on the deformed surface: int p J F^-T N . v dA."""
        if not pressure_terms:
            return None
        N = ufl.FacetNormal(mesh)
        J = ufl.det(F)
        return load.constant * sum(p * J * ufl.dot(ufl.inv(F).T * N, v) * ds(k)
                                 for p, ks in pressure_terms for k in ks)

    return W, pressure_residual

