"""Time marching ends a step at every corner of a load or temperature history (a cut-back must not step
over a peak) and makes no sliver steps where the corners already lie on the dt grid."""
from fem_forms.solvers.time_stepping import StepOutcome, history_corners, march


class Recorder:
    """A stepper that accepts every step except, once, the first one longer than `reject_above`."""

    def __init__(self, reject_above: float = float("inf")):
        self.ends, self.reject_above = [], reject_above

    def step(self, t: float, dt: float) -> StepOutcome:
        if dt > self.reject_above:
            self.reject_above = float("inf")
            return StepOutcome(False, 1, "forced cut-back")
        return StepOutcome(True, 1, "")

    def undo(self) -> None:
        pass


def _run(stepper, dt, t_end, stops):
    ends = []
    rep = march(stepper, 0.0, t_end, dt, lambda t, h, k: ends.append((t, h)), stops=stops)
    return ends, rep


def test_corners_are_step_ends_even_after_a_cut_back():
    corners = history_corners([[0.0, 0.0], [0.0105, 1.0], [0.03, 0.0]], None, [[0.0, 20.0], [0.017, 80.0]])
    assert corners == (0.0105, 0.017, 0.03)
    ends, rep = _run(Recorder(reject_above=0.0009), 1e-3, 0.04, corners)
    times = [t for t, _ in ends]
    for c in corners:
        assert min(abs(t - c) for t in times) < 1e-15
    assert rep.rejected == 1 and abs(times[-1] - 0.04) < 1e-15
    assert all(h <= 1e-3 * (1 + 1e-12) for _, h in ends)


def test_corners_on_the_grid_make_no_sliver_steps():
    ends, rep = _run(Recorder(), 1e-3, 0.5, history_corners([[0.0, 0.0], [0.01, 1.0], [0.5, 1.0]]))
    assert rep.steps == 500
    assert min(h for _, h in ends) > 0.999e-3


class Creeping:
    """Accepts a step only if it is shorter than the last accepted one: two cuts in a row each time, and
    dt creeps down without ever reaching max_cutbacks cuts in a row."""

    def __init__(self):
        self.last = float("inf")

    def step(self, t: float, dt: float) -> StepOutcome:
        if dt >= self.last * (1 - 1e-12):
            return StepOutcome(False, 1, "Newton diverged")
        self.last = dt
        return StepOutcome(True, 1, "")

    def undo(self) -> None:
        pass


def test_a_step_that_keeps_being_cut_gives_up():
    import pytest
    from fem_forms.errors import SolveError

    class Never(Creeping):
        def step(self, t, dt):
            return StepOutcome(False, 1, "Newton diverged")
    with pytest.raises(SolveError, match=r"time step cut 3 times in a row at t = 0 "):
        march(Never(), 0.0, 1.0, 0.1, lambda *a: None, max_cutbacks=3)
    with pytest.raises(SolveError, match=r"dt below its floor"):      # cuts never 4 in a row, dt creeps down
        march(Creeping(), 0.0, 1.0, 0.1, lambda *a: None, max_cutbacks=4)
