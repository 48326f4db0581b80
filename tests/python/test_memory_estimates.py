"""The campaign's memory estimates (tools/workflow/prepare.py's own_memory_mb, from `sdcrack check
--json`) against the peaks measured in a real nightly (tests/data/nightly-peaks.tsv: every
repository scene at levels 0-5): each job's own estimate is at least its measured peak, and
halving the estimates makes that false, so the check can fail. Under Slurm each job also asks
for Snakemake's share; test_slurm.py checks the whole requests against sacct."""

import csv
import json
import os
import pathlib
import re
import subprocess

import pytest
from prepare import PYTHON_JOB_MB, memory_request_mb, own_memory_mb, with_absolute_mesh
from scene_text import set_key

ROOT = pathlib.Path(__file__).resolve().parents[2]
EXE = pathlib.Path(os.environ.get("SDCRACK_BIN", ROOT / "target" / "release" / "sdcrack")).resolve()
PEAKS = ROOT / "tests" / "data" / "nightly-peaks.tsv"

pytestmark = pytest.mark.skipif(not EXE.is_file(), reason=f"no sdcrack binary at {EXE}")


def peaks():
    """[(scene, job kind, level or None, max_rss MB)] of the nightly's jobs."""
    rows = [line for line in PEAKS.read_text().splitlines() if not line.startswith("#")]
    out = []
    for r in csv.DictReader(rows, delimiter="\t"):
        job = r["job"]
        m = re.search(r"-l(\d+)", job)
        kind = "check" if job.startswith("check-") else job.split("-")[0]
        out.append((r["scene"], kind, m.group(1) if m else None, float(r["max_rss_mb"])))
    return out


@pytest.fixture(scope="module")
def plans(tmp_path_factory):
    """`sdcrack check --json` of each scene of the nightly at its levels 0-5."""
    d = tmp_path_factory.mktemp("scenes")
    out = {}
    for name in sorted({p[0] for p in peaks()}):
        src = ROOT / "scenes" / f"{name}.toml"
        if not src.is_file():
            src = ROOT / "tests" / "data" / "scenes" / f"{name}.toml"
        text = set_key(src.read_text(), "levels", "[0, 1, 2, 3, 4, 5]")
        # a scene on a mesh file names it relative to its own folder: the campaign's absolute copy
        text, _ = with_absolute_mesh(str(src), text, None)
        scene = d / f"{name}.toml"
        scene.write_text(text)
        r = subprocess.run([str(EXE), "check", str(scene), "--json"], capture_output=True,
                           text=True)
        assert r.returncode == 0, r.stderr
        out[name] = json.loads(r.stdout)
    return out


def below(plans, scale=1.0):
    """The jobs whose own estimate × scale is below their measured peak."""
    return [(scene, kind, level, round(own_memory_mb(kind, plans[scene], level) * scale), peak)
            for scene, kind, level, peak in peaks()
            if own_memory_mb(kind, plans[scene], level) * scale < peak]


def test_every_own_estimate_is_above_the_nightly_peak(plans):
    assert len(peaks()) > 500
    assert {p[1] for p in peaks()} == {"solver", "dolfinx", "freefem", "check", "report"}
    assert below(plans) == []


def test_halved_estimates_fall_below_measured_peaks(plans):
    halved = below(plans, 0.5)
    kinds = {k for _, k, _, _, _ in halved}
    # the solver at levels 4-5, dolfinx from level 0 on, the checks and the reports
    assert {"solver", "dolfinx", "check", "report"} <= kinds, halved
    assert len(halved) > 100, len(halved)


def test_a_request_adds_snakemake_to_the_own_estimate():
    plan = {"memory_mb": {"0": 129, "2": 134}, "mesh_memory_mb": {"0": 1, "2": 6}}
    assert own_memory_mb("solver", plan, 2) == 134
    assert own_memory_mb("dolfinx", plan, 0) == PYTHON_JOB_MB["dolfinx"] + 1
    assert own_memory_mb("report", plan) == PYTHON_JOB_MB["report"] + 6
    assert memory_request_mb(134) == 434


def test_the_elastic_report_counts_its_mesh_part_twice(plans):
    """An elastic scene's report (both references' vector fields and stresses on the finest mesh)
    peaked above the scalar report's estimate at level 5 (elastic-williams-open, 890 MB against
    856 MB): prepare.py counts its part that grows with the mesh twice; its reference jobs keep the
    scalar references' estimates, above their peaks."""
    plan = plans["elastic-williams-open"]
    assert plan["problem"] == "elasticity"
    (peak,) = [p[3] for p in peaks() if p[:2] == ("elastic-williams-open", "report")]
    scalar = {k: v for k, v in plan.items() if k != "problem"}
    assert own_memory_mb("report", scalar) < peak <= own_memory_mb("report", plan)
    kinds = {p[1] for p in peaks() if p[0] == "elastic-williams-open"}
    assert kinds == {"dolfinx", "freefem", "solver", "report"}


def test_the_elastic_solver_counts_its_mesh_part_four_times(plans):
    """The smooth-domain method's solver job (the AFW system's LDLᵀ factor) peaked at 2309 MB at
    level 5 of elastic-williams-open, 3.2 times the scalar solver's estimate of that mesh (728
    MB): prepare.py counts its part that grows with the mesh ELASTIC_SOLVER_MESH_FACTOR times,
    above every measured peak (levels 3-5, uniform and graded), where the scalar estimate is
    below each of them."""
    from prepare import ELASTIC_SOLVER_MESH_FACTOR
    assert ELASTIC_SOLVER_MESH_FACTOR == 4
    rows = [p for p in peaks() if p[0].startswith("elastic-") and p[1] == "solver"]
    assert sorted({(p[0], p[2]) for p in rows}) == [
        (s, lv) for s in ("elastic-williams-open", "elastic-williams-open-graded")
        for lv in ("3", "4", "5")]
    short = []
    for scene, _, level, peak in rows:
        plan = plans[scene]
        assert plan["problem"] == "elasticity" and plan["multipliers"] == ["M1star"]
        assert own_memory_mb("solver", plan, level) >= peak, (scene, level)
        scalar = {k: v for k, v in plan.items() if k != "problem"}
        if own_memory_mb("solver", scalar, level) < peak:
            short.append((scene, level))
    assert sorted(short) == [(s, lv) for s in ("elastic-williams-open",
                                                "elastic-williams-open-graded") for lv in "345"]
