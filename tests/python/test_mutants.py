"""tools/mutants' catalogue and engine, without running it (ci/nightly runs it: ~40 min).

The catalogue must hold at least 15 realistic bugs covering the solver, both references and the
compare tool, each still applying to this checkout (its text found exactly once); the engine's
verdict must be FAIL (exit 1) on a survivor or a mutant that no longer applies, so that a rotted
catalogue cannot report success.
"""
import os
import subprocess
import sys
import time

import pytest

import ci_script
from conftest import run_env

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
mutants = ci_script.load("tools/mutants.py")

CATALOGUE = mutants.load_catalogue()


def test_catalogue_has_at_least_15_realistic_bugs_in_every_part():
    assert len(CATALOGUE) >= 15
    kinds = [mutants.kind(m) for m in CATALOGUE]
    assert {"solver", "reference", "compare"} <= set(kinds)
    assert kinds.count("solver") >= 8


@pytest.mark.parametrize("m", CATALOGUE, ids=[m["name"] for m in CATALOGUE])
def test_every_mutant_still_applies_to_this_checkout(m):
    if m["file"].startswith("compare/sdcompare_lib/") and not os.path.isdir(
            os.path.join(ROOT, "compare", "sdcompare_lib")):
        pytest.skip("ci/test-pip's copy of the tree has no compare/sdcompare_lib (it tests the "
                    "installed package); ci/test checks these mutants on the checkout")
    with open(os.path.join(ROOT, m["file"]), encoding="utf-8") as fh:
        text = fh.read()
    mutated = mutants.mutated_text(text, m)
    assert mutated != text and m["bug"].strip() and m["catches"].strip()
    if m["file"].endswith(".py"):
        compile(mutated, m["file"], "exec")  # still Python: the bug, not a syntax error, is judged


def test_a_mutant_whose_text_moved_is_refused():
    m = {"name": "x", "file": "f.rs", "find": "a", "replace": "b", "bug": "", "catches": ""}
    with pytest.raises(ValueError, match="occurs 0 times"):
        mutants.mutated_text("ccc", m)
    with pytest.raises(ValueError, match="occurs 2 times"):
        mutants.mutated_text("aa", m)


def verdict(status):
    return {"name": "m", "file": "src/x.rs", "bug": "b", "expected_check": "c", "kind": "solver",
            "status": status, "scene": "s" if status == "KILLED" else None,
            "reasons": ["series: broken/M1 u_l2: does not converge"] if status != "SURVIVED" else [],
            "caught_by": ["series"] if status == "KILLED" else []}


def test_exit_code_fails_on_a_survivor_or_a_broken_mutant_and_on_nothing_run():
    assert mutants.exit_code([verdict("KILLED")] * 3) == 0
    assert mutants.exit_code([verdict("KILLED"), verdict("SURVIVED")]) == 1
    assert mutants.exit_code([verdict("KILLED"), verdict("BROKEN")]) == 1
    assert mutants.exit_code([]) == 1
    assert mutants.line(verdict("SURVIVED")).startswith("SURVIVED")
    assert "s FAIL (series)" in mutants.line(verdict("KILLED"))


def test_caught_by_names_each_check_once():
    assert mutants.caught_by(["series: a", "interpolation yardstick: b", "series: c"]) == [
        "series", "interpolation yardstick"]


def test_record_replaces_only_the_marked_table(tmp_path):
    doc = tmp_path / "v.md"
    doc.write_text(f"head\n{mutants.BEGIN}\nold\n{mutants.END}\ntail\n")
    meta = {"date": "d", "commit": "c", "machine": "m", "seconds": 1.0, "scenes": ["s"]}
    mutants.record(str(doc), mutants.markdown([verdict("KILLED"), verdict("SURVIVED")], meta))
    text = doc.read_text()
    assert text.startswith("head\n") and text.endswith("tail\n") and "old" not in text
    assert "1 of 2 mutants killed" in text and "**SURVIVED**" in text
    # a | in a bug's text would end its table cell
    v = dict(verdict("KILLED"), bug="keeps 4|T|/45")
    row = mutants.markdown([v], meta).splitlines()[-1]
    assert "4\\|T\\|/45" in row and row.count(" | ") == 5
    doc.write_text("no markers\n")
    with pytest.raises(mutants.UsageError):
        mutants.record(str(doc), "t")
    assert doc.read_text() == "no markers\n"


