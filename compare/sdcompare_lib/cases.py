"""A case of sdcrack's results and the names it goes by: the case axes' vocabularies and
defaults, the key of a case (CaseKey, the solver's axes in its order), the reports' case order,
the variants' labels and the solver's field names. Standard library only: the campaign index
(tools/campaign_index.py) imports it where numpy is not installed (the GitHub nightly's index job).
"""
import decimal
from typing import NamedTuple


# The problem kind of a case (summary.json's `problem`, written for an elastic case only).
DEFAULT_PROBLEM = "scalar"

# The p masses of `sdcrack run` (summary.json: each case's `p_mass`, the plan's `p_masses`); a case
# without the key (an sdcrack older than the lumped p mass) is consistent.
P_MASSES = ("consistent", "lumped")
DEFAULT_P_MASS = "consistent"
# The spaces of p (summary.json: each case's `p_space`, the plan's `p_spaces`): the
# paper's continuous MINI p, or "broken-tangential", whose tangential component has one value per
# crack face at the interior vertices of a straight crack (p·ν shared; kinks and tips shared). A
# case without the key (an sdcrack older than the axis) is continuous. The broken-tangential p runs
# with broken u only: the plan is the product of its lists minus (continuous u, broken-tangential p).
DEFAULT_P_SPACE = "continuous"
BROKEN_TANGENTIAL = "broken-tangential"
P_SPACES = (DEFAULT_P_SPACE, BROKEN_TANGENTIAL)
# The p space's tag in labels (broken/M1/ptangential), as in the solver's field names
# (level3-broken-M1-lumped-ptangential-delta0); none for the continuous p.
P_SPACE_TAG = {DEFAULT_P_SPACE: "", BROKEN_TANGENTIAL: "ptangential"}


def p_mass(c):
    """The case's (or row's) p mass: its `p_mass` ("consistent" when absent)."""
    v = c.get("p_mass")
    return DEFAULT_P_MASS if v is None else str(v)


def p_space(c):
    """The case's (or row's) p space: its `p_space` ("continuous" when absent)."""
    v = c.get("p_space")
    return DEFAULT_P_SPACE if v is None else str(v)


def runs_together(u_space, ps):
    """Whether sdcrack runs this u space with this p space: a p whose tangential part jumps needs
    a u that may jump (never continuous u with the broken-tangential p)."""
    return not (u_space == "continuous" and ps == BROKEN_TANGENTIAL)


def p_space_tag(ps):
    """"ptangential" of the broken-tangential p space, "" of the continuous one."""
    return P_SPACE_TAG.get(ps, ps)


def variant_label(u_space, multiplier, pm=DEFAULT_P_MASS, ps=DEFAULT_P_SPACE):
    """"broken/M1" (consistent p mass, continuous p: as before either axis existed),
    "broken/M1/lumped", "broken/M1/ptangential", "broken/M1/lumped/ptangential"."""
    return "/".join([f"{u_space}/{multiplier}"] + [t for t in ("" if pm == DEFAULT_P_MASS else pm,
                                                              p_space_tag(ps)) if t])


def variant_suffix(pm=DEFAULT_P_MASS, ps=DEFAULT_P_SPACE):
    """" lumped", " ptangential", " lumped ptangential" after a case's "level L u m" in a problem
    line; nothing for the consistent p mass and the continuous p."""
    return "".join(f" {t}" for t in ("" if pm == DEFAULT_P_MASS else pm, p_space_tag(ps)) if t)


def variant_of(x):
    """(u space, multiplier, p mass, p space) of a case or of a series, table or plot row."""
    return str(x["u_space"]), str(x["multiplier"]), p_mass(x), p_space(x)


def variant_order(v):
    """Sort key of a variant (u, m, p mass, p space): the consistent p mass and the continuous p
    first, as a run without them lists its variants."""
    u, m, pm, ps = v
    return u, m, pm != DEFAULT_P_MASS, pm, ps != DEFAULT_P_SPACE, ps


