"""What the compare tool's tests that run the real solver share: where the sdcrack binary is and
the environment its runs (and the reference solvers it starts) need. One home for both; the
tests import it as a sibling module (pytest puts this folder on sys.path)."""
import os

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def sdcrack_bin():
    """$SDCRACK_BIN, else this checkout's release build (which may not exist: callers skip)."""
    return os.environ.get("SDCRACK_BIN") or os.path.join(ROOT, "target", "release", "sdcrack")


def env():
    """The process environment with FreeFEM's plugin path (Debian's) and matplotlib's headless
    backend, unless already set."""
    e = dict(os.environ)
    e.setdefault("FF_LOADPATH", "/usr/lib/freefem++")
    e.setdefault("MPLBACKEND", "Agg")
    return e
