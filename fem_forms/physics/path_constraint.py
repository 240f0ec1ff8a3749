"""The arc-length constraint (Riks; Crisfield's normal plane): the load factor lambda becomes an unknown, solved
with the displacement, and one more equation fixes how far a step goes along the load-displacement path:

    c(u, lambda) = s [ <u - u_k, t_u> / U + (lambda - lambda_k) t_lambda - ds ] = 0,

with <a, b> = int a . b dX / |body| (an L2 mean, the same on any number of ranks), U the displacement per unit
load factor of the first step (so that displacement and load weigh alike), (t_u, t_lambda) the unit direction
of the last accepted step (a secant: it keeps pointing forward through a limit point, where the load turns
back), ds the step's arc length, and s the full load's residual at rest (the equation reads as a force). With
t_u = 0, t_lambda = 1 the constraint is plain load control: lambda = lambda_k + ds. Every value is a Constant
or a Function: moving along the path compiles nothing."""
from __future__ import annotations

from dolfinx import fem
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.physics.scalars import GlobalScalar, derivative_wrt_constant


class ArcLength:
    """The constraint's Constants and Functions, its GlobalScalar (the load factor) and the path's inner product."""

    def __init__(self, model):
        mesh, V = model.mesh, model.V
        self.model = model
        self.u_k, self.t_u = fem.Function(V), fem.Function(V)        # last accepted u; direction
        self._a, self._b = fem.Function(V), fem.Function(V)          # operands of `inner`
        const = lambda v: fem.Constant(mesh, PETSc.ScalarType(v))    # noqa: E731
        self.lam_k, self.t_lam, self.ds = const(0.0), const(1.0), const(0.0)
        self.scale, self.per_u = const(1.0), const(0.0)               # s, 1 / U
        dx = model.dx
        self.body = mesh.comm.allreduce(fem.assemble_scalar(fem.form(fem.Constant(mesh, 1.0) * dx)), op=MPI.SUM)
        lam = model.load.constant
        along = ufl.dot(model.u_form - self.u_k, self.t_u) * self.per_u
        equation = self.scale / self.body * (along + (lam - self.lam_k) * self.t_lam - self.ds) * dx
        v = model.residual.arguments()[0]
        self.scalar = GlobalScalar("load factor", lam, equation,
                                   coupling=derivative_wrt_constant(model.residual, lam),
                                   gradient=ufl.derivative(equation, model.unknown, v),
                                   slope=derivative_wrt_constant(equation, lam))
        self._inner = fem.form(ufl.dot(self._a, self._b) * dx)
        self.U = 1.0
        self._load_rate = fem.form(self.scalar.coupling)                # dR/dlambda: minus the full load

    def load_work(self, step: np.ndarray) -> float:
        """The full load's work over an increment of the unknown (its local array, ghosts included):
        -<dR/dlambda, step>, the same on every rank. Positive while the path moves along the loads, rising or
        falling; negative where it turns back (a snap-back: the loaded points move against their load)."""
        b = fem.petsc.assemble_vector(self._load_rate)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        local = -float(np.dot(b.array, step[: b.getLocalSize()]))
        b.destroy()
        return self.model.mesh.comm.allreduce(local, op=MPI.SUM)

    def inner(self, a: np.ndarray, b: np.ndarray) -> float:
        """<a, b> of two displacement arrays (local, ghosts included), the same on every rank."""
        self._a.x.array[:], self._b.x.array[:] = a, b
        return self.model.mesh.comm.allreduce(fem.assemble_scalar(self._inner), op=MPI.SUM) / self.body

    def load_control(self, lam_k: float, dlam: float) -> None:
        """The next step is plain load control: lambda = lam_k + dlam."""
        self.t_u.x.array[:] = 0.0
        self.lam_k.value, self.t_lam.value, self.ds.value = lam_k, 1.0, dlam

    def along(self, u_k: np.ndarray, lam_k: float, du: np.ndarray, dlam: float, ds: float) -> None:
        """The next step goes ds from (u_k, lam_k) along the direction of the increment (du, dlam)."""
        norm = self.length(du, dlam)
        self.u_k.x.array[:] = u_k
        self.t_u.x.array[:] = du / (self.U * norm)
        self.lam_k.value, self.t_lam.value, self.ds.value = lam_k, dlam / norm, ds

    def predictor(self) -> tuple[np.ndarray, float]:
        """(u, lambda) at distance ds along the direction: the Newton start of the step."""
        ds = float(self.ds.value)
        return (self.u_k.x.array + self.U * ds * self.t_u.x.array,
                float(self.lam_k.value) + ds * float(self.t_lam.value))

    def first_step_done(self, du: np.ndarray, dlam: float) -> float:
        """Fix U from the first (load-controlled) step; returns that step's arc length."""
        size = np.sqrt(self.inner(du, du))
        self.U = size / dlam if size > 0 and dlam > 0 else 1.0
        self.per_u.value = 1.0 / self.U
        return self.length(du, dlam)

    def length(self, du: np.ndarray, dlam: float) -> float:
        """The arc length of an increment (du, dlam), in the path's weighting."""
        return float(np.sqrt(self.inner(du, du) / self.U**2 + dlam**2))
