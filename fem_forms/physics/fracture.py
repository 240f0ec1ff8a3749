"""Phase-field fracture ([fracture]): damage d in [0, 1], a P1 field beside the displacement, and the energy
    E(u, d) = int g(d) psi+(F) + psi-(F) dX + Gc / c_w int (w(d) / l + l |grad d|^2) dX
(Bourdin, Francfort & Marigo 2000), g(d) = (1 - k)(1 - d)^2 + k, AT1: w = d, c_w = 8/3 (an elastic phase until
the stress reaches sqrt(3 Gc E / (8 l))); AT2: w = d^2, c_w = 2. The split of psi into what damage degrades (psi+)
and what it does not (psi-, compression) is written on psi(F) itself, for any isotropic model:
volumetric-deviatoric (Amor, Marigo & Maurini 2009) takes the volumetric part as psi of the purely volumetric
deformation, psi(J^(1/3) I) (small strain: psi(I + tr(eps)/3 I)), undegraded in compression (J < 1); spectral
(Miehe, Welschinger & Hofacker 2010; isotropic linear materials) degrades the energy of the tensile principal
strains, lambda/2 <tr eps>+^2 + mu sum <eps_i>+^2 (physics/principal.py).

The solid's energy reads the damage through the Context (ctx.extra["damage"]), so the displacement problem is
the model's own forms with d a coefficient; the damage problem is this energy's derivative in d, solved with
the bound d_old <= d <= 1 (irreversibility: d_old the last accepted damage) by a VI Newton (solvers/bounds.py)."""
from __future__ import annotations

from dolfinx import fem
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.errors import InputError
from fem_forms.physics.principal import tensile_energy
from fem_forms.physics.term_integrals import Integrals
from fem_forms.physics.terms import Context, SubProblem, Term, register_terms

C_W = {"AT1": 8.0 / 3.0, "AT2": 2.0}
CRACKED = 0.95                 # cracked_volume: the volume where d is at least this


