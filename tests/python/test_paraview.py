"""tools/render-field: ParaView's default reader walks δ, and the picture is drawn (pvpython).

The rendering tests need ParaView (`pvpython`, Debian: paraview python3-paraview xvfb), an X
server (a DISPLAY, or Xvfb, which `ci/setup --tests` installs where pvpython is) and a results
folder in SDCRACK_RUN_DIR (ci/test runs the `mixed` scene at level 1 into one); they skip
otherwise, saying which is missing. They run tools/render-field on that folder and check: the PNG
exists, has the requested
size and is not one flat colour; the script's self-check passed, and what it saw agrees with
summary.json and fields.h5 read here with h5py: one time step per δ of the series, at every step
the u (and crack λ) range ParaView read is /cases/<fields_grid>/u's, the picture is the last step
(smallest δ). The bad-input, no-ParaView and no-X-server paths run everywhere (a fake pvpython,
PATH without Xvfb), and so does ci/setup's choice of packages (on fake apt-get and dpkg-query).
"""

import json
import os
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
RENDER = ROOT / "tools" / "render-field"


def pvpython():
    """The pvpython tools/render-field would use (PVPYTHON, else PATH), or None."""
    p = os.environ.get("PVPYTHON") or shutil.which("pvpython")
    return p if p and os.access(p, os.X_OK) else None


def no_x_server(env=None):
    """Why tools/render-field has no X server to render on (no DISPLAY, and no Xvfb on PATH to
    start one), or None. Debian's ParaView renders through GLX only."""
    env = os.environ if env is None else env
    if env.get("DISPLAY") or shutil.which("Xvfb", path=env.get("PATH", "")):
        return None
    return ("pvpython present but no Xvfb and no DISPLAY: install xvfb (ci/setup --tests does "
            "where pvpython is installed)")


def need_paraview_and_x():
    """Skips (with the reason) where ParaView or an X server for it is missing."""
    if not pvpython():
        pytest.skip("ParaView (pvpython) not installed")
    reason = no_x_server()
    if reason:
        pytest.skip(reason)


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
    """The series tools/render-field picks: broken-M1 at the finest level that has one."""
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
    need_paraview_and_x()
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
    cases = [c for c in summary["cases"]
             if c.get("fields_series") == f"fields/{series}.series.xdmf"]
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


