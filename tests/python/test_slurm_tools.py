"""tools/workflow/slurm_accounting.py and slurm_watch.py on made-up Slurm output (fake sacct,
squeue and sinfo on PATH): their arithmetic and verdicts, without a cluster (test_slurm.py runs
them on a real one)."""

import os
import pathlib
import subprocess
import sys

import pytest

import slurm_accounting
import slurm_watch

ROOT = pathlib.Path(__file__).resolve().parents[2]


def fake(tmp_path, monkeypatch, **outputs):
    """Commands on PATH that print the given text (name → stdout)."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir(exist_ok=True)
    for name, text in outputs.items():
        (bin_dir / name).write_text(f"#!/bin/sh\ncat <<'EOF'\n{text}\nEOF\n")
        (bin_dir / name).chmod(0o755)
    monkeypatch.setenv("PATH", f"{bin_dir}:{os.environ['PATH']}")


def test_sizes_in_mb():
    assert slurm_accounting.size_mb("205748K") == pytest.approx(200.92578125)
    assert slurm_accounting.size_mb("300M") == 300.0
    assert slurm_accounting.size_mb("1.5G") == 1536.0
    assert slurm_accounting.size_mb("300Mn") == 300.0
    assert slurm_accounting.size_mb("") == 0.0
    with pytest.raises(slurm_accounting.Refused):
        slurm_accounting.size_mb("12Q")


def campaign_with_logs(tmp_path, jobs):
    """A campaign folder whose Slurm logs name `jobs`: {id: (rule, wildcards)}."""
    out = tmp_path / "campaign"
    for job_id, (rule, wildcards) in jobs.items():
        d = out / ".snakemake" / "slurm_logs" / f"rule_{rule}" / wildcards
        d.mkdir(parents=True, exist_ok=True)
        (d / f"{job_id}.log").write_text("")
    return out


SACCT = "\n".join([
    "7|COMPLETED|500M|", "7.batch|COMPLETED||135000K", "7.extern|COMPLETED||1000K",
    "7.0|COMPLETED||150000K",
    "8|COMPLETED|400M|", "8.batch|COMPLETED||135000K", "8.0|COMPLETED||300000K",
    "9|COMPLETED|2000M|", "9.batch|COMPLETED||135000K", "9.0|COMPLETED||130000K",
])


def test_memory_verdict_judges_each_job_against_its_summed_steps(tmp_path, monkeypatch):
    out = campaign_with_logs(tmp_path, {"7": ("solver", "s_1_broken_M1_consistent_"),
                                        "8": ("reference", "s_dolfinx_2"),
                                        "9": ("report", "s")})
    fake(tmp_path, monkeypatch, sacct=SACCT)
    jobs, problems = slurm_accounting.judge(str(out), 2.0)
    peaks = {j["slurm_job"]: j["peak_mb"] for j in jobs}
    # batch + step 0; the extern step is no process of the job's
    assert peaks == {7: pytest.approx(278.3, abs=0.1), 8: pytest.approx(424.8, abs=0.1),
                     9: pytest.approx(258.8, abs=0.1)}
    assert [j["level"] for j in jobs] == ["1", "2", "-"]
    assert len(problems) == 2
    assert "Slurm job 8 (reference s_dolfinx_2): requested 400 MB, below its peak 425 MB" in problems[0]
    assert "Slurm job 9 (report s): requested 2000 MB, more than 2× its peak 259 MB" in problems[1]
    # the command line: FAIL, exit 1, the table and the count
    r = subprocess.run([sys.executable, str(ROOT / "tools" / "workflow" / "slurm_accounting.py"),
                        str(out)], capture_output=True, text=True)
    assert r.returncode == 1, r.stdout + r.stderr
    assert "3 Slurm jobs for 3 Snakemake jobs" in r.stdout
    assert "memory requests: FAIL (2 problem(s) in 3 jobs" in r.stdout


def test_a_job_run_twice_and_a_cancelled_one_are_said(tmp_path, monkeypatch):
    out = campaign_with_logs(tmp_path, {"7": ("solver", "s_1_broken_M1_consistent_"),
                                        "8": ("solver", "s_1_broken_M1_consistent_")})
    fake(tmp_path, monkeypatch, sacct="7|CANCELLED by 0|600M|\n7.batch|CANCELLED||135000K\n"
         "8|COMPLETED|600M|\n8.batch|COMPLETED||135000K\n8.0|COMPLETED||150000K")
    r = subprocess.run([sys.executable, str(ROOT / "tools" / "workflow" / "slurm_accounting.py"),
                        str(out)], capture_output=True, text=True)
    assert r.returncode == 1
    assert ("2 Slurm jobs for 1 Snakemake jobs; run more than once: "
            "solver s_1_broken_M1_consistent_ (2×)") in r.stdout
    assert "Slurm job 7 (solver s_1_broken_M1_consistent_) ended CANCELLED" in r.stdout


def test_no_slurm_logs_is_refused(tmp_path):
    r = subprocess.run([sys.executable, str(ROOT / "tools" / "workflow" / "slurm_accounting.py"),
                        str(tmp_path)], capture_output=True, text=True)
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and "no Slurm logs" in r.stderr


def test_the_watcher_stops_only_a_campaign_no_node_can_serve(tmp_path, monkeypatch):
    out = str(tmp_path)
    pending = f"11|PENDING|Resources|local|{out}\n12|PENDING|Priority|local|{out}"
    fake(tmp_path, monkeypatch, squeue=pending, sinfo="n1|drained|maintenance\nn2|down*|Not responding")
    message = slurm_watch.stranded(out)
    assert message.startswith("campaign: stopped: 2 job(s) pending and no node of partition local")
    assert "n1 drained (reason: maintenance); n2 down* (reason: Not responding)" in message
    # a node that can still take jobs, a job still running, another campaign's jobs: go on
    fake(tmp_path, monkeypatch, sinfo="n1|drained|maintenance\nn2|mixed|none")
    assert slurm_watch.stranded(out) is None
    fake(tmp_path, monkeypatch, squeue=pending + f"\n13|RUNNING|None|local|{out}",
         sinfo="n1|draining|maintenance")
    assert slurm_watch.stranded(out) is None
    fake(tmp_path, monkeypatch, squeue="11|PENDING|Resources|local|/elsewhere",
         sinfo="n1|drained|maintenance")
    assert slurm_watch.stranded(out) is None


def test_the_sacct_shim_names_a_cancelled_job_as_the_plugin_knows_it(tmp_path, monkeypatch):
    """Snakemake's Slurm plugin 2.8.0 waited forever for a job sacct calls "CANCELLED by 0"."""
    fake(tmp_path, monkeypatch, sacct="39|CANCELLED by 0\n40|COMPLETED\n41|CANCELLED by 1001")
    shims = ROOT / "tools" / "workflow" / "slurm-shims"
    env = dict(os.environ, PATH=f"{shims}:{os.environ['PATH']}")
    r = subprocess.run(["sacct", "-X", "--parsable2"], env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["39|CANCELLED", "40|COMPLETED", "41|CANCELLED"]
    # sacct's failure is the shim's
    (tmp_path / "bin" / "sacct").write_text("#!/bin/sh\necho 'sacct: error: down' >&2\nexit 1\n")
    r = subprocess.run(["sacct"], env=env, capture_output=True, text=True)
    assert r.returncode == 1 and "down" in r.stderr


def test_the_real_cluster_tests_run_in_the_nightly_not_in_ci_test():
    """test_slurm.py (~5.5 min on 2 cores) is left out of ci/test, which must stay under 25
    minutes, and run by the nightly's slurm job after ci/slurm-campaign (issue 42)."""
    import shlex

    import yaml  # python3-yaml, installed by ci/setup

    ci_test = (ROOT / "ci" / "test").read_text().replace("\\\n", " ")
    pytest_lines = [line for line in ci_test.splitlines()
                    if "-m pytest" in line and not line.lstrip().startswith("#")]
    assert len(pytest_lines) == 1, pytest_lines
    words = shlex.split(pytest_lines[0])
    assert "--ignore=tests/python/test_slurm.py" in words and "tests/python" in words
    jobs = yaml.safe_load((ROOT / ".github" / "workflows" / "nightly.yml").read_text())["jobs"]
    runs = [step.get("run", "") for step in jobs["slurm"]["steps"]]
    campaign = next(i for i, r in enumerate(runs) if "ci/slurm-campaign" in r)
    tests = next(i for i, r in enumerate(runs) if "-m pytest" in r
                 and "tests/python/test_slurm.py" in r)
    assert campaign < tests
