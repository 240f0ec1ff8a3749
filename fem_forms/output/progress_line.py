"""Show the solvers' progress events (fem_forms.progress) to a person watching a long run.

On a terminal: one status line rewritten in place (carriage return, cleared when a solve ends, so the
summary printed afterwards starts on a clean line). Anywhere else (a log file, a pipe, CI): one plain
line per accepted or rejected step and none per Newton iteration, so logs stay short. The CLI installs
it on rank 0 unless --quiet; the Python API stays silent unless the user calls ``show_progress()``.
"""
from __future__ import annotations

import shutil
import sys
import time
from typing import TextIO

from mpi4py import MPI

from fem_forms import progress

CLEAR = "\r\x1b[K"          # back to column 0, erase to the end of the line
REDRAW_EVERY_S = 0.1        # a terminal line is redrawn at most this often for Newton iterations
PLAIN_EVERY_S = 0.5         # in a log, accepted time steps faster than this are counted into the next line


class ProgressLine:
    """A reporter for ``progress.set_reporter``: keeps the latest step, iteration and residual and shows
    them. `stream` None means sys.stderr at the time of writing (so pytest's capture sees it); `tty`
    None means ask the stream."""

    def __init__(self, stream: TextIO | None = None, tty: bool | None = None) -> None:
        self._stream = stream
        self._tty = tty
        self.t0 = time.perf_counter()
        self.state: dict = {}
        self._shown = False          # a terminal line is on screen
        self._last_draw = -1.0
        self._time0: tuple[float, float] | None = None   # (wall, simulated time) at the first time step
        self._last_line = -1.0       # when a plain line was last written
        self._quiet_steps = 0        # accepted time steps not written on a line of their own since then
        self._selected: dict = {}    # selector key -> the boundary facets it took
        self._unsaid: list = []      # the keys whose count is still to be written

    # -- the reporter ------------------------------------------------------------------------------
    def __call__(self, event: str, **fields) -> None:
        st = self.state
        if event == "load_step":        # numbered as the summary counts them: accepted steps + 1
            st.update(load=fields.get("load"), step=st.get("accepted", 0) + 1, iteration=None, residual=None)
        elif event == "newton":
            st.update(load=fields.get("load", st.get("load")), iteration=fields.get("iteration"),
                      residual=fields.get("residual"))
        elif event == "time_step":
            st.update(time=fields.get("time"), dt=fields.get("dt"), time_step=fields.get("step"),
                      total_time=fields.get("total_time"), iteration=None)     # the step's last residual kept
            if self._time0 is None:
                self._time0 = (time.perf_counter(), float(fields.get("time") or 0.0))
        elif event == "step_accepted":
            st["accepted"] = st.get("accepted", 0) + 1
        elif event == "march_done":
            self._march_done(fields)
            return
        elif event == "solve_done":     # the next solve (e.g. a forward check) counts from 1 again
            self.close()
            self._say_selected()
            self.state = {}
            return
        elif event == "selected":       # once per selector: how many facets it took, said once solving starts
            if fields.get("key") not in self._selected:
                self._selected[fields.get("key")] = fields.get("facets")
                self._unsaid.append(fields.get("key"))
            return
        self._say_selected()            # (bad input found before then stays one line)
        if self.tty:
            if event != "newton" or time.perf_counter() - self._last_draw >= REDRAW_EVERY_S:
                self._draw(self.status())
        elif event in ("step_accepted", "step_rejected") or (event == "time_step" and self._due()):
            verdict = "rejected ({})".format(fields.get("why") or "failed") if event == "step_rejected" else \
                "accepted" + (f" (and {self._quiet_steps} steps before it)" if self._quiet_steps else "")
            iters = fields.get("iterations")
            self._line(f"fem-forms: {self.status(newton=False)}: {verdict}"
                       + (f" after {iters} Newton iterations" if iters is not None else ""),
                       counted=event != "step_rejected")
        elif event == "time_step":
            self._quiet_steps += 1

    def _say_selected(self) -> None:
        """The facet counts not written yet, each on a line (once solving starts, or a solve ended)."""
        if self._unsaid:
            self.close()
            self._write("".join(f"fem-forms: {k}: {self._selected[k]} boundary facets\n" for k in self._unsaid))
            self._unsaid = []

    def _due(self) -> bool:
        """Whether an accepted time step gets a line of its own in a log (at most one per PLAIN_EVERY_S)."""
        return time.perf_counter() - self._last_line >= PLAIN_EVERY_S

    def _line(self, text: str, counted: bool = True) -> None:
        """A plain line; `counted`: it accounts for the accepted steps not written since the last such line."""
        self._write(text + "\n")
        self._last_line = time.perf_counter()
        self._quiet_steps = 0 if counted else self._quiet_steps

    def _march_done(self, fields: dict) -> None:
        """The last line of a time march: where it got, in how many steps, how long it took."""
        self.close()
        self._say_selected()
        if not self.tty:
            rejected = fields.get("rejected") or 0
            ended = "stopped at" if fields.get("failed") else "reached"
            self._line(f"fem-forms: {ended} t = {fields.get('time', 0.0):.6g} s in {fields.get('steps')} steps"
                       + (f" ({rejected} rejected)" if rejected else "") + f", {time.perf_counter() - self.t0:.1f} s")
        self.state, self._time0 = {}, None            # a next march starts its own ETA

    def close(self) -> None:
        """Erase the terminal line (if one is shown), so what is printed next starts clean."""
        if self._shown:
            self._write(CLEAR)
            self._shown = False

    # -- formatting --------------------------------------------------------------------------------
    @property
    def tty(self) -> bool:
        if self._tty is None:
            isatty = getattr(self.stream, "isatty", None)
            self._tty = bool(isatty and isatty())
        return self._tty

    @property
    def stream(self) -> TextIO:
        return self._stream if self._stream is not None else sys.stderr

    def status(self, newton: bool = True) -> str:
        """The current state in one line: time step and ETA, load step, Newton iteration, residual, elapsed."""
        st, now = self.state, time.perf_counter()
        parts = []
        if st.get("time") is not None:
            parts.append(f"t = {st['time']:.4g}" + (f" / {st['total_time']:.4g} s" if st.get("total_time") else " s")
                         + f" (step {st.get('time_step')}, dt {st.get('dt', 0.0):.3g})")
        if st.get("step") is not None:
            parts.append(f"load step {st['step']} (load {st.get('load', 0.0):.4g})")
        if newton and st.get("iteration") is not None:
            parts.append(f"Newton {st['iteration']}")
        if st.get("residual") is not None:
            parts.append(f"residual {st['residual']:.2e}")
        parts.append(f"{now - self.t0:.1f} s")
        eta = self.eta(now)
        if eta is not None:
            parts.append(f"ETA {eta:.0f} s")
        return ", ".join(parts)

    def eta(self, now: float) -> float | None:
        """Remaining wall time from the simulated-time rate seen since the first time step."""
        st = self.state
        if self._time0 is None or not st.get("total_time") or st.get("time") is None:
            return None
        wall0, sim0 = self._time0
        done = st["time"] - sim0
        if done <= 0:
            return None
        return max(0.0, (now - wall0) / done * (st["total_time"] - st["time"]))

    def _draw(self, line: str) -> None:
        width = shutil.get_terminal_size((80, 24)).columns - 1     # never wrap: \r returns one row only
        self._write(CLEAR + line[:width])
        self._shown = True
        self._last_draw = time.perf_counter()

    def _write(self, text: str) -> None:
        s = self.stream
        s.write(text)
        s.flush()


def show_progress(enabled: bool = True, stream: TextIO | None = None,
                  comm: MPI.Comm = MPI.COMM_WORLD) -> ProgressLine | None:
    """Show solver progress on `stream` (default stderr) on rank 0 of `comm`; enabled=False silences it
    again. The Python API is silent until this is called; the CLI calls it unless --quiet."""
    reporter = ProgressLine(stream) if enabled and comm.rank == 0 else None
    progress.set_reporter(reporter)
    return reporter


def clear_line() -> None:
    """Erase the installed reporter's terminal line, if any, before a line is printed out of turn (an
    interrupt announced from a signal handler)."""
    shown = progress.reporter()
    if isinstance(shown, ProgressLine):
        shown.close()
