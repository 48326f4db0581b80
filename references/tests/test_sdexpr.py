"""Tests of compare/sdshared/sdexpr.py (run: /usr/bin/python3 -m pytest references/tests)."""

import math

import pytest

from sdshared import sdexpr
from sdshared.sdexpr import ExprError, evaluate, parse, to_freefem, to_numpy

np = pytest.importorskip("numpy")


def ev(src, x=0.3, y=-0.7):
    return evaluate(parse(src), x, y)


@pytest.mark.parametrize("src,value", [
    ("-2^2", -4.0),
    ("2^3^2", 512.0),
    ("(2^3)^2", 64.0),
    ("2^-1", 0.5),
    ("-x^2", -0.09),
    ("--x", 0.3),
    ("+-+x", -0.3),
    ("1-2-3", -4.0),
    ("8/4/2", 1.0),
    ("2*3^2", 18.0),
    ("1+2*3", 7.0),
    ("(1+2)*3", 9.0),
    ("6/2*3", 9.0),
    ("2^2*3", 12.0),
    ("-2*-3", 6.0),
    (".5", 0.5),
    ("1e-3", 1e-3),
    ("2.5E+1", 25.0),
    ("pi", math.pi),
    ("log(exp(2))", 2.0),
    ("max(1, -x)", 1.0),
    ("min(x, y)", -0.7),
    ("atan2(1, 0)", math.pi / 2),
])
def test_precedence_and_values(src, value):
    assert ev(src) == pytest.approx(value, rel=1e-15, abs=1e-15)
    assert to_numpy(src)(0.3, -0.7) == pytest.approx(value, rel=1e-15, abs=1e-15)


def test_tree_shapes():
    assert parse("-x^2") == ("neg", ("^", ("x",), ("num", 2.0)))
    assert parse("2^3^2") == ("^", ("num", 2.0), ("^", ("num", 3.0), ("num", 2.0)))
    assert parse("1-2-3") == ("-", ("-", ("num", 1.0), ("num", 2.0)), ("num", 3.0))


CASES = [
    ("x", lambda x, y: x),
    ("x*y + 1", lambda x, y: x * y + 1),
    ("sin(pi*x)*cos(pi*y) - y", lambda x, y: np.sin(np.pi * x) * np.cos(np.pi * y) - y),
    ("2*pi^2*sin(pi*x)*cos(pi*y)", lambda x, y: 2 * np.pi ** 2 * np.sin(np.pi * x) * np.cos(np.pi * y)),
    ("20*sin(2*pi*x)*sign(y)", lambda x, y: 20 * np.sin(2 * np.pi * x) * np.copysign(1.0, y)),
    ("exp(-(x^2+y^2)/0.1)", lambda x, y: np.exp(-(x ** 2 + y ** 2) / 0.1)),
    ("sqrt(abs(x))*log(1+y^2)", lambda x, y: np.sqrt(np.abs(x)) * np.log(1 + y ** 2)),
    ("tan(x/3) - atan2(y, x)", lambda x, y: np.tan(x / 3) - np.arctan2(y, x)),
    ("min(x, y) + max(x, 0.25)", lambda x, y: np.minimum(x, y) + np.maximum(x, 0.25)),
    ("-x^2 - y^2/2", lambda x, y: -(x ** 2) - y ** 2 / 2),
    ("sqrt(sqrt(((x-0.5)^2+y^2)*((x+0.5)^2+y^2)))*sin((atan2(y,x-0.5)+atan2(y,x+0.5))/2)",
     lambda x, y: np.sqrt(np.sqrt(((x - .5) ** 2 + y ** 2) * ((x + .5) ** 2 + y ** 2)))
     * np.sin((np.arctan2(y, x - .5) + np.arctan2(y, x + .5)) / 2)),
]


@pytest.mark.parametrize("src,ref", CASES)
def test_numpy_backend_matches_closures(src, ref):
    rng = np.random.default_rng(1)
    x = rng.uniform(-1, 1, 200)
    y = rng.uniform(-1, 1, 200)
    f = to_numpy(src)
    np.testing.assert_allclose(f(x, y), ref(x, y), rtol=1e-13, atol=1e-13)
    # scalar math evaluator agrees too
    for k in range(0, 200, 37):
        assert evaluate(parse(src), x[k], y[k]) == pytest.approx(float(ref(x[k], y[k])), rel=1e-13, abs=1e-13)


