"""compare/sdcompare-rerun on an elastic results folder (docs/elasticity.md): its solver cases
(issue 46) by summary.json's numbers per key and fields.h5's datasets, as a scalar folder's; with
--references it compares what the references solved, the mesh export they read,
each fields.h5 dataset, each reference summary.json case, the text outputs (u_level{L}.txt,
crack_level{L}.txt, the XDMF files) and report/report.json's values; without --references it has
nothing to compare and says so (exit 2), never "identical" over nothing.

Synthetic folders (elastic_synthetic.write_results, levels 0-1 on 4 × 4 cells) with a fields.h5,
an XDMF file and a report.json written here: no sdcrack, no reference solver.
"""
import json
import shutil
import subprocess
import sys
from pathlib import Path

import elastic_synthetic as es
import numpy as np
import pytest
from sdcompare_lib import rerun_diff

h5py = pytest.importorskip("h5py")
ROOT = Path(__file__).resolve().parents[2]
TOOLS = ("dolfinx", "freefem")
LEVELS = (0, 1)


def add_campaign_files(folder):
    """What sdcrack, the references' --fields and the compare tool add to write_results' folder:
    summary.json's empty cases, each tool's fields.h5 and fields/level{L}.xdmf, the report."""
    summary = json.loads((folder / "summary.json").read_text())
    summary.update(cases=[], kkt_tolerance=1e-10, provenance={"date_utc": "2026-11-28T21:00:00Z"})
    (folder / "summary.json").write_text(json.dumps(summary))
    for tool in TOOLS:
        (folder / tool / "fields").mkdir()
        with h5py.File(folder / tool / "fields.h5", "w") as f:
            for level in LEVELS:
                u = np.loadtxt(folder / tool / f"u_level{level}.txt")
                f[f"level{level}/u"] = np.column_stack([u, np.zeros(len(u))])
                f[f"level{level}/active"] = np.loadtxt(
                    folder / tool / f"crack_level{level}.txt")[:, 3].astype(np.int64)
                (folder / tool / "fields" / f"level{level}.xdmf").write_text(
                    f'<Xdmf><DataItem Format="HDF">../fields.h5:/level{level}/u</DataItem>'
                    '</Xdmf>\n')
    (folder / "report").mkdir()
    (folder / "report" / "report.json").write_text(json.dumps({
        "verdict": "PASS", "results_dir": str(folder), "provenance": {"date_utc": "x"},
        "sifs": [{"tool": t, "level": L, "K": [[1.0 + 0.01 * L, 0.5]]}
                 for t in TOOLS for L in LEVELS],
        "reasons": [], "checks": [{"check": "agreement", "status": "ok",
                                   "requires": "u within 1e-09 relative"}]}))
    return folder


@pytest.fixture(scope="module")
def original(tmp_path_factory):
    return add_campaign_files(es.write_results(tmp_path_factory.mktemp("o") / "williams",
                                               levels=LEVELS, tools=TOOLS))


@pytest.fixture
def rerun(original, tmp_path):
    """A copy of the original, its run-dependent parts changed: timings, dates, the report's
    folder path and provenance (none of them results)."""
    copy = Path(shutil.copytree(original, tmp_path / "williams"))
    for tool in TOOLS:
        s = json.loads((copy / tool / "summary.json").read_text())
        s["provenance"] = {"tool": tool, "date_utc": "1970-01-01T00:00:00Z"}
        for c in s["cases"]:
            c["timings_s"] = {"solve": 99.0}
        (copy / tool / "summary.json").write_text(json.dumps(s))
    r = json.loads((copy / "report" / "report.json").read_text())
    r.update(results_dir=str(copy), provenance={"date_utc": "y"})
    (copy / "report" / "report.json").write_text(json.dumps(r))
    return copy


def compare(original, rerun, *extra, capsys):
    code = rerun_diff.main([str(original), str(rerun), *map(str, extra)])
    out, err = capsys.readouterr()
    return code, out, err


def counts(folder):
    """(datasets, text files, reference cases, report.json values) of a folder, counted here."""
    datasets = 0
    for tool in TOOLS:
        with h5py.File(folder / tool / "fields.h5") as f:
            names = []
            f.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
            datasets += len(names)
    files = [p for top in ("mesh", *TOOLS) for p in (folder / top).rglob("*") if p.is_file()]
    texts = [p for p in files if p.suffix != ".h5" and not (p.name == "summary.json"
                                                            and p.parent.name in TOOLS)]
    cases = sum(len(json.loads((folder / t / "summary.json").read_text())["cases"]) for t in TOOLS)
    report = json.loads((folder / "report" / "report.json").read_text())
    values = len(rerun_diff.json_leaves({k: v for k, v in report.items()
                                         if k not in ("results_dir", "provenance")}))
    return datasets, len(texts), cases, values


