"""Progress of long runs, reported as events by the solvers and shown (or not) by a reporter.

The solvers call ``report(event, **fields)``; what is shown, where and how (one line updated in place on a
terminal, plain lines otherwise, nothing with --quiet or in the Python API by default) is the reporter's
business. Events: "load_step" (load, step), "newton" (load, iteration, residual), "step_accepted"
(load, iterations), "step_rejected" (load, why), "time_step" (time, dt, step, total_time, iterations: an
accepted time step), "step_refined" (time, dt, why: an accepted time step redone shorter for a contact event),
"march_done" (time, steps, rejected, failed: a time march ended or gave up), "solve_done"
(converged; a solve ended, so a terminal status line can be cleared before results are printed), "selected"
(key, facets: how many boundary facets a selector took).
The reporter shown to users is fem_forms.output.progress_line.ProgressLine.
"""
from __future__ import annotations

from typing import Callable

_reporter: Callable[..., None] | None = None


def set_reporter(reporter: Callable[..., None] | None) -> None:
    """Install the function that receives events (None: events are dropped)."""
    global _reporter
    _reporter = reporter


def reporter() -> Callable[..., None] | None:
    """The installed reporter (None: none)."""
    return _reporter


def report(event: str, **fields) -> None:
    """Pass an event to the installed reporter, if any (cheap when none is installed)."""
    if _reporter is not None:
        _reporter(event, **fields)