class PhaseField(Term):
    """The damage field, its constants (fem.Constants: new values compile nothing) and its energy pieces."""
    name = "phase-field fracture"
    role = "fracture"
    keys = ("fracture",)
    fields = ("damage",)
    energy_columns = ("fracture",)
    step_histories = ("crack",)

    def __init__(self, spec, mesh):
        self.spec = spec
        V = fem.FunctionSpace(mesh, ("Lagrange", 1))
        self.d = fem.Function(V, name="damage")
        self.notch = np.zeros(0, dtype=np.int32)        # local dofs held at d = 1 (set by the model)

        def const(v: float) -> fem.Constant:
            return fem.Constant(mesh, PETSc.ScalarType(v))
        self.Gc, self.ell, self.k = const(spec.toughness), const(spec.length), const(spec.residual_stiffness)
        self.model, self.split = spec.model, spec.split
        self.integral = Integrals(mesh.comm)
        self.stable_path: bool | None = None   # static runs: whether only stable states were accepted
        self.bifurcations: list = []           # where a saddle was left: load factor, eigenvalue, at (stable_path.py)

    def set_values(self, scene) -> None:
        fr = scene.fracture
        if fr is None or (fr.model, fr.split) != (self.model, self.split):
            raise InputError("fracture: a new model or split needs a new model (new constants do not)")
        self.Gc.value, self.ell.value, self.k.value = fr.toughness, fr.length, fr.residual_stiffness
        self.spec = fr

    def prepare(self, ctx: Context) -> None:
        ctx.extra["damage"] = self
        self.ctx = ctx
        self.notch = notch_dofs(ctx.loaded, self.d.function_space, self.spec.notch)
        self._warnings = [w for w in [resolution_warning(ctx.mesh, self.spec.length)] if w is not None]

    def warnings(self) -> list[str]:
        return self._warnings

    def state_fields(self) -> dict:
        return {"damage": self.d}

    def sub_problem(self, solid, ctx: Context) -> SubProblem:
        """The damage with u frozen: E(u, d) minimised over d_old <= d <= 1 (irreversibility)."""
        return SubProblem(self.d, self.damage_energy(solid, ctx), 1.0, True, self.spec.tolerance,
                          self.spec.max_iterations, self.spec.over_relaxation)

    def start(self, state) -> None:
        """Intact but for the notches (d = 1 there), committed: a new solve starts from the scene's cracks."""
        for f in (self.d, state.old["damage"]):
            f.x.array[:] = 0.0
            f.x.array[self.notch] = 1.0
            f.x.scatter_forward()
        self.surface0 = self._scalar("surface", self.crack_density())   # the notches' own surface energy

    def report(self, x) -> dict:
        checked = {} if self.stable_path is None else {"stable_path": self.stable_path}
        return {**self.record(), "crack_center": self.crack_center(), **checked,
                **({"bifurcations": self.bifurcations} if self.bifurcations else {})}

    def stored_energies(self, x) -> dict[str, float]:
        """The crack's surface energy beyond the notches' (what cracking dissipated)."""
        return {"fracture": self._scalar("surface", self.crack_density()) - self.surface0}

    def output_fields(self) -> list:
        return [self.d]

    # -- the energy ---------------------------------------------------------------------------------
    def degradation(self):
        """g(d) = (1 - k)(1 - d)^2 + k: 1 intact (the material's own stiffness), k cracked through."""
        return (1 - self.k) * (1 - self.d) ** 2 + self.k

    def degraded(self, psi, small_strain: bool, material=None):
        """psi(F) -> g(d) psi+(F) + psi-(F) by the scene's split (spectral: of the isotropic linear `material`,
        psi- = psi - psi+, so an intact part stores psi exactly)."""
        g = self.degradation()
        if self.split == "none":
            return lambda G: g * psi(G)
        if self.split == "spectral":
            if not small_strain or material is None:
                raise InputError("fracture.split = 'spectral': for model = 'linear' only (small strain)")

            def spectral(G):
                plus = tensile_energy(ufl.sym(G) - ufl.Identity(3), material.mu, material.lmbda)
                return psi(G) - (1 - g) * plus
            return spectral

        def split(G):
            I = ufl.Identity(3)
            if small_strain:
                theta = ufl.tr(ufl.sym(G) - I)
                volumetric, compressed = psi(I + theta / 3 * I), ufl.lt(theta, 0)
            else:
                J = ufl.det(G)
                volumetric, compressed = psi(J ** (1.0 / 3.0) * I), ufl.lt(J, 1)
            deviatoric = psi(G) - volumetric
            return g * deviatoric + ufl.conditional(compressed, volumetric, g * volumetric)
        return split

    def crack_density(self, d=None):
        """Gc / c_w (w(d) / l + l |grad d|^2): the surface energy per volume."""
        d = self.d if d is None else d
        w = d if self.model == "AT1" else d ** 2
        return self.Gc / C_W[self.model] * (w / self.ell + self.ell * ufl.inner(ufl.grad(d), ufl.grad(d)))

    def damage_energy(self, solid, ctx: Context) -> ufl.Form:
        """E(u, d) with u frozen: the solid's energy (degraded by d) plus the crack's surface energy."""
        return solid.energy(ctx) + ctx.volume(self.crack_density())

    # -- what a run reports -------------------------------------------------------------------------
    def _scalar(self, name: str, density) -> float:
        return self.integral(name, lambda: self.ctx.volume(density))

    def record(self) -> dict[str, float]:
        """The damage's largest value, the crack area (surface energy / Gc), its surface energy and the volume
        where d >= CRACKED; the same on every rank."""
        n = self.d.function_space.dofmap.index_map.size_local
        comm = self.d.function_space.mesh.comm
        surface = self._scalar("surface", self.crack_density())
        return {"damage_max": comm.allreduce(float(self.d.x.array[:n].max(initial=0.0)), op=MPI.MAX),
                "crack_area": surface / float(self.Gc.value), "surface_energy": surface,
                "cracked_volume": self._scalar("cracked", ufl.conditional(ufl.ge(self.d, CRACKED), 1.0, 0.0))}

    def crack_center(self) -> list | None:
        """The mean rest position of the nodes cracked through (d >= CRACKED), notches included; None where
        none is (the same on every rank)."""
        V = self.d.function_space
        n = V.dofmap.index_map.size_local
        cracked = self.d.x.array[:n] >= CRACKED
        x = V.tabulate_dof_coordinates()[:n][cracked]
        comm = V.mesh.comm
        count = comm.allreduce(int(cracked.sum()), op=MPI.SUM)
        total = comm.allreduce(x.sum(axis=0) if len(x) else np.zeros(3), op=MPI.SUM)
        return (total / count).tolist() if count else None


