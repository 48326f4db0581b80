"""tools/campaign as a Snakemake workflow (tools/workflow/Snakefile): job list, same numbers as one
process, incremental reruns, resuming a killed campaign, failing jobs in the index.

Runs on two small scenes derived from the repository's (closed-exact and mixed at levels 0-2,
mixed with two δ), so that the whole file takes about two minutes on 2 cores. Needs the workflow
venv of ci/setup (.venv-workflow/) and an sdcrack binary with `merge` (SDCRACK_BIN, else
target/release/sdcrack); skipped with the reason otherwise.
"""

import fcntl
import filecmp
import json
import os
import pathlib
import re
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from conftest import run_env
from scene_text import add_key, set_key

ROOT = pathlib.Path(__file__).resolve().parents[2]
EXE = pathlib.Path(os.environ.get("SDCRACK_BIN", ROOT / "target" / "release" / "sdcrack")).resolve()
SNAKEMAKE = ROOT / ".venv-workflow" / "bin" / "snakemake"
CAMPAIGN = ROOT / "tools" / "campaign"
h5py = pytest.importorskip("h5py")

LEVELS = [0, 1, 2]
U_SPACES, MULTIPLIERS, P_MASSES, TOOLS = 2, 3, 2, 2
SOLVER_JOBS = len(LEVELS) * U_SPACES * MULTIPLIERS * P_MASSES  # per scene
REFERENCE_JOBS = len(LEVELS) * TOOLS
# per level of a scene with [exact]: one per u space, one for the references (mixed has none)
CHECK_JOBS = len(LEVELS) * (U_SPACES + 1)
EXACT = ("closed-exact",)


def _skip_reason():
    if not SNAKEMAKE.is_file():
        return f"no workflow venv ({SNAKEMAKE}): run ci/setup"
    if not EXE.is_file():
        return f"no sdcrack binary at {EXE} (cargo build --release, or set SDCRACK_BIN)"
    if subprocess.run([str(EXE), "merge", "--help"], capture_output=True).returncode != 0:
        return f"{EXE} has no `merge` subcommand (an older build)"
    return None


pytestmark = pytest.mark.skipif(_skip_reason() is not None, reason=str(_skip_reason()))


def campaign(*args, binary=EXE, check=None, **kw):
    env = dict(os.environ, SDCRACK_BIN=str(binary))
    r = subprocess.run([str(CAMPAIGN), *map(str, args)], env=env, capture_output=True, text=True,
                       timeout=600, **kw)
    if check is not None:
        assert r.returncode == check, r.stdout[-4000:] + r.stderr[-4000:]
    return r


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    """Two small scenes, and an expectations file for them (the repository's bounds are at
    level 4, which these scenes do not have)."""
    d = tmp_path_factory.mktemp("scenes")
    out = []
    for name in ("closed-exact", "mixed"):
        text = set_key((ROOT / "scenes" / f"{name}.toml").read_text(), "levels",
                       "[" + ", ".join(map(str, LEVELS)) + "]")
        if name == "mixed":
            text = set_key(text, "deltas", "[1e-2, 0.0]")
        (d / f"{name}.toml").write_text(text)
        out.append(d / f"{name}.toml")
    (d / "expectations.toml").write_text(
        "# test bounds at level 2 of the small exact closed crack\n"
        '[[expectation]]\nscene = "closed-exact"\nu_space = "*"\nmultiplier = "*"\n'
        'quantity = "u_l2"\nlevel = 2\nmax_error = 1e-1\n')
    return out, d / "expectations.toml"


@pytest.fixture(scope="module")
def full_run(scenes, tmp_path_factory):
    """One uninterrupted campaign on both scenes, --cores 2."""
    files, expectations = scenes
    out = tmp_path_factory.mktemp("campaign") / "out"
    t = time.monotonic()
    r = campaign(*files, "--out", out, "--cores", 2, "--expectations", expectations)
    print(f"campaign: {time.monotonic() - t:.1f} s", file=sys.stderr)
    return out, r


@pytest.fixture(scope="module")
def single_run(scenes, tmp_path_factory):
    """The single-process path: `sdcrack run SCENE --out X`, then compare/sdcompare."""
    files, expectations = scenes
    out = tmp_path_factory.mktemp("single")
    for f in files:
        r = subprocess.run([str(EXE), "run", str(f), "--out", str(out), "--quiet"],
                           capture_output=True, text=True)
        assert r.returncode in (0, 3), r.stderr
        name = f.stem
        r = subprocess.run(["/usr/bin/python3", str(ROOT / "compare" / "sdcompare"), str(out / name),
                            "--quiet", "--expectations", str(expectations)],
                           capture_output=True, text=True)
        assert r.returncode in (0, 1, 3), r.stderr
    return out


def strip_timings(cases):
    return [{k: v for k, v in c.items() if k != "timings_s"} for c in cases]


def h5_items(path):
    items = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                items[name] = (obj[()], {k: obj.attrs[k] for k in obj.attrs})
        f.visititems(visit)
    return items


def assert_same_fields(a, b):
    ia, ib = h5_items(a), h5_items(b)
    assert sorted(ia) == sorted(ib), (a, b)
    for name in ia:
        (da, attrs_a), (db, attrs_b) = ia[name], ib[name]
        assert da.dtype == db.dtype and np.array_equal(da, db), (a, name)
        assert sorted(attrs_a) == sorted(attrs_b), (a, name)
        for k in attrs_a:
            assert np.array_equal(attrs_a[k], attrs_b[k]), (a, name, k)


def assert_same_results(a, b):
    """Two results folders of one scene hold the same numbers (timings and provenance aside)."""
    sa, sb = (json.loads((x / "summary.json").read_text()) for x in (a, b))
    assert sa["plan"] == sb["plan"]
    assert strip_timings(sa["cases"]) == strip_timings(sb["cases"])
    assert (a / "scene.toml").read_bytes() == (b / "scene.toml").read_bytes()
    assert_same_fields(a / "fields.h5", b / "fields.h5")
    xa = sorted(p.name for p in (a / "fields").glob("*.xdmf"))
    assert xa and xa == sorted(p.name for p in (b / "fields").glob("*.xdmf"))
    for name in xa:
        assert (a / "fields" / name).read_text() == (b / "fields" / name).read_text(), name
    tools = sorted(t for t in ("dolfinx", "freefem") if (b / t).is_dir())
    assert tools == sorted(t for t in ("dolfinx", "freefem") if (a / t).is_dir()) == \
        sorted(sa["plan"].get("references", tools))
    for tool in tools:
        ra, rb = (json.loads((x / tool / "summary.json").read_text()) for x in (a, b))
        assert strip_timings(ra["cases"]) == strip_timings(rb["cases"]), tool
        if (b / tool / "fields.h5").is_file():
            assert_same_fields(a / tool / "fields.h5", b / tool / "fields.h5")
        texts = sorted(p.name for p in (b / tool).glob("*.txt"))
        assert texts == sorted(p.name for p in (a / tool).glob("*.txt"))
        for name in texts:  # u per cracked-mesh vertex
            assert (a / tool / name).read_bytes() == (b / tool / name).read_bytes(), (tool, name)
    if tools:  # the meshes the references ran on
        ma = sorted(p.relative_to(a) for p in (a / "mesh").rglob("*") if p.is_file())
        assert ma and ma == sorted(p.relative_to(b) for p in (b / "mesh").rglob("*") if p.is_file())
        for rel in ma:
            assert (a / rel).read_bytes() == (b / rel).read_bytes(), rel
    va, vb = (json.loads((x / "report" / "report.json").read_text()) for x in (a, b))
    assert va["verdict"] == vb["verdict"]


