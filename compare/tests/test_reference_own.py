"""Each reference judged on its own (compare/sdcompare_lib/refcheck.py): its u and ∇u errors
converge at P1's orders for the regularity its own meshes show, and stay within the stated factor
of its own interpolation yardstick; a reference that fails either is named in the problem. Synthetic
series (res/a as refcheck.checks reads them), no run: cheap. The same checks on real results, and
a reference solving a wrong problem, are in test_damaged_results.py.
Run: /usr/bin/python3 -m pytest -q -p no:cacheprovider compare/tests/test_reference_own.py
"""
import math

import numpy as np
import pytest

from sdcompare_lib import exact, refcheck, theory

H0 = 0.35


def inputs(u_rate=1.0, p_rate=0.5, interp_p_rate=0.5, interp_u_rate=1.5, levels=5, graded=None,
           exact_u=True, tools=("dolfinx", "freefem"), p_ratio=0.9, u_ratio=1.2, bad=None):
    """res/a of a scene with references whose errors fall at the given rates per halving of h
    (of N^-1/2 on graded meshes: N = 200·4^level), their interpolation yardsticks at the interp
    rates, errors p_ratio × and u_ratio × the yardstick at level 0; bad(tool, level, q, e) may
    change an error."""
    rows, refs = [], {}
    for tool in tools:
        cases = []
        for lv in range(levels):
            h = H0 / 2 ** lv
            ip = 0.5 * 2.0 ** (-interp_p_rate * lv)
            iu = 0.05 * 2.0 ** (-interp_u_rate * lv)
            e = {"p_l2": p_ratio * 0.5 * 2.0 ** (-p_rate * lv),
                 "u_l2": u_ratio * 0.05 * 2.0 ** (-u_rate * lv)}
            if bad:
                e = {q: bad(tool, lv, q, v) for q, v in e.items()}
            rows.append({"source": tool, "level": lv, "u_l2": (e["u_l2"], e["u_l2"]),
                         "p_l2": (e["p_l2"], e["p_l2"]), "lambda_l2": (1.0, 1.0),
                         "interpolation": {"u_l2": iu, "p_l2": ip}})
            cases.append({"level": lv, "h": h, "unknowns": 200 * 4 ** lv})
        refs[tool] = {"summary": {"cases": cases}}
    disc = {"grading": {"beta": graded, "radius": 0.25}} if graded is not None else {}
    res = {"scene_file": {"discretization": disc}, "refs": refs}
    a = {"exact": object() if exact_u else None, "independent": rows, "gradient_growth": None}
    return res, a


def judged(res, a):
    """{label: (requirement, problems, not-applicable reason)} and a["reference_own"]."""
    return {label: (what, problems, na)
            for label, what, problems, na in refcheck.checks(res, a)}, a["reference_own"]


ORDERS, YARD = refcheck.ORDERS_LABEL, refcheck.YARDSTICK_LABEL


def test_a_singular_u_on_uniform_meshes_is_held_to_p1s_orders_for_s_one_half():
    """The interpolation yardstick's ∇ rate 0.5 < 0.9 gives s = 1/2: u order 1, ∇u 1/2 (the
    references' rates on open-exact); both pass at those rates, and the L² yardstick is not held
    (its ratio grows as h^-1/2 there)."""
    checks, own = judged(*inputs())
    assert checks[ORDERS][1] == [] and checks[ORDERS][2] is None, checks[ORDERS]
    assert "dolfinx u 1.00, 1.00 (order 1)" in checks[ORDERS][0]
    assert "freefem ∇u 0.50, 0.50 (order 0.5)" in checks[ORDERS][0]
    assert {r["expected_rate"] for r in own["orders"]} == {1.0, 0.5}
    assert checks[YARD][1] == [] and {r["quantity"] for r in own["yardstick"]} == {"p_l2"}


def test_a_smooth_u_is_held_to_orders_2_and_1_and_to_both_yardsticks():
    checks, own = judged(*inputs(u_rate=2.0, p_rate=1.0, interp_p_rate=1.0, interp_u_rate=2.0))
    assert checks[ORDERS][1] == [] and "(order 2)" in checks[ORDERS][0]
    assert {r["quantity"] for r in own["yardstick"]} == {"u_l2", "p_l2"}
    assert checks[YARD][1] == []
    # the same u rate 1 (a bug halving the order) fails, naming the reference and its quantity
    checks, _ = judged(*inputs(u_rate=1.0, p_rate=1.0, interp_p_rate=1.0, interp_u_rate=2.0))
    lines = checks[ORDERS][1]
    assert [ln.split(":")[0] for ln in lines] == [
        "reference dolfinx u_l2 on the uniform meshes", "reference freefem u_l2 on the uniform meshes"]
    assert "P1's order 2 for s = 1" in lines[0] and "threshold 1.9" in lines[0]


