"""The README reads in the order a new user needs it: what sdcrack is, the
quick start, then "your own problem" before any long command list, then the results folder as a
list rather than one long block; and every file or folder it names in the results folder exists
in a real results folder's listing (checked where ci/test provides one, SDCRACK_RUN_DIR)."""

import os
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
README = (ROOT / "README.md").read_text()
# a paragraph longer than this many lines is a wall of text (the old results-folder paragraph
# was 20 lines); lists, tables and code blocks do not count
MAX_PARAGRAPH_LINES = 10


def sections():
    return [m.group(1) for m in re.finditer(r"(?m)^## (.+)$", README)]


def section_text(title):
    m = re.search(rf"(?ms)^## {re.escape(title)}\n(.*?)(?=^## |\Z)", README)
    assert m, title
    return m.group(1)


def test_sections_in_the_order_a_new_user_needs():
    s = sections()
    heads = [next(i for i, x in enumerate(s) if x.startswith(p))
             for p in ("Quick start", "Your own problem", "The results folder")]
    assert heads == sorted(heads) and heads == [0, 1, 2], s


def test_your_own_problem_comes_before_any_long_command_block():
    own = README.index("## Your own problem")
    for block in re.finditer(r"(?ms)^```sh\n(.*?)^```", README[:own]):
        assert len(block.group(1).splitlines()) <= 4, block.group(0)
    assert "sdcrack scene --template" in section_text("Your own problem")


def paragraphs(text):
    """Plain paragraphs: blank-line separated, not lists, tables, code or images."""
    text = re.sub(r"(?ms)^```.*?^```", "", text)
    for para in re.split(r"\n\s*\n", text):
        lines = [x for x in para.splitlines() if x.strip()]
        if lines and not re.match(r"\s*([-*|!]|\d+\.)", lines[0]):
            yield lines


def test_no_paragraph_is_a_wall_of_text():
    for title in ("Your own problem", "The results folder `OUT/<scene>/`"):
        for lines in paragraphs(section_text(title)):
            assert len(lines) <= MAX_PARAGRAPH_LINES, "\n".join(lines)


def test_the_results_folder_names_what_a_run_writes():
    run = os.environ.get("SDCRACK_RUN_DIR")
    if not run:
        pytest.skip("SDCRACK_RUN_DIR is not set")
    text = section_text("The results folder `OUT/<scene>/`")
    listed = set(re.findall(r"^- `([\w.]+/?)`", text, flags=re.M))
    assert {"scene.toml", "summary.json", "fields.h5"} <= listed
    for name in listed - {"verification.h5", "report/"}:
        assert (pathlib.Path(run) / name).exists(), name