def expected_jobs(out, names):
    jobs = set()
    for name in names:
        for lv in LEVELS:
            for u in ("continuous", "broken"):
                for m in ("M0", "M1", "M1star"):
                    for pm in ("consistent", "lumped"):
                        jobs.add(("solver", f"shards/{name}/solver/l{lv}-{u}-{m}-{pm}"))
                if name in EXACT:
                    jobs.add(("check", f"checks/{name}/solver-l{lv}-{u}.json"))
            for tool in ("dolfinx", "freefem"):
                jobs.add(("reference", f"shards/{name}/{tool}/l{lv}"))
            if name in EXACT:
                jobs.add(("check", f"checks/{name}/references-l{lv}.json"))
        jobs.add(("report", name))
    return jobs


def dry_run_jobs(stdout):
    return {tuple(line.split()[:2]) for line in stdout.splitlines()
            if re.match(r"^  (solver|reference|check|report) ", line)}


def test_bad_arguments_one_line_exit_2(tmp_path):
    for args in (["--cores", "x"], ["--bogus"], ["--levels", "5-x"], [tmp_path / "missing.toml"],
                 ["--profile", "nosuch"]):
        r = campaign(*args, "--out", tmp_path / "o")
        assert r.returncode == 2, (args, r.stderr)
        assert len(r.stderr.strip().splitlines()) == 1 and r.stderr.startswith("campaign: "), r.stderr
    assert not (tmp_path / "o").exists()


def test_a_scene_named_like_a_campaign_folder_is_refused(scenes, tmp_path):
    """A scene named `checks` (or `shards`, `logs`, …) would write into the campaign's own
    folder: one line, exit 2, nothing run."""
    files, _ = scenes
    for reserved in ("checks", "shards"):
        scene = tmp_path / f"{reserved}.toml"
        scene.write_text(set_key(files[0].read_text(), "name", f'"{reserved}"'))
        r = campaign(scene, "--out", tmp_path / "out", "--dry-run", check=2)
        assert len(r.stderr.strip().splitlines()) == 1 and "cannot name a campaign folder" in r.stderr


def test_dry_run_lists_every_job(scenes, tmp_path):
    files, expectations = scenes
    r = campaign(*files, "--out", tmp_path / "out", "--dry-run", "--expectations", expectations,
                 check=0)
    jobs = dry_run_jobs(r.stdout)
    assert jobs == expected_jobs(tmp_path / "out", ["closed-exact", "mixed"])
    total = 2 * (SOLVER_JOBS + REFERENCE_JOBS + 1) + CHECK_JOBS
    assert len(jobs) == total == 95
    assert (f"campaign: dry run: {total} of {total} jobs would run "
            f"(solver {2 * SOLVER_JOBS}, reference {2 * REFERENCE_JOBS}, "
            f"check {CHECK_JOBS}, report 2)") in r.stdout
    # the Slurm profile parses under the pinned Snakemake and plans the same jobs
    r = campaign(*files, "--out", tmp_path / "out", "--dry-run", "--expectations", expectations,
                 "--profile", "slurm", check=0)
    assert dry_run_jobs(r.stdout) == jobs
    # nothing ran: only the inputs are there
    assert not (tmp_path / "out" / "shards").exists() and not (tmp_path / "out" / "mixed").exists()
    assert (tmp_path / "out" / "inputs" / "mixed.toml").read_bytes() == files[1].read_bytes()


# tools/campaign's default scenes (the README's main command), at their own levels
DEFAULT_SCENES = ("mixed", "closed-exact", "open-exact", "open-graded", "mixed-graded",
                  "open-smooth", "elastic-williams-open")


def test_the_default_campaign_runs_the_seven_scenes_and_the_elastic_one_at_its_levels(tmp_path):
    """Without SCENE arguments the campaign plans the six scalar scenes and
    scenes/elastic-williams-open.toml (issue 45, item 5) at the levels of each scene file: the
    elastic one's solver job per level (its one multiplier space, issue 46), reference jobs per
    tool and level and its report, no check job."""
    out = tmp_path / "out"
    r = campaign("--out", out, "--dry-run", check=0)
    config = json.loads((out / "inputs" / "config.dry-run.json").read_text())
    assert tuple(config["scenes"]) == DEFAULT_SCENES
    assert config["scene_files"]["elastic-williams-open"] == str(
        ROOT / "scenes" / "elastic-williams-open.toml")
    levels = [0, 1, 2, 3, 4]  # the scene file's `levels`
    assert config["plans"]["elastic-williams-open"]["levels"] == levels
    elastic = {j for j in dry_run_jobs(r.stdout) if "elastic-williams-open" in j[1]}
    assert elastic == ({("reference", f"shards/elastic-williams-open/{tool}/l{lv}")
                        for tool in ("dolfinx", "freefem") for lv in levels}
                       | {("solver", f"shards/elastic-williams-open/solver/l{lv}-elasticity-M1star")
                          for lv in levels}
                       | {("report", "elastic-williams-open")})


def test_same_numbers_as_one_process(full_run, single_run):
    out, r = full_run
    assert r.returncode in (0, 1), r.stdout[-3000:] + r.stderr[-3000:]
    for name in ("closed-exact", "mixed"):
        assert_same_results(out / name, single_run / name)
        verdict = json.loads((single_run / name / "report" / "report.json").read_text())["verdict"]
        assert f"  {verdict}  {out / name / 'report' / 'index.html'}" in r.stdout
    verdicts = [json.loads((single_run / n / "report" / "report.json").read_text())["verdict"]
                for n in ("closed-exact", "mixed")]
    assert r.returncode == (0 if verdicts == ["PASS", "PASS"] else 1)
    index = json.loads((out / "index.json").read_text())
    assert [(s["name"], s["verdict"]) for s in index["scenes"]] == \
        list(zip(("closed-exact", "mixed"), verdicts))
    assert f"index: {out / 'index.html'}" in r.stdout
    html = (out / "index.html").read_text()
    assert 'href="mixed/report/index.html"' in html
    # every job has its log, ending in its status line
    logs = sorted(p.name for p in (out / "logs" / "mixed").glob("*.log"))
    assert len(logs) == SOLVER_JOBS + REFERENCE_JOBS + 1  # no [exact]: no check job
    logs = sorted(p.name for p in (out / "logs" / "closed-exact").glob("*.log"))
    assert len(logs) == SOLVER_JOBS + REFERENCE_JOBS + CHECK_JOBS + 1
    assert re.search(r"campaign: sdcompare done \(exit [01]\)$",
                     (out / "logs" / "mixed" / "report.log").read_text().strip())


def test_second_run_reruns_nothing(full_run, scenes):
    out, _ = full_run
    files, expectations = scenes
    summaries = sorted(out.glob("shards/*/*/*/*/summary.json")) + \
        sorted(out.glob("shards/*/*/*/*/*/summary.json")) + sorted(out.glob("*/summary.json"))
    assert len(summaries) == 2 * (SOLVER_JOBS + REFERENCE_JOBS + 1)
    before = {p: (p.stat().st_ino, p.stat().st_mtime_ns) for p in summaries}
    r = campaign(*files, "--out", out, "--cores", 2, "--expectations", expectations)
    assert r.returncode in (0, 1), r.stderr[-3000:]
    assert "campaign: nothing to rerun, all 95 jobs up to date" in r.stdout
    assert before == {p: (p.stat().st_ino, p.stat().st_mtime_ns) for p in summaries}
    # and a dry run says the same
    r = campaign(*files, "--out", out, "--dry-run", "--expectations", expectations, check=0)
    assert "campaign: dry run: nothing to rerun, all 95 jobs up to date" in r.stdout


