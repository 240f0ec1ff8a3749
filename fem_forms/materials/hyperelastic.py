"""Hyperelastic energy densities psi(F) as UFL expressions: the built-in models and user functions."""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, Callable, ClassVar, Protocol

import ufl

from fem_forms.errors import InputError
from fem_forms.materials.anisotropic import Orthotropic, make_orthotropic
from fem_forms.materials.isochoric import ISOCHORIC_MODELS, ISOCHORIC_PARAMETERS, make_isochoric
from fem_forms.keys import Key, check_range
from fem_forms.kinematics import (biot_from_invariants, biot_invariants, green_strain, invariants, small_invariants,
                                  small_strain)


class Material(Protocol):
    """An energy density psi(F). Optional: `pk1(F)`, the same d psi / d F written another way (the chain rule
    through invariants, faster to compile); a material that has it gets its residual from it, so it must be
    exactly the derivative of psi (the energy line search uses psi)."""
    def psi(self, F) -> ufl.core.expr.Expr: ...

    def young_modulus(self, value: Callable) -> Any:
        """E of the small-strain limit (anisotropic: the stiffest direction's), `value(p)` giving a parameter's
        values (a float, or a field's cell values): the scale of barriers, penalties and round-off. None
        where the model has none (a user's psi)."""


SMALL_STRAIN_MODELS = ("linear", "orthotropic")     # psi of the infinitesimal strain: no finite rotations


def is_small_strain(material) -> bool:
    """Is psi written in the infinitesimal strain (sigma = P, no meaning for det F)?"""
    return bool(getattr(material, "small_strain", False))


@dataclass(frozen=True)
class GreenStrainForm:
    """A small-strain law beside finite-strain materials in one part: its energy of the Green strain in place
    of the infinitesimal one (its St Venant-Kirchhoff form, as FEBio's orthotropic elastic): the same stiffness
    at small strain, and frame-indifferent under the finite rotations the part undergoes."""
    law: Any
    small_strain: ClassVar[bool] = False

    def young_modulus(self, value: Callable):
        return self.law.young_modulus(value)

    def psi(self, F):
        return self.law.strain_energy(green_strain(F))

    def __getattr__(self, name: str):
        """The law's constants (mu, lmbda, C: a modulus for barrier and round-off scales) read through."""
        if name not in ("mu", "lmbda", "C"):     # not pk1 (the law's is of the small strain), nor law itself
            raise AttributeError(name)           # (not set yet while copied: no recursion)
        return getattr(self.law, name)


def young_of_lame(mu, lmbda):
    """E from the Lame parameters (floats or arrays of them)."""
    return mu * (3 * lmbda + 2 * mu) / (lmbda + mu)


def lame_from_young_poisson(E: float, nu: float) -> tuple[float, float]:
    """(mu, lambda) from Young's modulus E and Poisson's ratio nu."""
    return E / (2.0 * (1.0 + nu)), E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))


def _check_lame(mu: float, lmbda: float) -> None:
    """mu against its declared range (PARAMETER_KEYS), and the bulk modulus positive."""
    if not math.isfinite(mu):
        raise InputError(f"material.mu = {mu}: must be finite")
    check_range(_PARAMETER["mu"], mu, "material.mu")
    if not (math.isfinite(lmbda) and 3 * lmbda + 2 * mu > 0):
        raise InputError(f"material.lambda = {lmbda}: the bulk modulus lambda + 2 mu/3 must be positive")


@dataclass(frozen=True)
class LameModel:
    """A model with the Lame parameters mu and lambda (validated once, when built): its small-strain modulus."""
    mu: float
    lmbda: float

    def __post_init__(self):
        _check_lame(self.mu, self.lmbda)

    def young_modulus(self, value: Callable):
        return young_of_lame(value(self.mu), value(self.lmbda))


@dataclass(frozen=True)
class LinearElastic(LameModel):
    """Small-strain elasticity: psi = mu eps:eps + lambda/2 (tr eps)^2."""
    small_strain: ClassVar[bool] = True

    def strain(self, F):
        """The strain psi is quadratic in: eps = sym(grad u)."""
        return small_strain(F)

    def psi(self, F):
        return self.strain_energy(self.strain(F))

    def strain_energy(self, eps):
        """mu eps:eps + lambda/2 (tr eps)^2 of a symmetric strain tensor."""
        return self.mu * ufl.inner(eps, eps) + 0.5 * self.lmbda * ufl.tr(eps) ** 2

    def volumetric(self, F):
        """theta with psi = psi|_(lambda=0) + lambda/2 theta^2 (for the mixed u-p formulation)."""
        return ufl.tr(self.strain(F))