def wrong_problem_at_one_node(tools=("freefem",), amplitude=1.0):
    """A reference whose constraint has the wrong sign at one node where the crack opens: its jump
    is forced to 0 there, an O(1) hat-shaped error in ∇u whatever h (its L² norm ~ amplitude) and
    an O(h) one in u."""
    def bad(tool, lv, q, e):
        if tool not in tools:
            return e
        extra = amplitude if q == "p_l2" else amplitude * H0 / 2 ** lv
        return math.hypot(e, extra)
    return bad


def test_a_reference_solving_a_wrong_problem_fails_both_checks_named():
    """On a uniform singular scene (s = 1/2) FreeFEM's ∇u stalls (its error levels off at the
    hat's): the orders fail by the series rule and the ∇u error exceeds 1.05 × its interpolation
    yardstick; dolfinx, right, is not named."""
    checks, own = judged(*inputs(bad=wrong_problem_at_one_node()))
    orders = checks[ORDERS][1]
    assert len(orders) == 1 and orders[0].startswith("reference freefem p_l2 on the uniform "
                                                     "meshes: rate "), orders
    assert "P1's order 0.5 for s = 0.5" in orders[0]
    (yard,) = checks[YARD][1]
    assert yard.startswith("reference freefem p_l2 at level 4: error ") and "> 1.05 ×" in yard
    assert "5 of 5 levels over the bound" in yard
    assert not any("dolfinx" in p for p in orders + [yard])


def test_the_energy_yardstick_holds_at_factor_1_05_on_any_mesh():
    """Céa's constant 1 with 5 % for the load quadrature: a ratio 1.04 passes, 1.06 fails, on
    uniform and graded meshes, singular or smooth."""
    for graded in (None, 0.4, 0.5):
        for ratio, fails in ((1.04, False), (1.06, True)):
            checks, _ = judged(*inputs(p_ratio=ratio, graded=graded))
            assert bool(checks[YARD][1]) == fails, (graded, ratio, checks[YARD])


def test_the_l2_yardstick_is_held_only_on_uniform_meshes_of_a_smooth_u():
    smooth = dict(u_rate=2.0, p_rate=1.0, interp_p_rate=1.0, interp_u_rate=2.0)
    checks, _ = judged(*inputs(u_ratio=2.1, **smooth))
    (line,) = [p for p in checks[YARD][1] if p.startswith("reference dolfinx")]
    assert line.startswith("reference dolfinx u_l2 at level 0: error") and "> 2 ×" in line
    for kwargs in (dict(smooth, graded=0.4), dict(interp_p_rate=0.5)):  # graded; singular
        checks, own = judged(*inputs(u_ratio=9.0, **kwargs))
        assert checks[YARD][1] == [] and {r["quantity"] for r in own["yardstick"]} == {"p_l2"}


@pytest.mark.parametrize("quantity", ["u_l2", "p_l2"])
def test_graded_rates_per_halving_of_n_are_held_with_the_series_margin(quantity):
    """On meshes graded with β < 1/2 that resolve the tip (interpolation ∇ rate 1 per halving of
    N^-1/2): P1's order (u 2, ∇u 1) − theory.RATE_MARGIN; 0.05 short passes, 0.2 short fails."""
    order = theory.p1_order(quantity, 1.0)
    for shortfall, fails in ((0.05, False), (0.2, True)):
        r = {"u_l2": 2.0, "p_l2": 1.0}
        r[quantity] = order - shortfall
        checks, _ = judged(*inputs(u_rate=r["u_l2"], p_rate=r["p_l2"], interp_p_rate=1.0,
                                   interp_u_rate=2.0, graded=0.4, tools=("dolfinx",)))
        problems = checks[ORDERS][1]
        if fails:
            (line,) = problems
            assert line.startswith(f"reference dolfinx {quantity} on the graded meshes (β = 0.4): "
                                   f"rate {order - shortfall:.2f} < {order - 0.1:g}"), line
        else:
            assert problems == []


def test_a_rate_still_rising_cannot_be_judged_yet():
    """A reference whose u rates rise 1.38 → 1.79 toward 2 on three levels (a β = 0.6 mesh judged
    as 0.4): neither a problem nor a pass: it cannot be judged yet, with the levels to run."""
    def bad(tool, lv, q, e):
        return 0.05 * 2.0 ** -{0: 0.0, 1: 1.38, 2: 1.38 + 1.79}[lv] if q == "u_l2" else e
    checks, own = judged(*inputs(p_rate=1.0, interp_p_rate=1.0, interp_u_rate=2.0, graded=0.4,
                                 levels=3, tools=("dolfinx",), bad=bad))
    assert checks[ORDERS][1] == []
    (line,) = own["undecided"]
    assert line.startswith("reference dolfinx u_l2 on the graded meshes (β = 0.4): rate 1.79 from "
                           "level 1 to 2 < 1.9, rising from 1.38"), line
    assert "run levels up to" in line


