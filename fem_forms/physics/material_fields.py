"""Several materials in one energy: the materials of one model share its psi(F) with DG0 parameter fields
(one form, one kernel: as fast as one material); materials of different models each integrate their psi over
their own cells, or (where one expression is needed: stresses, a body load's own cell tags) add their psi
weighted by DG0 indicators."""
from __future__ import annotations

import copy
from dataclasses import dataclass
import dataclasses

from dolfinx import fem
import numpy as np
import ufl

from petsc4py import PETSc

from fem_forms.errors import InputError
from fem_forms.materials import Material
from fem_forms.materials.anisotropic import FiberReinforced, unit
from fem_forms.materials.hyperelastic import GreenStrainForm, is_small_strain
from fem_forms.physics.regions import MaterialRegions


def _numeric_fields(material) -> list[str]:
    """The parameters bound as fields: numbers, and tuples of numbers (a stiffness matrix)."""
    def numeric(v):
        return (isinstance(v, (int, float)) and not isinstance(v, bool)) or (
            isinstance(v, tuple) and all(isinstance(x, (int, float)) for x in v))
    return [f.name for f in dataclasses.fields(material) if numeric(getattr(material, f.name))]


def _kind(material) -> tuple:
    """What materials must share to share one psi with DG0 parameters: the model, and the number of terms of
    its list parameters (two Ogden materials of 2 and 3 terms are two parts)."""
    return (type(material), *(np.shape(getattr(material, n)) for n in _numeric_fields(material)))


@dataclass
class MaterialPart:
    """The materials (scene indices) sharing one model, its psi with DG0 parameters, and its cells."""
    material: Material
    members: list[int]
    fields: dict                       # parameter name -> DG0 Function
    indicator: fem.Function            # 1 on the part's cells, 0 elsewhere
    dx: ufl.Measure | None = None      # the part's cells (set by the solid on its Context's measure)


class MaterialMix:
    """Models of different kinds side by side: psi(F) = sum_parts indicator_p psi_p(F)."""

    def __init__(self, parts: list[MaterialPart]):
        self.parts = parts
        self.small_strain = all(getattr(p.material, "small_strain", False) for p in parts)

    def psi(self, F):
        terms = [p.indicator * p.material.psi(F) for p in self.parts]
        return sum(terms[1:], terms[0])

    def young_modulus(self, value):
        """Every part's moduli together (None if any part states none)."""
        each = [p.material.young_modulus(value) for p in self.parts]
        return None if any(e is None for e in each) else np.concatenate([np.ravel(e) for e in each])


class MaterialBinding:
    """The scene's materials bound to a mesh: `material` is what the solid's energy uses (one model with
    DG0 parameters, or a MaterialMix); `update` takes new values without compiling anything."""

    def __init__(self, specs: list, regions: MaterialRegions):
        self.regions = regions
        built = [s.material for s in specs]
        kinds: dict = {}
        for i, m in enumerate(built):
            kinds.setdefault(_kind(m), []).append(i)
        self.parts = []
        for members in kinds.values():
            first = built[members[0]]
            bound = copy.copy(first)
            fields = {}
            for name in _numeric_fields(first):
                fields[name] = regions.field(self._values(built, members, name), name)
                object.__setattr__(bound, name, fields[name])
            indicator = regions.field([1.0 if i in members else 0.0 for i in range(len(built))], "indicator")
            self.parts.append(MaterialPart(bound, members, fields, indicator))
        if not all(is_small_strain(p.material) for p in self.parts):        # small-strain laws in a finite part
            for p in self.parts:
                if is_small_strain(p.material):
                    p.material = GreenStrainForm(p.material)
        self.material = self.parts[0].material if len(self.parts) == 1 else MaterialMix(self.parts)
        self.layout = [(s.model, s.where, _kind(m)) for s, m in zip(specs, built)]   # what new values may not change

    @staticmethod
    def _values(built: list, members: list[int], name: str) -> list:
        """One value per material: the members' own, the first member's on the other materials' cells."""
        own = {i: np.asarray(getattr(built[i], name), dtype=float) for i in members}
        own = {i: v.reshape(6, 6) if v.size == 36 else v for i, v in own.items()}     # a stiffness matrix
        return [own.get(i, own[members[0]]) for i in range(len(built))]

    def update(self, specs: list) -> None:
        """New parameter values (the same models on the same cells; anything else needs a new model)."""
        if [(s.model, s.where, _kind(s.material)) for s in specs] != self.layout:
            raise InputError("material: a material's model, number of terms or cells changed: that needs a new "
                             "model (new values of its constants do not)")
        built = [s.material for s in specs]
        for part in self.parts:
            for name, f in part.fields.items():
                self.regions.fill(f, self._values(built, part.members, name))


def with_fibers(material: Material, specs: list, regions: MaterialRegions, loaded=None):
    """The solid's material plus the fibre families of the materials that have [material] fibers (each
    on its own cells when there are several materials), or `material` as it is when none has."""
    families = []
    for i, m in enumerate(specs):
        if m.fiber_direction is None and m.fiber_field is None:
            continue
        mesh = regions.mesh
        direction = (fem.Constant(mesh, unit(m.fiber_direction, m.key)) if m.fiber_field is None
                     else field_directions(loaded, m.fiber_field, regions, i, f"{m.key}.fibers.group_field"))
        families.append({
            "direction": direction,
            "E": fem.Constant(mesh, PETSc.ScalarType(m.fiber_E)),
            "k2": fem.Constant(mesh, PETSc.ScalarType(m.fiber_k2)), "kind": m.fiber_model, "index": i,
            "indicator": regions.field([1.0 if j == i else 0.0 for j in range(len(specs))], "fibers")
            if regions.several else None})
    return FiberReinforced(material, families) if families else material


def field_directions(loaded, name: str, regions: MaterialRegions, index: int, key: str) -> fem.Function:
    """A DG0 vector Function of unit fibre directions from the mesh file's cell field `name` (the cells of
    material `index`; the others keep a placeholder their indicator zeroes)."""
    fields = getattr(loaded, "cell_fields", {}) or {}
    if name not in fields:
        have = ", ".join(sorted(fields)) or "none (a gmsh .msh or a generated mesh carries no cell data)"
        raise InputError(f"{key} = {name!r}: the mesh file has no such cell field (its cell fields: {have})")
    values = np.asarray(fields[name], dtype=float)
    if values.ndim != 2 or values.shape[1] != 3:
        raise InputError(f"{key} = {name!r}: must be a vector per cell (3 components), got {values.shape[1:]}")
    own = regions.n_owned
    length = np.linalg.norm(values[:own], axis=1)
    mine = regions.index[:own] == index
    bad = int(np.count_nonzero(mine & (length == 0)))
    from mpi4py import MPI
    if regions.mesh.comm.allreduce(bad, op=MPI.SUM):
        raise InputError(f"{key} = {name!r}: zero vectors on cells of this material (a fibre needs a direction)")
    V = fem.VectorFunctionSpace(regions.mesh, ("DG", 0))
    f = fem.Function(V, name="fiber_direction")
    units = np.tile([1.0, 0.0, 0.0], (own, 1))
    units[length > 0] = values[:own][length > 0] / length[length > 0, None]
    f.x.array[:3 * own] = units.ravel()
    f.x.scatter_forward()
    return f
