"""Render u of one field series of an sdcrack results folder to a PNG (run by tools/render-field).

    pvpython tools/render_field.py RESULTS_DIR [--series NAME] [--out PNG] [--check-json FILE]

RESULTS_DIR is one scene's results folder (`sdcrack run ... --out OUT` writes OUT/SCENE/), holding
`fields.h5` and `fields/SERIES.series.xdmf` (+ `fields/SERIES.crack.series.xdmf`), one XDMF
temporal collection per (level, u space, multiplier, p mass) whose time steps 0, 1, 2, ... are the
δ sweep in decreasing δ (see crates/sdcrack-io/src/output/xdmf.rs; the one-state files `fields/CASE.xdmf` beside
them are for meshio.read). The default series is broken-M1 at the finest level that has one, else
the first series (by level, then name); --series takes `level4-broken-M1`, its file name or the
`fields_series` of summary.json.

What a new user does in the ParaView GUI is what this script does first, as a self-check: it
opens the series and its crack file with ParaView's default reader for `.xdmf` (OpenDataFile),
checks that the reader has one time step per step of the XDMF (and per case of the series in
summary.json, with the same δ), and at every time step compares the u that ParaView read with
/cases/CASE/u of fields.h5 (h5py), and the crack's lambda likewise. A mismatch is an error.

Then it renders u at the last time step (smallest δ): colour map symmetric about 0, scalar bar
titled "u", faint mesh edges where the triangles are large enough to see, the crack polyline on
top in black, the camera fitting the domain; 1200x900 unless --size says otherwise.

Prints one line `render-field: wrote PNG (SERIES, δ = D, step K of N; ...)`. Exit status: 0 done,
2 bad input (folder, fields or series missing), 1 anything else (self-check or rendering failed).
With --validate-only it checks the input and picks the series without importing ParaView (plain
python3 does), printing nothing on success. --check-json FILE writes what the self-check saw.
"""

import argparse
import json
import math
import os
import re
import sys
import xml.etree.ElementTree as ET

PREFIX = "render-field:"
GREEK_FONTS = ["/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
               "/usr/share/fonts/TTF/DejaVuSans.ttf",
               "/usr/share/fonts/dejavu/DejaVuSans.ttf",
               "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
               "/Library/Fonts/Arial Unicode.ttf",
               "C:/Windows/Fonts/arial.ttf"]


class BadInput(Exception):
    """Exit 2: the input is unusable."""