def test_an_identical_elastic_rerun_exits_0_with_its_counts(original, rerun, capsys):
    d, t, c, v = counts(rerun)
    assert (d, c) == (2 * 2 * len(LEVELS), 2 * len(LEVELS)) and t > 2 * 3 * len(LEVELS) and v > 10
    code, out, err = compare(original, rerun, "--references", capsys=capsys)
    assert (code, err) == (0, "")
    assert out == (f"identical: {d} datasets, {t} text files, {c} reference cases, "
                   f"{v} report.json values\nreferences: dolfinx, freefem rerun, compared\n")
    # the command line as the campaign's checks run it (with this test's interpreter: the pip
    # run's has the installed sdcompare_lib, the Debian run's is /usr/bin/python3)
    p = subprocess.run([sys.executable, str(ROOT / "compare" / "sdcompare-rerun"),
                        str(original), str(rerun), "--references"], capture_output=True, text=True)
    assert (p.returncode, p.stdout, p.stderr) == (0, out, "")


def test_a_rerun_of_one_level_without_a_report_compares_what_it_has(original, rerun, capsys):
    """`sdcrack run SCENE --level 1` writes level 1 only (mesh/scene.json's `levels` = [1]: not
    a result) and no report."""
    for top in ("mesh", *TOOLS):
        for p in (rerun / top).rglob("*0*"):
            shutil.rmtree(p) if p.is_dir() else p.unlink()
    for tool in TOOLS:
        s = json.loads((rerun / tool / "summary.json").read_text())
        s["cases"] = [c for c in s["cases"] if c["level"] == 1]
        (rerun / tool / "summary.json").write_text(json.dumps(s))
        with h5py.File(rerun / tool / "fields.h5", "r+") as f:
            del f["level0"]
    scene = json.loads((rerun / "mesh" / "scene.json").read_text())
    assert scene["levels"] == list(LEVELS)
    scene["levels"] = [1]
    (rerun / "mesh" / "scene.json").write_text(json.dumps(scene, indent=2))
    shutil.rmtree(rerun / "report")
    code, out, _ = compare(original, rerun, "--references", capsys=capsys)
    assert code == 0, out
    assert out.startswith("identical: 4 datasets, ") and " text files, 2 reference cases\n" in out
    assert "report/report.json: not in the rerun, not compared\n" in out


def test_a_rerun_of_one_reference_says_which_it_has_not(original, rerun, capsys):
    shutil.rmtree(rerun / "freefem")
    code, out, _ = compare(original, rerun, "--references", capsys=capsys)
    assert code == 0 and out.startswith("identical: 4 datasets, "), out
    assert out.endswith("\nreferences: dolfinx rerun, compared; freefem not in the rerun\n")


def forge_dataset(folder):
    with h5py.File(folder / "freefem" / "fields.h5", "r+") as f:
        u = f["level1/u"][()]
        u[3, 1] *= 1 + 1e-12
        f["level1/u"][...] = u


def forge_text(folder):
    """The last digit of one number of dolfinx/u_level1.txt (the rerun's u, not its fields.h5)."""
    path = folder / "dolfinx" / "u_level1.txt"
    lines = path.read_text().splitlines()
    words = lines[4].split()
    words[1] = repr(float(words[1]) * (1 + 1e-12))
    lines[4] = " ".join(words)
    path.write_text("\n".join(lines) + "\n")
    return words[1]


def test_one_changed_dataset_is_named_and_fails(original, rerun, capsys):
    forge_dataset(rerun)
    code, out, _ = compare(original, rerun, "--references", capsys=capsys)
    lines = out.splitlines()
    assert code == 1
    assert lines[0].startswith("differs: dataset /level1/u (freefem/fields.h5): max abs "
                               "difference ")
    d, t, c, v = counts(rerun)
    assert lines[1] == (f"1 of {d} datasets, 0 of {t} text files, 0 of {c} reference cases and "
                        f"0 of {v} report.json values differ bit for bit (the first of each is "
                        "named above)")
    assert compare(original, rerun, "--references", "--rtol", "1e-10", capsys=capsys)[0] == 0
    assert compare(original, rerun, "--references", "--rtol", "1e-14", capsys=capsys)[0] == 1


def test_one_changed_text_number_is_named_and_fails(original, rerun, capsys):
    was = (original / "dolfinx" / "u_level1.txt").read_text().splitlines()[4].split()[1]
    now = forge_text(rerun)
    code, out, _ = compare(original, rerun, "--references", capsys=capsys)
    assert code == 1
    assert out.splitlines()[0] == (f"differs: file dolfinx/u_level1.txt: line 5 word 2: {now} vs "
                                   f"original {was}")
    assert "0 of 8 datasets, 1 of " in out
    # within a tolerance above the change (relative to the column's largest |u_y|) it passes
    assert compare(original, rerun, "--references", "--rtol", "1e-10", capsys=capsys)[0] == 0
    assert compare(original, rerun, "--references", "--rtol", "1e-15", capsys=capsys)[0] == 1


