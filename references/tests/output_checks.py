"""Checks of a reference's result folder shared by the reference tests (not a test module):
summary.json's provenance, and the field files (every *.xdmf readable by meshio, the HDF5
attributes); and `load_module`, which imports a reference's solve.py under a name of its own."""

import importlib.util
import json
import platform
import re
from pathlib import Path

import numpy as np

from sdshared import sdfields
from sdshared import sdresults

# The references' crack fields, named as in every solver's files (README's field table).
CRACK_FIELDS = {"jump", "contact_force"}


def load_module(name, path):
    """The Python file `path` imported as module `name` (each test file its own copy)."""
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def assert_provenance(summary, tool, script=None):
    """summary["provenance"] has every key of sdresults.PROVENANCE_KEYS, none empty; `script`: the
    solve.py the command line must name (a command-line run)."""
    if not isinstance(summary, dict):
        summary = json.loads(Path(summary).read_text())
    prov = summary["provenance"]
    assert set(prov) == set(sdresults.PROVENANCE_KEYS), prov
    for key, value in prov.items():
        assert value not in (None, "", [], {}), (key, value)
    assert prov["tool"] == tool == summary["tool"]
    assert isinstance(prov["tool_version"], str) and prov["tool_version"] != "unknown", prov
    assert re.fullmatch(r"[0-9]+\.[0-9]+\S*", prov["tool_version"]), prov
    assert prov["python"] == platform.python_version()
    assert prov["numpy"] == np.__version__
    assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", prov["date_utc"]), prov
    assert isinstance(prov["command_line"], list) and all(isinstance(a, str) for a in prov["command_line"])
    assert isinstance(prov["cores"], int) and prov["cores"] >= 1
    # the BLAS/OpenMP threads it ran with: each variable's value, null where unset
    assert set(prov["threads"]) == {name for name, _ in sdresults.PINNED_THREADS}, prov
    assert all(v is None or isinstance(v, str) for v in prov["threads"].values()), prov
    if script is not None:
        assert Path(prov["command_line"][0]).resolve() == Path(script).resolve(), prov["command_line"]
    return prov


def assert_fields_readable(out, export, summary, tool):
    """Every *.xdmf under `out` is read by meshio.read: the per-level grid has finite point data of
    the mesh's length (u among them), the crack grid finite CRACK_FIELDS (jump = u⁺ − u⁻ and
    contact_force = the nodal λ ≥ 0, 0 at the tips; not under its old name multiplier) of the cracks' length and one line per segment within a crack (cracks.txt; absent: one crack); there is
    no top-level fields.xdmf; fields.h5's datasets carry level, h, tool."""
    import h5py
    import meshio

    out, export = Path(out), Path(export)
    levels = {c["level"]: c for c in summary["cases"]}
    assert not (out / "fields.xdmf").exists()
    found = sorted(p.relative_to(out).as_posix() for p in out.rglob("*.xdmf"))
    assert found == sorted([f"fields/level{L}.xdmf" for L in levels] + [f"fields/level{L}.crack.xdmf" for L in levels])
    for rel in found:
        m = meshio.read(out / rel)
        L = int(re.match(r"fields/level(\d+)", rel).group(1))
        n = len(m.points)
        assert n > 0 and np.isfinite(m.points).all()
        if rel.endswith(".crack.xdmf"):
            crack = np.loadtxt(export / f"level{L}" / "crack.txt", dtype=np.int64, ndmin=2)
            cracks = export / f"level{L}" / "cracks.txt"
            ranges = np.loadtxt(cracks, dtype=np.int64, ndmin=2) if cracks.exists() else [(0, len(crack))]
            assert n == len(crack)
            assert [(b.type, len(b.data)) for b in m.cells] == [("line", n - len(ranges))]
            within = {(k, k + 1) for first, c in ranges for k in range(first, first + c - 1)}
            assert {tuple(map(int, s)) for s in m.cells[0].data} == within, rel
            assert CRACK_FIELDS <= set(m.point_data) and "multiplier" not in m.point_data, rel
            pairs = np.asarray(crack)
            u = np.loadtxt(out / f"u_level{L}.txt")
            np.testing.assert_array_equal(m.point_data["jump"], u[pairs[:, 0]] - u[pairs[:, 1]])
            force = sdfields.crack_field(m.point_data, "contact_force")
            assert force.min() >= -1e-10 * max(1.0, force.max()), rel  # λ ≥ 0 (KKT_TOLERANCE)
            assert (force[pairs[:, 0] == pairs[:, 1]] == 0).all(), rel  # 0 at the tips
        else:
            tri = np.loadtxt(export / f"level{L}" / "triangles.txt", dtype=np.int64, ndmin=2)
            assert n == levels[L]["unknowns"]
            assert [(b.type, len(b.data)) for b in m.cells] == [("triangle", len(tri))]
            assert {"u", "p"} <= set(m.point_data), rel  # p = ∇u_h at the vertices (sdfields)
            assert m.point_data["p"].shape == (n, 3), rel
            np.testing.assert_array_equal(m.point_data["u"], np.loadtxt(out / f"u_level{L}.txt"))
        for name, values in m.point_data.items():
            assert values.shape[0] == n and np.isfinite(values).all(), (rel, name)
        for name, blocks in m.cell_data.items():
            for values, block in zip(blocks, m.cells):
                assert len(values) == len(block.data) and np.isfinite(values).all(), (rel, name)
    with h5py.File(out / "fields.h5", "r") as h5:
        assert h5.attrs["tool"] == tool
        datasets = []
        h5.visititems(lambda name, obj: datasets.append((name, obj)) if isinstance(obj, h5py.Dataset) else None)
        assert datasets
        for name, ds in datasets:
            L = int(re.search(r"level(\d+)", name).group(1))
            assert ds.attrs["level"] == L and ds.attrs["tool"] == tool, name
            assert ds.attrs["h"] == levels[L]["h"], name