class Failure(Exception):
    """Exit 1: the self-check or the rendering failed."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2
        raise BadInput(message)


# the time-series files (crates/sdcrack-io/src/output/xdmf.rs): NAME.series.xdmf; NAME.xdmf holds one state
SERIES = ".series.xdmf"

def parse_args(argv):
    p = _Parser(prog="render-field", add_help=True)
    p.add_argument("results", metavar="RESULTS_DIR")
    p.add_argument("--series", help="series name (default: finest broken-M1, else the first)")
    p.add_argument("--out", help="PNG to write (default RESULTS_DIR/render/SERIES.png)")
    p.add_argument("--size", default="1200x900", help="WIDTHxHEIGHT in pixels (default 1200x900)")
    p.add_argument("--edges", choices=["auto", "on", "off"], default="auto",
                   help="mesh edges: auto = only where triangles are large enough to see")
    p.add_argument("--check-json", help="write the self-check's findings to this JSON file")
    p.add_argument("--validate-only", action="store_true", help=argparse.SUPPRESS)
    a = p.parse_args(argv)
    m = re.fullmatch(r"(\d+)x(\d+)", a.size)
    if not m or not (16 <= int(m.group(1)) <= 8192 and 16 <= int(m.group(2)) <= 8192):
        raise BadInput(f"--size {a.size!r}: want WIDTHxHEIGHT, 16..8192 each")
    a.width, a.height = int(m.group(1)), int(m.group(2))
    return a


# --------------------------------------------------------------------------- input (no ParaView)

def level_of(name):
    m = re.match(r"level(\d+)-", name)
    return int(m.group(1)) if m else -1


def list_series(results):
    fields = os.path.join(results, "fields")
    if not os.path.isdir(fields):
        raise BadInput(f"{results}: no fields/ folder (run with [outputs] fields)")
    names = [f[: -len(SERIES)] for f in os.listdir(fields)
             if f.endswith(SERIES) and not f.endswith(".crack" + SERIES)]
    if not names:
        raise BadInput(f"{fields}: no field series (*{SERIES})")
    return sorted(names, key=lambda n: (level_of(n), n))


def pick_series(results, requested):
    names = list_series(results)
    if requested:
        name = os.path.basename(requested)
        for suffix in (SERIES, ".xdmf"):
            name = name.removesuffix(suffix)
        if name not in names:
            raise BadInput(f"unknown series {requested!r} in {results} "
                           f"(have {', '.join(names[:4])}{', ...' if len(names) > 4 else ''})")
        return name
    broken_m1 = [n for n in names if re.fullmatch(r"level\d+-broken-M1", n)]
    if broken_m1:
        return max(broken_m1, key=level_of)
    return names[0]


def parse_series(path):
    """The steps of one XDMF temporal collection, in file order."""
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        raise BadInput(f"{path}: not readable XML ({e})")
    coll = root.find("./Domain/Grid")
    if coll is None or coll.get("CollectionType") != "Temporal":
        raise BadInput(f"{path}: no temporal collection under Domain")
    steps = []
    for g in coll.findall("./Grid"):
        time = g.find("./Time")
        info = {i.get("Name"): i.get("Value") for i in g.findall("./Information")}
        attrs = {}
        for a in g.findall("./Attribute"):
            item = a.find("./DataItem")
            text = (item.text or "").strip() if item is not None else ""
            h5, _, dataset = text.rpartition(":")
            attrs[a.get("Name")] = (os.path.normpath(os.path.join(os.path.dirname(path), h5)),
                                    dataset, a.get("Center"))
        geom = g.find("./Geometry/DataItem")
        steps.append({
            "grid": g.get("Name"),
            "time": float(time.get("Value")) if time is not None else float(len(steps)),
            "delta": info.get("delta"),
            "points": int(geom.get("Dimensions").split()[0]) if geom is not None else None,
            "attributes": attrs,
        })
    if not steps:
        raise BadInput(f"{path}: the collection has no steps")
    return steps


def summary_cases(results, series):
    """(δ, fields_grid) of the series' cases in summary.json, in order; None without a summary."""
    path = os.path.join(results, "summary.json")
    if not os.path.isfile(path):
        return None
    with open(path) as f:
        cases = json.load(f).get("cases", [])
    want = f"fields/{series}{SERIES}"
    return [(c.get("delta"), c.get("fields_grid")) for c in cases
            if c.get("fields_series") == want]


def expect_from_summary(results, series, steps, crack_steps):
    """Tie every step to its case in summary.json: same count, same δ, same grid name; the data
    ParaView shows at step k must then be /cases/<fields_grid of case k>/u (and crack/lambda)."""
    cases = summary_cases(results, series)
    if cases is None:
        return None
    xdmf_deltas = [float(s["delta"]) if s["delta"] is not None else None for s in steps]
    deltas = [d for d, _ in cases]
    if len(cases) != len(steps) or any(
            x is None or d is None or not math.isclose(x, float(d), rel_tol=1e-12, abs_tol=0.0)
            for x, d in zip(xdmf_deltas, deltas)):
        raise Failure(f"{series}: δ of the XDMF steps {xdmf_deltas} differ from "
                      f"summary.json's {deltas}")
    h5 = os.path.join(results, "fields.h5")
    for k, (s, (_, grid)) in enumerate(zip(steps, cases)):
        if s["grid"] != grid:
            raise Failure(f"{series}: step {k} is grid {s['grid']!r}, summary.json's case "
                          f"{k} is {grid!r}")
        s["expect"] = {"u": (h5, f"/cases/{grid}/u")}
        if crack_steps is not None and k < len(crack_steps):
            crack_steps[k]["expect"] = {"lambda": (h5, f"/cases/{grid}/crack/lambda")}
    return deltas


# --------------------------------------------------------------------------- self-check (ParaView)

def _read_h5(path, dataset):
    import h5py
    import numpy as np
    with h5py.File(path, "r") as f:
        return np.asarray(f[dataset])


