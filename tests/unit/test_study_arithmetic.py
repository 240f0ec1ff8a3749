"""The study's arithmetic: Richardson extrapolation and the Pareto front, on closed-form sequences."""
import numpy as np

from fem_forms.study import estimate_errors, key_size, pareto, richardson, Run


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


def _ladder(values, size):
    """Converged runs P1 and P2 on three levels with the given key numbers and part size."""
    return [Run(d, lv, {}, None, values=np.asarray(v, dtype=float), size=size, ok=True)
            for (d, lv), v in values.items()]


def test_errors_are_relative_to_the_finest_run_when_the_key_numbers_are_not_zero():
    runs = _ladder({(1, 0): [0.9], (1, 1): [0.99], (2, 0): [0.98], (2, 1): [0.998], (2, 2): [1.0]}, size=1.0)
    estimate_errors(runs, [1, 2])
    assert [r.error_kind for r in runs] == ["relative"] * 5
    np.testing.assert_allclose([r.error_finest for r in runs], [0.1, 0.01, 0.02, 0.002, 0.0], atol=1e-15)


def test_key_numbers_at_round_off_give_absolute_errors_not_a_ratio_of_noise():
    # a probe on a clamp of a 1 m part: displacements of 1e-17 m, differing run to run by round-off
    noise = {(1, 0): [3e-17], (1, 1): [-2e-17], (2, 0): [1e-17], (2, 1): [4e-17], (2, 2): [1e-17]}
    runs = _ladder(noise, size=1.0)
    estimate_errors(runs, [1, 2])
    assert {r.error_kind for r in runs} == {"absolute"}
    np.testing.assert_allclose([r.error_finest for r in runs], [2e-17, 3e-17, 0.0, 3e-17, 0.0], atol=1e-30)
    # relative, the same numbers would have read as errors of 200 % and 300 %
    assert max(r.error_finest for r in runs) < 1e-16


def test_key_size_is_the_largest_probe_point_displacement_or_frequency():
    assert key_size({"frequencies_hz": [10.0, 250.0]}) == 250.0
    s = {"max_displacement": 0.02, "probes": {"a": {"point": [0.3, 0.4, 0.0], "displacement": [0, 0, 1e-17]}}}
    assert key_size(s) == 0.5


def test_a_tolerance_on_absolute_errors_is_relative_to_the_part_size():
    from fem_forms.study import cheapest_meeting
    runs = [Run(1, 0, {}, None, wall=1.0, error_finest=5e-3, size=1.0, error_kind="absolute", ok=True),
            Run(2, 0, {}, None, wall=2.0, error_finest=1e-5, size=1.0, error_kind="absolute", ok=True)]
    assert cheapest_meeting(runs, 1e-3).wall == 2.0           # 5 mm on a 1 m part misses 1e-3; 10 um meets it


def test_runs_with_different_numbers_of_modes_compare_the_modes_all_have():
    # `up_to`: a coarse mesh's stiffer modes may leave one of them above the limit
    runs = _ladder({(1, 0): [110.0], (1, 1): [101.0, 300.0], (2, 0): [102.0, 290.0], (2, 1): [100.2, 280.0],
                    (2, 2): [100.0, 279.0, 400.0]}, size=400.0)
    estimate_errors(runs, [1, 2])
    np.testing.assert_allclose([r.error_finest for r in runs], [0.1, 0.01, 0.02, 0.002, 0.0], atol=1e-15)
