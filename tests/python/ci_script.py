"""Loads one of the checkout's tool scripts (tools/, files, not an importable package) as a module,
for the tests of its functions: one home for the loader those tests share."""

import importlib.util
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[2]


def load(relative_path, name=None):
    """The module of ROOT/relative_path (e.g. "tools/bench_norms.py"), executed once per call."""
    path = ROOT / relative_path
    spec = importlib.util.spec_from_file_location(name or path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
