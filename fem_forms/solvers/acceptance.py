"""When a step SNES solved is accepted: one check for the static continuation, the implicit dynamic step and
the heat step. SNES can report convergence on a wrong state ("converged in 0 iterations" after a diverged solve was seen with dolfinx 0.5.2), so a step is
accepted only when SNES converged AND its state is finite on every rank AND admissible (no inverted cells)
AND its residual is small against a scale of its own or at round-off. The thresholds live here."""
from __future__ import annotations

from mpi4py import MPI
import numpy as np

from fem_forms.solvers.reports import StepRecord
from fem_forms.solvers.snes import SNESDriver

# Statics and dynamics: the residual at the accepted state must be below this fraction of the step's scale.
# 1000x above SNES's own snes_rtol (1e-9), so a step SNES really converged always passes, while a stop on
# step length (snes_stol) far from equilibrium, or a "converged in 0 iterations" on a stale solver, fails.
ACCEPTED = 1e-6
# Linear heat steps (`ksponly`: one LU or Krylov solve, no Newton iteration to go on with): the residual
# after the solve must have fallen by this much from the one before it. Looser than ACCEPTED because the
# iterative path stops at 1e-8 of the *preconditioned* residual, which bounds the true residual's drop only
# up to the preconditioner's conditioning. A rejection halves dt in a transient march and ends a steady
# solve; ACCEPTED here was never measured, so the value stays the one the thermal tests were written with.
LINEAR_DROP = 1e-5
# A residual below this many times the round-off estimate (machine eps x |K|_inf x |u|_inf x sqrt(n),
# SNESDriver.roundoff_floor) passes whatever its relative size: stiff, nearly incompressible materials put
# that floor near 1e-6 of the load's residual, where no Newton step can go lower (measured on the
# nearly incompressible block of tests/system/test_incompressible.py).
ROUNDOFF_SAFETY = 1e3


def step_scale(record: StepRecord, load_scale: float = 0.0) -> float:
    """The residual a step's relative test is measured against: the larger of `load_scale` (statics: the
    residual of the unloaded state under the full load, so that a small load step is not asked for 1e-6 of
    its own small residual) and the step's first residual (dynamics and heat have no load scale: 0)."""
    r0 = record.residuals[0] if record.residuals else 0.0
    return max(load_scale, r0)


def why_rejected(driver: SNESDriver, record: StepRecord, rtol: float | None = ACCEPTED,
                 load_scale: float = 0.0, reassemble: bool = True, stable_only: bool = False) -> str | None:
    """Why the step `driver` just solved (its `record`) must be rejected, or None to accept it. In order:
    SNES's reason; NaN or Inf in the unknown on any rank; the problem's `inadmissible()`; with `stable_only`
    (statics), a saddle of a volume-controlled problem (constrained_stability.py: the last tangent's inertia);
    a residual above `rtol` x step_scale(record, load_scale) and above the round-off floor (no residual test
    when rtol is None). The residual is re-assembled at the state, independently of SNES, or with `reassemble`
    False taken as SNES's last one (the same number where the state is SNES's last iterate, one assembly less);
    its value is left in record.checked_residual."""
    if not record.accepted:
        return f"SNES {record.reason}"
    if not finite_everywhere(driver.p.u.x.array, driver.comm):
        return NOT_FINITE
    if driver.p.inadmissible is not None and (bad := driver.p.inadmissible()):
        return bad
    if stable_only and (stability := stability_check(driver)) is not None and (bad := stability.instability()):
        return bad
    if rtol is None:
        return None
    if reassemble or not record.residuals:
        rn = driver.residual_norm()
    else:
        rn = record.residuals[-1]
    record.checked_residual = rn
    scale = step_scale(record, load_scale)
    if rn > rtol * scale and rn > driver.roundoff_floor(ROUNDOFF_SAFETY):
        return f"residual {rn:.3e} left, above {rtol:g} of its scale {scale:.3e}"
    return None


NOT_FINITE = "NaN or Inf in the solution"


def stability_check(driver: SNESDriver):
    """The volume-controlled problem's stability check (solvers/constrained_stability.py), or None."""
    return driver.bordered.stability if driver.bordered is not None else None


def left_the_domain(record: StepRecord, why: str | None) -> bool:
    """Whether a rejected step failed because an iterate left the solid's domain (a NaN residual or state:
    an element turned inside out) rather than for slow convergence or a plastic collapse."""
    return "NAN" in record.reason.upper() or why == NOT_FINITE or "inverted" in (why or "")


def finite_everywhere(values: np.ndarray, comm: MPI.Comm) -> bool:
    """Whether an array holds no NaN or Inf on any rank (the same answer on all ranks)."""
    return comm.allreduce(bool(np.all(np.isfinite(values))), op=MPI.LAND)

