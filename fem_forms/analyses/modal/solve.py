"""Modal analysis: natural frequencies and mode shapes from K phi = omega^2 M phi.

K is the tangent of the scene's energy (model.jacobian, i.e. ufl.derivative twice) either at rest
(u = 0, loads off: linearised elasticity) or, with `[modal] prestress = true`, at the static
equilibrium under the scene's loads, found by the static analysis. M is the consistent mass
rho u.v, or its diagonal (HRZ) lumping. Supported dofs map to infinite eigenvalues (K diagonal 1,
M diagonal 0). Parts without supports are solved about a small negative shift; their rigid-body
modes (omega^2 ~ 0) are counted and left out of the reported modes. `up_to` asks for every mode
below a frequency instead of a count (band.py: counted by inertia, then found).
"""
from __future__ import annotations

from dataclasses import dataclass
import math
import time

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms import progress
from fem_forms.analyses.static.solve import StaticResult, solve_static
from fem_forms.errors import InputError, SolveError
from fem_forms.meshes import bounding_box
from fem_forms.model import Model, build_model
from fem_forms.analyses.modal.band import Band, solve_band
from fem_forms.output import probes
from fem_forms.output.radiation import check_listener
from fem_forms.output.summary import header
from fem_forms.physics.inertia import Inertia
from fem_forms.physics.rigid_motion import free_modes
from fem_forms.scene import Scene
from fem_forms.solvers import eigen, linear

RIGID_EXTRA = 6          # modes requested beyond `count` when rigid-body modes may be present
SHIFT_FRACTION = 1e-2    # unsupported parts: target = -SHIFT_FRACTION x (estimated first omega^2)
RIGID_FRACTION = 1e-3    # |omega^2| < RIGID_FRACTION x |that target| counts as rigid-body motion
# "auto" keeps MUMPS far longer than a Newton step does: one factorisation serves ~50 solves, and
# it beat CG+GAMG 7-38x at every size to 141k dofs (benchmarks/modal_scaling.md)
DIRECT_UP_TO_DOFS = 500_000


@dataclass
class Operators:
    """Assembled stiffness and mass with the supports applied, and what the mode post-processing needs."""
    K: PETSc.Mat
    M: PETSc.Mat
    translations: list             # M r_d for unit translations r_x, r_y, r_z (full mass, no supports)
    total_mass: float
    omega2_scale: float            # rough estimate of the first elastic omega^2 (sets shift, threshold)

    def destroy(self) -> None:
        for obj in (self.K, self.M, *self.translations):
            obj.destroy()


@dataclass
class ModalResult:
    """What a modal solve found: the model, the elastic modes and the numbers results.json reports."""
    model: Model
    omega2: np.ndarray             # elastic eigenvalues [rad^2/s^2], ascending
    modes: list                    # one fem.Function per elastic mode, mass-normalised
    rigid_modes: int
    total_mass: float
    effective_mass_fraction: np.ndarray | None   # (modes, 3), only when the part is supported
    static: StaticResult | None
    target: float
    linear_solver: str
    converged: int
    iterations: int
    eigensolve_time_s: float = 0.0     # SLEPc setup + solve (factorisation included)
    wall_time_s: float = 0.0
    band: Band | None = None           # `up_to`: the inertia counts and what was found

    @property
    def frequencies_hz(self) -> np.ndarray:
        """f = omega / 2 pi; a negative omega^2 (unstable prestressed state) gives a negative f."""
        return np.sign(self.omega2) * np.sqrt(np.abs(self.omega2)) / (2 * math.pi)

    def summary(self) -> dict:
        scene, m = self.model.scene, self.model
        emf = self.effective_mass_fraction
        out = {
            **header("modal", scene, m.mesh.comm, m.dofs, self.wall_time_s),
            "element": f"P{scene.discretization.degree} {m.mesh.topology.cell_name()}",
            "quadrature_degree": scene.discretization.quadrature,
            "mass": scene.modal.mass,
            "prestress": scene.modal.prestress,
            "physics": m.physics + ["inertia"],
            "frequencies_hz": self.frequencies_hz.tolist(),
            "omega2": self.omega2.tolist(),
            "rigid_modes": self.rigid_modes,
            "unstable_modes": int(np.sum(self.omega2 < 0)),
            "total_mass": self.total_mass,
            "materials": m.materials_report(),
            "effective_mass_fraction": None if emf is None else emf.tolist(),
            "effective_mass_fraction_sum": None if emf is None else emf.sum(axis=0).tolist(),
            "eigensolver": {"type": "krylovschur", "st": "sinvert", "target": self.target,
                            "inner": "mumps" if self.linear_solver == "direct" else "cg+gamg",
                            "converged": self.converged, "iterations": self.iterations,
                            "time_s": self.eigensolve_time_s},
        }
        if self.band is not None:
            out["band"] = self.band.summary(self.rigid_modes)
            out["modes_below_limit"] = out["band"]["modes_below_limit"]
            out["eigensolver"].update(method=self.band.method, inner="mumps")
        if self.static is not None:
            s = self.static.summary()
            out["static"] = {k: s[k] for k in ("newton_iterations", "load_steps", "residual_norm",
                                                "max_displacement")}
        return out


