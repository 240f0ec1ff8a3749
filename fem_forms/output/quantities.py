"""Stresses and strains of a solved model by name: recovered fields (output/recovery.py), their values
at probes, and the fields written for ParaView.

Stresses come from the material's energy by ufl.diff (P = d psi / d F; in the mixed formulation the
energy with the pressure field), never written by hand: PK1 P, PK2 S = F^-1 P, Cauchy sigma = P F^T / J.
For the small-strain model ("linear") sigma = P: linear theory does not tell the stress measures apart.
Each tensor is recovered once (cached). Output fields are nodal P1 values of the recovered fields, so
ParaView shows at a node what a probe there reports; the measures UFL cannot express (Biot and Hencky
strain, principal stresses) are computed with numpy (output/measures.py) from the recovered F and sigma
at those nodes.
"""
from __future__ import annotations

from dolfinx import fem
import numpy as np
import ufl

from fem_forms.materials.hyperelastic import is_small_strain
from fem_forms.output import measures, probes
from fem_forms.output.fields import p1_interpolant
from fem_forms.output.recovery import Recovery
from fem_forms.output.strength import StrengthCheck, has_strength
from fem_forms.scene.spec import FIELD_NAMES

# the fields recovered by L2 projection of a UFL expression (the others derive from them)
PROJECTED = ("cauchy_stress", "pk1_stress", "pk2_stress", "green_strain", "infinitesimal_strain",
             "deformation_gradient")


def tensor_expressions(model) -> dict:
    """UFL expressions of the model's deformation gradient, strains and stresses, by name."""
    ctx = model.context
    F = ctx.F
    P = model.solid.pk1(ctx)    # elastic: pressure and thermal strain included; plastic: at the committed history
    sigma = P if is_small_strain(model.material) else P * F.T / ufl.det(F)
    I = ufl.Identity(3)
    return {"deformation_gradient": F, "pk1_stress": P, "pk2_stress": ufl.inv(F) * P,
            "cauchy_stress": sigma, "green_strain": 0.5 * (F.T * F - I),
            "infinitesimal_strain": ufl.sym(F - I)}


class Quantities:
    """The recovered stresses and strains of one solved model (computed on first request)."""

    def __init__(self, model):
        self.model = model
        self.recovery = Recovery(model.mesh, model.V.ufl_element().degree(),
                                 model.scene.discretization.quadrature)
        self._expressions = tensor_expressions(model)
        self._recovered: dict = {}
        self._p1: dict = {}
        self._fields: dict = {}
        self._strength = None

    def recovered(self, name: str) -> fem.Function:
        """One of PROJECTED as a continuous field on the displacement's Lagrange space."""
        if name not in self._recovered:
            self._recovered[name] = self.recovery.project(self._expressions[name], name)
        return self._recovered[name]

    def at_probes(self, points: probes.ProbeSet) -> dict[str, dict]:
        """{probe: {"stress": Cauchy 3x3 [Pa], "von_mises": [Pa], "strain": Green-Lagrange 3x3}} from the
        recovered fields at each located point (MPI-correct, same answer on any rank count)."""
        if not points.names:
            return {}
        sigma = points.evaluate(self.recovered("cauchy_stress"))
        strain = points.evaluate(self.recovered("green_strain"))
        out = {}
        for name in points.names:
            s = np.reshape(sigma[name], (3, 3))
            out[name] = {"stress": s.tolist(), "von_mises": float(measures.von_mises(s)),
                         "strain": np.reshape(strain[name], (3, 3)).tolist()}
        return out

    def strength(self) -> dict | None:
        """The safety factor against the materials' strengths (output/strength.py), None without any."""
        if not has_strength(self.model.scene):
            return None
        return self.strength_check().report()

    def strength_check(self) -> StrengthCheck:
        if self._strength is None:
            self._strength = StrengthCheck(self.model, self._expressions["cauchy_stress"])
        return self._strength

    def _nodal(self, name: str) -> fem.Function:
        """A recovered tensor at the P1 nodes (the mesh's vertices)."""
        if name not in self._p1:
            self._p1[name] = p1_tensor(self.recovered(name), name)
        return self._p1[name]

    def field(self, name: str) -> fem.Function:
        """The output field `name` (one of scene.spec.FIELD_NAMES) as a P1 Function for XDMF (cached)."""
        if name not in self._fields:
            self._fields[name] = self._make_field(name)
        return self._fields[name]

    def _make_field(self, name: str) -> fem.Function:
        if name == "displacement":
            return p1_interpolant(self.model.u, "displacement")
        if name in PROJECTED:
            return self._nodal(name)
        if name == "von_mises":
            return from_nodes(self._nodal("cauchy_stress"), measures.von_mises, (), name)
        if name == "principal_stresses":
            return from_nodes(self._nodal("cauchy_stress"), measures.principal_values, (3,), name)
        if name in measures.STRAINS_OF_F:
            return from_nodes(self._nodal("deformation_gradient"), measures.STRAINS_OF_F[name], (3, 3), name)
        if name == "utilization":
            return self.strength_check().field()
        if name == "material":
            regions = self.model.context.materials
            return regions.field(list(range(len(regions.materials))), "material")
        return term_field(self.model, name)    # a term's own (contact_pressure); the reader refuses unknown names


def term_field(model, name: str) -> fem.Function:
    """A field the terms compute (contact_pressure) at the mesh's vertices as a P1 Function: each term adds its
    share, zero where none has any."""
    f = fem.Function(fem.FunctionSpace(model.mesh, ("Lagrange", 1)), name=name)
    for term in model.terms:
        term.add_output_field(name, f)
    return f


def p1_tensor(f: fem.Function, name: str) -> fem.Function:
    """A tensor Function interpolated at the mesh's P1 nodes."""
    T1 = fem.TensorFunctionSpace(f.function_space.mesh, ("Lagrange", 1))
    g = fem.Function(T1, name=name)
    g.interpolate(f)
    return g


def from_nodes(tensor: fem.Function, measure, shape: tuple, name: str) -> fem.Function:
    """measure(tensor at each node) as a P1 Function of value shape `shape` (numpy, node by node)."""
    mesh = tensor.function_space.mesh
    element = ("Lagrange", 1)
    if shape == ():
        space = fem.FunctionSpace(mesh, element)
    elif len(shape) == 1:
        space = fem.VectorFunctionSpace(mesh, element, dim=shape[0])
    else:
        space = fem.TensorFunctionSpace(mesh, element, shape=shape)
    if not np.array_equal(space.dofmap.list.array, tensor.function_space.dofmap.list.array):
        raise RuntimeError(f"{name}: P1 spaces of one mesh numbered their nodes differently")
    g = fem.Function(space, name=name)
    g.x.array[:] = np.asarray(measure(tensor.x.array.reshape(-1, 3, 3))).ravel()
    return g


def output_fields(quantities: Quantities, names: list[str]) -> list[fem.Function]:
    """The requested fields in the order asked (names were validated against FIELD_NAMES)."""
    unknown = [n for n in names if n not in FIELD_NAMES]
    if unknown:
        raise KeyError(unknown[0])
    return [quantities.field(n) for n in names]