def test_docs_record_a_run_of_the_whole_catalogue():
    with open(os.path.join(ROOT, "docs", "verification.md"), encoding="utf-8") as fh:
        text = fh.read()
    table = text.split(mutants.BEGIN, 1)[1].split(mutants.END, 1)[0]
    for m in CATALOGUE:
        assert f"`{m['name']}`" in table, f"mutant {m['name']} not in docs/verification.md's last run"


def test_bad_usage_exits_2_with_one_line():
    p = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "mutants.py"), "--only", "nope"],
                       env=run_env(), capture_output=True, text=True)
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "no mutant named nope" in p.stderr


def test_the_scratch_copy_has_fresh_modification_times(tmp_path):
    """A kept --work's target holds the last mutant's build and its file was restored since: a copy
    keeping the checkout's older times would make cargo take the mutated binary as up to date."""
    if not os.path.exists(os.path.join(ROOT, ".git")):
        pytest.skip("not a git checkout (ci/test-pip's copy of the tree): tools/mutants copies the "
                    "files git lists, and ci/test checks the copy on the checkout")
    before = time.time()
    mutants.copy_checkout(str(tmp_path))
    copied = tmp_path / "crates" / "sdcrack-core" / "src" / "fe" / "mini.rs"
    assert copied.read_bytes() == open(os.path.join(ROOT, "crates", "sdcrack-core", "src", "fe",
                                                    "mini.rs"), "rb").read()
    assert copied.stat().st_mtime >= before - 1


def test_default_scenes_end_with_the_elastic_ones_at_levels_0_to_3():
    """Issue 45: the elastic mutants need an elastic scene; cheap at levels 0–3, and last, where
    the Rust mutants (killed on a scalar scene first) never reach them. Issue 46: the graded
    Williams open crack last, whose opening's order 3/2 kills the lumped edge mass."""
    args = mutants.parse_args([])
    pairs = mutants.scene_list(args)
    elastic = [(os.path.relpath(s, ROOT), lv) for s, lv in pairs if "elastic-" in s]
    assert elastic == [("scenes/elastic-patch.toml", [0, 1, 2, 3]),
                       ("scenes/elastic-williams-open.toml", [0, 1, 2, 3]),
                       ("scenes/elastic-closed-slip.toml", [0, 1, 2, 3]),
                       ("scenes/elastic-williams-open-graded.toml", [0, 1, 2, 3])]
    assert [lv for _, lv in pairs[:-4]] == [None] * (len(pairs) - 4)
    every = mutants.scene_list(mutants.parse_args(["--levels", "0-1"]))
    assert {tuple(lv) for _, lv in every} == {(0, 1)}
    with pytest.raises(mutants.UsageError, match="expected A-B"):
        mutants.scene_list(mutants.parse_args(["--levels", "zero"]))


def test_a_scene_judged_on_fewer_levels_is_a_copy(tmp_path):
    """The copy has the campaign's levels line and an absolute mesh path; the original is
    untouched; a scene without one levels line is refused."""
    (tmp_path / "m.msh").write_text("mesh")
    src = tmp_path / "s.toml"
    text = ('name = "s"\n[discretization]\nmesh = { gmsh = "m.msh" }\nlevels = [0, 1, 2, 3, 4]\n')
    src.write_text(text)
    copy = mutants.scene_with_levels(str(src), [0, 1], str(tmp_path / "copies"))
    got = open(copy).read()
    assert "levels = [0, 1]\n" in got and f'gmsh = "{tmp_path / "m.msh"}"' in got
    assert src.read_text() == text
    bad = tmp_path / "b.toml"
    bad.write_text('name = "b"\n[discretization]\ncells = [4, 4]\n')
    with pytest.raises(mutants.UsageError, match="no single `levels = \\[...\\]` line"):
        mutants.scene_with_levels(str(bad), [0], str(tmp_path / "copies"))
