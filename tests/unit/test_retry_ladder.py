"""The one retry ladder of load continuation and implicit time steps (solvers/retry.py): which change comes
before the next attempt, each tried once per step size, and when the step is cut instead."""
from types import SimpleNamespace

from fem_forms.solvers.retry import RetryPolicy


class Driver:
    """What the ladder reads and changes of an SNES driver."""

    def __init__(self, linear_kind="direct", reuse_factor=False, stale=False, keep=False, persists=False):
        self.linear_kind, self.reuse_factor, self.stale = linear_kind, reuse_factor, stale
        self.keep_preconditioner = keep             # kept across solves (a time step's), else each solve's own
        self.user_options, self.bordered, self.rebuilds = {}, None, 0
        self.options = {"snes_lag_preconditioner_persists": True} if persists else {}   # a factor across steps

    def stale_preconditioner_failed(self):
        return self.stale

    def rebuild(self):
        self.rebuilds += 1


def failed(reason):
    return SimpleNamespace(accepted=False, reason=reason)


def test_cg_failing_on_a_fresh_preconditioner_switches_to_lu_and_retries_the_same_step():
    drv = Driver("iterative")
    switched = []
    policy = RetryPolicy(drv, "auto", on_direct=lambda: switched.append(True))
    report = SimpleNamespace(linear_solver="iterative")
    assert policy.same_size(failed("DIVERGED_LINEAR_SOLVE"), "SNES DIVERGED_LINEAR_SOLVE", 0.5, report)
    assert drv.linear_kind == "direct" and report.linear_solver == "iterative->direct" and switched == [True]
    # the scene asked for CG alone: no LU, the step is cut
    drv = Driver("iterative")
    assert not RetryPolicy(drv, "iterative").same_size(failed("DIVERGED_LINEAR_SOLVE"), "x", 0.5)
    assert drv.linear_kind == "iterative"


def test_a_preconditioner_kept_across_time_steps_that_failed_is_rebuilt_once_per_step():
    drv = Driver("iterative", stale=True, keep=True)
    policy = RetryPolicy(drv, "auto")
    rec = failed("DIVERGED_LINEAR_SOLVE")
    assert policy.same_size(rec, "x", 0.5)              # a fresh preconditioner, same step
    assert drv.linear_kind == "iterative"
    assert not policy.same_size(rec, "x", 0.5)          # stale again at the same size: cut
    assert policy.same_size(rec, "x", 0.25)             # the cut step may try it again
    # a load step's own kept preconditioner (renewed at every solve's start anyway): the step is cut
    assert not RetryPolicy(Driver("iterative", stale=True), "auto").same_size(rec, "x", 0.5)


def test_a_stalled_chord_becomes_newton_then_a_stale_factor_a_fresh_one():
    drv = Driver("direct", reuse_factor="chord")
    policy = RetryPolicy(drv, "direct")
    assert policy.same_size(failed("DIVERGED_MAX_IT"), "x", 0.5) and drv.reuse_factor is True
    assert not policy.same_size(failed("DIVERGED_MAX_IT"), "x", 0.5)     # Newton failed too: cut
    assert policy.same_size(failed("DIVERGED_LINEAR_SOLVE"), "x", 0.25) and drv.reuse_factor is False
    # a factor kept across time steps: one retry on the rebuild's fresh factor, the reuse itself kept
    drv = Driver("direct", reuse_factor=True, keep=True, persists=True)
    policy = RetryPolicy(drv, "direct")
    assert policy.same_size(failed("DIVERGED_LINEAR_SOLVE"), "x", 0.01) and drv.reuse_factor is True
    assert not policy.same_size(failed("DIVERGED_LINEAR_SOLVE"), "x", 0.01)


def test_a_time_steps_own_stale_factor_is_renewed_every_iteration_until_the_step_is_accepted():
    """A contact step factors once at its start (the factor is not kept across steps): the rebuild's factor would be
    the same one, so the retry factors at every Newton iteration, for this step (cut or not) until it is accepted."""
    drv = Driver("direct", reuse_factor=True, keep=True)
    policy = RetryPolicy(drv, "direct")
    assert policy.same_size(failed("DIVERGED_LINEAR_SOLVE"), "x", 0.01) and drv.reuse_factor is False
    assert not policy.same_size(failed("DIVERGED_LINEAR_SOLVE"), "x", 0.01)   # failed again: cut ...
    assert drv.reuse_factor is False                                          # ... still a factor per iteration
    rebuilds = drv.rebuilds
    policy.accepted()
    assert drv.reuse_factor is True and drv.rebuilds == rebuilds + 1          # one factor per step again
    policy.accepted()
    assert drv.rebuilds == rebuilds + 1                                       # nothing to undo: no rebuild


def test_the_other_line_search_serves_one_attempt_then_the_step_is_cut():
    drv = Driver("direct")
    drv.user_options["snes_linesearch_type"] = "bt"
    policy = RetryPolicy(drv, "direct", line_searches=("bt", "basic"))
    rec = failed("DIVERGED_LINE_SEARCH")
    assert policy.same_size(rec, "x", 0.01) and drv.user_options["snes_linesearch_type"] == "basic"
    assert not policy.same_size(rec, "x", 0.01)                          # cut, with the first line search
    assert drv.user_options["snes_linesearch_type"] == "bt"
    assert policy.same_size(rec, "x", 0.005)                            # the cut step may try it again
    rebuilds = drv.rebuilds
    policy.accepted()                                   # accepted with the other: back to the first, rebuilt
    assert drv.user_options["snes_linesearch_type"] == "bt" and drv.rebuilds == rebuilds + 1
    # a converged state rejected (not a saddle) is retried with the other line search too, where there is one
    converged = SimpleNamespace(accepted=True, reason="CONVERGED_FNORM_RELATIVE")
    assert policy.same_size(converged, "inverted elements", 0.02)
    assert not RetryPolicy(Driver(), "direct").same_size(converged, "inverted elements", 0.02)


def test_a_start_that_left_the_domain_is_replaced_by_the_last_state_once_per_step_size():
    starts = []
    policy = RetryPolicy(Driver(), "direct", plain_start=lambda: starts.append(True))
    nan_at_start = SimpleNamespace(accepted=False, reason="DIVERGED_FNORM_NAN", iterations=0)
    assert policy.same_size(nan_at_start, "SNES DIVERGED_FNORM_NAN", 0.01) and starts == [True]
    assert not policy.same_size(nan_at_start, "SNES DIVERGED_FNORM_NAN", 0.01)      # from there too: cut
    assert policy.same_size(nan_at_start, "SNES DIVERGED_FNORM_NAN", 0.005) and len(starts) == 2
    # a NaN met after some iterations is Newton's, not the start's: no plain start
    later = SimpleNamespace(accepted=False, reason="DIVERGED_FNORM_NAN", iterations=3)
    assert not RetryPolicy(Driver(), "direct", plain_start=lambda: starts.append(True)).same_size(later, "x", 0.01)
