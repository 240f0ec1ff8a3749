"""Rubber models with an isochoric-volumetric split: psi(F) = W(C_bar) + K/2 (ln J)^2, C_bar = J^(-2/3) C the
volume-preserving part of the deformation (Simo & Taylor 1991; FEBio's uncoupled materials, Abaqus' rubber
models with ln J in place of J - 1). W is the incompressible energy the literature fits (Ogden, Yeoh, Gent,
Arruda-Boyce), so published parameters carry over as printed; the bulk modulus K (`bulk`, or nu through the
initial shear modulus) says how nearly incompressible the part is, and the mixed u-p formulation takes
p = K ln J as its pressure."""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Callable, ClassVar

import numpy as np
import ufl

from fem_forms.errors import InputError
from fem_forms.kinematics import deviator_moments, invariants, principal_values_of

# Arruda-Boyce's series of the inverse Langevin function (Arruda & Boyce 1993; Abaqus, FEBio): C_i / lambda_m^(2i-2)
ARRUDA_BOYCE_SERIES = (1 / 2, 1 / 20, 11 / 1050, 19 / 7000, 519 / 673750)


def items(x) -> list:
    """The entries of a parameter list: a tuple of numbers, or a vector Constant / DG0 field (bound)."""
    if isinstance(x, (tuple, list)):
        return list(x)
    return [x[i] for i in range(x.ufl_shape[0])]


@dataclass(frozen=True)
class Isochoric:
    """psi = W(I1_bar, I2_bar) + bulk/2 (ln J)^2, written on the invariants (I1, I2, J) of C with I1_bar =
    J^(-2/3) I1, I2_bar = J^(-4/3) I2; a subclass gives W (`isochoric`) and its initial shear modulus. `pk1`
    is the same derivative taken by the chain rule through the three invariants (ufl.diff of psi with respect
    to each, times ufl.diff of the invariant with respect to F): the tangent differentiates P on scalars
    (a P2 tangent measured: Yeoh 0.125 s, Arruda-Boyce 0.21 s against 0.16 s and 0.43 s by ufl.diff of psi(F)
    with J^(-2/3) F^T F inside; neo-Hookean 0.10 s)."""
    bulk: float
    VOLUMETRIC_MODULUS: ClassVar[str] = "bulk"      # the modulus the mixed u-p formulation splits off

    def __post_init__(self):
        if not (math.isfinite(self.bulk) and self.bulk > 0):
            raise InputError(f"material.bulk = {self.bulk}: the bulk modulus must be positive")
        mu0 = self.shear_modulus(np.asarray)
        if not (np.all(np.isfinite(mu0)) and np.all(mu0 > 0)):
            raise InputError(f"material: the initial shear modulus is {float(np.min(mu0)):.6g} Pa; it must be "
                             "positive (a stable material at rest)")

    def psi(self, F):
        return self.psi_of_invariants(*invariants(F))

    def psi_of_invariants(self, I1, I2, J):
        return self.isochoric(J ** (-2.0 / 3.0) * I1, J ** (-4.0 / 3.0) * I2) + 0.5 * self.bulk * ufl.ln(J) ** 2

    def pk1(self, F):
        """P = d psi / d F by the chain rule through (I1, I2, J)."""
        F = ufl.variable(F)
        xs = [ufl.variable(x) for x in invariants(F)]
        psi = self.psi_of_invariants(*xs)
        return sum(ufl.diff(psi, x) * ufl.diff(x, F) for x in xs)

    def volumetric(self, F):
        """theta = ln J: psi = psi|_(bulk=0) + bulk/2 theta^2 (the mixed u-p formulation)."""
        return ufl.ln(ufl.det(F))

    def young_modulus(self, value: Callable):
        """E = 9 K mu0 / (3 K + mu0) of the small-strain limit."""
        mu0, K = self.shear_modulus(value), np.asarray(value(self.bulk))
        return 9 * K * mu0 / (3 * K + mu0)

    def isochoric(self, I1, I2):
        """W of the isochoric invariants I1_bar, I2_bar."""
        raise NotImplementedError

    def shear_modulus(self, value: Callable):
        raise NotImplementedError


def _rows(value: Callable, x, n: int) -> np.ndarray:
    """A list parameter's values as rows of n (one row per cell of a DG0 field, one row for numbers)."""
    return np.reshape(np.asarray(value(x), dtype=float), (-1, n))


