"""The Python back-ends still give the values recorded in expr_cases.json (which the Rust test
tests/expr_crosscheck.rs checks against crates/sdcrack-core/src/expr.rs)."""

import json
import pathlib

import pytest

HERE = pathlib.Path(__file__).resolve().parent
from sdshared.sdexpr import evaluate, parse, to_numpy

CASES = json.loads((HERE / "expr_cases.json").read_text())


@pytest.mark.parametrize("case", CASES["values"], ids=lambda c: f"{c['expr'][:20]}@{c['x']:.3f},{c['y']}")
def test_values(case):
    want = case["value"]
    for got in (evaluate(parse(case["expr"]), case["x"], case["y"]), float(to_numpy(case["expr"])(case["x"], case["y"]))):
        if isinstance(want, str):
            assert repr(got) == want
        else:
            assert got == pytest.approx(want, rel=1e-13, abs=1e-13)
