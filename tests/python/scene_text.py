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


# The small test scenes' geometry: the square (−1, 1)² cut by the crack (−0.5, 0)–(0.5, 0).
SQUARE_CRACK = {"domain": "{ rectangle = [[-1.0, -1.0], [1.0, 1.0]] }",
                "crack": "{ segment = [[-0.5, 0.0], [0.5, 0.0]] }"}


def square_scene(name, description, data, discretization, exact=None):
    """A scene file's text on SQUARE_CRACK, 4 × 4 cells, storing u, p and λ, without references:
    `data`, `discretization` and `exact` (optional) are {key: TOML value text}."""
    tables = [("geometry", SQUARE_CRACK), ("data", data)] + ([("exact", exact)] if exact else []) \
        + [("discretization", {"cells": "[4, 4]", **discretization}),
           ("outputs", {"fields": '["u", "p", "lambda"]', "references": "[]"})]
    return f'name = "{name}"\ndescription = "{description}"\n' + "".join(
        f"\n[{table}]\n" + "".join(f"{k} = {v}\n" for k, v in keys.items())
        for table, keys in tables)
