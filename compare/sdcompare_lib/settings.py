"""What the verdict may expect of a scene: the `[verification]` table of the scene copy in the
results folder (scene.toml, written by sdcrack), with the compare tool's defaults.

The defaults are not set from the outputs they judge:
* kkt_tolerance 1e-10: the solver's own acceptance tolerance of a contact solve (crates/sdcrack-core/src/study.rs
  KKT_TOLERANCE, documented in docs/design.md), applied to the references as well;
* reference_agreement 1e-8: the two references solve the same discrete problem (a convex QP on the
  same mesh), so their vertex values differ only by their solvers' tolerances;
* delta_slope_tolerance 0.1: Theorem 2.1 at the discrete level gives ‖x_δ − x_0‖ = O(δ) (the
  condensed system is linear in δ), slope 1; 0.1 absorbs the curvature of a least-squares fit over
  δ = 1 … 1e-8;
* the expected order of each series comes from the theory (theory.py: the regularity of the
  exact solution, Theorem 4.3); a converging series shows at least the expected order − 0.1 on
  each of its last two steps. `min_rate`, when a scene gives it, is a floor on top of that (0.4 is
  the least it may be: the paper's smallest rate 1/2 minus 0.1).
A scene may tighten every one of them (a smaller tolerance, a larger min_rate), never loosen it; it
may declare the expected order of some series itself, with a reason ([[verification.expected_rate]]),
and declare a check that does not apply to it, with a reason ([[verification.not_applicable]]).
"""
import math

from .read import InputError
from .cases import DEFAULT_P_SPACE, P_MASSES, P_SPACES

DEFAULTS = {"kkt_tolerance": 1e-10, "reference_agreement": 1e-8, "delta_slope_tolerance": 0.1,
            "min_rate": 0.4}
# Larger is looser for the tolerances, smaller is looser for min_rate.
_LOOSER = {"kkt_tolerance": 1, "reference_agreement": 1, "delta_slope_tolerance": 1, "min_rate": -1}
QUANTITIES = ("u_l2", "p_l2", "p_x", "lambda_l2")
# The keys of one [[verification.expected_rate]] (tests/python/test_schema.py ties these names
# to the solver's scene schema, `sdcrack schema`).
EXPECTED_RATE_KEYS = ("u_space", "multiplier", "p_mass", "p_space", "quantity", "rate", "reason")


def scene_lists(scene):
    """(levels, u_spaces, multipliers, deltas) the scene file asks for."""
    d = scene.get("discretization") or {}
    return (sorted(int(v) for v in d.get("levels", [])), list(d.get("u_spaces", [])),
            list(d.get("multipliers", [])), sorted((float(v) for v in d.get("deltas", [])),
                                                   reverse=True))


def scene_p_masses(scene):
    """The p masses the scene file asks for ([discretization] p_mass, default ["consistent"])."""
    d = scene.get("discretization") or {}
    return list(d.get("p_mass", ["consistent"]))


def scene_p_spaces(scene):
    """The p spaces the scene file asks for ([discretization] p_spaces, default ["continuous"])."""
    d = scene.get("discretization") or {}
    return list(d.get("p_spaces", [DEFAULT_P_SPACE]))


