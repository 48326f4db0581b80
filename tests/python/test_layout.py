"""The layering is the crate graph: the maths and the study (problem, expr, fe, mesh,
geometry, assembly, linalg, ordering, contact, multiplier, krylov, norms, the validated scene
struct, study) are the crate sdcrack-core, which depends on no TOML, CLI, HDF5 or JSON crate; the
scene's TOML format and the results formats are sdcrack-io, on top of it; the binary (command
line, bench, reference runner) is the root package sdcrack, on top of both. The compiler enforces
the direction (a crate cannot name one it does not depend on); these tests state the graph, so
that a dependency added against it is a failing test, not a quiet change."""

import json
import pathlib
import shutil
import subprocess
import tomllib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
CARGO = shutil.which("cargo") or str(pathlib.Path.home() / ".cargo" / "bin" / "cargo")

# Each workspace crate's direct dependencies (normal, i.e. not dev or build), exactly.
GRAPH = {
    "sdcrack-core": {"faer", "rayon", "thiserror", "serde", "strsim"},
    "sdcrack-io": {"sdcrack-core", "hdf5", "hdf5-sys", "thiserror", "serde", "serde_json",
                   "toml_edit", "strsim", "humantime"},
    "sdcrack": {"sdcrack-core", "sdcrack-io", "faer", "rayon", "thiserror", "clap", "serde",
                "serde_json", "indicatif"},
}
MANIFESTS = {
    "sdcrack-core": ROOT / "crates" / "sdcrack-core" / "Cargo.toml",
    "sdcrack-io": ROOT / "crates" / "sdcrack-io" / "Cargo.toml",
    "sdcrack": ROOT / "Cargo.toml",
}
# Crates of file formats and the command line: none of them may reach the core, even indirectly.
FORMATS = {"toml", "clap", "hdf5-metno", "hdf5-metno-sys", "serde_json", "indicatif", "humantime"}
# The modules of each crate (file or folder names under its src/).
MODULES = {
    "sdcrack-core": {"problem", "elasticity", "case", "expr", "fe", "mesh", "geometry", "assembly", "linalg", "ordering",
                     "contact", "multiplier", "krylov", "norms", "scene", "study", "afw"},
    "sdcrack-io": {"scene_file", "output", "plain", "did_you_mean", "one_line"},
    "sdcrack": {"cli", "bench", "references", "main"},
}


def manifest(crate):
    return tomllib.loads(MANIFESTS[crate].read_text())


def test_each_crate_depends_on_exactly_its_layer():
    for crate, expected in GRAPH.items():
        assert manifest(crate)["package"]["name"] == crate
        assert set(manifest(crate).get("dependencies", {})) == expected, crate


def test_the_core_lists_no_format_or_cli_crate_at_all():
    """Not even as a dev- or build-dependency: its tests build their scenes without TOML."""
    core = manifest("sdcrack-core")
    listed = {name for table in ("dependencies", "dev-dependencies", "build-dependencies")
              for name in core.get(table, {})}
    listed |= {spec.get("package", name) for name, spec in
               manifest("sdcrack")["workspace"]["dependencies"].items()
               if name in listed and isinstance(spec, dict)}
    assert not listed & (FORMATS | {"hdf5", "hdf5-sys", "sdcrack-io", "sdcrack"}), listed


def test_the_root_commands_cover_every_crate():
    workspace = manifest("sdcrack")["workspace"]
    members = {".", "crates/sdcrack-core", "crates/sdcrack-io"}
    assert set(workspace["members"]) == members
    assert set(workspace["default-members"]) == members


def test_the_modules_sit_in_their_crates():
    where = {"sdcrack-core": ROOT / "crates" / "sdcrack-core" / "src",
             "sdcrack-io": ROOT / "crates" / "sdcrack-io" / "src",
             "sdcrack": ROOT / "src"}
    for crate, src in where.items():
        found = {p.stem for p in src.iterdir() if p.suffix == ".rs" or p.is_dir()} - {"lib"}
        assert found == MODULES[crate], crate


@pytest.mark.skipif(not pathlib.Path(CARGO).exists(), reason="needs cargo")
def test_the_resolved_graph_keeps_formats_out_of_the_core():
    """cargo's own view, transitive: nothing the core compiles against is a format crate."""
    rustc = pathlib.Path(CARGO).with_name("rustc")
    host = subprocess.run([str(rustc) if rustc.exists() else "rustc", "-vV"], capture_output=True,
                          text=True, timeout=60, check=True).stdout.split("host: ")[1].split()[0]
    # this platform only: offline, cargo cannot fetch other platforms' crates (anstyle-wincon)
    out = subprocess.run([CARGO, "metadata", "--format-version", "1", "--offline",
                          "--filter-platform", host], cwd=ROOT, capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    meta = json.loads(out.stdout)
    names = {p["id"]: p["name"] for p in meta["packages"]}
    nodes = {n["id"]: n for n in meta["resolve"]["nodes"]}

    def normal_deps(pid):
        return {d["pkg"] for d in nodes[pid]["deps"]
                if any(k["kind"] is None for k in d["dep_kinds"])}

    by_name = {names[pid]: pid for pid in meta["workspace_members"]}
    assert set(by_name) == set(GRAPH)
    for crate, expected in GRAPH.items():
        direct = {names[d] for d in normal_deps(by_name[crate])}
        assert direct == {{"hdf5": "hdf5-metno", "hdf5-sys": "hdf5-metno-sys"}.get(e, e)
                          for e in expected}, crate
    seen, todo = set(), [by_name["sdcrack-core"]]
    while todo:
        pid = todo.pop()
        for d in normal_deps(pid) - seen:
            seen.add(d)
            todo.append(d)
    reached = {names[d] for d in seen}
    assert not reached & (FORMATS | {"sdcrack-io", "sdcrack"}), sorted(reached & FORMATS)
