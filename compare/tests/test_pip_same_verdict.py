"""The pip-installed sdcompare and the checkout's judge alike ("nothing silently weaker").

An installed sdcompare once found no expectations file and said PASS with "0 expectation row(s)
evaluated" where the checkout's judged every row. Here both judge the same results folders — the
repository's closed-exact scene (δ = 0, no references: seconds), once storing its fields, once
storing none (verification.h5 only), once with forged summary errors — and must agree on the
verdict, the reasons, the checks with their status, every series' rates and expected rates, and
every expectation row.

The installed sdcompare is the one beside the running interpreter (ci/test-pip runs this file with
.venv-pip/bin/python) or .venv-pip/bin/sdcompare of the checkout; without one the test skips (ci/test
runs ci/test-pip after the Debian run, so CI runs it). The checkout's sdcompare is
SDCRACK_CHECKOUT/compare/sdcompare (ci/test-pip sets it: its copy of the tree lacks sdcompare_lib),
else this file's checkout, run by Debian's /usr/bin/python3.
"""
import json
import math
import os
import shutil
import subprocess
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
from scene_text import set_key
from conftest import run_env, sdcrack_bin

SCENE = "closed-exact"


def installed_sdcompare():
    for path in (os.path.join(os.path.dirname(sys.executable), "sdcompare"),
                 os.path.join(ROOT, ".venv-pip", "bin", "sdcompare")):
        if os.path.isfile(path) and os.access(path, os.X_OK):
            return path
    return None


def stale_files(installed):
    """The checkout's sdcompare_lib and sdshared modules that the installed copy of .venv-pip/ (not the running
    interpreter's own, which ci/test-pip has just installed) lacks or holds in another version:
    an install older than the checkout judges with older code, which is not what this test is
    about (ci/test-pip reinstalls it before running this file)."""
    if os.path.dirname(installed) == os.path.dirname(sys.executable):
        return []
    import glob
    out = []
    for package in ("sdcompare_lib", "sdshared"):
        lib = os.path.join(ROOT, "compare", package)
        sites = glob.glob(os.path.join(os.path.dirname(os.path.dirname(installed)), "lib",
                                       "python3*", "site-packages", package))
        for f in sorted(glob.glob(os.path.join(lib, "*.py"))):
            there = [os.path.join(site, os.path.basename(f)) for site in sites]
            if not any(os.path.isfile(t) and open(t, "rb").read() == open(f, "rb").read()
                       for t in there):
                out.append(f"{package}/{os.path.basename(f)}")
    return out


def checkout_sdcompare():
    root = os.environ.get("SDCRACK_CHECKOUT", ROOT)
    script = os.path.join(root, "compare", "sdcompare")
    if not os.path.isdir(os.path.join(root, "compare", "sdcompare_lib")):
        return None
    py = "/usr/bin/python3" if os.path.exists("/usr/bin/python3") else sys.executable
    return [py, script]


@pytest.fixture(scope="module")
def tools():
    installed, checkout = installed_sdcompare(), checkout_sdcompare()
    if installed is None:
        pytest.skip("no pip-installed sdcompare (ci/test-pip installs one into .venv-pip/)")
    stale = stale_files(installed)
    if stale:
        pytest.skip(f"the pip-installed sdcompare of .venv-pip/ predates this checkout "
                    f"({', '.join(stale[:3])}{' …' if len(stale) > 3 else ''} differ): ci/test-pip "
                    "reinstalls it and runs this test")
    if checkout is None:
        pytest.skip("no checkout sdcompare (set SDCRACK_CHECKOUT)")
    if not os.access(sdcrack_bin(), os.X_OK):
        pytest.skip("no sdcrack binary (cargo build --release, or SDCRACK_BIN)")
    return installed, checkout


