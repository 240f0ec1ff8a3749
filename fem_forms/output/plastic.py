"""What a plastic solution reports: the largest equivalent plastic strain, the yielded volume fraction and
the plastic strain fields (cell averages, DG0) for ParaView. All from the committed history."""
from __future__ import annotations

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl


def plastic_term(model):
    """The model's plastic solid, or None."""
    return model.solid if model.solid.is_plastic else None


def _cell_values(expr, space, dx) -> np.ndarray:
    """Cell averages of expr on a DG0 space (owned cells, blocked): int expr w dx / int w dx."""
    w = ufl.TestFunction(space)
    one = ufl.as_tensor(np.ones(space.ufl_element().value_shape()).tolist()) if expr.ufl_shape else 1.0
    num = fpetsc.assemble_vector(fem.form(ufl.inner(expr, w) * dx))
    den = fpetsc.assemble_vector(fem.form(ufl.inner(one, w) * dx))
    for v in (num, den):
        v.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    values = num.array / den.array
    num.destroy()
    den.destroy()
    return values


def plastic_summary(model) -> dict:
    """max_plastic_strain: largest equivalent plastic strain (von Mises alpha, O'Brien |eps_p|) at any
    quadrature point; yielded_fraction: volume of the cells whose cell-average equivalent plastic strain
    is positive over the body's volume (undeformed)."""
    term = plastic_term(model)
    if term is None:
        return {}
    comm = model.mesh.comm
    Q = term.alpha.function_space
    n_owned = Q.dofmap.index_map.size_local * Q.dofmap.index_map_bs
    if term.equivalent is term.alpha:
        local = term.alpha.x.array[:n_owned]
    else:
        t = term.eps_p.x.array.reshape(-1, 9)
        local = np.sqrt((t * t).sum(axis=1))[:n_owned]
    largest = comm.allreduce(float(local.max()) if local.size else 0.0, op=MPI.MAX)
    D0 = fem.FunctionSpace(model.mesh, ("DG", 0))
    average = _cell_values(term.equivalent, D0, model.dx)
    volume = fpetsc.assemble_vector(fem.form(ufl.TestFunction(D0) * ufl.dx(domain=model.mesh)))
    vol = volume.array
    yielded = comm.allreduce(float(vol[average > 0].sum()), op=MPI.SUM)
    total = comm.allreduce(float(vol.sum()), op=MPI.SUM)
    volume.destroy()
    return {"max_plastic_strain": largest, "yielded_fraction": yielded / total}


def plastic_fields(model) -> list[fem.Function]:
    """plastic_strain (tensor) and equivalent_plastic_strain as cell averages (DG0) for the XDMF file."""
    term = plastic_term(model)
    if term is None:
        return []
    out = []
    for name, expr, space in (
            ("plastic_strain", term.plastic_strain, fem.TensorFunctionSpace(model.mesh, ("DG", 0))),
            ("equivalent_plastic_strain", term.equivalent, fem.FunctionSpace(model.mesh, ("DG", 0)))):
        f = fem.Function(space, name=name)
        n = space.dofmap.index_map.size_local * space.dofmap.index_map_bs
        f.x.array[:n] = _cell_values(expr, space, model.dx)[:n]
        f.x.scatter_forward()
        out.append(f)
    return out
