"""output/interrupts.py on one rank: a signal raises at once, except inside a critical section (the writing of
a step's files), where it waits for the section's end; a second signal does not wait; SIGTERM becomes
Terminated (exit 143); the handlers are put back afterwards. Signals are sent to this very process."""
import os
import signal
import time

from mpi4py import MPI
import pytest

from fem_forms.output.interrupts import Interrupts, Terminated


def send(signum: int) -> None:
    """Signal this process and give Python the bytecodes to run the handler."""
    os.kill(os.getpid(), signum)
    for _ in range(100):
        time.sleep(0.001)


def test_a_signal_raises_at_once_outside_critical_sections():
    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(Terminated) as info:
        with Interrupts(MPI.COMM_SELF, lambda: None):
            send(signal.SIGTERM)
            pytest.fail("the signal did not raise")
    assert info.value.exit_status == 143
    assert signal.getsignal(signal.SIGTERM) is before


def test_a_signal_in_a_critical_section_waits_for_its_end():
    finished = []
    with Interrupts(MPI.COMM_SELF, lambda: None) as interrupts:
        with pytest.raises(KeyboardInterrupt):
            with interrupts.critical():
                send(signal.SIGINT)
                finished.append("the section")          # reached: the signal waited
        assert finished == ["the section"]
        with pytest.raises(KeyboardInterrupt):
            interrupts.check()                           # and it stays recorded


def test_a_second_signal_does_not_wait():
    with Interrupts(MPI.COMM_SELF, lambda: None) as interrupts:
        with pytest.raises(KeyboardInterrupt):
            with interrupts.critical():
                send(signal.SIGINT)
                send(signal.SIGINT)
                pytest.fail("the second signal did not raise")


def test_no_signal_no_exception():
    with Interrupts(MPI.COMM_SELF, lambda: None) as interrupts:
        with interrupts.critical():
            pass
        interrupts.check()