def notch_dofs(loaded, V: fem.FunctionSpace, selectors: list) -> np.ndarray:
    """The local P1 dofs of the [[fracture.notch]] selectors: mesh nodes inside a box, or the nodes of a
    volume or surface group's cells or facets (InputError naming a notch that holds no node)."""
    mesh = V.mesh
    x = V.tabulate_dof_coordinates()
    found = []
    for sel in selectors:
        if sel.kind == "box":
            lo, hi = np.asarray(sel.lo), np.asarray(sel.hi)
            tol = 1e-9 * max(1.0, float(np.abs(np.concatenate([lo, hi])).max()))
            dofs = np.flatnonzero(np.all((x >= lo - tol) & (x <= hi + tol), axis=1)).astype(np.int32)
        elif sel.group in loaded.cells:
            dofs = fem.locate_dofs_topological(V, mesh.topology.dim, loaded.cells[sel.group])
        elif sel.group in loaded.groups:                  # a surface group: its tag value names its facets
            facets = loaded.facet_tags.indices[loaded.facet_tags.values == loaded.groups[sel.group]]
            dofs = fem.locate_dofs_topological(V, mesh.topology.dim - 1, facets)
        else:
            raise InputError(f"{sel.key}.group = {sel.group!r}: no such volume or surface group (the mesh has: "
                             f"{loaded.group_names()})")
        n = V.dofmap.index_map.size_local
        if not mesh.comm.allreduce(int(np.count_nonzero(dofs < n)), op=MPI.SUM):
            raise InputError(f"{sel.key}: holds no mesh node (a notch's box must contain nodes; refine the mesh "
                             "or widen the box)")
        found.append(np.asarray(dofs, dtype=np.int32))
    return np.unique(np.concatenate(found)) if found else np.zeros(0, dtype=np.int32)


def resolution_warning(mesh, ell: float) -> str | None:
    """A warning when even the finest cells are too coarse for the regularization length (their shortest edge
    above l: the crack's profile, about 4 l wide, spans fewer than four of them), else None."""
    x = mesh.geometry.x
    n = mesh.topology.index_map(mesh.topology.dim).size_local
    corners = {"tetrahedron": 4, "hexahedron": 8, "prism": 6}.get(mesh.topology.cell_name(), 4)
    nodes = mesh.geometry.dofmap.array.reshape(-1, len(mesh.geometry.dofmap.links(0)))[:n, :corners]
    p = x[nodes]
    edges = np.linalg.norm(p[:, :, None, :] - p[:, None, :, :], axis=-1)
    edges[:, np.arange(corners), np.arange(corners)] = np.inf
    shortest = mesh.comm.allreduce(float(edges.min(initial=np.inf)), op=MPI.MIN)
    if shortest > ell:
        return (f"fracture.length = {ell:g}: the finest cells' shortest edge is {shortest:.3g}, longer than l: the "
                "crack's profile is not resolved (mesh about l/3 or finer along the crack's path)")
    return None


@register_terms("fracture")
def fracture_terms(scene, mesh) -> list[Term]:
    """The phase field of a scene with [fracture] (none without)."""
    fr = getattr(scene, "fracture", None)
    if fr is None:
        return []
    return [PhaseField(fr, mesh)]