def test_dry_run_after_changes_lists_what_depends_on_them(full_run, scenes, tmp_path):
    """An edited scene reruns that scene's jobs only, a rebuilt binary every job; a dry run says
    so without touching the campaign's inputs."""
    out, _ = full_run
    files, expectations = scenes
    scene_copy = out / "inputs" / "mixed.toml"
    stamp = (scene_copy.read_bytes(), scene_copy.stat().st_mtime_ns)
    edited = tmp_path / "mixed.toml"
    edited.write_text(set_key(files[1].read_text(), "deltas", "[1e-1, 0.0]"))
    r = campaign(files[0], edited, "--out", out, "--dry-run", "--expectations", expectations,
                 check=0)
    assert dry_run_jobs(r.stdout) == expected_jobs(out, ["mixed"])
    assert (scene_copy.read_bytes(), scene_copy.stat().st_mtime_ns) == stamp
    rebuilt = tmp_path / "sdcrack"
    shutil.copyfile(EXE, rebuilt)
    with open(rebuilt, "ab") as fh:
        fh.write(b"\0")  # other bytes, same program
    rebuilt.chmod(0o755)
    r = campaign(*files, "--out", out, "--dry-run", "--expectations", expectations,
                 binary=rebuilt, check=0)
    assert dry_run_jobs(r.stdout) == expected_jobs(out, ["closed-exact", "mixed"])
    assert filecmp.cmp(out / "inputs" / "sdcrack", EXE, shallow=False)


def test_index_of_downloaded_scene_folders(full_run, tmp_path):
    """tools/campaign_index.py DIR on scene folders put together (the GitHub nightly's last job)."""
    out, _ = full_run
    for name in ("closed-exact", "mixed"):
        shutil.copytree(out / name / "report", tmp_path / name / "report")
    shutil.copytree(out / "logs" / "mixed", tmp_path / "logs" / "mixed")
    r = subprocess.run([sys.executable, str(ROOT / "tools" / "campaign_index.py"), str(tmp_path)],
                       env=run_env(), capture_output=True, text=True)
    index = json.loads((tmp_path / "index.json").read_text())
    want = {s["name"]: s["verdict"] for s in json.loads((out / "index.json").read_text())["scenes"]}
    assert {s["name"]: s["verdict"] for s in index["scenes"]} == want
    assert r.returncode == (0 if set(want.values()) == {"PASS"} else 1)
    # an expected scene without a folder is FAIL
    r = subprocess.run([sys.executable, str(ROOT / "tools" / "campaign_index.py"), str(tmp_path),
                        "--scene", "mixed", "--scene", "absent"], env=run_env(),
                       capture_output=True, text=True)
    assert r.returncode == 1
    assert "  FAIL  absent: no report" in r.stdout