def test_constant_broadcasts():
    f = to_numpy("2")
    assert f(np.zeros(5), np.zeros(5)).shape == (5,)


def test_signed_zero_selects_face():
    f = to_numpy("sign(y)")
    np.testing.assert_array_equal(f(np.zeros(4), np.array([0.0, -0.0, 2.0, -3.0])), [1, -1, 1, -1])
    assert ev("sign(y)", y=-0.0) == -1.0 and ev("sign(y)", y=0.0) == 1.0
    assert math.isnan(ev("sign(x)", x=math.nan))
    # open-crack exact solution: + face is positive, - face negative, jump = 2 sqrt(1/4 - x^2)
    u = to_numpy("sqrt(sqrt(((x-0.5)^2+y^2)*((x+0.5)^2+y^2)))*sin((atan2(y,x-0.5)+atan2(y,x+0.5))/2)")
    xs = np.array([-0.25, 0.0, 0.3])
    jump = u(xs, np.full(3, 0.0)) - u(xs, np.full(3, -0.0))
    np.testing.assert_allclose(jump, 2 * np.sqrt(0.25 - xs ** 2), rtol=1e-14)
    # outside the crack both sides agree
    np.testing.assert_allclose(u(np.array([0.75]), np.array([0.0])), u(np.array([0.75]), np.array([-0.0])), atol=1e-15)


# Values computed by hand from the formulas with Python's math module (independent of sdexpr),
# to be cross-checked against the Rust evaluator by the project lead.
HARD = [
    ("20*sin(2*pi*x)*sign(y)", 0.3, -0.0, -20 * math.sin(2 * math.pi * 0.3)),
    ("20*sin(2*pi*x)*sign(y)", 0.3, 0.0, 20 * math.sin(2 * math.pi * 0.3)),
    ("sin(pi*x)*cos(pi*y) - y", 0.25, 0.5, math.sin(math.pi * 0.25) * math.cos(math.pi * 0.5) - 0.5),
    ("2*pi^2*sin(pi*x)*cos(pi*y)", -0.4, 0.1, 2 * math.pi ** 2 * math.sin(-0.4 * math.pi) * math.cos(0.1 * math.pi)),
    ("atan2(y, x-0.5)", 0.0, -0.0, -math.pi),
    ("atan2(y, x-0.5)", 0.0, 0.0, math.pi),
    ("2*sqrt(0.25 - x^2)", 0.1, 0.0, 2 * math.sqrt(0.24)),
    ("exp(1)^2 - log(10)/3", 0.0, 0.0, math.e ** 2 - math.log(10) / 3),
    ("-3^2 + 2^-2 + 2^3^2", 0.0, 0.0, -9 + 0.25 + 512),
    ("abs(x)*tan(y) + min(x,y)/max(x,y)", -1.5, 0.7, 1.5 * math.tan(0.7) + (-1.5) / 0.7),
]


@pytest.mark.parametrize("src,x,y,value", HARD)
def test_hard_coded_values(src, x, y, value):
    assert evaluate(parse(src), x, y) == pytest.approx(value, rel=1e-14, abs=1e-14)
    assert to_numpy(src)(x, y) == pytest.approx(value, rel=1e-14, abs=1e-14)


# Error messages and 1-based columns: the table the Rust unit test (crates/sdcrack-core/src/expr/tests.rs)
# reads too, so that both implementations are held to one list (json and pathlib are imported with
# the tables that need them).
import json  # noqa: E402
import pathlib  # noqa: E402

# the folder of the tables shared with the Rust tests
TABLES = pathlib.Path(__file__).resolve().parent
ERRORS = [tuple(case) for case in json.loads((TABLES / "expr_error_cases.json").read_text())["cases"]]


@pytest.mark.parametrize("src,col,msg", ERRORS)
def test_error_columns(src, col, msg):
    with pytest.raises(ExprError) as e:
        parse(src)
    assert (e.value.column, e.value.message) == (col, msg)


def test_limits():
    assert parse("x + 1.") == ("+", ("x",), ("num", 1.0))
    with pytest.raises(ExprError) as e:
        parse("x" + "+x" * 6000)
    assert e.value.column == 10001
    with pytest.raises(ExprError) as e:
        parse("(" * 201 + "x" + ")" * 201)
    assert "nested deeper than 200" in e.value.message


