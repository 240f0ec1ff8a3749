"""Mass properties of a solid with a cellwise density: per-cell moment integrals and what follows from them.

Mass, first and second moments are linear in the cellwise density rho_e: with the per-cell integrals
D_e = [V, int x, int y, int z, int xx, int yy, int zz, int xy, int xz, int yz] (over the cell, on the rest
shape or on the deformed shape x = X + u), the body's moments are M = sum_e rho_e D_e. On the deformed
shape the integrals run over the rest cell (rho dv = rho_0 dV: a part keeps its mass as it deforms), so
D_e[0] stays the rest volume and rho_e the rest density. The per-cell
integrals come from one vector DG0 form (compiled once per cell type and displacement space), with a
quadrature degree that makes them exact for straight-sided tetrahedra, trilinear hexahedra and P1
displacements (and exact up to the P2 map's own degree for P2 displacements). Sums are over owned cells
and reduced over MPI ranks.
"""
from __future__ import annotations

from dataclasses import dataclass

from dolfinx import fem
from mpi4py import MPI
import numpy as np
import ufl

from fem_forms.physics import quadrature

N_MOMENTS = 10     # V, x, y, z, xx, yy, zz, xy, xz, yz
_FORMS: dict = {}


def _degree(cell: str, p: int) -> int:
    """Quadrature degree exact for x x^T det(dx/dxi) with x of degree p (per variable on hexahedra)."""
    if cell == "tetrahedron":
        return 2 * p + 3 * (p - 1)
    return 2 * p + 3 * p + 2


def _form(mesh, u: fem.Function | None):
    key = (id(mesh), None if u is None else id(u))
    if key not in _FORMS:
        Q = fem.VectorFunctionSpace(mesh, ("DG", 0), dim=N_MOMENTS)
        v = ufl.TestFunction(Q)
        X = ufl.SpatialCoordinate(mesh)
        if u is None:
            x, p = X, 1
        else:
            x = X + u                              # mass conserved: no det F (rho dv = rho_0 dV)
            p = u.function_space.ufl_element().degree()
        q = _degree(mesh.topology.cell_name(), p)
        vals = ufl.as_vector([1.0, x[0], x[1], x[2], x[0] * x[0], x[1] * x[1], x[2] * x[2],
                              x[0] * x[1], x[0] * x[2], x[1] * x[2]])
        form = fem.form(ufl.inner(vals, v) * ufl.dx(metadata=quadrature.metadata(mesh.topology.cell_name(), q)))
        _FORMS[key] = (form, Q, mesh, u)          # holding mesh and u keeps their ids unique
    return _FORMS[key][:2]


def cell_moments(mesh, u: fem.Function | None = None) -> np.ndarray:
    """(owned cells, 10): each owned cell's volume, first and second moment integrals, on the rest shape
    (u None) or on the deformed shape X + u."""
    form, Q = _form(mesh, u)
    vec = fem.petsc.assemble_vector(form)
    n = mesh.topology.index_map(3).size_local
    out = vec.array.reshape(-1, N_MOMENTS)[:n].copy()
    vec.destroy()
    return out


def total_moments(density: np.ndarray, moments: np.ndarray, comm: MPI.Comm) -> np.ndarray:
    """Body moments M = sum over owned cells of rho_e D_e, summed over ranks."""
    local = density @ moments if len(moments) else np.zeros(N_MOMENTS)
    return comm.allreduce(np.asarray(local, dtype=float), op=MPI.SUM)


def second_moment_matrix(M: np.ndarray) -> np.ndarray:
    """int rho x x^T dV as a 3x3 matrix from the moment vector."""
    xx, yy, zz, xy, xz, yz = M[4:10]
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def second_moment_about(M: np.ndarray, p: np.ndarray) -> np.ndarray:
    """int rho (x - p)(x - p)^T dV: linear in M for a fixed point p."""
    S1 = M[1:4]
    return second_moment_matrix(M) - np.outer(p, S1) - np.outer(S1, p) + M[0] * np.outer(p, p)


def inertia_from_second_moment(S: np.ndarray) -> np.ndarray:
    """Inertia tensor tr(S) I - S."""
    return np.trace(S) * np.eye(3) - S


@dataclass
class MassProperties:
    """Mass, centre of mass, inertia about the CoM and its principal moments and axes (columns)."""
    mass: float
    center_of_mass: np.ndarray
    inertia: np.ndarray
    principal_moments: np.ndarray
    principal_axes: np.ndarray

    @classmethod
    def from_moments(cls, M: np.ndarray) -> "MassProperties":
        m = float(M[0])
        c = M[1:4] / m
        inertia = inertia_from_second_moment(second_moment_about(M, c))
        inertia = 0.5 * (inertia + inertia.T)
        w, V = np.linalg.eigh(inertia)
        for j in range(3):                         # a sign convention: largest component positive
            if V[np.argmax(np.abs(V[:, j])), j] < 0:
                V[:, j] = -V[:, j]
        return cls(m, c, inertia, w, V)

    def as_dict(self) -> dict:
        return {"mass": self.mass, "center_of_mass": self.center_of_mass.tolist(),
                "inertia": self.inertia.tolist(), "principal_moments": self.principal_moments.tolist(),
                "principal_axes": self.principal_axes.T.tolist()}
