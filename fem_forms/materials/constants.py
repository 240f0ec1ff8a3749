"""Material parameters as fem.Constants: forms built from a bound material compile once, and a new value
compiles nothing. Kept apart from the models so that reading a scene needs no dolfinx."""
from __future__ import annotations

import copy
import dataclasses

from dolfinx import fem
import numpy as np
from petsc4py import PETSc

from fem_forms.errors import InputError
from fem_forms.materials.hyperelastic import Material, UserMaterial


def bind_constants(material: Material, mesh) -> Material:
    """The same model with each numeric parameter as a fem.Constant on `mesh` (same values): forms built
    from it compile once, and a new value (set_parameters) compiles nothing. A user's psi(F) function is
    returned as it is (its numbers are its own)."""
    if not dataclasses.is_dataclass(material) or isinstance(material, UserMaterial):
        return material
    bound = copy.copy(material)
    for f in dataclasses.fields(material):
        value = getattr(material, f.name)
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            object.__setattr__(bound, f.name, fem.Constant(mesh, PETSc.ScalarType(value)))
        elif isinstance(value, tuple) and len(value) == 36:            # a 6 x 6 stiffness (orthotropic)
            object.__setattr__(bound, f.name, fem.Constant(mesh, np.reshape(value, (6, 6)).astype(PETSc.ScalarType)))
        elif isinstance(value, tuple) and value:                       # a list of terms (Ogden's mu_i, alpha_i)
            object.__setattr__(bound, f.name, fem.Constant(mesh, np.asarray(value, dtype=PETSc.ScalarType)))
    return bound


def set_parameters(bound: Material, new: Material) -> None:
    """Give the Constants of a bound material the values of `new`, a validated model of the same kind."""
    if type(bound) is not type(new):
        raise InputError(f"material: cannot change a {type(bound).__name__} into a {type(new).__name__} "
                         "without rebuilding the model")
    for f in dataclasses.fields(new):
        target = getattr(bound, f.name)
        if isinstance(target, fem.Constant):
            target.value = np.reshape(getattr(new, f.name), target.value.shape)


def parameter_value(x) -> float:
    """A material parameter as a float, whether it is a number or a fem.Constant."""
    return float(x.value) if isinstance(x, fem.Constant) else float(x)


def parameter_values(x):
    """A material parameter as a float, or as the array of a DG0 parameter field's local values (or of a
    list parameter's terms)."""
    if isinstance(x, fem.Function):
        return np.asarray(x.x.array, dtype=float)
    if isinstance(x, fem.Constant) and np.ndim(x.value):
        return np.asarray(x.value, dtype=float)
    if isinstance(x, (tuple, list)):
        return np.asarray(x, dtype=float)
    return parameter_value(x)
