"""The expected orders of convergence have one home, scenes/orders.toml: the compare tool's theory
module reads it (here: from a checkout the repository's file, installed the packaged copy of the
same file, and a value changed in a copy changes the orders and reasons it judges with), the Rust
tests read it through tests/common/orders.rs (tests/orders_table.rs)."""
import importlib.util
import os
import shutil
import tomllib

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
from sdcompare_lib import theory

TABLE = os.path.join(ROOT, "scenes", "orders.toml")
QUANTITIES = ("u_l2", "p_l2", "p_x", "lambda_l2")
P_SPACES = ("continuous", "broken-tangential")


def table_text():
    with open(TABLE, encoding="utf-8") as fh:
        return fh.read()


def edited(text, old, new):
    assert text.count(old) == 1, old
    return text.replace(old, new)


def theory_reading(tmp_path, text):
    """The theory module loaded afresh from a copy of its file inside a checkout-like folder
    (compare/PACKAGE/theory.py beside scenes/orders.toml = `text`), so that it reads that table:
    its relative imports are the real package's."""
    (tmp_path / "scenes").mkdir()
    (tmp_path / "scenes" / "orders.toml").write_text(text, encoding="utf-8")
    (tmp_path / "compare" / "lib").mkdir(parents=True)
    copy = tmp_path / "compare" / "lib" / "theory.py"
    shutil.copyfile(theory.__file__, copy)
    package = theory.__name__.rpartition(".")[0]
    spec = importlib.util.spec_from_file_location(f"{package}._orders_probe", copy)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def judgements(th):
    """Every expected order with its reason, and the thresholds and regularities, that `th` gives
    over a grid of series."""
    out = [th.regularity(r) for r in (None, 0.5, 0.89, 0.9, 1.0)]
    for q in QUANTITIES:
        for m in ("M0", "M1", "M1star"):
            for pm in ("consistent", "lumped"):
                for s in (0.5, 1.0):
                    for closed in (False, True):
                        for ps in P_SPACES:
                            out.append(th.expected_rate(q, m, pm, s, closed, ps))
        out.append((th.p1_order(q, 0.5), th.p1_order(q, 1.0)))
    out.append((th.threshold(2.0), th.threshold(1.0, 0.95)))
    return out


def test_the_compare_tool_reads_the_repository_table():
    path = theory.orders_file()
    module_dir = os.path.dirname(os.path.abspath(theory.__file__))
    if os.path.samefile(os.path.dirname(os.path.dirname(module_dir)), ROOT):
        assert os.path.samefile(path, TABLE)
    else:  # installed (ci/test-pip): the packaged copy of the same file
        assert not os.path.samefile(path, TABLE)
        with open(path, "rb") as a, open(TABLE, "rb") as b:
            assert a.read() == b.read()
    with open(TABLE, "rb") as fh:
        raw = tomllib.load(fh)
    assert theory.RATE_MARGIN == raw["rule"]["margin"]
    assert theory.SMOOTH_S == raw["regularity"]["smooth_s"]
    assert theory.SINGULAR_S == raw["regularity"]["singular_s"]
    assert theory.SMOOTH_INTERPOLATION_RATE == raw["regularity"]["smooth_interpolation_rate"]
    assert theory.P1_ORDER_PER_S == raw["p1"]
    assert theory.OPEN_CRACK_RATE == raw["open_crack"]["order"]
    assert theory.PAPER_LAMBDA_RATE == raw["lambda"]["paper"]
    assert theory.P0_JUMP_RATE == raw["lambda"]["p0_jump"]


def test_the_same_table_read_afresh_judges_alike(tmp_path):
    assert judgements(theory_reading(tmp_path, table_text())) == judgements(theory)


def test_a_value_changed_in_a_copy_of_the_table_changes_the_orders(tmp_path):
    text = edited(table_text(), "margin = 0.1\n", "margin = 0.25\n")
    text = edited(text, "M1star = 0.75\n", "M1star = 0.8\n")
    text = edited(text, "smooth_interpolation_rate = 0.9\n", "smooth_interpolation_rate = 0.96\n")
    th = theory_reading(tmp_path, text)
    assert th.threshold(2.0) == 2.0 - 0.25
    order, reason = th.expected_rate("lambda_l2", "M1star", "consistent", 0.5)
    assert order == 0.8 and "h^0.8" in reason
    assert th.regularity(0.93)[0] == th.SINGULAR_S
    assert theory.regularity(0.93)[0] == theory.SMOOTH_S, "the module in use keeps its table"


def test_a_table_without_a_number_the_theory_reads_is_refused(tmp_path):
    with pytest.raises(ValueError, match="p0_jump"):
        theory_reading(tmp_path, edited(table_text(), "p0_jump = 1.0\n", ""))