@dataclass(frozen=True)
class StVenantKirchhoff(LinearElastic):
    """St. Venant-Kirchhoff: psi = mu E:E + lambda/2 (tr E)^2 with E the Green strain (the small-strain law
    written in the Green strain, so a rigid rotation stores no energy)."""
    small_strain: ClassVar[bool] = False

    def strain(self, F):
        return green_strain(F)


@dataclass(frozen=True)
class NeoHookean(LameModel):
    """Compressible neo-Hookean: psi = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2."""
    def psi(self, F):
        I1, _, J = invariants(F)
        lnJ = ufl.ln(J)
        return 0.5 * self.mu * (I1 - 3) - self.mu * lnJ + 0.5 * self.lmbda * lnJ**2

    def volumetric(self, F):
        return ufl.ln(ufl.det(F))


@dataclass(frozen=True)
class MooneyRivlin:
    """Compressible Mooney-Rivlin:
    psi = C10 (I1 - 3) + C01 (I2 - 3) - 2 (C10 + 2 C01) ln J + lambda/2 (ln J)^2.
    Stress-free at F = I; small-strain shear modulus mu = 2 (C10 + C01)."""
    C10: float
    C01: float
    lmbda: float

    def __post_init__(self):
        for name in ("C10", "C01"):
            check_range(_PARAMETER[name], getattr(self, name), f"material.{name}")
        if not self.C10 + self.C01 > 0:
            raise InputError(f"material.C10/C01 = {self.C10}/{self.C01}: their sum must be positive")
        _check_lame(2 * (self.C10 + self.C01), self.lmbda)

    def young_modulus(self, value: Callable):
        return young_of_lame(2.0 * (value(self.C10) + value(self.C01)), value(self.lmbda))

    def psi(self, F):
        I1, I2, J = invariants(F)
        lnJ = ufl.ln(J)
        return (self.C10 * (I1 - 3) + self.C01 * (I2 - 3)
                - 2 * (self.C10 + 2 * self.C01) * lnJ + 0.5 * self.lmbda * lnJ**2)

    def volumetric(self, F):
        return ufl.ln(ufl.det(F))


@dataclass(frozen=True)
class Corotated(LameModel):
    """Corotational elasticity (the lecture's corotational frames F = R U):
    psi = mu |F - R|^2 + lambda/2 (tr(R^T F) - 3)^2, with R the rotation of the polar decomposition.

    With R^T F = U this is mu |U - I|^2 + lambda/2 (tr U - 3)^2: linear elasticity on the Biot strain
    U - I, which is also the lecture's "linear form in the rotated frame" (its small strain
    sym(R^T F) - I is U - I itself), so the two choices are one energy. Its stress is the familiar
    P = 2 mu (F - R) + lambda (tr U - 3) R (McAdams et al. 2011). Small strain: U - I = eps +
    O(|grad u|^2), so it agrees with LinearElastic to first order; unlike it, a rigid rotation stores
    no energy. Large compression is not penalised as J -> 0 (no ln J): keep strains moderate.

    Evaluated as psi = mu |U - I|^2 + lambda/2 (tr U - 3)^2 (|F - R|^2 = tr C - 2 tr(R^T F) + 3 =
    |U - I|^2), both from kinematics.biot_invariants: smooth functions of the invariants of C, accurate
    for stretches 0.14 to 7.4, differentiable at repeated stretches, written in small quantities so the
    energy of tiny strains carries no O(mu eps_machine) round-off. ufl.derivative goes through them, so
    residual and tangent are exact for the assembled energy. Measured JIT (P1 residual and tangent):
    135 s with R from kinematics.polar_rotation, 8 s through tr U alone (same numbers), about 17 min
    for the tangent of 4 matrix Newton steps R <- (R + R^-T)/2; `pk1` (the chain rule through the
    invariants, the residual's P) brought the first run of a P1 beam from 25.1 s to 10.4 s. The mixed u-p
    split (volumetric) is exact, but its Taylor-Hood tangent did not finish compiling within 6 minutes here."""
    def psi(self, F):
        return self.psi_of_invariants(*small_invariants(F))

    def psi_of_invariants(self, e1, e2, j):
        """psi as a function of the small invariants (e1, e2, j) of kinematics.small_invariants."""
        trace, norm2 = biot_from_invariants(e1, e2, j)
        return self.mu * norm2 + 0.5 * self.lmbda * trace**2

    def pk1(self, F):
        """P = d psi / d F by the chain rule through the three invariants: ufl.diff of psi with respect to
        each (scalar) invariant times ufl.diff of the invariant with respect to F. The same P as
        ufl.diff(psi(F), F) (tangent and residual matrices equal to 3e-16), but the nested tr U iteration
        is differentiated for three scalars instead of nine components of F: the P1 tangent kernel
        compiled in 5.3 s instead of 18.7 s (gcc on 1 MB of C), assembly as fast."""
        F = ufl.variable(F)
        xs = [ufl.variable(x) for x in small_invariants(F)]
        psi = self.psi_of_invariants(*xs)
        return sum(ufl.diff(psi, x) * ufl.diff(x, F) for x in xs)

    def volumetric(self, F):
        """theta = tr U - 3, so psi = psi|_(lambda=0) + lambda/2 theta^2 (the mixed u-p formulation)."""
        return biot_invariants(F)[0]