def tool_path(tmp_path, *tools):
    """A PATH of one folder holding links to the named tools only (no Xvfb, no xvfb-run)."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir(exist_ok=True)
    for t in tools:
        (bin_dir / t).symlink_to(shutil.which(t))
    return str(bin_dir)


def fake_results(tmp_path):
    """A results folder that passes tools/render-field's input check: fields.h5 (empty) and one
    series of one step with u."""
    d = tmp_path / "scene"
    (d / "fields").mkdir(parents=True)
    (d / "fields.h5").write_bytes(b"")
    (d / "fields" / "level1-broken-M1.series.xdmf").write_text(
        '<?xml version="1.0"?><Xdmf Version="3.0"><Domain>'
        '<Grid Name="s" GridType="Collection" CollectionType="Temporal">'
        '<Grid Name="c0"><Time Value="0"/><Information Name="delta" Value="0"/>'
        '<Attribute Name="u" Center="Node"><DataItem>../fields.h5:/cases/c0/u</DataItem>'
        "</Attribute></Grid></Grid></Domain></Xdmf>")
    return d


def test_without_x_server_the_paraview_tests_skip(tmp_path):
    """PATH without Xvfb and no DISPLAY: the reason to skip; a DISPLAY or an Xvfb: none."""
    path = tool_path(tmp_path, "bash")
    assert no_x_server({"PATH": path}).startswith("pvpython present but no Xvfb and no DISPLAY: ")
    assert no_x_server({"PATH": path, "DISPLAY": ":0"}) is None
    xvfb = tmp_path / "xbin" / "Xvfb"
    xvfb.parent.mkdir()
    xvfb.write_text("#!/bin/sh\n")
    xvfb.chmod(0o755)
    assert no_x_server({"PATH": f"{path}:{xvfb.parent}"}) is None


def test_render_field_without_x_server_is_one_line_exit_1(tmp_path):
    """No DISPLAY, no Xvfb on PATH, and a pvpython that segfaults as Debian's does there: one line
    saying to install xvfb, exit 1 (not 139)."""
    fake = tmp_path / "pvpython"
    fake.write_text("#!/bin/sh\nulimit -c 0\nkill -SEGV $$\n")  # no core file
    fake.chmod(0o755)
    path = tool_path(tmp_path, "bash", "python3", "dirname", "mktemp", "grep", "tail", "rm")
    env = {"PATH": path, "PVPYTHON": str(fake), "TMPDIR": str(tmp_path), "HOME": str(tmp_path)}
    rc, out, err = render(fake_results(tmp_path), "--out", tmp_path / "u.png", env=env)
    assert rc == 1, out + err
    assert out.startswith("render-field: no DISPLAY and no Xvfb, and pvpython was killed by "
                          "signal 11 (SEGV): this ParaView needs an X server (install xvfb"), out
    assert out.count("\n") == 1 and err == ""


SETUP_FAKES = {
    "dpkg-query": "exit 1",  # nothing installed: every package is listed for apt-get
    "apt-get": 'echo "$*" >>"$HOME/apt.log"',
    "sudo": 'exec "$@"',
    "cargo": "exit 0",
}


def setup_installs(tmp_path, *args, pvpython=False):
    """The packages a copy of ci/setup asks apt-get for, on fake dpkg-query, apt-get and cargo
    (and a workflow venv that is already there); with pvpython=True a pvpython is on PATH."""
    root = tmp_path / ("with-pv" if pvpython else "without-pv")
    (root / "ci").mkdir(parents=True)
    text = (ROOT / "ci" / "setup").read_text()
    (root / "ci" / "setup").write_text(text)
    (root / "ci" / "setup").chmod(0o755)
    version = next(line.split("=", 1)[1] for line in text.splitlines()
                   if line.startswith("SNAKEMAKE_VERSION="))
    fakes = dict(SETUP_FAKES, snakemake=f"echo {version}")
    if pvpython:
        fakes["pvpython"] = "exit 0"
    path = tool_path(root, "bash", "grep", "id", "dirname")
    for name, body in fakes.items():
        f = pathlib.Path(path) / name
        f.write_text(f"#!/bin/sh\n{body}\n")
        f.chmod(0o755)
    (root / ".venv-workflow" / "bin").mkdir(parents=True)
    (root / ".venv-workflow" / "bin" / "snakemake").symlink_to(pathlib.Path(path) / "snakemake")
    # and the checkout's venv .venv/, already made: a python that runs and names its site folder
    (root / ".venv" / "bin").mkdir(parents=True)
    (root / ".venv" / "site").mkdir()
    (root / ".venv" / "pyvenv.cfg").write_text("include-system-site-packages = true\n")
    venv_python = root / ".venv" / "bin" / "python"
    venv_python.write_text(f"#!/bin/sh\necho {root / '.venv' / 'site'}\n")
    venv_python.chmod(0o755)
    p = subprocess.run([str(root / "ci" / "setup"), *args], capture_output=True, text=True,
                       timeout=60, env={"PATH": path, "HOME": str(root)})
    assert p.returncode == 0, p.stdout + p.stderr
    (install,) = [line.split()[3:] for line in (root / "apt.log").read_text().splitlines()
                  if line.startswith("install")]
    return install


def test_setup_tests_installs_xvfb_where_paraview_is(tmp_path):
    """ci/setup --tests adds xvfb where pvpython is installed, not elsewhere, and plain ci/setup
    neither Chromium nor xvfb."""
    assert "xvfb" in setup_installs(tmp_path, "--tests", pvpython=True)
    without = setup_installs(tmp_path, "--tests")
    assert "chromium" in without and "xvfb" not in without
    plain = setup_installs(tmp_path / "plain", pvpython=True)
    assert "xvfb" not in plain and "chromium" not in plain and "gmsh" in plain


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
