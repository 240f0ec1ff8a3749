"""The study's arithmetic: Richardson extrapolation and the Pareto front, on closed-form sequences."""
import numpy as np

from fem_forms.study import pareto, richardson, Run


def test_richardson_recovers_the_limit_of_a_second_order_sequence():
    limit = np.array([1.0, -2.0])
    seq = [limit + np.array([0.3, 0.1]) * h**2 for h in (1.0, 0.5, 0.25)]
    np.testing.assert_allclose(richardson(seq), limit, rtol=1e-12)
    assert richardson(seq[:2]) is None
    assert richardson([seq[0], seq[0] + 1, seq[0] + 3]) is None     # diverging: no estimate


def test_pareto_front_keeps_only_undominated_runs():
    runs = [Run(1, 0, {}, None, wall=1.0, error_finest=0.5, ok=True),
            Run(1, 1, {}, None, wall=2.0, error_finest=0.6, ok=True),     # slower and worse
            Run(2, 0, {}, None, wall=3.0, error_finest=0.01, ok=True)]
    assert [r.wall for r in pareto(runs)] == [1.0, 3.0]
