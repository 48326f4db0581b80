"""tools/bench_unstructured.py's verdict: the issue's bound of 1.5 × holds for every measured level,
and a ratio above it, a missing ratio or no measurement at all fails."""

import ci_script

bench = ci_script.load("tools/bench_unstructured.py")


def test_the_bound_is_the_issues():
    assert bench.BOUND == 1.5


def test_ratios_within_the_bound_pass():
    assert bench.within_bound([{"ratio": 1.09}, {"ratio": 1.0}])
    assert bench.within_bound([{"ratio": 1.5}])


def test_a_level_over_the_bound_fails():
    assert not bench.within_bound([{"ratio": 1.09}, {"ratio": 1.51}])


def test_nothing_measured_fails():
    assert not bench.within_bound([])
    assert not bench.within_bound([{"ratio": None}])
    assert not bench.within_bound([{"ratio": float("nan")}])