@dataclass(frozen=True)
class UserMaterial:
    """Wraps a user's own energy density function psi(F) -> UFL expression."""
    function: Callable
    name: str = "user"

    def young_modulus(self, value: Callable) -> None:
        return None                       # a user's psi(F) states no modulus

    def psi(self, F):
        return self.function(F)


MODELS = {
    "linear": LinearElastic,
    "stvk": StVenantKirchhoff,
    "neo-hookean": NeoHookean,
    "mooney-rivlin": MooneyRivlin,
    "corotated": Corotated,
    "orthotropic": Orthotropic,
    **ISOCHORIC_MODELS,
}


# the parameters a hyperelastic model is built from, declared once: the scene reads them with these Keys
# (type only) and their ranges are checked once, against these declarations: E and nu by make_material
# (they are not kept), mu, C10 and C01 by the model that holds them (its __post_init__, so a model built
# directly in Python is checked the same way); lambda's rule involves mu (a positive bulk modulus)
_MU = Key("mu", "number", "shear modulus (with lambda); gent, arruda-boyce: their mu", unit="Pa",
          exclusive_minimum=0, checked_by="material")
PARAMETER_KEYS = (
    Key("E", "number", "Young's modulus (with nu)", unit="Pa", exclusive_minimum=0,
        note="Young's modulus must be positive", checked_by="material"),
    Key("nu", "number", "Poisson's ratio (with E; or alone for the rubber models: their bulk modulus at small "
        "strain)", exclusive_minimum=-1.0, exclusive_maximum=0.5,
        note="Poisson's ratio must lie in (-1, 0.5) for a compressible model", checked_by="material"),
    Key("mu", "either", "shear modulus (with lambda); gent, arruda-boyce: their mu; ogden: the list mu_i",
        unit="Pa", keys=(_MU, Key("mu", "vector", "ogden: mu_i (sum mu_i alpha_i / 2 is the shear modulus)",
                                  unit="Pa", min_items=1))),
    Key("lambda", "number", "Lame's first parameter (with mu)", unit="Pa", attr="lmbda", checked_by="material"),
    Key("C10", "number", "Mooney-Rivlin C10 (default 3 mu / 8); yeoh: C10 (half the shear modulus)", unit="Pa",
        minimum=0, checked_by="material"),
    Key("C01", "number", "Mooney-Rivlin C01 (default mu / 8)", unit="Pa", minimum=0, checked_by="material"),
    Key("C20", "number", "yeoh: C20, the (I1 - 3)^2 coefficient", unit="Pa", checked_by="material"),
    Key("C30", "number", "yeoh: C30, the (I1 - 3)^3 coefficient", unit="Pa", checked_by="material"),
    Key("alpha", "vector", "ogden: the exponents alpha_i, one per mu_i", min_items=1, checked_by="material"),
    Key("Jm", "number", "gent: the locking limit of I1 - 3", exclusive_minimum=0, checked_by="material"),
    Key("lambda_m", "number", "arruda-boyce: the chains' locking stretch", exclusive_minimum=0,
        checked_by="material"),
    Key("bulk", "number", "the rubber models' bulk modulus K (or nu): psi = W(J^(-1/3) F) + K/2 (ln J)^2",
        unit="Pa", exclusive_minimum=0, checked_by="material"),
)
_PARAMETER = {k.name: k for k in PARAMETER_KEYS if k.kind != "either"} | {"mu": _MU}


