"""Sound pressure at a listener radiated by a vibrating surface: the simple-source (free-space Rayleigh) integral.

For a surface displacement amplitude u at angular frequency omega (time factor e^{i omega t}), each
surface element radiates as a monopole of strength its normal acceleration:

    p(x) = (rho / 4 pi) int_S (-omega^2 u.n) e^{-ikR} / R dS,   R = |x - y|,  k = omega / c,

over the whole closed boundary. It neglects the scattering by the body itself (the double-layer term of
the Kirchhoff-Helmholtz integral), so it is exact only for a compact body (ka << 1). Against the
closed form of a pulsating sphere it gives sinc(ka) (1 + ika) e^{-ika} times the exact pressure:
0.3 % off at ka = 0.1, 7 % at 0.5, 19 % at 1. It keeps what makes small, low modes quiet: opposite
faces of a bending bar cancel (the acoustic short circuit); an oscillating sphere comes out 2/3 of its
exact, already weak, dipole pressure at small ka. The baffled-plate Rayleigh integral (1/2 pi over the
surface) would double a compact body's pressure and lose the cancellation. For a thin part it cancels too
much: against a boundary element solve on the struck bar it is 7.8 dB too quiet in the median, up to
17 dB for the lowest bending modes (benchmarks/radiation_bem.md).
"""
from __future__ import annotations

import math

from dolfinx import fem
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.errors import InputError
from fem_forms.output import probes


def check_listener(u: fem.Function, listener) -> None:
    """InputError if the listener lies in or on the part (the radiated pressure is heard in the air)."""
    try:
        probes.evaluate(u, {"listener": listener})
    except InputError:
        return
    raise InputError(f"sound.listener = {listener}: lies in or on the part; it must be in the air")


class Radiation:
    """Pressure amplitude at one listener point from displacement fields of one function space."""

    def __init__(self, V: fem.FunctionSpace, listener, density: float, speed_of_sound: float):
        mesh = V.mesh
        self.comm = mesh.comm
        self.u = fem.Function(V)
        self.k = fem.Constant(mesh, PETSc.ScalarType(0.0))
        self.listener = fem.Constant(mesh, PETSc.ScalarType(tuple(listener)))
        self.density, self.speed_of_sound = density, speed_of_sound
        x, n = ufl.SpatialCoordinate(mesh), ufl.FacetNormal(mesh)
        r = x - self.listener
        R = ufl.sqrt(ufl.dot(r, r))
        un = ufl.dot(self.u, n)
        # the kernel oscillates over a facet at high k: degree 2p + 2 (6 for P2) integrates kh ~ 1 well
        degree = 2 * V.ufl_element().degree() + 2
        ds = ufl.ds(domain=mesh, metadata={"quadrature_degree": degree})
        self.cos = fem.form(un * ufl.cos(self.k * R) / R * ds)
        self.sin = fem.form(un * ufl.sin(self.k * R) / R * ds)

    def integral(self, u: fem.Function, k: float) -> complex:
        """int_S u.n e^{-ikR} / R dS (collective; every rank gets the sum)."""
        self.u.x.array[:] = u.x.array
        self.k.value = k
        local = np.array([fem.assemble_scalar(self.cos), fem.assemble_scalar(self.sin)])
        total = np.empty_like(local)
        self.comm.Allreduce(local, total, op=MPI.SUM)
        return complex(total[0], -total[1])

    def pressure(self, u: fem.Function, omega: float) -> complex:
        """Complex pressure amplitude [Pa] at the listener for displacement amplitude u at omega."""
        k = omega / self.speed_of_sound
        return -self.density * omega**2 / (4 * math.pi) * self.integral(u, k)