def test_a_flipped_active_flag_fails_whatever_the_tolerance(original, rerun, capsys):
    path = rerun / "freefem" / "crack_level0.txt"
    crack = np.loadtxt(path)
    assert not crack[:, 3].any()
    crack[1, 3] = 1.0
    np.savetxt(path, crack, fmt="%.17g")
    code, out, _ = compare(original, rerun, "--references", "--rtol", "0.5", capsys=capsys)
    assert code == 1
    assert out.splitlines()[0] == ("differs: file freefem/crack_level0.txt: line 2 word 4: 1 vs "
                                   "original 0")


def test_a_changed_index_fails_whatever_the_tolerance(original, rerun, capsys):
    """An integer (a vertex index of the mesh export, a flag) must be equal: a tolerance
    relative to its column's largest value (here the largest vertex index) does not apply."""
    path = rerun / "mesh" / "level1" / "triangles.txt"
    lines = path.read_text().splitlines()
    was = lines[0].split()
    now = [was[0], was[1], str(int(was[2]) + 1)]
    lines[0] = " ".join(now)
    path.write_text("\n".join(lines) + "\n")
    code, out, _ = compare(original, rerun, "--references", "--rtol", "0.5", capsys=capsys)
    assert code == 1
    assert out.splitlines()[0] == (f"differs: file mesh/level1/triangles.txt: line 1 word 3: "
                                   f"{now[2]} vs original {was[2]}")


def test_a_json_file_with_the_same_values_in_other_bytes_is_not_bit_for_bit(original, rerun,
                                                                           capsys):
    path = rerun / "mesh" / "level0" / "mesh.json"
    path.write_text(json.dumps(json.loads(path.read_text()), indent=1))
    code, out, _ = compare(original, rerun, "--references", capsys=capsys)
    assert code == 1
    assert out.splitlines()[0] == ("differs: file mesh/level0/mesh.json: the same values, other "
                                   "bytes")
    assert compare(original, rerun, "--references", "--rtol", "0", capsys=capsys)[0] == 0


def test_a_changed_reference_case_and_report_value_are_named(original, rerun, capsys):
    s = json.loads((rerun / "dolfinx" / "summary.json").read_text())
    s["cases"][1]["iterations"] += 1
    (rerun / "dolfinx" / "summary.json").write_text(json.dumps(s))
    r = json.loads((rerun / "report" / "report.json").read_text())
    r["sifs"][1]["K"][0][0] += 1e-15
    (rerun / "report" / "report.json").write_text(json.dumps(r))
    code, out, _ = compare(original, rerun, "--references", capsys=capsys)
    lines = out.splitlines()
    assert code == 1
    assert lines[0] == "differs: dolfinx/summary.json case level 1: iterations: 2 vs original 1"
    assert lines[1] == ("differs: report/report.json: sifs[1].K[0][0]: "
                        f"{1.01 + 1e-15!r} vs original 1.01")
    assert " 1 of 4 reference cases and 1 of " in lines[2]
    # an iteration count must be equal within any tolerance, a float is within it
    code, out, _ = compare(original, rerun, "--references", "--rtol", "1e-12", capsys=capsys)
    assert code == 1 and " 1 of 4 reference cases and 0 of " in out


def test_the_report_verdict_is_compared(original, rerun, capsys):
    r = json.loads((rerun / "report" / "report.json").read_text())
    r["verdict"] = "FAIL"
    (rerun / "report" / "report.json").write_text(json.dumps(r))
    for extra in ((), ("--rtol", "0.1")):
        code, out, _ = compare(original, rerun, "--references", *extra, capsys=capsys)
        assert code == 1 and out.startswith(
            "differs: report/report.json: verdict: 'FAIL' vs original 'PASS'\n"), out


def test_without_references_it_exits_2_saying_there_is_no_solver_case(original, rerun, capsys):
    code, out, err = compare(original, rerun, capsys=capsys)
    assert (code, out) == (2, "")
    assert err == (f"sdcompare-rerun: {rerun}: an elastic scene's folder, no solver cases to "
                   "compare: --references compares its references' outputs\n")


