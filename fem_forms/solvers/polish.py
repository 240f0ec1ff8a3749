"""Finishing a Newton solve that the energy line search left near its answer: full Newton steps (no line search)
from where it stopped, kept only when they converge there and do not jump to another equilibrium.

Near the answer the energy's change falls below its round-off, so the energy line search sees no decrease: it takes
a tiny step while the residual is still above what round-off allows (CONVERGED_SNORM_RELATIVE; measured: 4.8e-5 left
where 1e-9 was reachable), or fails (DIVERGED_LINE_SEARCH; measured: 1e-9 from a staggered sub-solve's answer,
contact 2e-9, and the README's first scene at 3.9e-10 of its 4.2e-2 scale on an AVX-512 CPU, which then cut its load
step back: 35 Newton iterations for 17). Full Newton steps converge quadratically from there."""
from __future__ import annotations

import math

from petsc4py import PETSc

NEAR = 1e-6          # of the load scale: below it a failed line search is near an equilibrium (acceptance's bar)
FINISH_MOVE = 1e-6   # of max |u|: what finishing a solve may move u; more is a jump to another equilibrium
MAX_STEPS = 3
_FAILED = PETSc.SNES.ConvergedReason.DIVERGED_LINE_SEARCH
_SHORT_STEP = PETSc.SNES.ConvergedReason.CONVERGED_SNORM_RELATIVE


def near_equilibrium(driver, reason: int) -> bool:
    """The energy line search failed with the residual below NEAR of the load scale (no bounds); where no load scale
    is measured (a time step), below NEAR of the solve's first residual. Measured on the rocking hemisphere (Newmark,
    600 steps): 41 line searches failed at 1e-8..1e-6 of the first residual, each step then redone from its start."""
    if not driver.history:
        return False
    scale = driver.known_load_scale or driver.history[0]
    return driver.bounds is None and reason == _FAILED and driver.history[-1] < NEAR * scale


def stuck_at_equilibrium(driver, reason: int) -> bool:
    """near_equilibrium, accepted even unpolished in a `polish_stuck` or step-capping solve (elsewhere not: it sent
    2 ranks down another frictional path than 1)."""
    return (driver.polish_stuck or bool(driver.arrays.caps)) and near_equilibrium(driver, reason)


def _jumped(driver, reason: int, start: PETSc.Vec) -> bool:
    """A polish after a failed line search in a solve not flagged `polish_stuck` moved u by more than FINISH_MOVE of
    its size: it converged to another equilibrium (under continuation, past a limit load: measured 1.0e-5 over
    StVK's, when this polish was unguarded), not finished the solve it started from."""
    if reason != _FAILED or driver.polish_stuck or driver.arrays.caps:
        return False
    step = driver.x.copy()
    step.axpy(-1.0, start)
    moved, size = step.norm(PETSc.NormType.INFINITY), start.norm(PETSc.NormType.INFINITY)
    step.destroy()
    return moved > FINISH_MOVE * size


def polish(driver, reason: int) -> tuple[int, int, int]:
    """Up to MAX_STEPS full Newton steps after a line search stopped short or failed near an equilibrium, kept if SNES
    converged, the residual fell and u did not jump. Returns (reason, Newton iterations, Krylov iterations) added."""
    if driver.bounds is not None:       # a VI solve: setFromOptions resets its reduced KSP (PETSc error 60)
        return reason, 0, 0
    last = driver.history[-1] if driver.history else math.inf
    if not (near_equilibrium(driver, reason) or reason == _SHORT_STEP) \
            or last <= max(driver.base_atol(), driver.roundoff_floor(1.0)):
        return reason, 0, 0
    saved, history = driver.x.copy(), list(driver.history)
    max_it = driver.snes.getTolerances()[3]
    driver.set_line_search("basic")
    driver.snes.setTolerances(max_it=MAX_STEPS)
    driver.history = []
    if driver.pc_reuse is not None and not driver.keep_preconditioner:
        driver.pc_reuse.start_solve()
    with driver.factor_kept():                 # the step's kept LU factor, not a new one (snes.py)
        driver.snes.solve(None, driver.x)
    polished = driver.snes.getConvergedReason()
    its, kits = driver.snes.getIterationNumber(), driver.snes.getLinearSolveIterations()
    driver.set_line_search(driver.options["snes_linesearch_type"])
    driver.snes.setTolerances(max_it=max_it)
    if polished > 0 and driver.history and driver.history[-1] < last and not _jumped(driver, reason, saved):
        driver.history = history + driver.history[1:]
        saved.destroy()
        return polished, its, kits
    saved.copy(driver.x)                       # no better: keep the line search's answer
    driver.x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
    driver.history = history
    saved.destroy()
    return reason, its, kits