def _array_at(reader, t, centre, name):
    """The named array of the reader's output at time t, as numpy (builtin session)."""
    from vtk.util.numpy_support import vtk_to_numpy
    reader.UpdatePipeline(t)
    data = reader.GetClientSideObject().GetOutputDataObject(0)
    if data.IsA("vtkCompositeDataSet"):  # a reader that wraps the grid in a multiblock
        it = data.NewIterator()
        it.InitTraversal()
        data = it.GetCurrentDataObject()
    arrays = data.GetPointData() if centre != "Cell" else data.GetCellData()
    arr = arrays.GetArray(name)
    if arr is None:
        raise Failure(f"{reader.GetXMLName()} has no {centre or 'Node'} array {name!r} "
                      f"at t = {t:g}")
    return vtk_to_numpy(arr).astype(float), data


def check_file(simple, path, steps, name, report):
    """Open PATH with the default reader, walk every time step, compare NAME with the HDF5."""
    reader = simple.OpenDataFile(path)
    if reader is None:
        raise Failure(f"ParaView found no reader for {path}")
    tv = reader.TimestepValues  # a VectorProperty, or a bare float for a single step
    times = [float(tv)] if isinstance(tv, (int, float)) else [float(t) for t in (tv or [])]
    entry = {"file": path, "reader": reader.GetXMLName(), "times": times, "steps": []}
    report.append(entry)
    want = sorted(s["time"] for s in steps)
    if times != want:
        raise Failure(f"{os.path.basename(path)}: {reader.GetXMLName()} sees time steps {times}, "
                      f"the file has {want}")
    try:
        import h5py  # noqa: F401
        have_h5py = True
    except ImportError:
        have_h5py = False
    entry["compared_with_h5"] = have_h5py
    for s in sorted(steps, key=lambda s: s["time"]):
        if name not in s["attributes"]:
            if name == "lambda":  # a crack without lambda: its time steps were checked
                continue
            raise Failure(f"{os.path.basename(path)}: step {s['grid']} has no attribute {name}")
        h5, dataset, centre = s["attributes"][name]
        h5, dataset = s.get("expect", {}).get(name, (h5, dataset))
        values, data = _array_at(reader, s["time"], centre, name)
        row = {"time": s["time"], "grid": s["grid"], "delta": s["delta"],
               "points": data.GetNumberOfPoints(), "cells": data.GetNumberOfCells(),
               "range": [float(values.min()), float(values.max())], "dataset": dataset}
        if s["points"] is not None and data.GetNumberOfPoints() != s["points"]:
            raise Failure(f"{s['grid']}: ParaView read {data.GetNumberOfPoints()} points, "
                          f"the XDMF says {s['points']}")
        if have_h5py:
            ref = _read_h5(h5, dataset)
            row["h5_range"] = [float(ref.min()), float(ref.max())]
            if ref.shape != values.shape:
                raise Failure(f"{s['grid']}: {name} has shape {values.shape} in ParaView, "
                              f"{ref.shape} in {dataset}")
            scale = max(1.0, float(abs(ref).max()))
            err = float(abs(ref - values).max())
            row["max_abs_diff"] = err
            if not err <= 1e-12 * scale:
                raise Failure(f"{s['grid']}: {name} read by ParaView differs from {dataset} "
                              f"by {err:.3g}")
        entry["steps"].append(row)
    return reader


def edge_pixels(bounds, cells, width, height):
    """Typical triangle edge length in pixels once the domain fills the picture."""
    dx, dy = bounds[1] - bounds[0], bounds[3] - bounds[2]
    if cells <= 0 or dx <= 0 or dy <= 0:
        return 0.0
    px = min(0.72 * width / dx, 0.84 * height / dy)  # pixels per unit length (see render)
    return math.sqrt(2.0 * dx * dy / cells) * px


def nice_ticks(m):
    """Tick values at a round step within (-m, m), clear of the range labels at ±m."""
    raw = m / 3.0
    mag = 10.0 ** math.floor(math.log10(raw))
    step = next(k * mag for k in (1, 2, 2.5, 5, 10) if k * mag >= raw)
    n = int(math.floor(m / step))
    return [round(k * step, 12) for k in range(-n, n + 1) if abs(k * step) <= 0.93 * m]


