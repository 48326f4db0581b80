"""Reruns that prove themselves.

One command per rerunnable unit, the same in a folder's report and in `tools/cases RESULTS` (the
binary that wrote the folder, its scene copy, `--out sdcrack-rerun/<name>` relative to where it is
run); the rerun lands outside the results tree; `compare/sdcompare-rerun ORIGINAL RERUN` says
"identical" for an untouched rerun, exits 1 naming the first differing dataset or case number, and
exits 2 with one line on bad input. A real solver on a tiny scene (levels 0-1, δ = 1e-2, 0).
"""

import json
import os
import pathlib
import shlex
import shutil
import subprocess

import numpy as np
import pytest
from conftest import run_env
from scene_text import set_key

ROOT = pathlib.Path(__file__).resolve().parents[2]
EXE = pathlib.Path(os.environ.get("SDCRACK_BIN", ROOT / "target" / "release" / "sdcrack"))
PY = "/usr/bin/python3"
h5py = pytest.importorskip("h5py")
pytestmark = [
    pytest.mark.skipif(not (ROOT / "compare" / "sdcompare_lib").is_dir(),
                       reason="no compare/sdcompare_lib (ci/test-pip's copy of the tree)"),
    pytest.mark.skipif(not EXE.is_file(), reason="sdcrack binary not built"),
]
UNIT = "open-exact-l1-broken-M1"  # the unit rerun below: level 1, broken u, M1, its δ sweep
# the prefix of every rerun command: the BLAS/OpenMP threads the campaign's jobs run with
PIN = ["env", "OMP_NUM_THREADS=1", "GOTO_NUM_THREADS=1", "OPENBLAS_NUM_THREADS=1",
       "MKL_NUM_THREADS=1", "VECLIB_MAXIMUM_THREADS=1", "NUMEXPR_NUM_THREADS=1"]


def tiny_scene(folder, fields=None, references="[]"):
    text = (ROOT / "scenes" / "open-exact.toml").read_text()
    for key, value in (("levels", "[0, 1]"), ("references", references),
                       ("p_mass", '["consistent"]'), ("deltas", "[1e-2, 0.0]")):
        text = set_key(text, key, value)
    if fields is not None:
        text = set_key(text, "fields", fields)
    scene = folder / "open.toml"
    scene.write_text(text)
    return scene


def cases_commands(*args, cwd):
    """Field 7 on of each line of tools/cases, the trailing target comment left out."""
    out = subprocess.run([str(ROOT / "tools" / "cases"), *map(str, args)], cwd=cwd, check=True,
                         capture_output=True, text=True).stdout
    return [line.partition(" # target: ")[0].split(" ", 6)[6] for line in out.splitlines()]


def run_rerun(command, cwd):
    """Runs one rerun command as printed (its binary: EXE, which wrote the original) from cwd;
    returns its --out folder under cwd."""
    args = shlex.split(command)
    cwd.mkdir(parents=True, exist_ok=True)
    subprocess.run(args + ["--quiet"], cwd=cwd, check=True, capture_output=True)
    return cwd / args[args.index("--out") + 1]