@dataclass(frozen=True)
class Ogden(Isochoric):
    """Ogden (1972): W = sum_i mu_i / alpha_i (l1^alpha_i + l2^alpha_i + l3^alpha_i - 3) of the isochoric
    principal stretches, from the closed-form eigenvalues of C (kinematics.principal_values: a repeated stretch, as
    in uniaxial tension, keeps the stress exact). Its residual and tangent assemble 2.2-2.5x neo-Hookean's, a
    Newton iteration costs 1.46-1.51x (benchmarks/rubber_cost.md). Tried and left: the stretch powers' sums as
    functions of I1_bar and I2_bar (Cardano on two scalars, a Taylor series near isotropy): 0.33 s against 0.61 s
    for the P2 tangent, but the branches' round-off (1/p near isotropy, 1/sqrt(1 - r^2) near a double stretch) left
    residuals of 1e-5 of the load's that Newton could not reduce on a bent beam. Initial shear modulus
    sum_i mu_i alpha_i / 2."""
    mu: tuple = ()
    alpha: tuple = ()

    def __post_init__(self):
        for name in ("mu", "alpha"):                     # a number or a list, as a model built in Python may give
            value = getattr(self, name)
            object.__setattr__(self, name, tuple(float(x) for x in (value if np.ndim(value) else [value])))
        if not self.mu or len(self.mu) != len(self.alpha):
            raise InputError(f"material.alpha: give one exponent per mu (mu has {len(self.mu)}, alpha "
                             f"{len(self.alpha)})")
        for i, a in enumerate(self.alpha):
            if not (math.isfinite(a) and a != 0):
                raise InputError(f"material.alpha[{i}] = {a}: must be a nonzero number")
        super().__post_init__()

    def shear_modulus(self, value: Callable):
        n = len(self.mu) if isinstance(self.mu, tuple) else self.mu.ufl_shape[0]
        return 0.5 * (_rows(value, self.mu, n) * _rows(value, self.alpha, n)).sum(axis=1)

    def stretch_energy(self, logs):
        """W of the isochoric stretches' logarithms L_a = ln lbar_a^2, the powers lbar^alpha as exp(alpha / 2 L_a):
        one logarithm per stretch serves every term (the tangent 20 % faster than pow)."""
        return sum(m / a * (sum(ufl.exp(a / 2 * L) for L in logs) - 3)
                   for m, a in zip(items(self.mu), items(self.alpha)))

    def psi_of_moments(self, q, dd, det_d, J):
        """psi from C's deviator moments (kinematics.deviator_moments) and J. C_bar = J^(-2/3) C has C's
        eigenvectors, so ln lbar_a^2 = ln c_a - 2/3 ln J with c_a C's own closed-form eigenvalues: no J^(-2/3)
        inside the closed form (8 % fewer values in the P2 tangent's kernel)."""
        lnJ = ufl.ln(J)
        eigenvalues = principal_values_of(q, dd, det_d, floor=1e-6)     # the floor: kinematics.principal_values_of
        return self.stretch_energy([ufl.ln(c) - 2.0 / 3.0 * lnJ for c in eigenvalues]) + 0.5 * self.bulk * lnJ ** 2

    def psi(self, F):
        """W of the isochoric principal stretches, from the closed-form eigenvalues of C = F^T F."""
        return self.psi_of_moments(*deviator_moments(F.T * F), ufl.det(F))

    def pk1(self, F):
        """P = F S + d psi/dJ dJ/dF, S = 2 d psi/dC by the chain rule through C's three deviator moments (ufl.diff
        of psi in each, times ufl.diff of the moment in C): the tangent differentiates the eigenvalues on
        scalars and the moments on C, whose second derivatives are simpler than on F: the P2 tangent of the
        rubber-cost beam computes 6,335 values a quadrature point, 10,650 through F's moments and J^(-2/3) C,
        the same matrix to 12 digits."""
        F = ufl.variable(F)
        C = ufl.variable(F.T * F)
        moments = [ufl.variable(x) for x in deviator_moments(C)]
        J = ufl.variable(ufl.det(F))
        psi = self.psi_of_moments(*moments, J)
        S = 2 * sum(ufl.diff(psi, x) * ufl.diff(x, C) for x in moments)
        return F * S + ufl.diff(psi, J) * ufl.diff(J, F)


@dataclass(frozen=True)
class Yeoh(Isochoric):
    """Yeoh (1993): W = C10 (I1_bar - 3) + C20 (I1_bar - 3)^2 + C30 (I1_bar - 3)^3; shear modulus 2 C10."""
    C10: float = 0.0
    C20: float = 0.0
    C30: float = 0.0

    def shear_modulus(self, value: Callable):
        return 2.0 * np.asarray(value(self.C10), dtype=float)

    def isochoric(self, I1, I2):
        x = I1 - 3
        return self.C10 * x + self.C20 * x ** 2 + self.C30 * x ** 3


