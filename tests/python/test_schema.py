"""The scene schema has one home, the solver's serde structs (`sdcrack schema` prints it), and the
compare tool's knowledge of scenes is tied to it: the verification vocabulary (error quantities,
checks a scene may declare not applicable), the [verification] tables' keys, the names of p
masses and p spaces, and every scene key compare/sdcompare_lib/settings.py reads. A name gained on
one side only fails here.

The solver: $SDCRACK_BIN, else target/release/sdcrack.
"""
import ast
import json
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
from conftest import sdcrack_bin
from sdcompare_lib import cases, settings

SETTINGS_SOURCE = pathlib.Path(settings.__file__).read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def schema():
    exe = sdcrack_bin()
    if not os.access(exe, os.X_OK):
        pytest.skip(f"no sdcrack binary at {exe} (cargo build --release, or set SDCRACK_BIN)")
    out = subprocess.run([exe, "schema"], capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def keys(schema, table):
    """{key: entry} of `table` in the schema."""
    (found,) = [t for t in schema["tables"] if t["table"] == table]
    return {k["key"]: k for k in found["keys"]}


def test_verification_vocabulary_is_the_solvers(schema):
    vocabulary = schema["vocabulary"]
    assert tuple(vocabulary["quantities"]) == settings.QUANTITIES
    assert tuple(vocabulary["not_applicable_checks"]) == settings.DECLARABLE_CHECKS
    assert tuple(keys(schema, "verification.expected_failure")["quantity"]["values"]) \
        == settings.QUANTITIES


def test_verification_keys_are_the_solvers(schema):
    verification = keys(schema, "verification")
    numbers = {k for k, e in verification.items() if e["type"] == "number"}
    assert numbers == set(settings.DEFAULTS), "the tolerances with a compare-tool default"
    assert tuple(keys(schema, "verification.expected_rate")) == settings.EXPECTED_RATE_KEYS
    tables = {k for k, e in verification.items() if e["type"] == "list of table"}
    assert tables == {"expected_failure", "expected_rate", "not_applicable"}
    # every key of the [verification] tables is one the compare tool reads
    read_names = string_constants()
    for table in ("verification", "verification.expected_failure",
                  "verification.expected_rate", "verification.not_applicable"):
        missing = set(keys(schema, table)) - read_names
        assert not missing, f"settings.py does not read {table} keys {sorted(missing)}"


def test_names_of_p_masses_and_p_spaces_are_the_solvers(schema):
    discretization = keys(schema, "discretization")
    assert tuple(discretization["p_mass"]["values"]) == cases.P_MASSES
    assert tuple(discretization["p_spaces"]["values"]) == cases.P_SPACES


def test_case_key_is_the_solvers(schema):
    """cases.CaseKey's fields are the solver's case axes in its order (`sdcrack schema`'s
    "case_key": [{"axis", "values" (the names; [] for a number), "default"}]), the names of each
    named axis those the compare tool knows, and its defaults the compare tool's."""
    axes = schema["case_key"]
    assert tuple(a["axis"] for a in axes) == cases.CaseKey._fields
    by_axis = {a["axis"]: a for a in axes}
    assert by_axis["level"]["values"] == [] and by_axis["delta"]["values"] == []
    assert tuple(by_axis["p_mass"]["values"]) == cases.P_MASSES
    assert tuple(by_axis["p_space"]["values"]) == cases.P_SPACES
    assert by_axis["p_mass"]["default"] == cases.DEFAULT_P_MASS
    assert by_axis["p_space"]["default"] == cases.DEFAULT_P_SPACE
    # a case of summary.json without an axis that has a default reads as that default
    case = {a["axis"]: a["values"][0] if a["values"] else 0 for a in axes}
    for a in axes:
        if a["default"] is not None:
            absent = {k: v for k, v in case.items() if k != a["axis"]}
            assert getattr(cases.case_key(absent), a["axis"]) == a["default"], a["axis"]


def test_every_scene_key_settings_reads_is_in_the_schema(schema):
    known = {k["key"] for t in schema["tables"] for k in t["keys"]}
    tables = {t["table"].split(".")[-1] for t in schema["tables"]}
    gets = get_literals()
    assert gets, "settings.py reads no key?"
    unknown = gets - known - tables
    assert not unknown, f"settings.py reads keys the scene does not have: {sorted(unknown)}"


def get_literals():
    """The string literals `x` of the `….get("x", …)` calls in settings.py."""
    out = set()
    for node in ast.walk(ast.parse(SETTINGS_SOURCE)):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) \
                and node.func.attr == "get" and node.args \
                and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str):
            out.add(node.args[0].value)
    return out


def string_constants():
    """Every string constant of settings.py (the keys it reads, in calls, tuples and dicts)."""
    return {node.value for node in ast.walk(ast.parse(SETTINGS_SOURCE))
            if isinstance(node, ast.Constant) and isinstance(node.value, str)}