def _owned_constrained(bcs: list) -> np.ndarray:
    """Owned, unrolled local indices of every supported dof."""
    idx = [bc.dof_indices()[0][: bc.dof_indices()[1]] for bc in bcs]
    return np.unique(np.concatenate(idx)) if idx else np.empty(0, dtype=np.int32)


def assemble_operators(model: Model, kind: str = "direct", lumped: bool = False,
                       mat_type: str | None = None) -> Operators:
    """K (tangent at model.u, supported rows/columns -> diagonal 1) and M (-> diagonal 0)."""
    mesh, V = model.mesh, model.V
    mat_type = mat_type or ("baij" if kind == "direct" else "aij")     # GAMG rejects BAIJ
    a = model.compiled("jacobian")
    K = fpetsc.create_matrix(a, mat_type)
    fpetsc.assemble_matrix(K, a, bcs=model.bcs, diagonal=1.0)
    K.assemble()

    inertia = Inertia()
    du, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    m = fem.form(inertia.mass(model.context, du, v))
    e = fem.Constant(mesh, PETSc.ScalarType((0.0, 0.0, 0.0)))
    L = fem.form(inertia.mass(model.context, e, v))
    translations = []
    for d in range(3):                                   # M r_d, exactly, as a linear form
        e.value = np.eye(3)[d]
        b = fpetsc.assemble_vector(L)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        translations.append(b)
    total_mass = translations[0].sum()                   # partition of unity: sum of M r_x = rho V

    constrained = _owned_constrained(model.bcs)
    M = fpetsc.create_matrix(m, mat_type)                # same sparsity as K: K - sigma M in place
    if not lumped:
        fpetsc.assemble_matrix(M, m, bcs=model.bcs, diagonal=0.0)
        M.assemble()
    else:
        # HRZ lumping: the consistent diagonal scaled to keep the total mass. It equals row-sum
        # lumping for P1 and, unlike row sums (negative at P2 tetrahedron vertices), stays positive.
        fpetsc.assemble_matrix(M, m)
        M.assemble()
        diag = M.getDiagonal()
        diag.scale(3.0 * total_mass / diag.sum())
        diag.array[constrained] = 0.0
        M.zeroEntries()
        M.setDiagonal(diag)
        diag.destroy()

    # omega^2 scale: Rayleigh quotient of a uniform shear field (any material, no bulk modulus),
    # times the squared slenderness of the bounding box (beam/plate bending goes as (t / L)^2).
    # With supports the field is cut to zero at the supported dofs, which overestimates: this only
    # sets the free-free shift and the rigid-mode threshold, far below the first elastic mode.
    lo, hi = bounding_box(mesh)
    c = 0.5 * (lo + hi)
    shear = fem.Function(V)
    shear.interpolate(lambda x: np.vstack([x[1] - c[1] + x[2] - c[2], x[0] - c[0] + x[2] - c[2],
                                           x[0] - c[0] + x[1] - c[1]]))
    r = shear.vector.copy()
    r.array[constrained] = 0.0
    Kr, Mr = r.duplicate(), r.duplicate()
    K.mult(r, Kr)
    M.mult(r, Mr)
    ext = hi - lo
    q = abs(r.dot(Kr)) / r.dot(Mr) * (ext.min() / ext.max()) ** 2
    for obj in (r, Kr, Mr):
        obj.destroy()
    return Operators(K, M, translations, total_mass, q)


def _strike_point_check(model: Model, scene: Scene) -> None:
    """The strike point must lie in the part, the listener (if any) in the air."""
    if scene.sound is None:
        return
    try:
        probes.evaluate(model.u, {"strike": scene.sound.point})
    except InputError:
        raise InputError(f"sound.strike.point = {scene.sound.point}: point lies outside the mesh") from None
    if scene.sound.listener is not None:
        check_listener(model.u, scene.sound.listener)


def _sign_reference(V: fem.FunctionSpace) -> fem.Function:
    """A fixed, generic field: each mode's sign is chosen to make its overlap with it positive, so
    runs on any number of ranks give the same signs (within repeated eigenvalues the basis of the
    eigenspace remains the solver's choice)."""
    w = fem.Function(V)
    w.interpolate(lambda x: np.vstack([np.sin(12.9898 * x[0] + 78.233 * x[1] + 37.719 * x[2] + k)
                                       for k in (0.3, 1.7, 2.9)]))
    return w


def _held_by_support_terms(model: Model) -> bool:
    """Whether the model has support terms (a spring, a foundation) and with the [[fix]] they leave no rigid
    motion free (a model without them is judged as before, at no cost)."""
    if not any(t.support_hint for t in model.terms):
        return False
    zero = model.unknown.vector.duplicate()
    zero.set(0.0)
    try:
        return not free_modes(model, zero)[0]
    finally:
        zero.destroy()


