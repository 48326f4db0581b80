"""Editing repository scene files as text in tests (one home for the Python test suites).

Tests derive their scenes from `scenes/*.toml` by replacing single `key = value` lines, so that a
scene that moves a line makes the test fail loudly instead of silently running something else.
"""

import pathlib
import re

SCENES = pathlib.Path(__file__).resolve().parents[2] / "scenes"


def set_key(text, key, value):
    """Replaces the one line `key = ...` of a repository scene (fails loudly if it moved)."""
    new, n = re.subn(rf"(?m)^{key} = .*$", f"{key} = {value}", text)
    assert n == 1, f"scene line `{key} = ...` not found once"
    return new


def add_key(text, after, key, value):
    """Adds the line `key = value` after the one line `after = ...` of a repository scene (fails
    loudly if that line moved, or if the scene has a `key = ...` line already)."""
    assert not re.search(rf"(?m)^{key} = ", text), f"scene line `{key} = ...` already there"
    new, n = re.subn(rf"(?m)^{after} = .*$", lambda m: f"{m.group(0)}\n{key} = {value}", text)
    assert n == 1, f"scene line `{after} = ...` not found once"
    return new


def scene_with(name, *lines):
    """The text of the repository scene scenes/<name>.toml with each `(key, value)` of `lines`
    set in turn (set_key)."""
    text = (SCENES / f"{name}.toml").read_text(encoding="utf-8")
    for key, value in lines:
        text = set_key(text, key, value)
    return text
