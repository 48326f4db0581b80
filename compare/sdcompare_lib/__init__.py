"""sdcompare: convergence / agreement report for one sdcrack results folder.

In a checkout the references' shared modules (references/common: sdexpr, sdexport, ...) are made
importable here; installed (pyproject.toml), they are top-level modules beside this package."""
import os
import sys

_COMMON = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                       "references", "common")
if os.path.isdir(_COMMON) and _COMMON not in sys.path:
    sys.path.insert(0, _COMMON)
