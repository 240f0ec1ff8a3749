"""Anisotropic materials: small-strain orthotropic elasticity (nine engineering constants in material axes,
3D-printed parts, wood, laminae) and fibre reinforcement added to any finite-strain model (fabric, paper or
print lines along a direction, active in tension only)."""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Callable, ClassVar

import numpy as np
import ufl

from fem_forms.errors import InputError
from fem_forms.kinematics import small_strain

ORTHOTROPIC_CONSTANTS = ("E1", "E2", "E3", "G12", "G13", "G23", "nu12", "nu13", "nu23")
VOIGT = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))      # engineering shear strains 2 e23, 2 e13, 2 e12


def material_axes(axis1, axis2, key: str = "material") -> np.ndarray:
    """Rows a1, a2, a3 = a1 x a2 (unit vectors); axis2 must be perpendicular to axis1."""
    a1, a2 = np.asarray(axis1, float), np.asarray(axis2, float)
    n1, n2 = np.linalg.norm(a1), np.linalg.norm(a2)
    if n1 == 0 or n2 == 0:
        raise InputError(f"{key}.axis{1 if n1 == 0 else 2}: must not be the zero vector")
    a1, a2 = a1 / n1, a2 / n2
    if abs(a1 @ a2) > 1e-6:
        raise InputError(f"{key}.axis2 = {list(axis2)}: must be perpendicular to axis1 = {list(axis1)}")
    return np.array([a1, a2, np.cross(a1, a2)])


def orthotropic_stiffness(c: dict, axes: np.ndarray, key: str = "material") -> np.ndarray:
    """The 6 x 6 stiffness (Voigt, engineering shear) in the global frame from the nine constants in the
    material axes (rows of `axes`); InputError naming the constraint when the compliance is not positive
    definite (Lempriere 1968: E, G > 0, |nu_ij| < sqrt(E_i / E_j), and the determinant condition)."""
    for name in ORTHOTROPIC_CONSTANTS:
        if c.get(name) is None:
            raise InputError(f"{key}.{name}: missing (orthotropic needs {', '.join(ORTHOTROPIC_CONSTANTS)})")
        if not math.isfinite(c[name]) or (name[0] in "EG" and c[name] <= 0):
            raise InputError(f"{key}.{name} = {c[name]}: must be positive")
    E = [c["E1"], c["E2"], c["E3"]]
    nu = {(0, 1): c["nu12"], (0, 2): c["nu13"], (1, 2): c["nu23"]}
    for (i, j), v in nu.items():
        if abs(v) >= math.sqrt(E[i] / E[j]):
            raise InputError(f"{key}.nu{i + 1}{j + 1} = {v}: |nu{i + 1}{j + 1}| must be below "
                             f"sqrt(E{i + 1} / E{j + 1}) = {math.sqrt(E[i] / E[j]):.4g} (positive definite stiffness)")
    S = np.zeros((6, 6))
    for i in range(3):
        S[i, i] = 1.0 / E[i]
    for (i, j), v in nu.items():
        S[i, j] = S[j, i] = -v / E[i]
    S[3, 3], S[4, 4], S[5, 5] = 1.0 / c["G23"], 1.0 / c["G13"], 1.0 / c["G12"]
    if np.linalg.det(S[:3, :3]) * E[0] * E[1] * E[2] <= 0:
        raise InputError(f"{key}: 1 - nu12 nu21 - nu23 nu32 - nu13 nu31 - 2 nu21 nu32 nu13 must be positive "
                         "(the Poisson's ratios make the stiffness indefinite)")
    local = _tensor(np.linalg.inv(S))
    R = np.asarray(axes)
    rotated = np.einsum("pi,qj,rk,sl,pqrs->ijkl", R, R, R, R, local)
    return np.array([[rotated[a + b] for b in VOIGT] for a in VOIGT])


def _tensor(Cv: np.ndarray) -> np.ndarray:
    """The fourth-order tensor C_ijkl of a Voigt stiffness (minor symmetries filled in)."""
    C = np.zeros((3, 3, 3, 3))
    for I, (i, j) in enumerate(VOIGT):
        for J, (k, l) in enumerate(VOIGT):
            for a, b in ((i, j), (j, i)):
                for c_, d in ((k, l), (l, k)):
                    C[a, b, c_, d] = Cv[I, J]
    return C


