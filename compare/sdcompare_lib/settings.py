"""What the verdict may expect of a scene: the `[verification]` table of the scene copy in the
results folder (scene.toml, written by sdcrack), with the compare tool's defaults.

The defaults are not set from the outputs they judge:
* kkt_tolerance 1e-10: the solver's own acceptance tolerance of a contact solve (src/study.rs
  KKT_TOLERANCE, documented in docs/design.md), applied to the references as well;
* reference_agreement 1e-8: the two references solve the same discrete problem (a convex QP on the
  same mesh), so their vertex values differ only by their solvers' tolerances;
* delta_slope_tolerance 0.1: Theorem 2.1 at the discrete level gives ‖x_δ − x_0‖ = O(δ) (the
  condensed system is linear in δ), slope 1; 0.1 absorbs the curvature of a least-squares fit over
  δ = 1 … 1e-8;
* min_rate 0.4: the smallest rate Theorem 4.3 claims is h^{1/2} (M0, M1); an observed rate is an
  estimate, so a converging series must show at least 1/2 − 0.1 on each of its last two steps.
A scene may tighten every one of them (a smaller tolerance, a larger min_rate), never loosen it.
"""
import math

from .read import InputError

DEFAULTS = {"kkt_tolerance": 1e-10, "reference_agreement": 1e-8, "delta_slope_tolerance": 0.1,
            "min_rate": 0.4}
# Larger is looser for the tolerances, smaller is looser for min_rate.
_LOOSER = {"kkt_tolerance": 1, "reference_agreement": 1, "delta_slope_tolerance": 1, "min_rate": -1}
QUANTITIES = ("u_l2", "p_l2", "p_x", "lambda_l2")


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
        f = {"reason": reason}
        for key, values in known.items():
            value = e.get(key, "*")
            if value != "*" and value not in values:
                raise InputError(f"{where}: verification.expected_failure[{i}].{key} = {value!r} "
                                 f"is not among the scene's {key} values {values}")
            f[key] = value
        fails.append(f)
    out["expected_failures"] = fails
    return out


def expected_failure(settings, u_space, multiplier, quantity):
    """The reason a series is declared not to converge, or None. A declaration names no p mass:
    it applies to the series of both p masses."""
    for f in settings["expected_failures"]:
        if all(f[k] in ("*", v) for k, v in (("u_space", u_space), ("multiplier", multiplier),
                                              ("quantity", quantity))):
            return f["reason"]
    return None
