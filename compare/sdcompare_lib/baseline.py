"""What counts as a change since a baseline (an earlier results folder or campaign folder): the
tolerances and the measure of a change, one home for sdcompare's baseline flags
(verdict.compare_baseline) and the campaign index's list of changes (tools/campaign_index.py).

An error norm changes when its relative change (rel_change: |new − old| over the larger
magnitude, dimensionless) exceeds BASELINE_ERROR_RTOL; a convergence rate (an exponent,
dimensionless) when its absolute change exceeds BASELINE_RATE_ATOL. Standard library only: the
index runs where numpy is not installed (the GitHub nightly's index job)."""

BASELINE_ERROR_RTOL = 1e-6
BASELINE_RATE_ATOL = 1e-4


def rel_change(old, new):
    """|new − old| relative to the larger of |old|, |new| (and 1e-300: two zeros give 0.0)."""
    return 0.0 if old == new else abs(new - old) / max(abs(old), abs(new), 1e-300)


def error_change(old, new):
    """The relative change of an error norm (rel_change) when it exceeds BASELINE_ERROR_RTOL,
    else None."""
    rc = rel_change(old, new)
    return rc if rc > BASELINE_ERROR_RTOL else None


def rate_change(old, new):
    """The absolute change of a convergence rate when it exceeds BASELINE_RATE_ATOL, else None."""
    d = abs(new - old)
    return d if d > BASELINE_RATE_ATOL else None