def test_freefem_rendering():
    assert to_freefem("-x^2") == "(-(x ^ 2.0))"
    assert to_freefem("2*pi") == "(2.0 * pi)"
    assert to_freefem("sign(y)") == "((y) >= 0 ? 1. : -1.)"
    assert to_freefem("atan2(y, x-0.5)") == "atan2(y, (x - 0.5))"
    assert to_freefem("min(log(x), 1e-3)") == "min(log(x), 0.001)"
    # the rendering, read back by sdexpr after mapping the ternary, gives the same function
    src = "sin(pi*x)*cos(pi*y) - y/3 + 2^3^2*exp(-x)"
    ff = to_freefem(src)
    f1, f2 = to_numpy(src), to_numpy(ff)
    xs = np.linspace(-1, 1, 7)
    np.testing.assert_allclose(f1(xs, xs[::-1]), f2(xs, xs[::-1]), rtol=1e-15)


def test_ufl_backend():
    ufl = pytest.importorskip("ufl")
    cell = ufl.triangle
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", cell, 1))
    x = ufl.SpatialCoordinate(domain)
    for src, _ in CASES:
        e = sdexpr.to_ufl(src, x)
        assert isinstance(e, ufl.core.expr.Expr)
        assert e.ufl_shape == ()


# ---------------------------------------------------------------------------------------------
# Symbolic derivative (sdexpr.derivative), conventions of Expr::derivative in crates/sdcrack-core/src/expr.rs
# ---------------------------------------------------------------------------------------------

# The expressions whose derivatives are checked, the list the Rust test derivatives_match_finite_differences
# reads too (crates/sdcrack-core/src/expr/tests.rs).
DERIV_SRCS = json.loads((TABLES / "expr_derivative_cases.json").read_text())["expressions"]


def _fd(f, x, y, var, h=1e-3):
    """5-point central difference (error O(h^4))."""
    if var == "x":
        g = lambda t: f(x + t, y)  # noqa: E731
    else:
        g = lambda t: f(x, y + t)  # noqa: E731
    return (-g(2 * h) + 8 * g(h) - 8 * g(-h) + g(-2 * h)) / (12 * h)


@pytest.mark.parametrize("src", DERIV_SRCS)
def test_derivative_matches_finite_differences(src):
    tree = parse(src)
    f = lambda x, y: evaluate(tree, x, y)  # noqa: E731
    d = {v: sdexpr.derivative(tree, v) for v in ("x", "y")}
    rng = np.random.default_rng(7)
    checked = 0
    while checked < 25:
        x, y = rng.uniform(0.3, 1.6), rng.uniform(0.35, 1.5)
        # stay 1e-2 away from the kinks / jumps of abs, sign, min, max in these expressions
        kinks = [x - y, x * x - y, 2 - x, math.sin(3 * x), x - 1.2, y - 0.9]
        if min(abs(k) for k in kinks) < 1e-2:
            continue
        checked += 1
        for v in ("x", "y"):
            fd = _fd(f, x, y, v)
            got = evaluate(d[v], x, y)
            assert abs(got - fd) <= 1e-7 * (1 + abs(fd)), f"d/d{v} {src} at ({x}, {y}): {got} vs fd {fd}"
            # the numpy back-end gives the same values
            assert to_numpy(d[v])(x, y) == pytest.approx(got, rel=1e-14, abs=1e-14)


def test_derivative_simplification_as_in_rust():
    # the cases of the Rust unit test derivative_simplification (crates/sdcrack-core/src/expr.rs)
    D = sdexpr.derivative
    assert D("x", "x") == ("num", 1.0)
    assert D("x", "y") == ("num", 0.0)
    assert D("3*x + 2", "x") == ("num", 3.0)
    assert D("x^2", "x") == ("*", ("num", 2.0), ("x",))          # Rust: "(2 * x)"
    assert D("sin(y)", "x") == ("num", 0.0)
    assert D("sign(x)", "x") == ("num", 0.0)
    assert D("x*y", "y") == ("x",)
    assert D(D("x*y", "x"), "x") == ("num", 0.0)
    assert "sign" in repr(D("min(x, 2*x)", "x"))
    assert D(D("min(x, 2*x)", "x"), "x") == ("num", 0.0)
    with pytest.raises(ValueError):
        D("x", "z")


