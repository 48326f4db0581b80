"""tools/bench_norms.py's goal: the norms cost ≤ 0.25 × the solve phases at every measured level;
one level over it, a missing ratio or nothing measured fails."""

import ci_script

bench = ci_script.load("tools/bench_norms.py")


def test_the_bound_is_the_issues():
    assert bench.BOUND == 0.25


def test_every_level_within_the_bound_is_met():
    assert bench.ratio_goal([{"ratio": 0.1}, {"ratio": 0.25}]) == (True, 0.25)


def test_one_level_over_the_bound_is_missed():
    met, worst = bench.ratio_goal([{"ratio": 0.1}, {"ratio": 0.26}])
    assert not met and worst == 0.26
    assert "MISSED (worst 0.260)" in bench.goal_line([{"ratio": 0.1}, {"ratio": 0.26}])


def test_nothing_measured_is_missed():
    assert not bench.ratio_goal([])[0]
    assert not bench.ratio_goal([{"ratio": 0.1}, {"ratio": None}])[0]
    assert not bench.ratio_goal([{"ratio": float("nan")}])[0]


def test_one_case_keeps_one_level_and_drops_fields_and_references():
    text = 'levels = [0, 1, 2]\np_mass = ["consistent", "lumped"]\nfields = ["u"]\nreferences = ["dolfinx"]\n'
    assert bench.one_case(text, 3) == ('levels = [3]\np_mass = ["consistent"]\nfields = []\n'
                                       'references = []\n')
