"""The continuation's predictor (solvers/continuation.py predicted_move) against exact paths: the quadratic through
three accepted states reproduces any quadratic path exactly at unequal spacing; with two states it is the secant."""
import numpy as np

from fem_forms.solvers.continuation import predicted_move


def path(lam: float) -> np.ndarray:
    """A quadratic load path u(lambda) with a different curvature per entry."""
    return np.array([1.0, -2.0, 0.5]) * lam + np.array([3.0, 0.7, -4.0]) * lam ** 2


def accepted(*lams: float) -> list:
    """(u_k - u_{k-1}, dlam) of the steps between successive load factors, as the continuation keeps them."""
    return [(path(b) - path(a), b - a) for a, b in zip(lams, lams[1:])]


def test_three_states_predict_a_quadratic_path_exactly():
    recent = accepted(0.1, 0.25, 0.3)[-2:]
    for t in (0.05, 0.075, 0.2):                           # shorter, grown 1.5x, much longer than the last step
        np.testing.assert_allclose(path(0.3) + predicted_move(t, recent), path(0.3 + t), rtol=1e-13, atol=1e-14)


def test_two_states_give_the_secant():
    recent = accepted(0.2, 0.3)
    t = 0.15
    secant = path(0.3) + t * (path(0.3) - path(0.2)) / 0.1
    np.testing.assert_allclose(path(0.3) + predicted_move(t, recent), secant, rtol=1e-13)
    # bit for bit the secant the continuation always took: contact keeps it, and a round-off change of its start
    # moved a frictional rocking toy's period by 2 %
    np.testing.assert_array_equal(predicted_move(t, recent), (t / recent[0][1]) * recent[0][0])
    assert np.abs(secant - path(0.45)).max() > 0.05           # the secant misses a curved path; the quadratic does not