def test_where_the_checks_do_not_apply_they_say_why():
    for kwargs, label, why in (
            (dict(exact_u=False), ORDERS, "the scene has no [exact]"),
            (dict(exact_u=False), YARD, "the scene has no [exact]"),
            (dict(tools=()), ORDERS, "the scene runs no reference"),
            (dict(graded=0.5), ORDERS, "β = 0.5 is not below the tip singularity's exponent")):
        checks, _ = judged(*inputs(**kwargs))
        assert checks[label][1] == [] and checks[label][2].startswith(why), (kwargs, checks[label])
    # β = 1/2: the yardstick (Céa, any mesh) still applies
    checks, _ = judged(*inputs(graded=0.5))
    assert checks[YARD][2] is None and checks[YARD][1] == []
    # fewer than three levels: the orders cannot be judged yet (the series rule's reason)
    checks, own = judged(*inputs(levels=2))
    assert checks[ORDERS][1] == [] and len(own["undecided"]) == 4
    assert all("3 are needed to measure two rates" in x for x in own["undecided"])


def test_the_interpolation_yardstick_is_the_interpolant_on_the_cracked_mesh():
    """exact.p1_interpolation_errors of a u linear on each face of a unit square cut across along
    y = 1/2 (u = y + 1 above, y − 1 below: a jump of 2) is zero to round-off — each face's corners
    take that face's values — and that of u = x² is the P1 interpolation error of x², h/√3 in ∇
    on a grid of right triangles of legs h (the interpolant's slope is 2x at each cell's middle:
    ∫(2x − 2x_mid)² = h⁴/3 per cell)."""
    n = 4
    h = 1.0 / n
    xs = np.linspace(0, 1, n + 1)
    P = [(x, y) for y in xs for x in xs]
    idx = {(i, j): j * (n + 1) + i for j in range(n + 1) for i in range(n + 1)}
    minus = {}
    for i in range(n + 1):  # the − copy of every node on the cut y = 1/2
        minus[idx[(i, n // 2)]] = len(P)
        P.append((xs[i], 0.5))
    T = []
    for j in range(n):
        for i in range(n):
            a, b, c, d = idx[(i, j)], idx[(i + 1, j)], idx[(i + 1, j + 1)], idx[(i, j + 1)]
            for tri in ((a, b, c), (a, c, d)):
                T.append(tuple(minus.get(v, v) for v in tri) if j == n // 2 - 1 else tri)
    P, T = np.array(P), np.array(T)
    crack = np.array([[idx[(i, n // 2)], minus[idx[(i, n // 2)]]] for i in range(n + 1)])
    cut = [[0.0, 0.5], [1.0, 0.5]]
    faces = exact.ExactSolution("y + sign(y - 0.5)", px="0", py="1", crack=cut)
    e = exact.p1_interpolation_errors(P, T, crack, faces)
    assert e["u_l2"] < 1e-12 and e["p_l2"] < 1e-12, e
    square = exact.ExactSolution("x^2", px="2*x", py="0", f="-2", crack=cut)
    e = exact.p1_interpolation_errors(P, T, crack, square)
    assert e["p_l2"] == pytest.approx(h / math.sqrt(3.0), rel=1e-10), e


def test_a_zero_yardstick_holds_round_off_and_nothing_more():
    """Where u is P1 on the mesh (interpolation error 0), the reference's error must be round-off:
    1e-14 passes (yardsticks.ABS_FLOOR), 1e-6 fails with "a zero yardstick"."""
    for error, fails in ((1e-14, False), (1e-6, True)):
        res, a = inputs(tools=("dolfinx",))
        for r in a["independent"]:
            r["interpolation"]["p_l2"] = 0.0 if r["level"] == 4 else r["interpolation"]["p_l2"]
            if r["level"] == 4:
                r["p_l2"] = (error, error)
        checks, _ = judged(res, a)
        problems = checks[YARD][1]
        assert bool(problems) == fails, problems
        if fails:
            assert problems[0].startswith("reference dolfinx p_l2 at level 4: error 1.000e-06 > "
                                          "1.05 × its interpolation yardstick 0.000e+00 (a zero "
                                          "yardstick; 1 of 5 levels"), problems