def _lowest(ops: Operators, scene: Scene, kind: str, symmetric: bool, nns, free_target: float,
            rigid_below: float):
    """`count`: the lowest elastic modes, about 0 for a supported part, else about free_target."""
    count = scene.modal.count
    # supported: target 0. If the supports leave rigid-body motion, K is singular: the solve then
    # fails or finds too few elastic modes, and is repeated as for an unsupported part.
    held = bool(scene.fix) or rigid_below == 0.0          # held by [[fix]], or with the terms' supports
    attempts = ([(0.0, count)] if held else []) + [(free_target, count + RIGID_EXTRA)]
    for i, (target, nev) in enumerate(attempts):
        last = i == len(attempts) - 1
        try:
            res = eigen.eigensolve(ops.K, ops.M, nev, target, kind, symmetric=symmetric,
                                   options=scene.solver.petsc, near_nullspace=nns)
        except (PETSc.Error, SolveError) as e:
            if last or isinstance(e, SolveError):     # retry only a failed factorisation
                raise SolveError(f"{scene.title}: modal solve failed: {e}") from None
            continue
        rigid = np.abs(res.values) < rigid_below
        elastic = np.flatnonzero(~rigid)[:count]
        if len(elastic) == count:
            return res, rigid, elastic, target
        for vec in res.vectors:
            vec.destroy()
        if last:
            raise SolveError(f"{scene.title}: only {len(elastic)} elastic modes among the {res.converged} "
                             f"converged ({int(rigid.sum())} rigid-body modes); ask for fewer modes")


def solve_modal(scene: Scene, material=None, model: Model | None = None) -> ModalResult:
    """The scene's `[modal] count` lowest elastic modes, or all below `up_to`. Raises InputError for
    bad input and SolveError when the prestress solve or the eigensolver fails."""
    t0 = time.perf_counter()
    spec = scene.modal
    model = model or build_model(scene, material)
    model.only_ufl_terms("modal analysis")
    _strike_point_check(model, scene)
    symmetric = model.conservative or not spec.prestress
    if spec.up_to is not None and not symmetric:
        raise InputError("modal.up_to: needs a symmetric stiffness, and follower loads under prestress "
                         "make it non-symmetric; use count")
    static = None
    if spec.prestress:
        static = solve_static(scene, material, model=model)
        if not static.report.converged:
            raise SolveError(f"{scene.title}: prestress (static) solve did not converge: "
                             f"{static.report.message}")
    else:
        model.load.set(0.0)                     # at rest: follower loads add no load stiffness
        model.u.x.array[:] = 0.0
    kind = "direct" if spec.up_to is not None else scene.solver.linear   # up_to counts with a factorisation
    if kind == "auto":
        kind = "direct" if model.dofs <= DIRECT_UP_TO_DOFS else "iterative"
    ops = assemble_operators(model, kind, lumped=spec.mass == "lumped")
    nns = linear.rigid_body_modes(model.V) if kind == "iterative" else None

    free_target = -SHIFT_FRACTION * ops.omega2_scale
    # a body the terms' supports (springs, foundations, however soft) hold with the [[fix]] has no rigid-body
    # mode: a mode far below the body's elastic scale (a stiff plate bouncing on a soft bed) is a mode there
    rigid_below = 0.0 if _held_by_support_terms(model) else RIGID_FRACTION * abs(free_target)
    band = None
    try:
        if spec.up_to is not None:
            try:
                res, band = solve_band(ops.K, ops.M, spec.up_to, free_target, scene.solver.petsc,
                                       scene.limits.modes)
            except (PETSc.Error, SolveError) as e:
                raise SolveError(f"{scene.title}: modal solve failed: {e}") from None
            rigid = np.abs(res.values) < rigid_below
            elastic, target = np.flatnonzero(~rigid), band.lower
        else:
            res, rigid, elastic, target = _lowest(ops, scene, kind, symmetric, nns, free_target, rigid_below)
    except BaseException:
        ops.destroy()
        raise

    w = _sign_reference(model.V)
    modes, gammas = [], []
    for k, i in enumerate(elastic):
        vec = res.vectors[i]
        if vec.dot(w.vector) < 0:
            vec.scale(-1.0)
        f = fem.Function(model.V, name=f"mode_{k + 1:02d}")
        vec.copy(f.vector)
        f.x.scatter_forward()
        modes.append(f)
        gammas.append([vec.dot(b) for b in ops.translations])   # participation phi^T M r_d
    for vec in res.vectors:
        vec.destroy()
    emf = np.asarray(gammas).reshape(-1, 3) ** 2 / ops.total_mass if scene.fix else None
    result = ModalResult(model, res.values[elastic], modes, int(rigid.sum()), ops.total_mass, emf,
                         static, target, kind, res.converged, res.iterations, res.solve_time, band=band)
    ops.destroy()
    result.wall_time_s = time.perf_counter() - t0
    progress.report("solve_done", converged=bool(res.converged))
    return result