@pytest.mark.parametrize("src,x,y,var,value", [
    ("abs(x)", 0.0, 0.0, "x", 1.0),          # abs' = sign, sign(+0) = 1
    ("abs(x)", -0.0, 0.0, "x", -1.0),        # sign(-0) = -1
    ("sign(x)", 0.0, 0.0, "x", 0.0),         # sign' = 0, also at the jump
    ("min(x, 2*x)", 0.0, 0.0, "x", 2.0),     # tie: min takes the second argument's derivative
    ("max(x, 2*x)", 0.0, 0.0, "x", 1.0),     # tie: max takes the first argument's
    ("min(x, 2*x)", 1.0, 0.0, "x", 1.0),     # x < 2x: the first
    ("min(x, 2*x)", -1.0, 0.0, "x", 2.0),
    ("max(x, 0)", -0.0, 0.0, "x", 1.0),      # -0 < 0 is false: the first, as Rust's a < b test
    ("max(x, 0)", -1e-300, 0.0, "x", 0.0),
    ("max(x, 0)", 1e-300, 0.0, "x", 1.0),
    ("min(y, x)", 0.5, 0.5, "y", 0.0),       # tie: second argument (x), d/dy x = 0
    ("sqrt(x)", 4.0, 0.0, "x", 0.25),
    ("atan2(y, x)", 1.0, 1.0, "x", -0.5),
    ("2^x", 3.0, 0.0, "x", 8 * math.log(2)),
    ("x^y", 2.0, 3.0, "y", 8 * math.log(2)),
    ("x^y", 2.0, 3.0, "x", 12.0),
])
def test_derivative_conventions(src, x, y, var, value):
    d = sdexpr.derivative(src, var)
    assert evaluate(d, x, y) == pytest.approx(value, rel=1e-15, abs=1e-300)
    assert float(to_numpy(d)(x, y)) == pytest.approx(value, rel=1e-15, abs=1e-300)


def test_derivative_of_open_exact_u_and_its_faces():
    # u = Im w, w = sqrt(z - 1/2) sqrt(z + 1/2), w' = z / w: u_x = Im(z/w), u_y = Re(z/w)
    src = "sqrt(sqrt(((x-0.5)^2+y^2)*((x+0.5)^2+y^2)))*sin((atan2(y,x-0.5)+atan2(y,x+0.5))/2)"
    px, py = to_numpy(sdexpr.derivative(src, "x")), to_numpy(sdexpr.derivative(src, "y"))
    rng = np.random.default_rng(3)
    x, y = rng.uniform(-1, 1, 400), rng.uniform(-1, 1, 400)
    z = x + 1j * y
    wp = z / (np.sqrt(z - 0.5) * np.sqrt(z + 0.5))
    np.testing.assert_allclose(px(x, y), wp.imag, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(py(x, y), wp.real, rtol=1e-12, atol=1e-12)
    # on the faces of the crack (y = +-0): u± = ±sqrt(1/4 - x^2), so u_x = ∓x/sqrt(1/4 - x^2), u_y = 0
    xs = np.linspace(-0.45, 0.45, 19)
    for side in (1.0, -1.0):
        ys = np.full_like(xs, math.copysign(0.0, side))
        np.testing.assert_allclose(px(xs, ys), -side * xs / np.sqrt(0.25 - xs ** 2), rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(py(xs, ys), 0.0, atol=1e-13)


def test_derivative_of_closed_exact_u():
    src = "sin(pi*x)*cos(pi*y) - y"
    px, py = to_numpy(sdexpr.derivative(src, "x")), to_numpy(sdexpr.derivative(src, "y"))
    rng = np.random.default_rng(4)
    x, y = rng.uniform(-1, 1, 100), rng.uniform(-1, 1, 100)
    np.testing.assert_allclose(px(x, y), np.pi * np.cos(np.pi * x) * np.cos(np.pi * y), rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(py(x, y), -np.pi * np.sin(np.pi * x) * np.sin(np.pi * y) - 1, rtol=1e-14,
                               atol=1e-14)


def test_derivative_trees_render_and_reparse():
    # the result uses only the documented tree forms: FreeFEM renders it, and differentiating twice works
    for src in DERIV_SRCS:
        for v in ("x", "y"):
            d = sdexpr.derivative(src, v)
            assert isinstance(to_freefem(d), str)
            dd = sdexpr.derivative(d, "x")
            assert np.isfinite(to_numpy(dd)(0.77, 0.61))