def test_second_campaign_on_the_same_folder_is_refused(tmp_path, scenes):
    files, _ = scenes
    (tmp_path / "out").mkdir()
    with open(tmp_path / "out" / ".campaign.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        r = campaign(files[0], "--out", tmp_path / "out", "--dry-run")
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and "in use by another campaign" in r.stderr
    assert not (tmp_path / "out" / "inputs").exists()


def completed_shards(out):
    """Shard folders Snakemake has finished (it touches .snakemake_timestamp at the end)."""
    return {p.parent for p in out.glob("shards/*/*/*/.snakemake_timestamp")}


def test_killed_campaign_resumes(full_run, scenes, tmp_path):
    out = tmp_path / "out"
    files, expectations = scenes
    cmd = [str(CAMPAIGN), *map(str, files), "--out", str(out), "--cores", "2",
           "--expectations", str(expectations)]
    env = dict(os.environ, SDCRACK_BIN=str(EXE))
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    try:
        deadline = time.monotonic() + 300
        while len(completed_shards(out)) < 12:
            assert proc.poll() is None, "the campaign ended before it could be killed"
            assert time.monotonic() < deadline
            time.sleep(0.1)
        done = completed_shards(out)
        # let Snakemake record these as finished, and more jobs start
        while len(completed_shards(out)) < len(done) + 4:
            assert proc.poll() is None, "the campaign ended before it could be killed"
            time.sleep(0.1)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    assert not (out / "mixed" / "report").exists() or not (out / "closed-exact" / "report").exists()
    stamps = {}
    for shard in done:
        for summary in [*shard.glob("*/summary.json"), *shard.glob("*/*/summary.json")]:
            stamps[summary] = (summary.stat().st_ino, summary.stat().st_mtime_ns)
    assert len(stamps) == len(done)
    r = campaign(*files, "--out", out, "--cores", 2, "--expectations", expectations)
    assert r.returncode in (0, 1), r.stdout[-3000:] + r.stderr[-3000:]
    assert "nothing to rerun" not in r.stdout
    assert stamps == {p: (p.stat().st_ino, p.stat().st_mtime_ns) for p in stamps}, \
        "finished shards were rerun"
    full, _ = full_run
    for name in ("closed-exact", "mixed"):
        assert_same_results(out / name, full / name)
    assert json.loads((out / "index.json").read_text())["verdict"] == \
        json.loads((full / "index.json").read_text())["verdict"]


def test_failed_job_shows_in_the_index(scenes, tmp_path):
    """A solver job that fails (exit 1) leaves no shard folder; its scene is FAIL in the index,
    with the job's log; the campaign exits non-zero. The other jobs still run (--keep-going)."""
    files, expectations = scenes
    wrapper = tmp_path / "sdcrack-failing"
    wrapper.write_text(
        "#!/bin/sh\n"
        '# exits 1 for the solver shards of level 1, runs the real binary otherwise\n'
        'if [ "$1" = run ]; then prev=""\n'
        '  for a in "$@"; do\n'
        '    if [ "$prev" = --level ] && [ "$a" = 1 ]; then echo "wrapper: failing <level 1> on purpose" >&2; exit 1; fi\n'
        '    prev="$a"\n'
        "  done\n"
        "fi\n"
        f'exec "{EXE}" "$@"\n')
    wrapper.chmod(0o755)
    scene = tmp_path / "closed-exact.toml"
    scene.write_text(set_key(files[0].read_text(), "levels", "[0, 1]"))
    out = tmp_path / "out"
    r = campaign(scene, "--out", out, "--cores", 2, "--expectations", expectations,
                 binary=wrapper)
    assert r.returncode != 0
    failed = sorted(out.glob("shards/closed-exact/solver/l1-*"))
    assert failed == [], "a failed job leaves no shard folder"
    assert len(list(out.glob("shards/closed-exact/solver/l0-*"))) == SOLVER_JOBS // len(LEVELS)
    assert len(list(out.glob("shards/closed-exact/*/l1"))) == TOOLS  # the references ran
    assert not (out / "closed-exact").exists()
    index = json.loads((out / "index.json").read_text())
    (row,) = index["scenes"]
    assert row["name"] == "closed-exact" and row["verdict"] == "FAIL" and index["verdict"] == "FAIL"
    jobs = {j["job"] for j in row["failed_jobs"]}
    assert jobs == {f"solver-l1-{u}-{m}-{pm}" for u in ("continuous", "broken")
                    for m in ("M0", "M1", "M1star") for pm in ("consistent", "lumped")}
    job = row["failed_jobs"][0]
    assert "failing <level 1> on purpose" in job["tail"] and "failed (exit 1)" in job["tail"]
    html = (out / "index.html").read_text()
    assert f'href="{job["log"]}"' in html
    assert "failing &lt;level 1&gt; on purpose" in html
    assert "  FAIL  closed-exact: no report" in r.stdout


def critical_path(out, *extra):
    return subprocess.run(["/usr/bin/python3", str(ROOT / "tools" / "workflow" / "critical_path.py"),
                           str(out), *extra], capture_output=True, text=True)


def test_critical_path_of_known_durations(tmp_path):
    """Scene a: shards 1 s and 5 s, report 2 s (path 7 s); scene b: shard 3 s, report 6 s (9 s)."""
    header = "s\th:m:s\tmax_rss\tmax_vms\tmax_uss\tmax_pss\tio_in\tio_out\tmean_load\tcpu_time\n"
    for scene, jobs in (("a", {"solver-l0-broken-M1-consistent": 1, "dolfinx-l1": 5, "report": 2}),
                        ("b", {"freefem-l0": 3, "report": 6})):
        (tmp_path / "benchmarks" / scene).mkdir(parents=True)
        for job, s in jobs.items():
            (tmp_path / "benchmarks" / scene / f"{job}.tsv").write_text(
                header + f"{s}\t0:00:0{s}\t1\t1\t1\t1\t0\t0\t0\t0.1\n")
    r = critical_path(tmp_path, "--json")
    assert r.returncode == 0, r.stderr
    cp = json.loads(r.stdout)
    assert (cp["critical_s"], cp["scene"], cp["shard"]) == (9.0, "b", "freefem-l0")
    assert cp["sum_s"] == 17.0 and cp["jobs"] == 5
    assert cp["per_rule_s"] == {"dolfinx": 5.0, "freefem": 3.0, "report": 8.0, "solver": 1.0}
    assert cp["per_scene"]["a"]["path_s"] == 7.0
    # the critical path's goals: report 8 of 17 s = 47 % > 15 %; path 9 s = 1.8 × the longest shard (5 s)
    assert [g["met"] for g in cp["goals"]] == [False, False]
    assert cp["goals"][0]["goal"].startswith(
        "compare tool (report and check jobs) 47.1 % of the job-seconds")
    assert "= 1.80 × the longest solver or reference job (5.0 s" in cp["goals"][1]["goal"]
    text = critical_path(tmp_path).stdout
    assert text.count(": MISSED\n") == 2
    # reports of 0.1 s: 0.2 of 9.2 s = 2.2 %, path 5.1 s = 1.02 × 5 s: both met
    for scene in ("a", "b"):
        (tmp_path / "benchmarks" / scene / "report.tsv").write_text(
            header + "0.1\t0:00:00\t1\t1\t1\t1\t0\t0\t0\t0.1\n")
    cp = json.loads(critical_path(tmp_path, "--json").stdout)
    assert [g["met"] for g in cp["goals"]] == [True, True], cp["goals"]
    r = critical_path(tmp_path / "nothing")
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1


def test_check_jobs_on_the_critical_path(tmp_path):
    """A check job starts when the last of its shards ends: scene a's check of level 0's broken
    solver shards (1 s and 2 s) takes 7 s, a chain of 9 s, longer than its dolfinx shard (5 s)
    and that level's reference check (1 s); with its report (2 s) the path is 11 s, against scene
    b's 9 s. The compare tool's share counts the checks: (2 + 6 + 7 + 1) of 27 s. The goal's
    yardstick stays the longest solver or reference job (5 s)."""
    header = "s\th:m:s\tmax_rss\tmax_vms\tmax_uss\tmax_pss\tio_in\tio_out\tmean_load\tcpu_time\n"
    for scene, jobs in (("a", {"solver-l0-broken-M1-consistent": 1,
                               "solver-l0-broken-M0-consistent": 2, "dolfinx-l1": 5, "report": 2,
                               "check-solver-l0-broken": 7, "check-references-l1": 1}),
                        ("b", {"freefem-l0": 3, "report": 6})):
        (tmp_path / "benchmarks" / scene).mkdir(parents=True)
        for job, s in jobs.items():
            (tmp_path / "benchmarks" / scene / f"{job}.tsv").write_text(
                header + f"{s}\t0:00:0{s}\t1\t1\t1\t1\t0\t0\t0\t0.1\n")
    cp = json.loads(critical_path(tmp_path, "--json").stdout)
    assert (cp["critical_s"], cp["scene"], cp["shard"], cp["check"]) == (
        11.0, "a", "solver-l0-broken-M0-consistent", "check-solver-l0-broken")
    assert (cp["shard_s"], cp["check_s"], cp["report_s"]) == (2.0, 7.0, 2.0)
    assert cp["per_rule_s"]["check"] == 8.0 and cp["sum_s"] == 27.0
    assert cp["goals"][0]["goal"].startswith(
        "compare tool (report and check jobs) 59.3 % of the job-seconds")
    assert "= 2.20 × the longest solver or reference job (5.0 s" in cp["goals"][1]["goal"]
    # the reference check follows dolfinx-l1: 5 + 1 s, a path of 8 s once the solver check is fast
    (tmp_path / "benchmarks" / "a" / "check-solver-l0-broken.tsv").write_text(
        header + "0.5\t0:00:00\t1\t1\t1\t1\t0\t0\t0\t0.1\n")
    cp = json.loads(critical_path(tmp_path, "--json").stdout)
    assert cp["per_scene"]["a"]["path_s"] == 8.0
    assert (cp["per_scene"]["a"]["shard"], cp["per_scene"]["a"]["check"]) == (
        "dolfinx-l1", "check-references-l1")
    text = critical_path(tmp_path).stdout
    assert "check-references-l1" in text


def test_every_job_is_measured(full_run):
    """Snakemake measures every job (benchmark files), and the critical path is the longest
    shard plus the report of one scene, at most the sum of all jobs."""
    out, _ = full_run
    r = critical_path(out, "--json")
    assert r.returncode == 0, r.stderr
    cp = json.loads(r.stdout)
    assert cp["jobs"] == 2 * (SOLVER_JOBS + REFERENCE_JOBS + 1) + CHECK_JOBS
    assert cp["per_rule_s"]["check"] > 0
    assert 0 < cp["critical_s"] < cp["sum_s"]
    assert cp["scene"] in ("closed-exact", "mixed") and cp["report_s"] > 0


def test_the_pinned_engine_is_installed():
    """ci/setup's pins are what the venv holds: Snakemake and its Slurm executor plugin."""
    setup = (ROOT / "ci" / "setup").read_text()
    pins = dict(re.findall(r"^(SNAKEMAKE_VERSION|SLURM_PLUGIN_VERSION)=(\S+)$", setup, re.M))
    assert set(pins) == {"SNAKEMAKE_VERSION", "SLURM_PLUGIN_VERSION"}
    r = subprocess.run([str(SNAKEMAKE), "--version"], capture_output=True, text=True)
    assert r.stdout.strip() == pins["SNAKEMAKE_VERSION"]
    r = subprocess.run([str(SNAKEMAKE.parent / "python"), "-c",
                        "import importlib.metadata as m; "
                        "print(m.version('snakemake-executor-plugin-slurm'))"],
                       capture_output=True, text=True)
    assert r.stdout.strip() == pins["SLURM_PLUGIN_VERSION"], r.stderr
    constraints = (ROOT / "tools" / "workflow" / "constraints.txt").read_text()
    assert f"snakemake=={pins['SNAKEMAKE_VERSION']}" in constraints


def test_a_scene_on_a_mesh_file_runs_from_its_copy(tmp_path):
    """The copy of a scene with `mesh = { gmsh = "meshes/….msh" }` in OUT/inputs/ names the mesh
    file by its absolute path (it is relative to the scene file) and records its sha256, and the
    workflow's plan of it (sdcrack check on the copy) succeeds."""
    import hashlib

    src = tmp_path / "elsewhere"
    shutil.copytree(ROOT / "scenes" / "meshes", src / "meshes")
    scene = src / "user-mesh.toml"
    shutil.copyfile(ROOT / "scenes" / "user-mesh.toml", scene)
    r = campaign(scene, "--out", tmp_path / "out", "--levels", "0-1", "--dry-run", check=0)
    copy = (tmp_path / "out" / "inputs" / "user-mesh.toml").read_text()
    mesh = src / "meshes" / "trapezoid-two-cracks.msh"
    assert f'gmsh = "{mesh}"' in copy, copy
    digest = hashlib.sha256(mesh.read_bytes()).hexdigest()
    assert copy.rstrip().endswith(f"# mesh file sha256: {digest}"), copy[-200:]
    jobs = dry_run_jobs(r.stdout)
    # levels 0-1 × 2 u spaces × 3 multipliers × 2 p masses, 2 tools × 2 levels, 1 report (no
    # [exact]: no check job)
    assert len(jobs) == 2 * 2 * 3 * 2 + 2 * 2 + 1, sorted(jobs)


def test_index_lines_say_what_converged_and_the_first_problem():
    """The index's one-line summaries, from a hand-made report.json: the variants whose every
    quantity converges and the range of their last rates, the expected failures, and the
    report's first reason."""
    import ci_script

    ci = ci_script.load("tools/campaign_index.py")

    def s(u, m, q, status, rate, pm="consistent"):
        return {"u_space": u, "multiplier": m, "p_mass": pm, "quantity": q, "status": status,
                "rates": [1.0, rate]}
    report = {"reasons": ["broken/M0 p_l2: rate 0.21 < 0.4", "second"], "series": [
        s("broken", "M1", "u_l2", "converges", 0.95), s("broken", "M1", "lambda_l2", "converges", 0.88),
        s("broken", "M1", "u_l2", "converges", 0.99, "lumped"),
        s("broken", "M1", "lambda_l2", "converges", 0.86, "lumped"),
        s("broken", "M0", "u_l2", "converges", 0.9), s("broken", "M0", "p_l2", "does not converge", 0.21),
        s("continuous", "M1", "u_l2", "expected failure", -0.03)]}
    # the last rates per p mass (sdcompare_lib/choices.py), never one range across them
    assert ci.converged_line(report) == ("2 of 4 variants converge (broken/M1, broken/M1/lumped); "
                                         "last rates per p mass: consistent u 0.95, λ 0.88; "
                                         "lumped u 0.99, λ 0.86; 1 declared expected failure(s)")
    assert ci.first_problem(report) == "broken/M0 p_l2: rate 0.21 < 0.4"
    assert ci.first_problem({"series": []}) is None
    assert ci.converged_line({"series": []}) == "no series measured"



# The p space axis: the broken-tangential p runs with the broken u only, so a plan's
# solver units are levels × u spaces × multipliers × p masses × p spaces minus every (continuous u,
# broken-tangential p); its shards and jobs carry "-ptangential" after the p mass, the continuous
# p's keep the names of before the axis.
BOTH_P_SPACES = '["continuous", "broken-tangential"]'


def served_solver_shards(name, levels, u_spaces=("continuous", "broken"),
                         p_spaces=("continuous", "broken-tangential")):
    """The solver shards a plan serves, counted here without the workflow's code."""
    shards = set()
    for lv in levels:
        for u in u_spaces:
            for m in ("M0", "M1", "M1star"):
                for pm in ("consistent", "lumped"):
                    for ps in p_spaces:
                        if u == "continuous" and ps == "broken-tangential":
                            continue  # sdcrack refuses the pair (exit 2)
                        suffix = "-ptangential" if ps == "broken-tangential" else ""
                        shards.add(f"shards/{name}/solver/l{lv}-{u}-{m}-{pm}{suffix}")
    return shards


def test_jobs_of_a_plan_with_and_without_p_spaces():
    """tools/workflow/prepare.py's list of a plan's jobs (which the Snakefile, the job count and
    tools/cases share): a plan without p spaces (or with the continuous p alone) has exactly the
    shard names of before the axis, in the same order; with both p spaces the broken u gets a
    -ptangential shard per multiplier and p mass, the continuous u none."""
    import ci_script

    prepare = ci_script.load("tools/workflow/prepare.py")
    plan = {"name": "s", "levels": [0, 1], "u_spaces": ["continuous", "broken"],
            "multipliers": ["M0", "M1", "M1star"], "p_masses": ["consistent", "lumped"],
            "references": ["dolfinx"], "exact": True}
    before = [f"shards/s/solver/l{lv}-{u}-{m}-{pm}" for lv in (0, 1)
              for u in ("continuous", "broken") for m in ("M0", "M1", "M1star")
              for pm in ("consistent", "lumped")]
    checks = [f"checks/s/solver-l{lv}-{u}.json" for lv in (0, 1) for u in ("continuous", "broken")]
    checks += [f"checks/s/references-l{lv}.json" for lv in (0, 1)]
    for p_spaces in (None, ["continuous"]):
        p = dict(plan) if p_spaces is None else dict(plan, p_spaces=p_spaces)
        assert prepare.jobs_of(p) == (before, ["shards/s/dolfinx/l0", "shards/s/dolfinx/l1"],
                                      checks, "s")
    both = dict(plan, p_spaces=["continuous", "broken-tangential"])
    solver, _, checks_both, _ = prepare.jobs_of(both)
    assert len(solver) == len(set(solver)) == 2 * (3 * 2 + 3 * 2 * 2) == 36
    assert set(solver) == served_solver_shards("s", (0, 1))
    assert not [s for s in solver if "-continuous-" in s and s.endswith("-ptangential")]
    assert checks_both == checks  # one check per level and u space, whatever the p spaces
    # a check's shards: its level's and u space's, both p spaces of the broken u
    assert prepare.solver_units(both, level="1", u_space="continuous") == [
        (1, "continuous", m, pm, "continuous") for m in ("M0", "M1", "M1star")
        for pm in ("consistent", "lumped")]
    assert len(prepare.solver_units(both, level=1, u_space="broken")) == 12
    # the broken-tangential p alone, on the broken u: a -ptangential shard per unit
    alone = dict(plan, u_spaces=["broken"], p_spaces=["broken-tangential"])
    assert prepare.jobs_of(alone)[0] == [s + "-ptangential" for s in before if "-broken-" in s]


def snakemake_dry_run(out):
    """Snakemake's own dry run of the campaign prepared in `out` (its config.dry-run.json), with
    the shell commands."""
    return subprocess.run([str(SNAKEMAKE), "--snakefile", str(ROOT / "tools" / "workflow" / "Snakefile"),
                           "--directory", str(out), "--configfile",
                           str(out / "inputs" / "config.dry-run.json"), "--cores", "1",
                           "--dry-run", "--printshellcmds"], env=run_env(), capture_output=True,
                          text=True)


def dry_run_blocks(text):
    """The jobs of `snakemake --dry-run --printshellcmds`: dicts of rule, input (a list), output,
    shell."""
    jobs, job = [], None
    for line in text.splitlines():
        m = re.match(r"^(?:local)?rule (\w+):$", line)
        if m:
            job = {"rule": m.group(1), "input": [], "output": "", "shell": ""}
            jobs.append(job)
        elif job is not None and (m := re.match(r"^\s+(input|output): (.*)$", line)):
            job[m.group(1)] = m.group(2).split(", ") if m.group(1) == "input" else m.group(2)
        elif job is not None and line.startswith("Shell command: "):
            job["shell"] = line[len("Shell command: "):]
    return jobs


def test_dry_run_of_both_p_spaces(scenes, tmp_path):
    """A scene with p_spaces = ["continuous", "broken-tangential"] and both u spaces: the dry run
    lists exactly the served solver jobs (no continuous u with the broken-tangential p), each
    broken-tangential job runs `--p-space broken-tangential` into its -ptangential shard, every
    continuous-p job `--p-space continuous` into the shard of before; each level's check of the
    broken u reads both p spaces' shards, and the report merges every shard."""
    files, expectations = scenes
    scene = tmp_path / "closed-exact.toml"
    scene.write_text(add_key(files[0].read_text(), "p_mass", "p_spaces", BOTH_P_SPACES))
    out = tmp_path / "out"
    r = campaign(scene, "--out", out, "--dry-run", "--expectations", expectations, check=0)
    jobs = dry_run_jobs(r.stdout)
    want = served_solver_shards("closed-exact", LEVELS)
    assert len(want) == len(LEVELS) * (MULTIPLIERS * P_MASSES + MULTIPLIERS * P_MASSES * 2) == 54
    assert {o for rule, o in jobs if rule == "solver"} == want
    assert not [o for _, o in jobs if "-continuous-" in o and o.endswith("-ptangential")]
    others = {j for j in expected_jobs(out, ["closed-exact"]) if j[0] != "solver"}
    assert jobs == {("solver", o) for o in want} | others
    checks = len(LEVELS) * (U_SPACES + 1)
    total = len(want) + REFERENCE_JOBS + checks + 1
    assert (f"campaign: dry run: {total} of {total} jobs would run (solver {len(want)}, "
            f"reference {REFERENCE_JOBS}, check {checks}, report 1)") in r.stdout
    assert sum(o.endswith("-ptangential") for _, o in jobs) == len(LEVELS) * MULTIPLIERS * P_MASSES
    # the jobs' commands: Snakemake's own dry run of the same config, with the shell commands
    sm = snakemake_dry_run(out)
    assert sm.returncode == 0, sm.stdout[-3000:] + sm.stderr[-3000:]
    blocks = dry_run_blocks(sm.stdout)
    solver = {b["output"]: b["shell"] for b in blocks if b["rule"] == "solver"}
    assert set(solver) == want
    for shard, shell in solver.items():
        lv, u, m, pm = re.fullmatch(r"shards/closed-exact/solver/l(\d+)-(\w+)-(\w+)-(\w+)"
                                    r"(?:-ptangential)?", shard).groups()
        ps = "broken-tangential" if shard.endswith("-ptangential") else "continuous"
        assert (f" --level {lv} --u-space {u} --multiplier {m} --p-mass {pm} --p-space {ps} "
                f"--solver-only --quiet --out {shard}") in shell, shell
    assert sum("--p-space broken-tangential" in s for s in solver.values()) == 18
    assert not [s for s in solver.values() if "--u-space continuous" in s
                and "--p-space broken-tangential" in s]
    checks = {b["output"]: {i for i in b["input"] if i.startswith("shards/")}
              for b in blocks if b["rule"] == "check_solver"}
    assert set(checks) == {f"checks/closed-exact/solver-l{lv}-{u}.json" for lv in LEVELS
                           for u in ("continuous", "broken")}
    for check, shards in checks.items():
        lv, u = re.fullmatch(r"checks/closed-exact/solver-l(\d+)-(\w+)\.json", check).groups()
        assert shards == {s for s in want if s.startswith(f"shards/closed-exact/solver/l{lv}-{u}-")}
        assert len(shards) == (12 if u == "broken" else 6)
    (report,) = [b for b in blocks if b["rule"] == "report"]
    assert {i for i in report["input"] if i.startswith("shards/closed-exact/solver/")} == want
    for shard in want:
        assert f" {shard}/closed-exact " in report["shell"]


def test_index_labels_of_the_p_spaces():
    """The index's variants tell the p spaces apart (broken/M1/ptangential,
    broken/M1/lumped/ptangential); the continuous p's labels are those of before the axis, whether
    report.json writes its p_space (a run with both p spaces) or not (a run without the axis)."""
    import ci_script

    ci = ci_script.load("tools/campaign_index.py")

    def s(u, m, q, status, rate, pm="consistent", ps=None):
        row = {"u_space": u, "multiplier": m, "p_mass": pm, "quantity": q, "status": status,
               "rates": [1.0, rate]}
        if ps is not None:
            row["p_space"] = ps
        return row
    assert ci.variant_key(s("broken", "M1", "u_l2", "converges", 1.0)) == "broken/M1"
    assert ci.variant_key(s("broken", "M1", "u_l2", "converges", 1.0, ps="continuous")) == \
        "broken/M1"
    assert ci.variant_key(s("broken", "M1", "u_l2", "converges", 1.0, "lumped", "continuous")) == \
        "broken/M1/lumped"
    assert ci.variant_key(s("broken", "M1", "u_l2", "converges", 1.0,
                            ps="broken-tangential")) == "broken/M1/ptangential"
    assert ci.variant_key(s("broken", "M1", "u_l2", "converges", 1.0, "lumped",
                            "broken-tangential")) == "broken/M1/lumped/ptangential"
    report = {"series": [
        s("broken", "M1", "u_l2", "converges", 0.95, ps="continuous"),
        s("broken", "M1", "u_l2", "converges", 0.99, ps="broken-tangential"),
        s("broken", "M1", "u_l2", "converges", 0.97, "lumped", "broken-tangential"),
        s("broken", "M0", "u_l2", "does not converge", 0.2, ps="broken-tangential"),
        s("continuous", "M1", "u_l2", "expected failure", -0.03, ps="continuous")]}
    assert ci.converged_line(report) == (
        "3 of 5 variants converge (broken/M1, broken/M1/lumped/ptangential, "
        "broken/M1/ptangential); last rates per p mass × p space: consistent/pcontinuous u 0.95; "
        "consistent/ptangential u 0.99; lumped/ptangential u 0.97; 1 declared expected failure(s)")
    # one p mass and one p space: one range, as before
    report["series"] = [x for x in report["series"] if x.get("p_space") != "broken-tangential"]
    report["series"].append(s("broken", "M1star", "u_l2", "converges", 0.99, ps="continuous"))
    assert "; last rates u 0.95–0.99; " in ci.converged_line(report)


def test_both_p_spaces_merge_as_one_process(tmp_path):
    """A campaign of a scene with both p spaces (closed-exact at levels 0-1, no references) runs
    the served solver jobs, its checks cover both p spaces' shards, and the merge gives the
    folder a single `sdcrack run` writes: same plan (with p_spaces), cases, fields and XDMF
    (the -ptangential ones included) and the same verdict."""
    text = (ROOT / "scenes" / "closed-exact.toml").read_text()
    for key, value in (("levels", "[0, 1]"), ("references", "[]")):
        text = set_key(text, key, value)
    scene = tmp_path / "closed-exact.toml"
    scene.write_text(add_key(text, "p_mass", "p_spaces", BOTH_P_SPACES))
    expectations = tmp_path / "expectations.toml"
    expectations.write_text(
        '[[expectation]]\nscene = "closed-exact"\nu_space = "*"\nmultiplier = "*"\n'
        'quantity = "u_l2"\nlevel = 1\nmax_error = 1.0\n')
    out = tmp_path / "out"
    r = campaign(scene, "--out", out, "--cores", 2, "--expectations", expectations)
    assert r.returncode in (0, 1), r.stdout[-3000:] + r.stderr[-3000:]
    shards = {str(p.relative_to(out)) for p in out.glob("shards/closed-exact/solver/*")}
    assert shards == served_solver_shards("closed-exact", (0, 1))
    for shard in shards:  # each shard holds its own p space's cases, and only those
        summary = json.loads((out / shard / "closed-exact" / "summary.json").read_text())
        ps = "broken-tangential" if shard.endswith("-ptangential") else "continuous"
        assert summary["plan"]["p_spaces"] == [ps]
        assert {c["p_space"] for c in summary["cases"]} == {ps}
    assert sorted(p.name for p in (out / "checks" / "closed-exact").iterdir()) == [
        f"solver-l{lv}-{u}.json" for lv in (0, 1) for u in ("broken", "continuous")]
    single = tmp_path / "single"
    r = subprocess.run([str(EXE), "run", str(out / "inputs" / "closed-exact.toml"), "--out",
                        str(single), "--quiet"], capture_output=True, text=True)
    assert r.returncode in (0, 3), r.stderr
    r = subprocess.run(["/usr/bin/python3", str(ROOT / "compare" / "sdcompare"),
                        str(single / "closed-exact"), "--quiet", "--expectations",
                        str(expectations)],
                       capture_output=True, text=True)
    assert r.returncode in (0, 1, 3), r.stderr
    assert_same_results(out / "closed-exact", single / "closed-exact")
    merged = json.loads((out / "closed-exact" / "summary.json").read_text())
    assert merged["plan"]["p_spaces"] == ["continuous", "broken-tangential"]
    assert len(merged["cases"]) == 2 * 18 * 5  # levels × served units × δ
    assert any("-ptangential" in c["fields_grid"] for c in merged["cases"])
    assert not [c for c in merged["cases"]
                if (c["u_space"], c["p_space"]) == ("continuous", "broken-tangential")]


# ----------------------------------------------------------------------------- elastic scenes
# An elastic scene (docs/elasticity.md): its plan (`sdcrack check --json`: "problem":
# "elasticity", empty scalar axes, its multipliers and deltas) gives a solver job per level and
# multiplier (the smooth-domain method with the δ sweep, issue 46; none for a scene listing no
# solver case), reference jobs per tool and level and a report job, no check job (`sdcompare
# --precompute` reads the scalar problem's shards only), and its report gets no --baseline (the
# elastic report refuses it).

def elastic_scene(tmp_path, name="elastic-patch", levels="[0, 1]", deltas=None):
    scene = tmp_path / f"{name}.toml"
    text = set_key((ROOT / "scenes" / f"{name}.toml").read_text(), "levels", levels)
    if deltas is not None:
        text = set_key(text, "deltas", deltas)
    scene.write_text(text)
    return scene


def test_jobs_of_an_elastic_plan():
    """prepare.py's jobs of an elastic plan (as `sdcrack check --json` prints it): the references
    per tool and level, no solver, no check although the scene has [exact]; the same plan
    without "problem" (a scalar plan with empty axes) would have its references' checks."""
    import ci_script

    prepare = ci_script.load("tools/workflow/prepare.py")
    plan = {"name": "e", "problem": "elasticity", "cases": 0, "levels": [0, 1], "u_spaces": [],
            "multipliers": [], "p_masses": [], "p_spaces": [], "deltas": [],
            "references": ["dolfinx", "freefem"], "exact": True}
    refs = ["shards/e/dolfinx/l0", "shards/e/dolfinx/l1", "shards/e/freefem/l0",
            "shards/e/freefem/l1"]
    assert prepare.is_elastic(plan)
    assert prepare.jobs_of(plan) == ([], refs, [], "e")
    assert prepare.reference_shards(plan, level="1") == ["shards/e/dolfinx/l1", "shards/e/freefem/l1"]
    scalar = {k: v for k, v in plan.items() if k != "problem"}
    assert not prepare.is_elastic(scalar)
    assert prepare.jobs_of(scalar)[2] == ["checks/e/references-l0.json",
                                          "checks/e/references-l1.json"]
    # with solver cases: one solver job per level and multiplier (the δ sweep inside), still no
    # check; a scalar plan has no elastic unit
    solved = dict(plan, cases=4, multipliers=["M1star"], deltas=[1e-3, 0.0])
    assert prepare.elastic_solver_units(solved) == [(0, "M1star"), (1, "M1star")]
    assert prepare.elastic_solver_units(solved, level="1") == [(1, "M1star")]
    assert prepare.elastic_solver_units(dict(scalar, multipliers=["M1"])) == []
    assert prepare.jobs_of(solved) == (["shards/e/solver/l0-elasticity-M1star",
                                        "shards/e/solver/l1-elasticity-M1star"], refs, [], "e")


def test_dry_run_of_an_elastic_scene(scenes, tmp_path):
    """The dry run of an elastic scene beside a scalar one: the elastic scene's solver jobs (one
    per level, its one multiplier space), reference jobs and report, the scalar scene's jobs as
    without it; the report merges the solver and reference shards and runs the compare tool
    without --precomputed and without --baseline (the scalar one keeps its baseline); the solver
    job runs `sdcrack run` of its level and multiplier without the scalar axes."""
    files, expectations = scenes
    scene = elastic_scene(tmp_path)
    out = tmp_path / "out"
    baseline = tmp_path / "old"
    for name in ("closed-exact", "elastic-patch"):
        (baseline / name).mkdir(parents=True)
    r = campaign(files[0], scene, "--out", out, "--dry-run", "--expectations", expectations,
                 "--baseline", baseline, check=0)
    jobs = dry_run_jobs(r.stdout)
    solver = {("solver", f"shards/elastic-patch/solver/l{lv}-elasticity-M1star") for lv in (0, 1)}
    elastic = {("reference", f"shards/elastic-patch/{t}/l{lv}") for t in ("dolfinx", "freefem")
               for lv in (0, 1)} | {("report", "elastic-patch")} | solver
    assert jobs == expected_jobs(out, ["closed-exact"]) | elastic
    total = SOLVER_JOBS + REFERENCE_JOBS + CHECK_JOBS + 1 + len(elastic)
    assert (f"campaign: dry run: {total} of {total} jobs would run (solver {SOLVER_JOBS + 2}, "
            f"reference {REFERENCE_JOBS + 4}, check {CHECK_JOBS}, report 2)") in r.stdout
    config = json.loads((out / "inputs" / "config.dry-run.json").read_text())
    assert config["plans"]["elastic-patch"]["problem"] == "elasticity"
    assert "problem" not in config["plans"]["closed-exact"]
    assert config["baselines"] == {"closed-exact": str(baseline / "closed-exact")}
    sm = snakemake_dry_run(out)
    assert sm.returncode == 0, sm.stdout[-3000:] + sm.stderr[-3000:]
    blocks = {b["output"]: b for b in dry_run_blocks(sm.stdout)}
    report = blocks["elastic-patch"]["shell"]
    assert "inputs/sdcrack merge " + " ".join(
        [f"shards/elastic-patch/solver/l{lv}-elasticity-M1star/elastic-patch" for lv in (0, 1)]
        + [f"shards/elastic-patch/{t}/l{lv}/elastic-patch" for t in ("dolfinx", "freefem")
           for lv in (0, 1)]) + " --out ." in report
    assert "--precomputed" not in report and "--baseline" not in report
    assert "--baseline" in blocks["closed-exact"]["shell"]
    assert "--precomputed" in blocks["closed-exact"]["shell"]
    shell = blocks["shards/elastic-patch/dolfinx/l1"]["shell"]
    assert shell.endswith("inputs/sdcrack reference inputs/elastic-patch.toml --tool dolfinx "
                          "--level 1 --out shards/elastic-patch/dolfinx/l1")
    shell = blocks["shards/elastic-patch/solver/l1-elasticity-M1star"]["shell"]
    assert shell.endswith("inputs/sdcrack run inputs/elastic-patch.toml --level 1 --multiplier "
                          "M1star --solver-only --quiet --out "
                          "shards/elastic-patch/solver/l1-elasticity-M1star")
    assert "--u-space" not in shell and "--p-mass" not in shell


def test_elastic_scene_campaign_equals_one_process(scenes, tmp_path):
    """The campaign of an elastic scene (the patch test at levels 0-1 with δ = 1e-3 and 0, both
    references) writes by its solver and reference jobs and merge the folder one `sdcrack run`
    writes (the summary's cases and numbers, every dataset of fields.h5, each reference's cases,
    u and crack files and fields, the mesh export) with the same verdict, and the index's row
    says what converged and the SDM's and the references' errors at the finest level. Levels 0-1
    are too few for a rate: INCONCLUSIVE, exit 0."""
    _, expectations = scenes
    scene = elastic_scene(tmp_path, deltas="[1e-3, 0.0]")
    out = tmp_path / "out"
    r = campaign(scene, "--out", out, "--cores", 2, "--expectations", expectations, check=0)
    single = tmp_path / "single"
    s = subprocess.run([str(EXE), "run", str(out / "inputs" / "elastic-patch.toml"), "--out",
                        str(single), "--quiet"], capture_output=True, text=True)
    assert s.returncode == 0, s.stderr
    s = subprocess.run(["/usr/bin/python3", str(ROOT / "compare" / "sdcompare"),
                        str(single / "elastic-patch"), "--quiet", "--expectations",
                        str(expectations)], capture_output=True, text=True)
    assert s.returncode == 3, s.stdout + s.stderr
    a, b = out / "elastic-patch", single / "elastic-patch"
    sa, sb = (json.loads((x / "summary.json").read_text()) for x in (a, b))
    for key in ("provenance", "wall_s", "fields_write_s", "shards"):
        sa.pop(key, None), sb.pop(key, None)
    ca, cb = strip_timings(sa.pop("cases")), strip_timings(sb.pop("cases"))
    assert sa == sb and sa["problem"] == "elasticity"
    assert ca == cb and [(c["level"], c["delta"]) for c in ca] == [
        (0, 1e-3), (0, 0.0), (1, 1e-3), (1, 0.0)]
    assert_same_fields(a / "fields.h5", b / "fields.h5")
    for tool in ("dolfinx", "freefem"):
        ra, rb = (json.loads((x / tool / "summary.json").read_text()) for x in (a, b))
        assert strip_timings(ra["cases"]) == strip_timings(rb["cases"]), tool
        texts = sorted(p.name for p in (b / tool).glob("*.txt"))
        assert texts == sorted(p.name for p in (a / tool).glob("*.txt")) and len(texts) == 4
        for name in texts:
            assert (a / tool / name).read_bytes() == (b / tool / name).read_bytes(), (tool, name)
        assert_same_fields(a / tool / "fields.h5", b / tool / "fields.h5")
    ma = sorted(p.relative_to(a) for p in (a / "mesh").rglob("*") if p.is_file())
    assert ma and ma == sorted(p.relative_to(b) for p in (b / "mesh").rglob("*") if p.is_file())
    for rel in ma:
        assert (a / rel).read_bytes() == (b / rel).read_bytes(), rel
    va, vb = (json.loads((x / "report" / "report.json").read_text()) for x in (a, b))
    assert va["verdict"] == vb["verdict"] == "INCONCLUSIVE"
    assert not (out / "checks").exists()
    assert sorted(p.name for p in (out / "logs" / "elastic-patch").glob("*.log")) == \
        ["dolfinx-l0.log", "dolfinx-l1.log", "freefem-l0.log", "freefem-l1.log", "report.log",
         "solver-l0-elasticity-M1star.log", "solver-l1-elasticity-M1star.log"]
    (row,) = json.loads((out / "index.json").read_text())["scenes"]
    assert row["verdict"] == "INCONCLUSIVE" and row["problem"] == "elasticity"
    assert re.match(r"0 of \d+ series converge, \d+ cannot be judged yet", row["converged"])
    assert row["glance"]["line"].startswith("the SDM's errors at level 1 (sdcrack M1star δ=0): ")
    assert "; the references' errors at level 1 (the larger of theirs): u 0, ∇u 0, σ 0, " \
        "opening 0, slip 0, K_I tip 1 0, K_I tip 2 0" in row["glance"]["line"]
    assert row["glance"]["level"] == 1 and row["glance"]["against"] == "exact"
    assert f"  INCONCLUSIVE  {a / 'report' / 'index.html'}" in r.stdout


def elastic_report(verdict="PASS", reasons=(), rate=1.0, error=1e-3):
    """A hand-made elastic report.json (compare/sdcompare_lib/elastic_report.py's keys)."""
    def s(tool, q, status="converges", r=rate, e=error):
        return {"tool": tool, "quantity": q, "levels": [0, 1, 2], "errors": [4 * e, 2 * e, e],
                "rates": [1.0, r], "status": status}
    series = [s(t, q) for t in ("dolfinx", "freefem") for q in ("u_l2", "u_h1", "K_I tip 1")]
    if verdict == "FAIL":
        series[1] = s("dolfinx", "u_h1", "does not converge", 0.2)
    return {"verdict": verdict, "reasons": list(reasons), "problem": "elasticity",
            "scene": "e", "series": series,
            "agreement": [{"level": L, "u_rel": 10.0 ** (-15 + L)} for L in (0, 1, 2)]}


def test_index_rows_of_elastic_reports(tmp_path):
    """The index's row of an elastic report (no solver, no glance): what converged per series, the
    references' largest errors at the finest level and their agreement; a FAIL report's row is FAIL
    with its first reason; without exact fields, the SIFs, fronts and distances; against a baseline
    the series are matched per reference and quantity."""
    import ci_script

    ci = ci_script.load("tools/campaign_index.py")
    ok = elastic_report()
    assert ci.elastic_converged_line(ok) == ("6 of 6 series converge (dolfinx, freefem); last "
                                             "rates u 1.00, ∇u 1.00, K_I tip 1 1.00")
    g = ci.elastic_glance(ok)
    assert g == {"line": "no solver case; the references' errors at level 2 (the larger "
                         "of theirs): u 0.001, ∇u 0.001, K_I tip 1 0.001; they agree in u to 1e-13 "
                         "(relative)", "level": 2, "against": "exact", "delta": None}
    bad = elastic_report("FAIL", ["series: dolfinx u_h1: rate 0.20 < 0.4"])
    assert ci.elastic_converged_line(bad) == ("5 of 6 series converge (freefem); last rates u "
                                              "1.00, ∇u 1.00, K_I tip 1 1.00")
    for name, report in (("ok", ok), ("bad", bad)):
        (tmp_path / name / "report").mkdir(parents=True)
        (tmp_path / name / "report" / "report.json").write_text(json.dumps(report))
    rows, verdict, _ = ci.build(str(tmp_path), ["ok", "bad"])
    assert verdict == "FAIL"
    assert [(r["name"], r["verdict"], r["first_problem"]) for r in rows] == [
        ("ok", "PASS", None), ("bad", "FAIL", "series: dolfinx u_h1: rate 0.20 < 0.4")]
    assert rows[0]["glance"] == g and rows[0]["problem"] == "elasticity"
    html = (tmp_path / "index.html").read_text()
    assert "no solver case" in html and "5 of 6 series converge" in html
    # without exact fields: the first reference's SIFs and fronts, the distances to its finest level
    plain = {"problem": "elasticity", "verdict": "PASS", "series": [],
             "sifs": [{"tool": t, "level": L, "K": [[0.5 + L, -0.25]]}
                      for t in ("freefem", "dolfinx") for L in (0, 1)],
             "fronts": [{"tool": "dolfinx", "level": 1, "fronts": [[-0.125, 0.0]]}],
             "field_distances": [{"tool": "dolfinx", "level": 0, "finest": 1, "u_l2": 0.03,
                                  "u_h1": 0.4}],
             "agreement": []}
    assert ci.elastic_converged_line(plain).startswith("no series")
    assert ci.elastic_glance(plain) == {
        "line": "no solver case; the references at level 1: dolfinx's (K_I, K_II) per "
                "tip (1.5, -0.25), contact fronts at x = -0.12, level 0 to it: u 0.03 (L²), "
                "0.4 (H¹)", "level": 1, "against": "reference finest level", "delta": None}
    # with the smooth-domain method's series: its errors first, the references' apart (the
    # solver's σ 1e-4 is not the references' largest); without exact fields its case count
    sdm = elastic_report()
    sdm["series"] += [{"tool": "sdcrack M1star δ=0", "quantity": q, "levels": [0, 1, 2],
                       "errors": [4e-4, 2e-4, 1e-4], "rates": [1.0, 1.0], "status": "converges"}
                      for q in ("stress_sym_l2", "opening_l2")]
    assert ci.elastic_glance(sdm)["line"] == (
        "the SDM's errors at level 2 (sdcrack M1star δ=0): opening 0.0001, stress_sym_l2 0.0001; "
        "the references' errors at level 2 (the larger of theirs): u 0.001, ∇u 0.001, K_I tip 1 "
        "0.001; they agree in u to 1e-13 (relative)")
    assert ci.elastic_glance(dict(plain, solver={"cases": 6}))["line"].startswith(
        "the SDM: 6 cases judged (no exact fields); the references at level 1: ")
    # a baseline: the series matched per reference and quantity
    moved = elastic_report(error=2e-3)
    changes = ci.report_changes(ok, moved)
    assert {c["series"] for c in changes} == {f"{t} {q}" for t in ("dolfinx", "freefem")
                                              for q in ("u_l2", "u_h1", "K_I tip 1")}
    assert ci.report_changes(ok, elastic_report()) == []
