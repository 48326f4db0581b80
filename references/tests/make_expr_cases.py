"""Writes expr_cases.json: values of the Python translator (compare/sdshared/sdexpr.py) at
random points, crack faces (y = +0.0 / -0.0) included (non-finite values as the strings
'inf', '-inf', 'nan'), and its parse errors. The Rust test
tests/expr_crosscheck.rs evaluates the same strings with crates/sdcrack-core/src/expr.rs and must agree, and
test_expr_cases.py checks that the Python back-ends still give these values. Regenerate with
`.venv/bin/python references/tests/make_expr_cases.py` after changing the grammar
(the checkout's Python, which ci/setup gives the package sdshared)."""

import json
import math
import pathlib
import random

HERE = pathlib.Path(__file__).resolve().parent
from sdshared.sdexpr import ExprError, evaluate, parse

EXPRESSIONS = [
    "20*sin(2*pi*x)*sign(y)",
    "2*pi^2*sin(pi*x)*cos(pi*y)",
    "sin(pi*x)*cos(pi*y) - y",
    "sqrt(sqrt(((x-0.5)^2+y^2)*((x+0.5)^2+y^2)))*sin((atan2(y,x-0.5)+atan2(y,x+0.5))/2)",
    "2*sqrt(0.25 - x^2)",
    "exp(-x^2)*log(2 + y) - tan(x*y)/3",
    "abs(x - 0.25)*sign(y) + min(x, y)^2 - max(x, -y)",
    "-x^2 + 2^-y + 2^3^0.5",
    "atan2(y, -1) + atan2(-y, x)",
    "x/y",
]
BAD = ["", "sinn(x)", "z", "atan2(x)", "(x+1", "x+1)", "x y", "x+", "1e999", "2 $ x"]


def main():
    rng = random.Random(20261123)
    points = [(rng.uniform(-1, 1), rng.uniform(-1, 1)) for _ in range(20)]
    points += [(rng.uniform(-0.5, 0.5), s) for s in (0.0, -0.0) for _ in range(5)]
    values = []
    for src in EXPRESSIONS:
        tree = parse(src)
        for x, y in points:
            v = evaluate(tree, x, y)
            values.append({"expr": src, "x": x, "y": y, "value": v if math.isfinite(v) else repr(v)})
    errors = []
    for src in BAD:
        try:
            parse(src)
        except ExprError as e:
            errors.append({"expr": src, "column": e.column, "message": str(e.message)})
    out = HERE / "expr_cases.json"
    out.write_text(json.dumps({"values": values, "errors": errors}, indent=1) + "\n")
    print(f"wrote {len(values)} values and {len(errors)} errors to {out}")


if __name__ == "__main__":
    main()