def voigt_strain(eps):
    """[e11, e22, e33, 2 e23, 2 e13, 2 e12] of a symmetric UFL tensor."""
    return ufl.as_vector([eps[i, j] if i == j else 2 * eps[i, j] for i, j in VOIGT])


@dataclass(frozen=True)
class Orthotropic:
    """Small-strain orthotropic elasticity: psi = 1/2 e . C e, e the Voigt strain, C the 6 x 6 stiffness in
    the global frame (a tuple of 36 numbers; a fem.Constant or DG0 field once bound to a mesh)."""
    C: tuple
    small_strain: ClassVar[bool] = True

    def young_modulus(self, value: Callable):
        """The diagonal stiffnesses C11, C22, C33 (of every cell): the stiffest direction's modulus."""
        C = value(self.C) if not isinstance(self.C, tuple) else np.asarray(self.C)
        return np.reshape(C, (-1, 36))[:, [0, 7, 14]]

    def psi(self, F):
        return self.strain_energy(small_strain(F))

    def strain_energy(self, eps):
        """1/2 e . C e of a symmetric strain tensor (the Green strain in a finite-strain part)."""
        e = voigt_strain(eps)
        C = ufl.as_matrix(np.reshape(self.C, (6, 6)).tolist()) if isinstance(self.C, tuple) else self.C
        return 0.5 * ufl.dot(e, C * e)


def make_orthotropic(c: dict, axis1, axis2, key: str = "material") -> Orthotropic:
    """The orthotropic model from the nine constants and two axes (validated)."""
    if axis1 is None or axis2 is None:
        raise InputError(f"{key}.axis{1 if axis1 is None else 2}: missing (orthotropic needs axis1 and axis2)")
    return Orthotropic(tuple(orthotropic_stiffness(c, material_axes(axis1, axis2, key), key).ravel()))


FIBER_MODELS = ("holzapfel", "quadratic")


def fiber_energy(F, a0, E_f, k2, kind: str):
    """Energy per rest volume of fibres along the unit vector a0, in tension only (I4 = a0 . C a0 > 1):
    quadratic E_f/8 (I4 - 1)^2, or Holzapfel-Gasser-Ogden k1/(2 k2) (exp(k2 (I4 - 1)^2) - 1) with
    k1 = E_f/4; both add E_f to the small-strain stiffness along a0 (I4 - 1 ~ 2 e_ff)."""
    s = ufl.dot(a0, F.T * F * a0) - 1
    if kind == "quadratic":
        psi = E_f / 8 * s ** 2
    else:
        psi = E_f / (8 * k2) * (ufl.exp(k2 * s ** 2) - 1)
    return ufl.conditional(ufl.gt(s, 0), psi, 0)


class FiberReinforced:
    """A finite-strain model plus fibre families, each on its material's cells (a DG0 indicator; None:
    everywhere). Every fibre value is a fem.Constant: new values compile nothing."""

    def __init__(self, base, families: list):
        self.base = base
        self.families = families           # dicts: direction, E, k2 (Constants), kind, indicator, index

    def fiber_psi(self, F):
        terms = []
        for f in self.families:
            psi = fiber_energy(F, f["direction"], f["E"], f["k2"], f["kind"])
            terms.append(psi if f["indicator"] is None else f["indicator"] * psi)
        return sum(terms[1:], terms[0])

    def psi(self, F):
        return self.base.psi(F) + self.fiber_psi(F)

    def young_modulus(self, value: Callable):
        return self.base.young_modulus(value)             # the matrix's (fibres aside)

    def update(self, specs: list) -> None:
        """New fibre values from the scene's materials (the same families: other fibres need a new model)."""
        now = [(i, m.fiber_model) for i, m in enumerate(specs)
               if m.fiber_direction is not None or m.fiber_field is not None]
        if now != [(f["index"], f["kind"]) for f in self.families]:
            raise InputError("material: fibres added, removed or of another model need a new model (new values "
                             "of direction, E and k2 do not)")
        for f in self.families:
            m = specs[f["index"]]
            if m.fiber_direction is not None:              # a cell field's directions stay the mesh file's
                f["direction"].value = unit(m.fiber_direction, m.key)
            f["E"].value, f["k2"].value = m.fiber_E, m.fiber_k2


def unit(v, key: str) -> np.ndarray:
    """v / |v|, refusing the zero vector."""
    v = np.asarray(v, float)
    n = np.linalg.norm(v)
    if n == 0:
        raise InputError(f"{key}.fibers.direction: must not be the zero vector")
    return v / n
