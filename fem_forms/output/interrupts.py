"""Stopping a run on Ctrl-C (SIGINT) or SIGTERM without losing what it has found, and without a deadlock
under MPI.

The CLI turns both signals into exceptions (KeyboardInterrupt, `Terminated`; exit 130 / 143). Raised at
once, they are safe in one process: the outputs of the last accepted step are already on disk and
results.json is written from what rank 0 holds. Under MPI they are not: mpirun sends SIGTERM to every
rank, each rank's handler runs at its own next Python bytecode, and a rank that leaves the computation
between two collective calls leaves the others blocked in the next one for ever (no handler runs inside
a blocking C call). Worse, mpirun follows its SIGTERM with SIGKILL after about a second (Open MPI's
`odls_base_sigkill_timeout`, 1 s by default; measured here: SIGCONT at once, SIGTERM 1 s later, SIGKILL
1 s after that). So `Interrupts`, around a static run:
- one rank (serial): a signal raises at once, except inside a `critical()` section (the per-step writing
  of files), where it waits for the section's end;
- several ranks: a signal is only recorded, and rank 0 at once writes the interrupted results.json of
  the last accepted step (non-collective: nothing can block it) and prints the one line; every rank
  raises together at the next `check()` (a collective agreement after each accepted step), so collective
  writing never meets a rank that has left. If SIGKILL comes first, results.json is already there.
A second signal raises at once (the user insists).
"""
from __future__ import annotations

from contextlib import contextmanager
import signal
import sys
from typing import Callable

from mpi4py import MPI

from fem_forms.output.progress_line import clear_line


class Terminated(KeyboardInterrupt):
    """SIGTERM (e.g. from mpirun, a batch system or `kill`), handled like Ctrl-C with its own status."""
    exit_status = 143


def interrupt(signum: int) -> KeyboardInterrupt:
    """The exception a signal becomes: Terminated for SIGTERM, KeyboardInterrupt for the rest."""
    return Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()


class Interrupts:
    """Signal handling of a run that keeps its last accepted state on disk (see the module docstring).
    `save()` writes the interrupted results.json from rank 0's data, without any collective call."""

    def __init__(self, comm: MPI.Comm, save: Callable[[], None]):
        self.comm, self.save = comm, save
        self.signum = 0              # the first signal received (0: none)
        self.announced = False       # rank 0 printed "fem-forms: interrupted" already
        self._critical = 0
        self._previous: dict = {}

    def __enter__(self) -> "Interrupts":
        try:
            for signum in (signal.SIGINT, signal.SIGTERM):
                self._previous[signum] = signal.signal(signum, self._handle)
        except ValueError:           # not the main thread: signals stay as they were
            pass
        return self

    def __exit__(self, *exc) -> None:
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)
        self._previous = {}

    def _handle(self, signum, frame) -> None:
        first = self.signum == 0
        if first:
            self.signum = signum
        if not first or (self.comm.size == 1 and not self._critical):
            raise interrupt(self.signum)
        if self.comm.size > 1 and self.comm.rank == 0:
            try:
                self.save()
            except Exception:        # noqa: BLE001 (raised here it would strand the other ranks; the run
                pass                 # writes it again when every rank stops at the next check)
            clear_line()
            print("fem-forms: interrupted", file=sys.stderr, flush=True)
            self.announced = True

    @contextmanager
    def critical(self):
        """A section no signal cuts short (writing a step's files); a signal received in it is acted on at
        its end (one rank) or at the next check (several ranks)."""
        self._critical += 1
        try:
            yield
        finally:
            self._critical -= 1
        if self.comm.size == 1 and self.signum and not self._critical:
            raise interrupt(self.signum)

    def check(self) -> None:
        """Collective on several ranks: if any rank received a signal, every rank raises it here."""
        signum = self.signum if self.comm.size == 1 else self.comm.allreduce(self.signum, op=MPI.MAX)
        if signum:
            e = interrupt(signum)
            e.announced = self.announced
            raise e
