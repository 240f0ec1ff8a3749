"""Before Newton: is there anything to solve, and can the supports hold the loads at all?

Both questions are answered from the residual at the rest state under full load, r0 = -f (the
stress-free rest state contributes nothing): f = 0 with no prescribed displacement means u = 0 is the
answer; a rigid motion m that the supports leave free (zero on every held dof) and on which the loads
do work (f . m != 0) means no static equilibrium exists (Newton would meet a singular tangent and
wander, then report "did not converge"). The six rigid modes are restricted to the held dofs and
their Gram matrix's null space gives the free motions.
"""
from __future__ import annotations

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
import numpy as np
from petsc4py import PETSc

from fem_forms.errors import InputError
from fem_forms.meshes import bounding_box

MODE_NAMES = ("translation x", "translation y", "translation z", "rotation about x", "rotation about y",
              "rotation about z")
FREE = 1e-12          # Gram eigenvalue of a mode (unit-scaled) that moves no held dof
WORK = 1e-8           # |f . m| / (|f| |m|) above which the loads push a free mode


def rest_residual(model) -> PETSc.Vec:
    """The residual at u = 0 (the unknown's space) under full load, no supports applied."""
    unknown = model.unknown
    saved, lam = unknown.x.array.copy(), model.load.value
    unknown.x.array[:] = 0.0
    model.load.set(1.0)
    try:
        b = fpetsc.assemble_vector(model.compiled("residual"))
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    finally:
        unknown.x.array[:] = saved
        model.load.set(lam)
    return b


def prescribes_motion(scene) -> bool:
    """Whether any support prescribes a non-zero displacement."""
    return any(fix.value[c] != 0.0 for fix in scene.fix for c in fix.components)


def nothing_to_solve(model, r0: PETSc.Vec) -> bool:
    """No loads (or loads that vanish) and no prescribed displacement: u = 0 is the answer."""
    if model.terms.arrays or model.global_scalars():   # an array term's forces and a scalar's equation (a
        return False                                     # prescribed cavity volume) are not in r0: let Newton look
    loaded = bool(model.scene.load) or model.context.thermal_strain is not None   # a temperature change loads
    return not prescribes_motion(model.scene) and (not loaded or r0.norm() == 0.0)


def _rigid_modes(model) -> list[PETSc.Vec]:
    """The six rigid modes on the unknown's space (rotations about the mesh centre, scaled by its
    half-diagonal so every mode moves nodes by about 1)."""
    lo, hi = bounding_box(model.mesh)
    centre, scale = (lo + hi) / 2, max(float(np.linalg.norm(hi - lo)) / 2, 1e-300)
    w = fem.Function(model.unknown.function_space)
    target = w if model.unknown is model.u else w.sub(0)          # mixed: the displacement part
    modes = []
    for k in range(6):
        def mode(x, k=k):
            v = np.zeros((3, x.shape[1]))
            if k < 3:
                v[k] = 1.0
            else:
                axis = np.eye(3)[k - 3]
                v[:] = np.cross(axis, (x.T - centre)).T / scale
            return v
        w.x.array[:] = 0.0
        target.interpolate(mode)
        w.x.scatter_forward()
        modes.append(w.vector.copy())
    return modes


def free_modes(model, r0: PETSc.Vec) -> tuple[list[str], list[str]]:
    """Names of the rigid motions the supports leave free, and of those among them the loads do work on."""
    modes = _rigid_modes(model)
    lam = model.load.value
    model.load.set(0.0)                     # prescribed values 0: set_bc below copies the mode's values
    held = []
    try:
        for m in modes:
            z = m.duplicate()
            z.set(0.0)
            fpetsc.set_bc(z, model.bcs, x0=m, scale=-1.0)    # z = m on held dofs, 0 elsewhere
            held.append(z)
    finally:
        model.load.set(lam)
    gram = np.array([[a.dot(b) for b in held] for a in held])
    for term in model.terms:                           # what the terms' supports hold (an obstacle's push)
        rows = term.holds(model, modes)
        if rows is not None:
            gram += rows.T @ rows
    values, vectors = np.linalg.eigh(gram)
    rnorm = r0.norm()
    free, pushed = [], []
    for val, q in zip(values, vectors.T):
        if val > FREE:
            continue
        name = MODE_NAMES[int(np.argmax(np.abs(q)))]
        free.append(name)
        f = modes[0].duplicate()
        f.set(0.0)
        for c, m in zip(q, modes):
            f.axpy(float(c), m)
        if rnorm > 0.0 and abs(r0.dot(f)) > WORK * rnorm * f.norm():
            pushed.append(name)
        f.destroy()
    for v in modes + held:
        v.destroy()
    return sorted(set(free), key=MODE_NAMES.index), sorted(set(pushed), key=MODE_NAMES.index)


def check_supports_hold_loads(model, r0: PETSc.Vec) -> None:
    """One-line InputError when the supports leave a rigid motion free: with the loads pushing it no
    equilibrium exists; without, the answer would be defined only up to that motion (a singular tangent)."""
    free, pushed = free_modes(model, r0)
    hint = "".join(f" ({t.support_hint})" for t in model.terms if t.support_hint)
    if free and not pushed:
        raise InputError(f"fix: the supports leave the body free ({', '.join(free)}); the loads do not push it "
                         "that way, but a static answer would then be defined only up to that motion; hold it "
                         "(another [[fix]] component, e.g. where = { point = [x, y, z] })" + hint)
    if pushed:
        other = ("[modal] prestress = false" if model.scene.analysis == "modal" else
                 "use analysis = \"dynamic\"" if hint else "use analysis = \"modal\"")
        raise InputError(f"fix: the supports leave the body free ({', '.join(pushed)}) and the loads push it "
                         "that way, so no static equilibrium exists; hold more components (another [[fix]], "
                         f"e.g. where = {{ point = [x, y, z] }}) or {other}" + hint)