def verification(scene, where):
    """The scene's [verification] with defaults: dict(smoke, kkt_tolerance, reference_agreement,
    delta_slope_tolerance, min_rate, expected_failures=[dict(u_space, multiplier, quantity, reason)]).
    A loosened default or a malformed declaration is an InputError (exit 2)."""
    v = scene.get("verification") or {}
    out = {"smoke": bool(v.get("smoke", False))}
    for key, default in DEFAULTS.items():
        value = v.get(key, default)
        if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value) \
                or value <= 0:
            raise InputError(f"{where}: verification.{key} = {value!r} must be a finite number > 0")
        if (value - default) * _LOOSER[key] > 0:
            raise InputError(f"{where}: verification.{key} = {value:g} loosens the default "
                             f"{default:g}; a scene may only tighten it")
        out[key] = float(value)
    _, u_spaces, multipliers, _ = scene_lists(scene)
    known = {"u_space": u_spaces, "multiplier": multipliers, "quantity": list(QUANTITIES)}
    fails = []
    for i, e in enumerate(v.get("expected_failure", [])):
        reason = str(e.get("reason", "")).strip()
        if not reason:
            raise InputError(f"{where}: verification.expected_failure[{i}] has no reason")
        fails.append({"reason": reason,
                      **_series_keys(e, known, f"{where}: verification.expected_failure[{i}]")})
    out["expected_failures"] = fails
    out["min_rate_declared"] = "min_rate" in v
    out["expected_rates"] = _expected_rates(v, known, where)
    out["not_applicable"] = _not_applicable(v, where)
    return out


def _series_keys(e, known, name):
    """{key: value or "*"} of a declaration's series keys (u_space, multiplier, quantity), each a
    value the scene runs (InputError naming `name` otherwise)."""
    out = {}
    for key, values in known.items():
        value = e.get(key, "*")
        if value != "*" and value not in values:
            raise InputError(f"{name}.{key} = {value!r} is not among the scene's {key} values "
                             f"{values}")
        out[key] = value
    return out


def _expected_rates(v, known, where):
    """[[verification.expected_rate]]: dict(u_space, multiplier, p_mass, p_space, quantity, rate,
    reason); p_mass and p_space "*" when not given."""
    out = []
    for i, e in enumerate(v.get("expected_rate", [])):
        name = f"{where}: verification.expected_rate[{i}]"
        reason = str(e.get("reason", "")).strip()
        if not reason:
            raise InputError(f"{name} has no reason (say where the order comes from)")
        rate = e.get("rate")
        if not isinstance(rate, (int, float)) or isinstance(rate, bool) or not math.isfinite(rate) \
                or not 0 < rate <= 4:
            raise InputError(f"{name}.rate = {rate!r} must be a number in (0, 4]")
        d = {"rate": float(rate), "reason": reason, "p_mass": e.get("p_mass", "*"),
             "p_space": e.get("p_space", "*")}
        if d["p_mass"] not in ("*",) + P_MASSES:
            raise InputError(f"{name}.p_mass = {d['p_mass']!r} is none of consistent, lumped, '*'")
        if d["p_space"] not in ("*",) + P_SPACES:
            raise InputError(f"{name}.p_space = {d['p_space']!r} is none of "
                             f"{', '.join(P_SPACES)}, '*'")
        d.update(_series_keys(e, known, name))
        bad = set(e) - set(EXPECTED_RATE_KEYS)
        if bad:
            raise InputError(f"{name}: unknown key(s) {sorted(bad)}")
        out.append(d)
    return out


# Checks a scene may declare not to apply to it ([[verification.not_applicable]]).
DECLARABLE_CHECKS = ("interpolation yardstick", "reference yardstick", "δ → 0",
                     "Theorem 2.1 (exact)")


def _not_applicable(v, where):
    """{check: reason} of [[verification.not_applicable]]."""
    out = {}
    for i, e in enumerate(v.get("not_applicable", [])):
        name = f"{where}: verification.not_applicable[{i}]"
        check, reason = e.get("check"), str(e.get("reason", "")).strip()
        if check not in DECLARABLE_CHECKS:
            raise InputError(f"{name}.check = {check!r} is none of {', '.join(DECLARABLE_CHECKS)}")
        if not reason:
            raise InputError(f"{name} has no reason")
        out[check] = reason
    return out


def expected_failure(settings, u_space, multiplier, quantity):
    """The reason a series is declared not to converge, or None. A declaration names no p mass and
    no p space: it applies to the series of every p mass and p space."""
    for f in settings["expected_failures"]:
        if all(f[k] in ("*", v) for k, v in (("u_space", u_space), ("multiplier", multiplier),
                                              ("quantity", quantity))):
            return f["reason"]
    return None
