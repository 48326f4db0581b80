"""Files and folders written under a temporary name beside the final one and renamed only when
complete, so an interrupted writer leaves nothing half-written under the final name (write_atomic:
one file, every Python writer of the project; staged_folder, replace_folder: the references'
result folders and sdcompare's report/); the
`provenance` of summary.json (tool and library versions, date, command line, cores, the BLAS/OpenMP
threads, PINNED_THREADS: what the campaign and the rerun commands pin); and the
per-case `status` both references write (KKT residuals against the shared tolerance)."""

import json
import os
import platform
import shutil
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def staged_folder(out):
    """Yields a new temporary folder beside `out`; when the block completes it replaces `out`
    (the caller decides beforehand whether replacing is allowed), on any error it is removed."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.tmp-", dir=out.parent))
    try:
        yield tmp
        replace_folder(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def replace_folder(tmp, final):
    """Renames the complete folder `tmp` to `final` (same filesystem). An existing `final` is first
    renamed to a hidden folder beside it, then the new one into place, then the old one deleted:
    two atomic renames, so `final` is never half-written (absent only for the instant between
    them). The caller decides beforehand whether replacing is allowed."""
    final = os.fspath(final)
    if not os.path.lexists(final):
        os.rename(tmp, final)
        return
    parent, name = os.path.split(os.path.abspath(final))
    old = tempfile.mkdtemp(prefix=f".{name}.old-", dir=parent)
    os.rename(final, os.path.join(old, name))
    os.rename(tmp, final)
    shutil.rmtree(old, ignore_errors=True)


def write_atomic(path, data, mode=None, check=None):
    """Writes `data` (str: as UTF-8 text; bytes: as they are) to `path` through the temporary file
    .NAME.tmp-PID beside it, renamed over `path` once complete, so readers see the old file or the
    new one, never half of one. mode: the new file's permission bits (None: the umask's).
    check(tmp): called on the complete temporary file before the rename; whatever it raises
    propagates, the temporary file removed and `path` left as it was."""
    folder, name = os.path.split(os.fspath(path))
    tmp = os.path.join(folder, f".{name}.tmp-{os.getpid()}")
    try:
        if isinstance(data, bytes):
            with open(tmp, "wb") as fh:
                fh.write(data)
        else:
            with open(tmp, "w", encoding="utf-8") as fh:
                fh.write(data)
        if mode is not None:
            os.chmod(tmp, mode)
        if check is not None:
            check(tmp)
        os.replace(tmp, path)
    except BaseException:
        if os.path.lexists(tmp):
            os.unlink(tmp)
        raise


# The thread counts of the BLAS and OpenMP libraries under the references (numpy, scipy, PETSc
# for dolfinx; FreeFem++'s solvers), pinned to 1 wherever the campaign runs a job: the variables
# Snakemake's shell sets to a job's `threads` (1 for a reference job), which the campaign's
# Snakefile also sets itself, and every rerun command of a report and of tools/cases
# (render.rerun_args). A reduction split over another number of threads adds in another order:
# a FreeFEM field rerun unpinned on this machine differed by 1.78e-15 (issue 42), pinned it is
# identical. sdcrack itself calls no BLAS (its linear algebra is faer, its threads rayon's, whose
# count leaves its results bit-identical: docs/workflow.md, "Thread count"). One home: the
# Snakefile, render.py and the provenance below read it from here.
PINNED_THREADS = (("OMP_NUM_THREADS", "1"), ("GOTO_NUM_THREADS", "1"),
                  ("OPENBLAS_NUM_THREADS", "1"), ("MKL_NUM_THREADS", "1"),
                  ("VECLIB_MAXIMUM_THREADS", "1"), ("NUMEXPR_NUM_THREADS", "1"))


def pinned_env_args():
    """["env", "OMP_NUM_THREADS=1", ...]: the prefix that runs a command with PINNED_THREADS."""
    return ["env"] + [f"{name}={value}" for name, value in PINNED_THREADS]


def threads_of(environ):
    """{variable of PINNED_THREADS: its value in `environ`, None where unset}: the threads a
    process ran with (provenance `threads`)."""
    return {name: environ.get(name) for name, _ in PINNED_THREADS}


def threads_pinned(threads):
    """Whether a provenance's `threads` (threads_of) are PINNED_THREADS: True, False, or None when
    not recorded (a folder written before issue 42)."""
    if not isinstance(threads, dict):
        return None
    return all(threads.get(name) == value for name, value in PINNED_THREADS)


PROVENANCE_KEYS = ("tool", "tool_version", "python", "numpy", "date_utc", "command_line", "cores",
                   "threads")


def provenance(tool, tool_version):
    """{"tool", "tool_version", "python", "numpy", "date_utc" (now, "YYYY-MM-DDTHH:MM:SSZ"),
    "command_line" (sys.argv), "cores" (os.cpu_count()), "threads" (threads_of the process's
    environment: the BLAS/OpenMP thread counts it ran with)}: what produced a result folder."""
    import numpy

    return {"tool": tool, "tool_version": str(tool_version), "python": platform.python_version(),
            "numpy": numpy.__version__, "date_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "command_line": list(sys.argv), "cores": os.cpu_count(),
            "threads": threads_of(os.environ)}


def write_summary(folder, scene, tool, cases, tool_version, problem=None):
    """folder/summary.json = {"scene", "tool", ["problem",] "provenance" (see `provenance`; date =
    now), "cases"}; returns the dict. `problem`: the problem kind of an elastic scene
    ("elasticity", docs/elasticity.md), absent for the scalar problem (None)."""
    summary = {"scene": scene, "tool": tool}
    if problem is not None:
        summary["problem"] = problem
    summary |= {"provenance": provenance(tool, tool_version), "cases": cases}
    (Path(folder) / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    return summary


def exit_status(cases, prefix):
    """A reference run's exit status once its results are written: 3 when some case's `status` is
    not "converged" (each such case named on stderr after `prefix`: its results are not
    trustworthy), else 0."""
    bad = [c for c in cases if c["status"] != "converged"]
    for c in bad:
        print(f"{prefix}level {c['level']}: {c['status']}", file=sys.stderr)
    return 3 if bad else 0


# ---- KKT residuals and case status ---------------------------------------------------------------

KKT_KEYS = ("equations", "primal", "dual", "complementarity")
KKT_TOLERANCE = 1e-10  # as the Rust solver's KKT_TOLERANCE (crates/sdcrack-core/src/study.rs): every residual is relative


def case_status(kkt, tolerance=KKT_TOLERANCE, failure=None):
    """The `status` of one case: "converged" when the QP solver reported success (`failure` is None)
    and every KKT residual of `kkt` (the four KKT_KEYS) is ≤ `tolerance`; otherwise
    "not_converged: " and the reasons, e.g. "not_converged: complementarity 3.0e-04 > 1e-10" or
    "not_converged: active set did not converge in 100 solves". A missing or NaN residual fails."""
    reasons = [] if failure is None else [str(failure)]
    for key in KKT_KEYS:
        v = kkt.get(key) if isinstance(kkt, dict) else None
        if not isinstance(v, (int, float)) or isinstance(v, bool):
            reasons.append(f"{key} missing")
        elif not v <= tolerance:  # also NaN
            reasons.append(f"{key} {v:.1e} > {tolerance:.0e}")
    return "converged" if not reasons else "not_converged: " + "; ".join(reasons)


def kkt_measures(residual, scale, jump, lam, jump_scale):
    """The references' relative KKT residuals of a contact QP (docs/design.md; the elastic ones of
    docs/elasticity.md): "equations" the componentwise backward error of the free rows' residual
    K u − F − Bᵀλ against its scale |K||u| + |Bᵀλ| + |F|; "primal" the largest violation of the
    constraint jump ≥ 0 over jump_scale (‖B‖∞‖u‖∞, or 1 where that is 0); "dual" the largest
    negative λ over ‖λ‖∞ (1 where 0); "complementarity" max |λ_j jump_j| over both scales."""
    import numpy as np

    lam, jump = np.asarray(lam, dtype=float), np.asarray(jump, dtype=float)
    l_scale = np.abs(lam).max(initial=0.0) or 1.0
    return {
        "equations": componentwise_backward_error(residual, scale),
        "primal": float(max(0.0, -jump.min(initial=0.0)) / jump_scale),
        "dual": float(max(0.0, -lam.min(initial=0.0)) / l_scale),
        "complementarity": float(np.abs(lam * jump).max(initial=0.0) / (l_scale * jump_scale)),
    }


def componentwise_backward_error(residual, scale):
    """max_i |r_i| / scale_i (Oettli–Prager, as crates/sdcrack-core/src/linalg.rs): 0/0 counts as 0, a non-zero residual
    over a zero scale as ∞, a NaN residual gives NaN."""
    import numpy as np

    r = np.abs(np.asarray(residual, dtype=float))
    s = np.asarray(scale, dtype=float)
    if np.isnan(r).any():
        return float("nan")
    nz = r != 0.0
    if not nz.any():
        return 0.0
    with np.errstate(divide="ignore"):
        q = np.where(s[nz] > 0.0, r[nz] / np.where(s[nz] > 0.0, s[nz], 1.0), np.inf)
    return float(q.max())