def make_material(model: str, *, E: float | None = None, nu: float | None = None,
                  mu: float | list | None = None, lmbda: float | None = None,
                  C10: float | None = None, C01: float | None = None, orthotropic: dict | None = None,
                  axis1=None, axis2=None, **rubber) -> Material:
    """Build a named model from (E, nu) or (mu, lambda); Mooney-Rivlin also takes C10, C01
    (default split C01 = mu/8, C10 = 3 mu/8 of mu = 2 (C10 + C01) when only E, nu are given); orthotropic
    its nine constants (`orthotropic`, by name) in the axes axis1, axis2; the rubber models of isochoric.py
    their own parameters (`rubber`: alpha, C20, C30, Jm, lambda_m) with mu or C10, and bulk or nu."""
    if model not in MODELS:
        raise InputError(f"material.model = {model!r}: unknown model (choose from {', '.join(MODELS)})")
    if model in ISOCHORIC_MODELS:
        for name, value in (("E", E), ("lambda", lmbda), ("C01", C01), *(orthotropic or {}).items(),
                            ("axis1", axis1), ("axis2", axis2)):
            if value is not None:
                raise InputError(f"material.{name}: not for model = {model!r} (it takes "
                                 f"{', '.join(ISOCHORIC_PARAMETERS[model])} and bulk or nu)")
        if nu is not None:
            check_range(_PARAMETER["nu"], nu, "material.nu")
        return make_isochoric(model, {"mu": mu, "C10": C10, **rubber}, nu)
    extra = next((k for k, v in rubber.items() if v is not None), None)
    if extra is not None:
        raise InputError(f"material.{extra}: only for model = "
                         f"{' or '.join(repr(m) for m, ps in ISOCHORIC_PARAMETERS.items() if extra in ps)} "
                         f"(model is {model!r})")
    if isinstance(mu, (list, tuple)):
        raise InputError(f"material.mu = {list(mu)}: a list only for model = 'ogden' (model is {model!r})")
    given = {k: v for k, v in (orthotropic or {}).items() if v is not None}
    if model == "orthotropic":
        extra = next((n for n, v in (("E", E), ("nu", nu), ("mu", mu), ("lambda", lmbda), ("C10", C10),
                                     ("C01", C01)) if v is not None), None)
        if extra is not None:
            raise InputError(f"material.{extra}: not for model = 'orthotropic' (give E1 E2 E3 G12 G13 G23 "
                             "nu12 nu13 nu23)")
        return make_orthotropic(orthotropic or {}, axis1, axis2)
    if given or axis1 is not None or axis2 is not None:
        name = next(iter(given), "axis1" if axis1 is not None else "axis2")
        raise InputError(f"material.{name}: only for model = 'orthotropic' (model is {model!r})")
    if model != "mooney-rivlin" and (C10 is not None or C01 is not None):
        raise InputError(f"material.{'C10' if C10 is not None else 'C01'}: only for model = 'mooney-rivlin' "
                         f"(model is {model!r})")
    if E is not None or nu is not None:
        if E is None or nu is None:
            raise InputError("material: give both E and nu (or mu and lambda)")
        for name, value in (("E", E), ("nu", nu)):
            if not math.isfinite(value):
                raise InputError(f"material.{name} = {value}: must be finite")
            check_range(_PARAMETER[name], value, f"material.{name}")
        mu, lmbda = lame_from_young_poisson(E, nu)
    if model == "mooney-rivlin":
        if C10 is None and C01 is None:
            if mu is None:
                raise InputError("material: mooney-rivlin needs E and nu, or C10, C01 and lambda")
            C10, C01 = 0.375 * mu, 0.125 * mu
        if lmbda is None or C10 is None or C01 is None:
            raise InputError("material: mooney-rivlin needs C10, C01 and lambda (or E and nu)")
        return MooneyRivlin(float(C10), float(C01), float(lmbda))
    if mu is None or lmbda is None:
        raise InputError(f"material: {model!r} needs E and nu, or mu and lambda")
    return MODELS[model](float(mu), float(lmbda))


def as_material(material) -> Material:
    """Accept a Material or a plain function psi(F)."""
    if hasattr(material, "psi"):
        return material
    if callable(material):
        return UserMaterial(material, getattr(material, "__name__", "user"))
    raise InputError(f"material: {material!r} is neither a material nor a function psi(F)")