def render(simple, reader, crack, t, delta, series, a, out):
    view = simple.CreateView("RenderView")
    view.ViewSize = [a.width, a.height]
    view.OrientationAxesVisibility = 0
    view.UseColorPaletteForBackground = 0
    view.Background = [1.0, 1.0, 1.0]
    view.ViewTime = t

    disp = simple.Show(reader, view)
    disp.Representation = "Surface"
    simple.ColorBy(disp, ("POINTS", "u"))
    disp.Ambient, disp.Diffuse = 1.0, 0.0  # unlit: the colours are the colour map's
    lut = simple.GetColorTransferFunction("u")
    lut.ApplyPreset("Cool to Warm", True)
    lut.AutomaticRescaleRangeMode = "Never"
    reader.UpdatePipeline(t)  # the colour range and bounds are the shown step's
    info = reader.GetDataInformation()
    lo, hi = reader.PointData["u"].GetRange()
    m = max(abs(lo), abs(hi)) or 1.0
    lut.RescaleTransferFunction(-m, m)
    simple.GetOpacityTransferFunction("u").RescaleTransferFunction(-m, m)
    bar = simple.GetScalarBar(lut, view)
    bar.Title = "u"
    bar.HorizontalTitle = 1
    bar.ComponentTitle = ""
    bar.TitleColor = bar.LabelColor = [0.1, 0.1, 0.1]
    bar.TitleFontSize = 22
    bar.LabelFontSize = 16
    bar.TitleBold = 1
    bar.ScalarBarThickness = 20
    bar.ScalarBarLength = 0.6
    bar.WindowLocation = "Any Location"
    bar.Orientation = "Vertical"
    bar.Position = [0.86, 0.2]
    bar.RangeLabelFormat = "%-#.2f"
    bar.AddRangeLabels = 1
    bar.DrawTickLabels = 1
    bar.UseCustomLabels = 1
    bar.CustomLabels = nice_ticks(m)
    bar.LabelFormat = "%-#.6g"
    bar.Visibility = 1

    bounds = info.GetBounds()
    cells = info.GetNumberOfCells()
    show_edges = a.edges == "on" or (
        a.edges == "auto" and edge_pixels(bounds, cells, a.width, a.height) >= 9.0)
    if show_edges:
        edges = simple.ExtractEdges(Input=reader)
        ed = simple.Show(edges, view)
        ed.ColorArrayName = ["POINTS", ""]  # solid colour
        ed.AmbientColor = ed.DiffuseColor = [0.15, 0.15, 0.15]
        ed.Opacity = 0.22
        ed.LineWidth = 1.0

    # The domain's boundary (and, for a broken u, the crack's faces) in thin grey: u = 0 on the
    # boundary is the colour map's grey, close to the background.
    border = simple.FeatureEdges(Input=simple.ExtractSurface(Input=reader), BoundaryEdges=1,
                                 FeatureEdges=0, NonManifoldEdges=0, ManifoldEdges=0)
    bd = simple.Show(border, view)
    bd.ColorArrayName = ["POINTS", ""]  # solid colour
    bd.AmbientColor = bd.DiffuseColor = [0.35, 0.35, 0.35]
    bd.LineWidth = 2.0
    bd.RenderLinesAsTubes = 1  # round joints: no pixel gaps between segments

    if crack is not None:
        cd = simple.Show(crack, view)
        cd.Representation = "Surface"
        cd.ColorArrayName = ["POINTS", ""]  # solid colour
        cd.AmbientColor = cd.DiffuseColor = [0.0, 0.0, 0.0]
        cd.LineWidth = 5.0
        cd.RenderLinesAsTubes = 1

    # ParaView's built-in fonts have no Greek letters: δ needs a font file that has them.
    font = next((f for f in GREEK_FONTS if os.path.isfile(f)), None)
    letter = "\u03b4" if font else "delta"
    scene = f"{a.scene}: " if a.scene else ""
    title = simple.Text(Text=f"{scene}u at {letter} = {delta}    ({series})")
    td = simple.Show(title, view)
    if font:
        td.FontFamily = "File"
        td.FontFile = font
    td.WindowLocation = "Upper Center"
    td.FontSize = 22
    td.Color = [0.1, 0.1, 0.1]

    # Camera: looking down -z, parallel projection; the domain takes the left ~72 % of the width
    # (the scalar bar sits to its right) and ~84 % of the height (the title above it).
    cx, cy = 0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3])
    dx, dy = bounds[1] - bounds[0], bounds[3] - bounds[2]
    aspect = a.width / a.height
    scale = max(dy / 0.84, dx / 0.72 / aspect) / 2.0  # parallel scale = half the visible height
    shift = 0.5 * 2 * scale * aspect * (0.5 - 0.42)  # move the domain's centre to 42 % of the width
    view.InteractionMode = "2D"
    view.CameraParallelProjection = 1
    view.CameraFocalPoint = [cx + shift, cy + 0.01 * scale, 0.0]
    view.CameraPosition = [cx + shift, cy + 0.01 * scale, 10.0 * max(dx, dy, 1e-12)]
    view.CameraViewUp = [0.0, 1.0, 0.0]
    view.CameraParallelScale = scale

    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    simple.SaveScreenshot(out, view, ImageResolution=[a.width, a.height],
                          TransparentBackground=0, CompressionLevel="9")
    if not os.path.isfile(out):
        raise Failure(f"ParaView wrote no {out}")
    return show_edges


