"""Editing repository scene files as text in tests (one home for the Python test suites).

Tests derive their scenes from `scenes/*.toml` by replacing single `key = value` lines, so that a
scene that moves a line makes the test fail loudly instead of silently running something else.
"""

import re


def set_key(text, key, value):
    """Replaces the one line `key = ...` of a repository scene (fails loudly if it moved)."""
    new, n = re.subn(rf"(?m)^{key} = .*$", f"{key} = {value}", text)
    assert n == 1, f"scene line `{key} = ...` not found once"
    return new