def compare_rerun(original, rerun, *extra):
    p = subprocess.run([str(ROOT / "compare" / "sdcompare-rerun"), str(original), str(rerun),
                        *extra], capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


def files_under(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


@pytest.fixture(scope="module")
def original(tmp_path_factory):
    """A results folder of the tiny scene, run by EXE (its provenance `executable`)."""
    tmp = tmp_path_factory.mktemp("orig")
    subprocess.run([str(EXE), "run", str(tiny_scene(tmp)), "--out", str(tmp / "results"),
                    "--quiet"], check=True, capture_output=True)
    return tmp / "results" / "open-exact"


@pytest.fixture(scope="module")
def rerun(original, tmp_path_factory):
    """One unit's rerun from `tools/cases RESULTS`, run from an unrelated directory: (its --out
    folder, the results tree's files before and after)."""
    before = files_under(original.parent)
    command = next(c for c in cases_commands(original, cwd=ROOT) if c.endswith("/" + UNIT))
    out = run_rerun(command, tmp_path_factory.mktemp("elsewhere"))
    return out, before, files_under(original.parent)


@pytest.fixture
def forged(rerun, tmp_path):
    """A copy of the rerun's results folder, to forge."""
    return pathlib.Path(shutil.copytree(rerun[0] / "open-exact", tmp_path / "forged"))


def test_ci_cases_prints_the_reports_commands(original, tmp_path):
    """`tools/cases RESULTS` prints, field 7 on, exactly the commands of the folder's report
    (report.json's `rerun` of each KKT row, report.md's Rerun commands table), character for
    character: the binary that wrote the folder, its scene copy, a relative --out."""
    folder = pathlib.Path(shutil.copytree(original, tmp_path / "open-exact"))
    p = subprocess.run([PY, str(ROOT / "compare" / "sdcompare"), str(folder), "--quiet",
                        "--expectations", os.devnull], capture_output=True, text=True)
    assert p.returncode == 3, p.stderr  # two levels: the rates cannot be judged yet (INCONCLUSIVE)
    report = json.loads((folder / "report" / "report.json").read_text())
    from_json = sorted({k["rerun"] for k in report["kkt"]})
    md = (folder / "report" / "report.md").read_text()
    section = md.split("\n## Rerun commands\n")[1].split("\n## ")[0]
    from_md = sorted(line.rsplit("| `", 1)[1].removesuffix("` |")
                     for line in section.splitlines() if line.startswith("| ") and "| `" in line)
    got = cases_commands(folder, cwd=tmp_path)
    assert len(got) == 2 * 2 * 3
    assert sorted(got) == from_json == from_md
    # the campaign's BLAS/OpenMP threads, then the binary that wrote the folder
    assert {tuple(shlex.split(c)[:len(PIN)]) for c in got} == {tuple(PIN)}
    assert {os.path.realpath(shlex.split(c)[len(PIN)]) for c in got} == {os.path.realpath(EXE)}
    assert all(shlex.split(c)[-1].startswith("sdcrack-rerun/open-exact-l") for c in got)
    # no references in this scene: nothing to leave out
    assert not any("--solver-only" in c for c in got)
    # and the paragraph says where they write and how to compare
    assert f"compare/sdcompare-rerun {shlex.quote(str(folder))} sdcrack-rerun/<name>" in section


def test_a_rerun_lands_outside_the_results_tree_and_is_identical(original, rerun):
    out, before, after = rerun
    assert before == after, "the rerun wrote into the results tree"
    assert not out.is_relative_to(original.parent)
    rc, stdout, stderr = compare_rerun(original, out)
    with h5py.File(out / "open-exact" / "fields.h5") as f:
        n = []
        f.visititems(lambda name, o: n.append(name) if isinstance(o, h5py.Dataset) else None)
    assert (rc, stdout, stderr) == (0, f"identical: {len(n)} datasets, 2 cases\n", "")
    # the results folder inside the --out folder names the same rerun
    assert compare_rerun(original, out / "open-exact")[:2] == (0, stdout)


def test_a_forged_dataset_is_named_and_fails(original, forged):
    name = "cases/level1-broken-M1-delta1e-2/u"
    with h5py.File(forged / "fields.h5", "r+") as f:
        u = f[name][()]
        i = int(np.argmax(np.abs(u)))
        u[i] *= 1 + 1e-12
        f[name][...] = u
    rc, out, err = compare_rerun(original, forged)
    lines = out.splitlines()
    assert rc == 1 and err == "", err
    assert lines[0].startswith(f"differs: dataset /{name} (fields.h5): max abs difference ")
    assert "max rel difference 1.0" in lines[0] or "max rel difference 9.9" in lines[0], lines[0]
    assert lines[-1].startswith("1 of ") and "datasets and 0 of 2 cases differ bit for bit" in out
    # within a relative tolerance above the forgery it passes, below it fails
    assert compare_rerun(original, forged, "--rtol", "1e-10")[0] == 0
    assert compare_rerun(original, forged, "--rtol", "1e-14")[0] == 1


def test_a_forged_iteration_count_fails(original, forged):
    summary = json.loads((forged / "summary.json").read_text())
    case = next(c for c in summary["cases"] if c["delta"] == 0.0)
    want = case["iterations"]
    case["iterations"] += 1
    (forged / "summary.json").write_text(json.dumps(summary))
    for extra in ((), ("--rtol", "0.5")):  # an integer must be equal, tolerance or not
        rc, out, _ = compare_rerun(original, forged, *extra)
        assert rc == 1
        assert out.splitlines()[0] == ("differs: summary.json case level 1 broken M1 consistent "
                                       f"continuous δ 0: iterations: {want + 1} vs original "
                                       f"{want}")


def test_timings_and_file_names_are_not_compared(original, forged):
    summary = json.loads((forged / "summary.json").read_text())
    for c in summary["cases"]:
        c["timings_s"] = {k: 2 * v for k, v in c["timings_s"].items()}
    summary["provenance"]["date_utc"] = "1970-01-01T00:00:00Z"
    summary["wall_s"] = 1e6
    (forged / "summary.json").write_text(json.dumps(summary))
    assert compare_rerun(original, forged)[0] == 0


def test_reference_fields_of_a_rerun_are_compared_on_request(original, forged, tmp_path):
    """A rerun of a scene with references reran them (with this checkout's reference scripts):
    --references compares their dolfinx/ and freefem/fields.h5 too (written here by hand: the
    references are too slow for this test)."""
    copy = pathlib.Path(shutil.copytree(original, tmp_path / "original"))
    for folder, value in ((copy, 1.0), (forged, 1.0 + 2e-16)):
        (folder / "dolfinx").mkdir()
        with h5py.File(folder / "dolfinx" / "fields.h5", "w") as f:
            f["level1/u"] = np.array([0.5, value])
    assert compare_rerun(copy, forged)[0] == 0  # sdcrack's own fields only, by default
    rc, out, _ = compare_rerun(copy, forged, "--references")
    assert rc == 1 and out.startswith("differs: dataset /level1/u (dolfinx/fields.h5): ")
    shutil.rmtree(copy / "dolfinx")
    rc, _, err = compare_rerun(copy, forged, "--references")
    assert rc == 2 and err.endswith("/original: no dolfinx/fields.h5, which the rerun has\n")


def bad_rerun(forged, kind):
    if kind == "dataset absent from the original":
        with h5py.File(forged / "fields.h5", "r+") as f:
            f["cases/level1-broken-M1-delta0/extra"] = np.zeros(3)
    elif kind == "case absent from the original":
        summary = json.loads((forged / "summary.json").read_text())
        summary["cases"][0]["level"] = 7
        (forged / "summary.json").write_text(json.dumps(summary))
    elif kind == "no fields.h5":
        (forged / "fields.h5").unlink()
    elif kind == "unreadable fields.h5":
        (forged / "fields.h5").write_text("not HDF5")
    elif kind == "malformed summary.json":
        (forged / "summary.json").write_text("{")
    elif kind == "missing folder":
        shutil.rmtree(forged)
    return forged


@pytest.mark.parametrize("kind, says", [
    ("dataset absent from the original", "dataset /cases/level1-broken-M1-delta0/extra is not in "),
    ("case absent from the original", "case level 7 broken M1 consistent continuous δ "),
    ("no fields.h5", "no fields.h5 or verification.h5 to compare"),
    ("unreadable fields.h5", "unreadable HDF5 file"),
    ("malformed summary.json", "malformed JSON"),
    ("missing folder", "no such folder"),
])
def test_bad_input_is_one_line_and_exit_2(original, forged, kind, says):
    rc, out, err = compare_rerun(original, bad_rerun(forged, kind))
    assert (rc, out) == (2, ""), (kind, out, err)
    assert err.startswith("sdcompare-rerun: ") and says in err and err.count("\n") == 1, err
    rc, out, err = compare_rerun(original, forged, "--rtol", "x")
    assert rc == 2 and err.count("\n") == 1 and "--rtol" in err, err


def test_a_verification_h5_rerun_is_compared(tmp_path):
    """A scene that stores no viewable fields (`fields = []`) keeps verification.h5: that file is
    compared, the same way."""
    subprocess.run([str(EXE), "run", str(tiny_scene(tmp_path, "[]")), "--out",
                    str(tmp_path / "results"), "--quiet"], check=True, capture_output=True)
    folder = tmp_path / "results" / "open-exact"
    assert not (folder / "fields.h5").exists() and (folder / "verification.h5").is_file()
    command = next(c for c in cases_commands(folder, cwd=tmp_path) if c.endswith("/" + UNIT))
    out = run_rerun(command, tmp_path / "elsewhere")
    rc, stdout, _ = compare_rerun(folder, out)
    assert rc == 0 and stdout.startswith("identical: ") and stdout.endswith(" datasets, 2 cases\n")


# ---------------------------------------------------------------- with the references (issue 42)
def reference_env():
    """The environment of a run with references: this checkout's reference scripts (whatever
    checkout built EXE), FreeFEM's plugins, compare/ on PYTHONPATH."""
    return dict(run_env(), SDCRACK_REFERENCES=str(ROOT / "references"))


def h5_datasets(path):
    with h5py.File(path) as f:
        n = []
        f.visititems(lambda name, o: n.append(name) if isinstance(o, h5py.Dataset) else None)
    return len(n)


@pytest.fixture(scope="module")
def original_with_references(tmp_path_factory):
    """The tiny scene with both references (M1 only), run as the campaign's jobs run,
    with the BLAS/OpenMP threads pinned (PIN), and its report (whose rerun commands are tested)."""
    tmp = tmp_path_factory.mktemp("orig-refs")
    text = tiny_scene(tmp, references='["dolfinx", "freefem"]').read_text()
    text = set_key(text, "multipliers", '["M1"]')
    scene = tmp / "open-refs.toml"
    scene.write_text(text)
    p = subprocess.run(PIN + [str(EXE), "run", str(scene), "--out", str(tmp / "results"),
                              "--quiet"], env=reference_env(), capture_output=True, text=True)
    if p.returncode == 2 and "is not available" in p.stderr:
        pytest.skip(p.stderr.strip())
    assert p.returncode == 0, p.stderr
    folder = tmp / "results" / "open-exact"
    p = subprocess.run([PY, str(ROOT / "compare" / "sdcompare"), str(folder), "--quiet",
                        "--expectations", os.devnull], capture_output=True, text=True,
                       env=run_env())
    assert p.returncode == 3, p.stderr  # two levels: the rates cannot be judged yet (INCONCLUSIVE)
    return folder


def test_a_reports_rerun_command_reruns_the_case_alone_and_says_which_references_it_reused(
        original_with_references, tmp_path):
    """The report's command for one case, run as printed (a shell, from an unrelated directory):
    the BLAS/OpenMP threads pinned, the case rerun with `--solver-only`, the references not;
    `sdcompare-rerun ORIGINAL RERUN --references` says identical and names the references it
    reused."""
    folder = original_with_references
    report = json.loads((folder / "report" / "report.json").read_text())
    command = next(k["rerun"] for k in report["kkt"]
                   if (k["level"], k["u_space"]) == (1, "broken"))
    words = shlex.split(command)
    assert words[:len(PIN)] == PIN and words[len(PIN) + 3] == "--solver-only", command
    assert words[-2:] == ["--out", "sdcrack-rerun/open-exact-l1-broken-M1"], command
    assert command in (folder / "report" / "report.md").read_text()
    # the report's provenance: the references ran pinned
    provenance = (folder / "report" / "report.md").read_text().split("## Provenance")[1]
    assert provenance.count("BLAS/OpenMP threads pinned to 1") == 2, provenance
    cwd = tmp_path / "elsewhere"
    cwd.mkdir()
    p = subprocess.run(["bash", "-c", command + " --quiet"], cwd=cwd, env=reference_env(),
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    rerun = cwd / "sdcrack-rerun" / "open-exact-l1-broken-M1"
    assert not (rerun / "open-exact" / "dolfinx").exists()
    rc, out, err = compare_rerun(folder, rerun, "--references")
    n = h5_datasets(rerun / "open-exact" / "fields.h5")
    assert (rc, err) == (0, ""), out + err
    assert out == (f"identical: {n} datasets, 2 cases\n"
                   f"references: dolfinx, freefem not rerun (--solver-only): the original's "
                   f"{folder}/dolfinx, {folder}/freefem reused\n")


def test_a_rerun_asked_to_rerun_the_references_gives_them_back_bit_for_bit(
        original_with_references, tmp_path):
    """The same command without `--solver-only` (the references asked for) reruns the level's
    references too, pinned alike, and every dataset of theirs is identical to the original's."""
    folder = original_with_references
    report = json.loads((folder / "report" / "report.json").read_text())
    command = next(k["rerun"] for k in report["kkt"]
                   if (k["level"], k["u_space"]) == (1, "broken"))
    asked = command.replace(" --solver-only", "")
    assert asked != command
    p = subprocess.run(["bash", "-c", asked + " --quiet"], cwd=tmp_path, env=reference_env(),
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    rerun = tmp_path / "sdcrack-rerun" / "open-exact-l1-broken-M1" / "open-exact"
    n = {f: h5_datasets(rerun / f) for f in ("fields.h5", "dolfinx/fields.h5", "freefem/fields.h5")}
    assert n["dolfinx/fields.h5"] > 0 and n["freefem/fields.h5"] > 0, n
    rc, out, err = compare_rerun(folder, rerun, "--references")
    assert (rc, err) == (0, ""), out + err
    assert out == (f"identical: {sum(n.values())} datasets, 2 cases\n"
                   "references: dolfinx, freefem rerun, compared\n")
    # their provenance records the pinned threads
    from sdshared.sdresults import threads_pinned

    for tool in ("dolfinx", "freefem"):
        prov = json.loads((rerun / tool / "summary.json").read_text())["provenance"]
        assert threads_pinned(prov["threads"]) is True, prov
    # without --references the references are said rerun, not compared
    rc, out, _ = compare_rerun(folder, rerun)
    assert rc == 0 and out.splitlines()[-1] == (
        "references: dolfinx, freefem rerun, not compared (--references compares them)")
