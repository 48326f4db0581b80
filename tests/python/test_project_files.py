"""The project's LICENSE and CITATION.cff agree with Cargo.toml, and the citation names the paper
the method comes from (Belhachmi, Sac-Epée, Sokolowski, C. R. Math. 338 (2004) 499-504)."""

import pathlib
import tomllib


import yaml  # noqa: E402  python3-yaml, installed by ci/setup

ROOT = pathlib.Path(__file__).resolve().parents[2]
SPDX_FIRST_LINE = {"MIT": "MIT License"}  # the licence texts this check knows


def cargo_package():
    """The root package's table, keys inherited from the workspace (`license.workspace = true`)
    resolved from [workspace.package]."""
    cargo = tomllib.loads((ROOT / "Cargo.toml").read_text())
    inherited = cargo.get("workspace", {}).get("package", {})
    return {k: inherited[k] if v == {"workspace": True} else v for k, v in cargo["package"].items()}


def test_license_file_matches_cargo_toml():
    license_id = cargo_package()["license"]
    assert license_id in SPDX_FIRST_LINE, f"unknown licence {license_id}: extend this test"
    assert (ROOT / "LICENSE").read_text().splitlines()[0] == SPDX_FIRST_LINE[license_id]


def test_citation_cff_names_the_software_and_the_paper():
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0"
    for key in ("message", "title", "authors", "type"):
        assert cff[key], key
    pkg = cargo_package()
    assert cff["license"] == pkg["license"]
    assert str(cff["version"]) == pkg["version"]
    (paper,) = [r for r in cff["references"] if r.get("doi") == "10.1016/j.crma.2004.01.008"]
    assert [a["family-names"] for a in paper["authors"]] == ["Belhachmi", "Sac-Epée", "Sokolowski"]
    assert (paper["year"], paper["volume"], paper["start"], paper["end"]) == (2004, 338, 499, 504)
