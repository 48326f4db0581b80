"""The case status both references write (compare/sdshared/sdresults.py): "converged" only when the
QP solver reported success and every KKT residual is within the tolerance; any damaged residual,
missing or NaN residual, or solver failure gives "not_converged: <reasons>".

Run: /usr/bin/python3 -m pytest references/tests/test_status.py -q
"""

import math

import pytest

from sdshared import sdresults

GOOD = {"equations": 2e-16, "primal": 0.0, "dual": 0.0, "complementarity": 1e-17}


def test_converged_when_every_residual_is_within_tolerance():
    assert sdresults.KKT_TOLERANCE == 1e-10  # the Rust solver's KKT_TOLERANCE (crates/sdcrack-core/src/study.rs)
    assert sdresults.case_status(GOOD) == "converged"
    assert sdresults.case_status(dict(GOOD, dual=1e-10)) == "converged"  # ≤, as the solver


@pytest.mark.parametrize("key", ["equations", "primal", "dual", "complementarity"])
def test_a_damaged_residual_is_not_converged(key):
    status = sdresults.case_status(dict(GOOD, **{key: 3e-4}))
    assert status == f"not_converged: {key} 3.0e-04 > 1e-10"
    assert sdresults.case_status(dict(GOOD, **{key: 1.0000001e-10})) != "converged"
    assert sdresults.case_status(dict(GOOD, **{key: math.nan})).startswith("not_converged")
    assert sdresults.case_status(dict(GOOD, **{key: math.inf})).startswith("not_converged")
    missing = {k: v for k, v in GOOD.items() if k != key}
    assert sdresults.case_status(missing) == f"not_converged: {key} missing"


def test_solver_failure_comes_first():
    status = sdresults.case_status(dict(GOOD, primal=1e-3), failure="active set did not converge in 100 solves")
    assert status == "not_converged: active set did not converge in 100 solves; primal 1.0e-03 > 1e-10"
    assert sdresults.case_status(GOOD, failure="cycled") == "not_converged: cycled"
    assert sdresults.case_status(dict(GOOD, dual=1e-8), tolerance=1e-6) == "converged"


def test_componentwise_backward_error_conventions():
    """As componentwise_backward_error in crates/sdcrack-core/src/linalg.rs."""
    cbe = sdresults.componentwise_backward_error
    assert cbe([0.0, 1e-16], [0.0, 1.0]) == 1e-16  # 0/0 counts as 0
    assert cbe([-2.0, 1.0], [4.0, 8.0]) == 0.5
    assert cbe([1e-300], [0.0]) == math.inf
    assert math.isnan(cbe([0.0, math.nan], [1.0, 1.0]))
    assert cbe([], []) == 0.0