def shortest_exponent_form(d):
    """(mantissa, exponent) of a positive finite float in the shortest digits that parse back to
    it: 0.01 → ("1", -2), 2.5e-3 → ("2.5", -3), 1.0 → ("1", 0)."""
    _, digits, exp = decimal.Decimal(repr(d)).normalize().as_tuple()
    m = "".join(map(str, digits))
    return m[0] + ("." + m[1:] if len(m) > 1 else ""), exp + len(digits) - 1


class CaseKey(NamedTuple):
    """A case's identity: the solver's case axes in the solver's order (its CaseKey, `sdcrack
    schema`'s "case_key": tests/python/test_schema.py ties the two). Read by field name, never by
    position. Cases are ordered by `order()`, the order the reports have always listed them in."""
    level: int
    u_space: str
    multiplier: str
    p_mass: str
    p_space: str
    delta: float
    # the problem kind: written only for an elastic case (whose key has no u space, p mass or p
    # space; the compare tool does not judge elastic solver cases yet)
    problem: str = DEFAULT_PROBLEM

    @classmethod
    def of(cls, c):
        """The key of a case (or row) of summary.json: its absent p axes and problem kind are
        the defaults."""
        return cls(level=int(c["level"]), u_space=str(c["u_space"]),
                   multiplier=str(c["multiplier"]), p_mass=p_mass(c), p_space=p_space(c),
                   delta=float(c["delta"]), problem=str(c.get("problem", DEFAULT_PROBLEM)))

    def series_name(self):
        """The solver's name of the case's δ sweep in the field files (its series_name):
        "level3-broken-M1", then "-lumped" for the lumped p mass, "-ptangential" for the
        broken-tangential p."""
        tags = "".join(f"-{t}" for t in ("" if self.p_mass == DEFAULT_P_MASS else self.p_mass,
                                         p_space_tag(self.p_space)) if t)
        return f"level{self.level}-{self.u_space}-{self.multiplier}{tags}"

    def case_name(self):
        """The solver's name of the case in the field files (its case_name, summary.json's
        fields_grid): the series name, then "-delta" and δ as Rust's `{:e}` writes it ("1e-2",
        "1e0"; "0" for zero), e.g. "level3-broken-M1-lumped-ptangential-delta0"."""
        if self.delta == 0:
            return f"{self.series_name()}-delta0"
        mant, e = shortest_exponent_form(abs(self.delta))
        return f"{self.series_name()}-delta{'-' if self.delta < 0 else ''}{mant}e{e}"

    def order(self):
        """The reports' case order: level, u space, multiplier, δ, then the p axes (which came
        last, so a run without them lists its cases as before them)."""
        return (self.level, self.u_space, self.multiplier, self.delta, self.p_mass, self.p_space)

    # Sorting keys (sorted(set of keys)) follows `order()`, not the tuple's field order.
    def __lt__(self, other):
        return self.order() < other.order()

    def __le__(self, other):
        return self.order() <= other.order()

    def __gt__(self, other):
        return self.order() > other.order()

    def __ge__(self, other):
        return self.order() >= other.order()


def case_key(c):
    """The CaseKey of a case (or row) of summary.json."""
    return CaseKey.of(c)


def case_order(c):
    """Sort key of cases (or rows) of summary.json: the reports' order (CaseKey.order)."""
    return CaseKey.of(c).order()


def plan_p_masses(plan):
    """The plan's p masses (["consistent"] for a plan written before the lumped p mass)."""
    v = plan.get("p_masses") if isinstance(plan, dict) else None
    return list(v) if isinstance(v, list) else [DEFAULT_P_MASS]


def plan_p_spaces(plan):
    """The plan's p spaces (["continuous"] for a plan written before the p space axis)."""
    v = plan.get("p_spaces") if isinstance(plan, dict) else None
    return list(v) if isinstance(v, list) else [DEFAULT_P_SPACE]
