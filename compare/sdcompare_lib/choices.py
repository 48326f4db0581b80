"""The discretisation choices that change a variant's numbers in kind — its u space, p mass and p
space (the broken-tangential p reaches P1's orders where the continuous one stays at 1/2, and
stood at 0.41–0.47× the references' u error on open-graded where the continuous p stood at
0.89–1.04×) — by which a range of ratios or rates is split wherever its rows have more than one,
never one range across them (issue 42). The multiplier stays inside a range.

Standard library only: the campaign index (tools/campaign_index.py) imports it without numpy."""

AXES = ("u space", "p mass", "p space")
# A row without p_mass / p_space is of the consistent p mass and the continuous p (read.py's
# defaults); the p space as the plots' notes write it, the continuous one named ("pcontinuous"),
# the broken-tangential one by its label tag (cases.P_SPACE_TAG: "ptangential").
DEFAULT_P_MASS, DEFAULT_P_SPACE = "consistent", "continuous"
P_SPACE_WORD = {"continuous": "pcontinuous", "broken-tangential": "ptangential"}


def choice(row):
    """(u space, p mass, p space word) of a row (a report's series, a glance row)."""
    pm, ps = row.get("p_mass") or DEFAULT_P_MASS, row.get("p_space") or DEFAULT_P_SPACE
    return str(row.get("u_space")), str(pm), P_SPACE_WORD.get(ps, str(ps))


def varying(rows):
    """The indices of AXES in which the rows differ."""
    keys = [choice(r) for r in rows]
    return [i for i in range(len(AXES)) if len({k[i] for k in keys}) > 1]


def varying_axes(rows):
    """The AXES the rows differ in, as words: "p mass × p space" ("" when none)."""
    return " × ".join(AXES[i] for i in varying(rows))


def split(rows):
    """[(label or None, rows)]: the rows per choice where they have more than one, labelled by
    the parts that vary ("lumped/ptangential"), in the rows' order of first appearance; one
    (None, rows) otherwise."""
    axes = varying(rows)
    if not axes:
        return [(None, list(rows))]
    out = {}
    for r in rows:
        k = choice(r)
        out.setdefault("/".join(k[i] for i in axes), []).append(r)
    return list(out.items())
