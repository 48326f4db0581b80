"""ci/render-field: ParaView's default reader walks δ, and the picture is drawn (pvpython).

The rendering tests need ParaView (`pvpython`, Debian: paraview python3-paraview xvfb) and a results
folder in SDCRACK_RUN_DIR (ci/test runs the `mixed` scene at level 1 into one); they skip
otherwise. They run ci/render-field on that folder and check: the PNG exists, has the requested
size and is not one flat colour; the script's self-check passed, and what it saw agrees with
summary.json and fields.h5 read here with h5py: one time step per δ of the series, at every step
the u (and crack λ) range ParaView read is /cases/<fields_grid>/u's, the picture is the last step
(smallest δ). The bad-input and no-ParaView paths run everywhere.
"""

import json
import os
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
RENDER = ROOT / "ci" / "render-field"


def pvpython():
    """The pvpython ci/render-field would use (PVPYTHON, else PATH), or None."""
    p = os.environ.get("PVPYTHON") or shutil.which("pvpython")
    return p if p and os.access(p, os.X_OK) else None


@pytest.fixture(scope="module")
def run_dir():
    d = os.environ.get("SDCRACK_RUN_DIR")
    if not d:
        pytest.skip("SDCRACK_RUN_DIR is not set")
    return pathlib.Path(d)


@pytest.fixture(scope="module")
def summary(run_dir):
    return json.loads((run_dir / "summary.json").read_text())


def render(*args, env=None):
    p = subprocess.run([str(RENDER), *map(str, args)], capture_output=True, text=True,
                       timeout=600, env=env)
    return p.returncode, p.stdout, p.stderr


def read_png(path):
    """(width, height, pixels as an (H, W, C) array) with Pillow, else matplotlib."""
    try:
        from PIL import Image
        with Image.open(path) as im:
            return im.size[0], im.size[1], np.asarray(im.convert("RGB"))
    except ImportError:
        import matplotlib.image as mpimg
        a = mpimg.imread(path)
        return a.shape[1], a.shape[0], a


def default_series(summary):
    """The series ci/render-field picks: broken-M1 at the finest level that has one."""
    names = {pathlib.Path(c["fields_series"]).name.removesuffix(".series.xdmf")
             for c in summary["cases"] if c.get("fields_series")}
    m1 = [n for n in names if n.endswith("-broken-M1")]
    return max(m1, key=lambda n: int(n.split("-")[0][len("level"):])) if m1 else sorted(names)[0]


def h5_range(run_dir, dataset):
    h5py = pytest.importorskip("h5py")
    with h5py.File(run_dir / "fields.h5", "r") as f:
        a = np.asarray(f[dataset])
    return [float(a.min()), float(a.max())]


@pytest.mark.parametrize("which", ["default", "M0"])
def test_render_field_walks_delta_and_draws_u(run_dir, summary, tmp_path, which):
    if not pvpython():
        pytest.skip("ParaView (pvpython) not installed")
    series = default_series(summary)
    args = [run_dir]
    if which == "M0":  # λ per crack segment (Center="Cell")
        series = series.replace("-M1", "-M0")
        args += ["--series", series]
    png, check = tmp_path / "u.png", tmp_path / "check.json"
    rc, out, err = render(*args, "--out", png, "--size", "800x600", "--check-json", check)
    assert rc == 0, out + err
    lines = out.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"render-field: wrote {png} ({series}, "), out

    # The picture: requested size, and not one flat colour (a colour map was drawn).
    assert png.is_file()
    w, h, pixels = read_png(png)
    assert (w, h) == (800, 600)
    colours = np.unique(pixels.reshape(-1, pixels.shape[-1]), axis=0)
    assert len(colours) > 100, f"{len(colours)} colours"

    # The self-check, against summary.json and fields.h5 read here.
    rep = json.loads(check.read_text())
    assert rep["self_check"] == "ok" and rep["series"] == series
    cases = [c for c in summary["cases"] if c.get("fields_series") == f"fields/{series}.series.xdmf"]
    assert len(cases) >= 2
    field, crack = rep["files"]
    assert field["reader"] == crack["reader"]  # ParaView's default for .xdmf (Xdmf3ReaderS)
    for f in (field, crack):
        assert f["times"] == [float(k) for k in range(len(cases))]  # one step per δ, in order
        assert len(f["steps"]) == len(cases)
    for k, case in enumerate(cases):
        grid = case["fields_grid"]
        s = field["steps"][k]
        assert s["time"] == k and s["grid"] == grid
        assert float(s["delta"]) == pytest.approx(case["delta"], rel=1e-12, abs=0)
        assert s["range"] == h5_range(run_dir, f"/cases/{grid}/u")
        if field["compared_with_h5"]:  # pvpython had h5py (Debian's does): whole arrays
            assert s["max_abs_diff"] == 0.0
        c = crack["steps"][k]
        assert c["grid"] == grid + "/crack"
        assert c["range"] == h5_range(run_dir, f"/cases/{grid}/crack/lambda")
    shown = rep["rendered"]
    assert shown["time"] == len(cases) - 1
    assert float(shown["delta"]) == min(c["delta"] for c in cases)
    assert f"\u03b4 = {shown['delta']}," in lines[0]


