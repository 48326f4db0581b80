"""Result folders of the reference solvers: written under a temporary name beside the final one
and renamed only when complete, so an interrupted run leaves nothing under the final name."""

import json
import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def staged_folder(out):
    """Yields a new temporary folder beside `out`; when the block completes it replaces `out`
    (the caller decides beforehand whether replacing is allowed), on any error it is removed."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.tmp-", dir=out.parent))
    try:
        yield tmp
        if out.exists():
            shutil.rmtree(out)
        os.rename(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def write_summary(folder, scene, tool, cases):
    """folder/summary.json = {"scene", "tool", "cases"}; returns the dict."""
    summary = {"scene": scene, "tool": tool, "cases": cases}
    (Path(folder) / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    return summary
