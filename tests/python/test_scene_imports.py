"""The modules of the scene format (crates/sdcrack-io/src/scene_file/*.rs) import one another without a
cycle: the serde structs (raw.rs) are the leaf every other part reads, the schema is derived from
them, validation and messages sit on top. A cycle (raw → verification → schema → raw, as it was
when the `[verification]` structs lived in verification.rs) means no module can be read, tested or
moved without the others; this test states the graph, as test_layout.py states the crate graph.

An edge A → B is a `use super::B…` / `use crate::scene_file::B…` of module A, or a path
`super::B::…` / `crate::scene_file::B::…` in its code (comments left out), where B is a sibling
module. The parent (scene_file.rs) is not a node: it declares the modules and re-exports; that no child
takes anything from it (the shared types live in error.rs, limits.rs, …) is test_module_graph.py's."""

import pathlib
import re

from graphs import find_cycle

SCENE = pathlib.Path(__file__).resolve().parents[2] / "crates" / "sdcrack-io" / "src" / "scene_file"


def code_of(text):
    """`text` without `//` comments (doc comments name modules in prose)."""
    return "\n".join(line.split("//", 1)[0] for line in text.splitlines())


def imports(code, modules):
    """The sibling modules that the Rust `code` of one module names."""
    found = set()
    prefix = r"(?:super|crate::scene_file)::"
    for group in re.findall(prefix + r"\{([^}]*)\}", code):
        # `use super::{raw::X, schema::Y, Z}`: the first segment of each item
        found |= {item.strip().split("::")[0] for item in group.split(",")}
    found |= set(re.findall(prefix + r"([a-z_][a-z0-9_]*)\b", code))
    return found & modules


def graph(files):
    """Module name → the sibling modules it imports, for `files` (name → Rust text)."""
    modules = set(files) - {"mod"}
    return {m: imports(code_of(files[m]), modules) - {m} for m in modules}


def cycle(edges):
    """One import cycle of `edges` as a list of modules (first = last), or None."""
    return find_cycle(edges)


def scene_files():
    return {p.stem: p.read_text() for p in SCENE.glob("*.rs")}


def test_the_scene_format_modules_import_without_a_cycle():
    edges = graph(scene_files())
    assert {"raw", "schema", "validate", "verification"} <= set(edges)
    assert cycle(edges) is None, " → ".join(cycle(edges))


def test_the_serde_structs_are_a_leaf():
    """raw.rs imports no sibling: the `[verification]` structs live there too."""
    assert graph(scene_files())["raw"] == set()


def test_a_cycle_is_found():
    """The check fails on the cycle it was written against, in each spelling of an import."""
    files = {
        "mod": "mod raw; mod schema; mod verification;",
        "raw": "use super::verification::VerificationToml;",
        "verification": "use super::{schema::P_MASSES, SceneError};",
        "schema": "fn f() { let s = crate::scene_file::raw::SceneToml::default(); }",
    }
    edges = graph(files)
    assert edges == {"raw": {"verification"}, "verification": {"schema"}, "schema": {"raw"}}
    assert cycle(edges) == ["raw", "verification", "schema", "raw"]
    # a comment naming a module is no import; without the back-edge the graph is a chain
    files["schema"] = "// see super::raw\nfn f() {}"
    assert cycle(graph(files)) is None