def test_render_field_bad_input_is_one_line_exit_2(tmp_path):
    for args in ([tmp_path / "missing"], [tmp_path]):
        rc, out, err = render(*args)
        assert rc == 2, out + err
        assert len(out.strip().splitlines()) == 1 and out.startswith("render-field: "), out


def test_render_field_unknown_series_is_exit_2(run_dir):
    rc, out, err = render(run_dir, "--series", "level9-nothing-M7")
    assert rc == 2, out + err
    assert out.startswith("render-field: unknown series 'level9-nothing-M7'"), out


def test_render_field_without_paraview_skips(run_dir, tmp_path):
    env = dict(os.environ, PVPYTHON=str(tmp_path / "no-pvpython"))
    rc, out, err = render(run_dir, "--out", tmp_path / "u.png", env=env)
    assert (rc, out) == (0, "render-field: ParaView (pvpython) not installed; skipped\n"), err
    assert not (tmp_path / "u.png").exists()


PV_OPEN = r"""
import json, sys
from paraview.simple import OpenDataFile, UpdatePipeline, servermanager
out = []
for path in sys.argv[1:]:
    reader = OpenDataFile(path)
    times = list(getattr(reader, "TimestepValues", []) or [])
    if times:  # a series: the last step, as a user's time slider at its end
        UpdatePipeline(time=times[-1], proxy=reader)
    else:
        UpdatePipeline(proxy=reader)
    data = servermanager.Fetch(reader)
    if data.IsA("vtkMultiBlockDataSet"):
        data = data.GetBlock(0)
    pd = data.GetPointData()
    out.append({"path": path, "reader": reader.GetXMLName(), "points": data.GetNumberOfPoints(),
                "times": times,
                "arrays": sorted(pd.GetArrayName(i) for i in range(pd.GetNumberOfArrays()))})
print(json.dumps(out))
"""


def test_paraview_default_reader_opens_every_kind_of_xdmf(run_dir, summary):
    """One file of each kind of the XDMF convention (a series, a one-state file and its crack, a
    reference's level): ParaView's default reader opens it with the points and arrays the file
    names, and a series has one time step per δ, a state none."""
    if not pvpython():
        pytest.skip("ParaView (pvpython) not installed")
    case = next(c for c in summary["cases"] if c["u_space"] == "broken" and c["multiplier"] == "M1")
    series, state = run_dir / case["fields_series"], run_dir / case["fields_state"]
    ref = sorted(f for f in (run_dir / "dolfinx" / "fields").glob("level*.xdmf")
                 if not f.name.endswith(".crack.xdmf"))
    files = [series, state, state.with_name(state.name.replace(".xdmf", ".crack.xdmf"))] + ref[:1]
    p = subprocess.run([pvpython(), "-c", PV_OPEN, *map(str, files)], capture_output=True,
                       text=True, timeout=600)
    assert p.returncode == 0, p.stderr[-2000:]
    got = json.loads(p.stdout.strip().splitlines()[-1])
    steps = sum(1 for c in summary["cases"] if c.get("fields_series") == case["fields_series"])
    assert len(got) == len(files)
    assert all(g["points"] > 0 for g in got), got
    assert len(got[0]["times"]) == steps > 1 and {"u", "p", "delta"} <= set(got[0]["arrays"])
    assert len(got[1]["times"]) <= 1 and {"u", "p", "delta"} <= set(got[1]["arrays"])
    assert "lambda" in got[2]["arrays"]
    if ref:
        assert "u" in got[3]["arrays"]