def results(tmp, fields):
    """closed-exact at δ = 0 without references, storing `fields`: its results folder."""
    with open(os.path.join(ROOT, "scenes", f"{SCENE}.toml"), encoding="utf-8") as fh:
        text = fh.read()
    text = set_key(set_key(set_key(text, "deltas", "[0.0]"), "references", "[]"), "fields", fields)
    where = os.path.join(tmp, "scene")
    os.makedirs(where, exist_ok=True)
    path = os.path.join(where, f"{SCENE}.toml")
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(text)
    out = os.path.join(tmp, "out")
    p = subprocess.run([sdcrack_bin(), "run", path, "--out", out, "--quiet"],
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr[-2000:]
    return os.path.join(out, SCENE)


def forge(folder, factor):
    """Multiplies every u error the summary reports by `factor` (a forged summary)."""
    path = os.path.join(folder, "summary.json")
    with open(path, encoding="utf-8") as fh:
        summary = json.load(fh)
    for case in summary["cases"]:
        case["errors"]["u_l2"] *= factor
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(summary, fh)


def judge(cmd, folder):
    """Runs one sdcompare on a private copy of `folder`: (exit code, report.json or None)."""
    copy = folder + "-" + str(abs(hash(tuple(cmd))))
    shutil.copytree(folder, copy)
    p = subprocess.run([*cmd, copy], capture_output=True, text=True, env=run_env(), timeout=900)
    rep = os.path.join(copy, "report", "report.json")
    report = None
    if os.path.exists(rep):
        with open(rep, encoding="utf-8") as fh:
            report = json.load(fh)
    return p.returncode, report, p.stderr


def _num(x):
    return None if x is None or (isinstance(x, float) and math.isnan(x)) else round(x, 9)


def essence(report):
    """What a verdict consists of, with numbers rounded to 9 decimals (two numpy builds may differ
    in the last bits): verdict, reasons, checks, series, expectation rows."""
    return {
        "verdict": report["verdict"],
        "reasons": report["reasons"],
        "checks": [(c["check"], c["status"], c["problems"], c["not_applicable"])
                   for c in report["checks"]],
        "series": [(s["u_space"], s["multiplier"], s["p_mass"], s["quantity"], s["status"],
                    _num(s["expected_rate"]), s["expected_rate_reason"],
                    [_num(r) for r in s["rates"]]) for s in report["series"]],
        "expectations": [(e["index"], e.get("variant"), e["quantity"], e["status"])
                         for e in report["expectations"]],
        "expectations_file": os.path.basename(report["expectations_file"]),
    }


@pytest.mark.parametrize("case", ["fields stored", "no fields stored", "forged summary"])
def test_installed_and_checkout_sdcompare_agree(tools, tmp_path, case):
    installed, checkout = tools
    folder = results(str(tmp_path), '[]' if case != "fields stored" else '["u", "p", "lambda"]')
    if case == "forged summary":
        forge(folder, 0.9)
    (rc_i, rep_i, err_i), (rc_c, rep_c, err_c) = judge([installed], folder), judge(checkout, folder)
    assert rc_c in (0, 1), err_c
    assert (rc_i, err_i) == (rc_c, err_c)
    assert essence(rep_i) == essence(rep_c)
    assert rep_i["expectations"], "the repository's expectations name closed-exact"
    labels = [c["check"] for c in rep_c["checks"]]
    assert "independent errors" in labels and "interpolation yardstick" in labels
    # the verdict itself, so that agreeing on a wrong verdict does not pass
    assert rep_c["verdict"] == ("FAIL" if case == "forged summary" else "PASS"), rep_c["reasons"]
    if case == "forged summary":
        assert any(r.startswith("independent errors: ") for r in rep_c["reasons"])


def test_an_sdcompare_without_expectations_refuses_to_judge(tmp_path):
    """A copy of the tool with its orders table (scenes/orders.toml) but neither
    scenes/expectations.toml beside it nor the package's copy (Debian's python has no
    sdcompare_scenes) exits 2 with one line, writing no report."""
    checkout = checkout_sdcompare()
    if checkout is None or not os.access(sdcrack_bin(), os.X_OK):
        pytest.skip("needs the checkout's sdcompare and the sdcrack binary")
    py, script = checkout
    probe = subprocess.run([py, "-c", "import importlib.util as u; "
                            "print(u.find_spec('sdcompare_scenes') is None)"],
                           capture_output=True, text=True)
    if probe.stdout.strip() != "True":
        pytest.skip(f"{py} has the package's expectations installed")
    tool = tmp_path / "tool" / "compare"
    shutil.copytree(os.path.dirname(script), tool,
                    ignore=shutil.ignore_patterns("tests", "__pycache__"))
    os.makedirs(tmp_path / "tool" / "scenes")
    shutil.copy2(os.path.join(os.path.dirname(os.path.dirname(script)), "scenes", "orders.toml"),
                 tmp_path / "tool" / "scenes")
    folder = results(str(tmp_path), "[]")
    p = subprocess.run([py, str(tool / "sdcompare"), folder], capture_output=True, text=True,
                       env=run_env(), timeout=600, cwd=str(tmp_path))
    assert p.returncode == 2 and p.stderr.count("\n") == 1, p.stderr
    assert "no expectations file" in p.stderr
    assert not os.path.exists(os.path.join(folder, "report"))
