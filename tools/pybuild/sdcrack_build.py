"""The PEP 517 build backend of sdcrack-tools (pyproject.toml): setuptools' own, with two changes.

1. setuptools builds in the source tree (build/, *.egg-info); here it builds under
   target/pip-build/ (pyproject.toml's [tool.distutils.*] tables; git ignores target/), which this
   module creates, since setuptools needs the egg-info folder to exist. `pip install .` leaves the
   checkout as it found it.
2. The runtime dependencies are DEPENDENCIES, with h5py only when the installing interpreter
   cannot already import an h5py. Debian's python3-h5py is an h5py that pip does not see (its
   distribution is named `h5py._debian_h5py_serial`), so a venv made with --system-site-packages
   from Debian's python would otherwise get a second h5py from PyPI beside Debian's. The list is
   written to target/pip-build/requirements.txt, which pyproject.toml names as the source of its
   dynamic dependencies.
"""
import os
import subprocess
import sys

from setuptools.build_meta import *  # noqa: F401,F403  every hook of setuptools' backend

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.path.join(ROOT, "target", "pip-build")
# Lower bounds: Debian 12's versions (python3-numpy 1.24, python3-h5py 3.7, python3-matplotlib
# 3.6, python3-meshio 5.0), which ci/test uses through /usr/bin/python3.
DEPENDENCIES = ["numpy>=1.24", "matplotlib>=3.6", "meshio>=5.0"]
H5PY = "h5py>=3.7"


def h5py_importable(python=sys.executable):
    """Whether `python` imports h5py outside pip's isolated build environment (whose PYTHONPATH
    and PYTHONNOUSERSITE hide the interpreter's own site-packages)."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "PYTHONNOUSERSITE", "PYTHONHOME")}
    p = subprocess.run([python, "-c", "import h5py"], env=env, cwd="/", capture_output=True)
    return p.returncode == 0


def dependencies(importable):
    """The runtime dependencies: h5py only when none is importable."""
    return DEPENDENCIES + ([] if importable else [H5PY])


def _prepare():
    os.makedirs(BUILD, exist_ok=True)
    with open(os.path.join(BUILD, "requirements.txt"), "w", encoding="utf-8") as fh:
        fh.write("\n".join(dependencies(h5py_importable())) + "\n")


_prepare()