def bad(rerun, kind):
    if kind == "no reference outputs":
        for tool in TOOLS:
            shutil.rmtree(rerun / tool)
    elif kind == "a file the original has not":
        (rerun / "dolfinx" / "u_level7.txt").write_text("0 0\n")
    elif kind == "a level the original has not":
        s = json.loads((rerun / "freefem" / "summary.json").read_text())
        s["cases"][0]["level"] = 7
        (rerun / "freefem" / "summary.json").write_text(json.dumps(s))
    elif kind == "a scalar rerun":
        s = json.loads((rerun / "summary.json").read_text())
        del s["problem"]
        (rerun / "summary.json").write_text(json.dumps(s))
    elif kind == "elastic solver cases":
        s = json.loads((rerun / "summary.json").read_text())
        s["cases"] = [{"level": 0}]
        (rerun / "summary.json").write_text(json.dumps(s))
    elif kind == "malformed report.json":
        (rerun / "report" / "report.json").write_text("{")


@pytest.mark.parametrize("kind, says", [
    ("no reference outputs", "no reference outputs (dolfinx/, freefem/) to compare"),
    ("a file the original has not", "no dolfinx/u_level7.txt, which the rerun has"),
    ("a level the original has not", "level 7 is not in "),
    ("a scalar rerun", "a scalar results folder, the other one is elastic"),
    ("elastic solver cases", "summary.json: an elastic case without level, multiplier, delta "
     "or problem"),
    ("malformed report.json", "malformed JSON"),
])
def test_bad_input_is_one_line_and_exit_2(original, rerun, capsys, kind, says):
    bad(rerun, kind)
    code, out, err = compare(original, rerun, "--references", capsys=capsys)
    assert (code, out) == (2, ""), (kind, out)
    assert err.startswith("sdcompare-rerun: ") and says in err and err.count("\n") == 1, err


# ------------------------------------------------------------------ the solver's cases (issue 46)

@pytest.fixture(scope="module")
def original_sdm(tmp_path_factory):
    folder = es.write_results(tmp_path_factory.mktemp("s") / "williams", levels=LEVELS, tools=TOOLS)
    return es.write_sdm_cases(add_campaign_files(folder), es.williams(1.0, 0.0),
                              variants=(("M1star", 0.0), ("M1star", 1e-3)))


@pytest.fixture
def rerun_sdm(original_sdm, tmp_path):
    copy = Path(shutil.copytree(original_sdm, tmp_path / "williams"))
    s = json.loads((copy / "summary.json").read_text())
    for c in s["cases"]:
        c["timings_s"] = {"solve": 99.0}
    (copy / "summary.json").write_text(json.dumps(s))
    return copy


def test_an_identical_rerun_of_solver_cases_exits_0(original_sdm, rerun_sdm, capsys):
    with h5py.File(original_sdm / "fields.h5") as f:
        n = len(rerun_diff.dataset_names(h5py, f))
    code, out, err = compare(original_sdm, rerun_sdm, capsys=capsys)
    assert (code, err) == (0, ""), err
    assert out.splitlines()[0] == f"identical: 4 cases, {n} datasets"
    assert "references: dolfinx, freefem rerun, not compared" in out
    code, out, err = compare(original_sdm, rerun_sdm, "--references", capsys=capsys)
    assert code == 0 and out.startswith("identical: 4 cases, "), (out, err)


def test_a_changed_solver_error_and_dataset_are_named(original_sdm, rerun_sdm, capsys):
    s = json.loads((rerun_sdm / "summary.json").read_text())
    s["cases"][3]["errors"]["stress_l2"] *= 1 + 1e-15
    (rerun_sdm / "summary.json").write_text(json.dumps(s))
    code, out, err = compare(original_sdm, rerun_sdm, capsys=capsys)
    assert code == 1 and "differs: summary.json case level 1 M1star δ 1e-3: " in out, out
    assert "stress_l2" in out and "1 of 4 cases and 0 of " in out
    with h5py.File(rerun_sdm / "fields.h5", "a") as f:
        f["cases/level0-elasticity-M1star-delta0/gamma_h"][3] += 1e-12
    code, out, err = compare(original_sdm, rerun_sdm, "--rtol", "1e-6", capsys=capsys)
    assert code == 0, out
    code, out, err = compare(original_sdm, rerun_sdm, capsys=capsys)
    assert code == 1 and "differs: dataset /cases/level0-elasticity-M1star-delta0/gamma_h" in out


def test_a_solver_case_the_original_has_not_is_bad_input(original_sdm, rerun_sdm, capsys):
    s = json.loads((rerun_sdm / "summary.json").read_text())
    s["cases"][0]["delta"] = 0.5
    (rerun_sdm / "summary.json").write_text(json.dumps(s))
    code, out, err = compare(original_sdm, rerun_sdm, capsys=capsys)
    assert (code, out) == (2, "") and "case level 0 M1star δ 5e-1 is not in" in err, err