def main(argv):
    a = parse_args(argv)
    results = os.path.abspath(a.results)
    if not os.path.isdir(results):
        raise BadInput(f"{a.results}: no such folder")
    if not os.path.isfile(os.path.join(results, "fields.h5")):
        scenes = sorted(d for d in os.listdir(results)
                        if os.path.isfile(os.path.join(results, d, "fields.h5")))
        hint = (f"; give a scene's folder, e.g. {os.path.join(a.results, scenes[0])}" if scenes
                else " (run with [outputs] fields)")
        raise BadInput(f"{a.results}: no fields.h5{hint}")
    series = pick_series(results, a.series)
    path = os.path.join(results, "fields", series + SERIES)
    steps = parse_series(path)
    if any("u" not in s["attributes"] for s in steps):
        raise BadInput(f"series {series} has no u at every step (run with u in [outputs] fields)")
    crack_path = os.path.join(results, "fields", series + ".crack" + SERIES)
    crack_steps = parse_series(crack_path) if os.path.isfile(crack_path) else None
    out = os.path.abspath(a.out) if a.out else os.path.join(results, "render", series + ".png")
    if a.validate_only:
        return 0

    from paraview import simple

    report = {"series": series, "xdmf": path, "files": []}
    try:
        with open(os.path.join(results, "summary.json")) as f:
            a.scene = json.load(f).get("scene")
    except (OSError, ValueError, AttributeError):
        a.scene = None
    try:
        report["summary_deltas"] = expect_from_summary(results, series, steps, crack_steps)
        reader = check_file(simple, path, steps, "u", report["files"])
        crack = None
        if crack_steps is not None:
            crack = check_file(simple, crack_path, crack_steps, "lambda", report["files"])
            if [s["delta"] for s in crack_steps] != [s["delta"] for s in steps]:
                raise Failure(f"{series}: the crack file's steps have other δ than the field's")
        last = max(steps, key=lambda s: s["time"])
        if last["delta"] is not None and any(
                s["delta"] is not None and float(s["delta"]) < float(last["delta"]) for s in steps):
            raise Failure(f"{series}: the last time step is not the smallest δ")
        report["self_check"] = "ok"
        report["rendered"] = {"time": last["time"], "delta": last["delta"], "grid": last["grid"],
                              "png": out, "size": [a.width, a.height]}
        edges = render(simple, reader, crack, last["time"], last["delta"], series, a, out)
        report["rendered"]["edges"] = edges
    except Exception as e:
        report.setdefault("self_check", f"failed: {e}")
        report["error"] = f"{type(e).__name__}: {e}"
        raise
    finally:
        if a.check_json:
            with open(a.check_json, "w") as f:
                json.dump(report, f, indent=1)
    n = len(steps)
    k = sorted(s["time"] for s in steps).index(last["time"]) + 1
    h5 = ("u" + (", lambda" if crack_steps else "") + " = fields.h5"
          if report["files"][0].get("compared_with_h5") else "values not compared: no h5py")
    steps_word = "time step" if n == 1 else "time steps"
    print(f"{PREFIX} wrote {out} ({series}, \u03b4 = {last['delta']}, step {k} of {n}; "
          f"self-check ok: {report['files'][0]['reader']}, {n} {steps_word}, {h5})", flush=True)
    return 0


if __name__ == "__main__":
    try:
        code = main(sys.argv[1:])
    except BadInput as e:
        print(f"{PREFIX} {e}", flush=True)
        code = 2
    except Failure as e:
        print(f"{PREFIX} {e}", flush=True)
        code = 1
    except Exception as e:  # ParaView's own errors: still one line (the traceback on stderr)
        import traceback
        traceback.print_exc()
        print(f"{PREFIX} {type(e).__name__}: {e}", flush=True)
        code = 1
    sys.stdout.flush()
    # pvpython can crash while tearing down its render windows; the work is done by now.
    os._exit(code)