@dataclass(frozen=True)
class Gent(Isochoric):
    """Gent (1996): W = -mu Jm / 2 ln(1 - (I1_bar - 3) / Jm); the chains lock as I1_bar - 3 reaches Jm (the
    energy is infinite there: no state beyond it exists)."""
    mu: float = 0.0
    Jm: float = 0.0

    def __post_init__(self):
        if not (math.isfinite(self.Jm) and self.Jm > 0):
            raise InputError(f"material.Jm = {self.Jm}: the locking limit Jm must be positive")
        super().__post_init__()

    def shear_modulus(self, value: Callable):
        return np.asarray(value(self.mu), dtype=float)

    def isochoric(self, I1, I2):
        return -0.5 * self.mu * self.Jm * ufl.ln(1 - (I1 - 3) / self.Jm)

    def locking(self, F):
        """(I1_bar - 3) / Jm: 1 where the chains lock."""
        I1, _, J = invariants(F)
        return (J ** (-2.0 / 3.0) * I1 - 3) / self.Jm


@dataclass(frozen=True)
class ArrudaBoyce(Isochoric):
    """Arruda & Boyce (1993), eight-chain: W = mu sum_i C_i / lambda_m^(2i - 2) (I1_bar^i - 3^i), the 5-term
    series of Abaqus and FEBio; lambda_m the chains' locking stretch."""
    mu: float = 0.0
    lambda_m: float = 0.0

    def __post_init__(self):
        if not (math.isfinite(self.lambda_m) and self.lambda_m > 0):
            raise InputError(f"material.lambda_m = {self.lambda_m}: the locking stretch must be positive")
        super().__post_init__()

    def shear_modulus(self, value: Callable):
        """mu0 = 2 dW/dI1 at I1 = 3: mu (1 + 3/(5 lm^2) + 99/(175 lm^4) + ...)."""
        lm2 = np.asarray(value(self.lambda_m), dtype=float) ** 2
        return np.asarray(value(self.mu), dtype=float) * sum(
            2 * i * c * 3.0 ** (i - 1) / lm2 ** (i - 1) for i, c in enumerate(ARRUDA_BOYCE_SERIES, start=1))

    def isochoric(self, I1, I2):
        """Horner's form of the series in I1_bar (its powers one at a time: a quarter of the kernel's time)."""
        w = 0
        for i, c in reversed(list(enumerate(ARRUDA_BOYCE_SERIES, start=1))):
            w = (w + c / self.lambda_m ** (2 * i - 2)) * I1
        return self.mu * (w - sum(c / self.lambda_m ** (2 * i - 2) * 3.0 ** i
                                  for i, c in enumerate(ARRUDA_BOYCE_SERIES, start=1)))


ISOCHORIC_MODELS = {"ogden": Ogden, "yeoh": Yeoh, "gent": Gent, "arruda-boyce": ArrudaBoyce}
# each model's parameters (the scene keys), the required ones first; bulk or nu comes with all of them
ISOCHORIC_PARAMETERS = {"ogden": ("mu", "alpha"), "yeoh": ("C10", "C20", "C30"), "gent": ("mu", "Jm"),
                        "arruda-boyce": ("mu", "lambda_m")}
_REQUIRED = {"ogden": ("mu", "alpha"), "yeoh": ("C10",), "gent": ("mu", "Jm"), "arruda-boyce": ("mu", "lambda_m")}


def make_isochoric(model: str, given: dict, nu: float | None) -> Isochoric:
    """A rubber model from its parameters (`given`: name -> value or None; `bulk` among them) and the bulk
    modulus K, given as bulk or through Poisson's ratio nu at small strain: K = 2 mu0 (1 + nu) / (3 (1 - 2 nu))."""
    own = ISOCHORIC_PARAMETERS[model]
    values = {k: v for k, v in given.items() if v is not None and k != "bulk"}
    for name in values:
        if name not in own:
            raise InputError(f"material.{name}: not for model = {model!r} (it takes {', '.join(own)} and bulk "
                             "or nu)")
    for name in _REQUIRED[model]:
        if name not in values:
            raise InputError(f"material.{name}: missing (model = {model!r} needs {' and '.join(_REQUIRED[model])})")
    if model == "ogden":
        values = {k: tuple(float(x) for x in (v if isinstance(v, (list, tuple)) else [v])) for k, v in values.items()}
    elif isinstance(values.get("mu"), (list, tuple)):
        raise InputError(f"material.mu = {list(values['mu'])}: a list only for model = 'ogden'")
    bulk = given.get("bulk")
    if (bulk is None) == (nu is None):
        raise InputError(f"material: model = {model!r} needs bulk (the bulk modulus, Pa) or nu, one of the two")
    cls = ISOCHORIC_MODELS[model]
    if bulk is None:
        mu0 = float(np.min(cls(bulk=1.0, **values).shear_modulus(np.asarray)))
        bulk = 2 * mu0 * (1 + nu) / (3 * (1 - 2 * nu))
    return cls(bulk=float(bulk), **values)
