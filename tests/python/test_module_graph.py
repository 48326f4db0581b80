"""The layering inside a crate's folders, as test_layout.py states the graph between crates: a
folder's shared types live in a ground file of the folder, not in its parent file (`foo.rs` of
`foo/`), so that no child reaches back into its parent and the parent can be left to declare
its modules and re-export them.

Two rules, read off the source text (no build; a `use`, or a path in code, is what a module
names):
- no child module (nor any deeper descendant) names an item defined in an ancestor's own file: a
  struct, enum, fn, const, static, type, trait, union or macro written there, not a `mod`
  declaration and not a `pub use` re-export (naming a re-export is naming the sibling it comes
  from);
- the modules of each folder (its parent file and its children, a child standing for its own
  subfolder) import one another without a cycle.

Unit tests are exempt: a `#[cfg(test)]` module named `tests` or `testing` (a file or an inline
block) may `use super::*`, the Rust idiom for white-box tests, and so may a module declared with
`#[cfg(test)]` under any name. Comments and doc links do not count.

Both crates are held to both rules: the core, and sdcrack-io, whose folders (output,
output/xdmf, scene_file) keep their shared types in ground files too (output/results_dir.rs,
output/atomic.rs, output/xdmf/data.rs, scene_file/error.rs, …)."""

import pathlib
import re
from dataclasses import dataclass, field

import pytest

from graphs import find_cycle

ROOT = pathlib.Path(__file__).resolve().parents[2]
CRATES = {
    "sdcrack-core": ROOT / "crates" / "sdcrack-core" / "src",
    "sdcrack-io": ROOT / "crates" / "sdcrack-io" / "src",
}
TEST_MODULES = {"tests", "testing"}

ITEM = re.compile(
    r"^(?:pub(?:\([^)]*\))?\s+)?(?:(?:const|unsafe|async|extern\s+\"C\")\s+)*"
    r"(?:struct|enum|fn|const|static|type|trait|union)\s+(?:mut\s+)?([A-Za-z_]\w*)"
)
MACRO = re.compile(r"^macro_rules!\s*([A-Za-z_]\w*)")
MOD_DECL = re.compile(r"^((?:#\[[^\]]*\]\s*)*)(?:pub(?:\([^)]*\))?\s+)?mod\s+(\w+)\s*;")
INLINE_TEST_MOD = re.compile(r"^(\s*)(?:pub(?:\([^)]*\))?\s+)?mod\s+(\w+)\s*\{")
USE = re.compile(r"^\s*(?:pub(?:\([^)]*\))?\s+)?use\s+([^;]*);", re.M | re.S)
CODE_PATH = re.compile(r"(?<![\w:])([A-Za-z_]\w*(?:::[A-Za-z_]\w*)+)")


@dataclass
class Module:
    """One module file: its path of names from the crate root and the text that counts."""
    path: tuple
    file: pathlib.Path
    text: str = ""
    items: set = field(default_factory=set)
    children: dict = field(default_factory=dict)  # name -> declared under #[cfg(test)]
    imports: dict = field(default_factory=dict)   # name brought in by `use` -> full path


def strip_comments(text):
    """The text without `//` comments (doc comments included) and `/* */` blocks; a `//` inside
    a string literal is kept (an even count of quotes before it on its line)."""
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    lines = []
    for line in text.splitlines():
        cut = 0
        while (cut := line.find("//", cut)) >= 0 and line[:cut].count('"') % 2:
            cut += 2
        lines.append(line if cut < 0 else line[:cut])
    return "\n".join(lines)


def strip_inline_tests(text):
    """The text without inline `#[cfg(test)] mod tests { … }` blocks (rustfmt closes a block at
    the indentation it opened with)."""
    out, lines, i = [], text.splitlines(), 0
    while i < len(lines):
        m = INLINE_TEST_MOD.match(lines[i])
        gated = out and out[-1].strip() == "#[cfg(test)]"
        if m and (gated or m.group(2) in TEST_MODULES):
            closing = m.group(1) + "}"
            while i < len(lines) and lines[i].rstrip() != closing:
                i += 1
            i += 1
            continue
        out.append(lines[i])
        i += 1
    return "\n".join(out)


def use_paths(tree):
    """The full paths of one `use` tree: `super::{a, b::{C, D}}` -> super::a, super::b::C, ….
    `self` inside braces names the prefix itself; `as` renames are dropped."""
    tree = re.sub(r"\s+", "", tree)

    def expand(prefix, s):
        depth, start, parts = 0, 0, []
        for k, ch in enumerate(s):
            depth += ch == "{"
            depth -= ch == "}"
            if ch == "," and depth == 0:
                parts.append(s[start:k])
                start = k + 1
        parts.append(s[start:])
        paths = []
        for part in filter(None, parts):
            if "{" in part:
                head, inner = part.split("{", 1)
                paths += expand(prefix + head, inner[:-1])
            else:
                part = part.split("as", 1)[0] if re.search(r"\bas\b", part) else part
                full = prefix + part
                paths.append(full[:-len("::self")] if full.endswith("::self") else full)
        return paths

    return expand("", tree)


def read_crate(src):
    """Every module file of the crate under `src`, by its path of names."""
    modules = {}

    def visit(path, file):
        raw = strip_comments(file.read_text())
        module = Module(path, file)
        folder = file.parent if file.name in ("lib.rs", "main.rs", "mod.rs") else file.with_suffix("")
        for m in re.finditer(r"^.*$", raw, re.M):
            decl = MOD_DECL.match(m.group(0))
            if decl:
                before = raw[:m.start()].rstrip().splitlines()[-1:] or [""]
                gated = "cfg(test)" in decl.group(1) or before[0].strip() == "#[cfg(test)]"
                module.children[decl.group(2)] = gated
        module.text = strip_inline_tests(raw)
        for line in module.text.splitlines():
            if (m := ITEM.match(line) or MACRO.match(line)):
                module.items.add(m.group(1))
        for m in USE.finditer(module.text):
            for full in use_paths(m.group(1)):
                module.imports[full.rsplit("::", 1)[-1]] = full
        modules[path] = module
        for name in module.children:
            child = next((f for f in (folder / f"{name}.rs", folder / name / "mod.rs") if f.exists()), None)
            assert child is not None, f"{file}: mod {name} has no file"
            visit(path + (name,), child)

    visit((), src / "lib.rs")
    return modules


def is_test(modules, path):
    """Whether the module at `path`, or a module it sits in, is test code."""
    return any(modules[path[:k]].children[path[k]] or path[k] in TEST_MODULES
               for k in range(len(path)))


def resolve(modules, here, full):
    """The module and item that `full` (a path written in module `here`) names: (module path,
    item name), the item None when the path names a module. Paths that do not start with
    crate/super/self, or lead outside the crate's modules, give None."""
    parts = full.split("::")
    if parts[0] == "crate":
        at, parts = (), parts[1:]
    elif parts[0] in ("super", "self"):
        at = here
        while parts and parts[0] in ("super", "self"):
            at = at[:-1] if parts[0] == "super" else at
            parts = parts[1:]
    else:
        at = here
        if not parts or parts[0] not in modules[here].children:
            return None
    while parts and parts[0] in modules[at].children:
        at, parts = at + (parts[0],), parts[1:]
    return (at, parts[0] if parts else None)


def origin(modules, at, name, seen=()):
    """The module whose file defines `name` as named in module `at`: the module itself when it
    defines it, else where its `use` of that name leads (re-exports followed)."""
    module = modules[at]
    if name in module.items or name not in module.imports or (at, name) in seen:
        return at
    target = resolve(modules, at, module.imports[name])
    if target is None or target[1] is None:
        return at
    return origin(modules, target[0], target[1], seen + ((at, name),))


def references(modules, path):
    """(module, item) for every crate path that the non-test code of `path` writes: in `use`
    trees and in code (`super::diameter(…)`, `crate::mesh::centroid(…)`, `bisect::graded(…)`
    for a child module `bisect`)."""
    text = modules[path].text
    found = []
    for m in USE.finditer(text):
        found += use_paths(m.group(1))
    code = USE.sub("", text)
    found += CODE_PATH.findall(code)
    return [r for r in (resolve(modules, path, f) for f in found) if r is not None]


def back_references(modules):
    """'child -> ancestor::item' for every non-test module naming an item its ancestor's own
    file defines."""
    found = set()
    for path in modules:
        if not path or is_test(modules, path):
            continue
        for at, item in references(modules, path):
            if item and at == path[:len(at)] and at != path and item in modules[at].items:
                found.add(f"{'::'.join(path)} -> {'::'.join(at) or 'crate'}::{item}")
    return sorted(found)


def folders(modules):
    """The module paths that are folders: modules with at least one child module."""
    return sorted(p for p, m in modules.items() if p and m.children)


def folder_graph(modules, folder):
    """The import edges among the modules of `folder` (its parent file as '', its children by
    name, a child's descendants counted as the child), test modules left out."""
    members = [c for c in modules[folder].children if not is_test(modules, folder + (c,))]

    def member(path):
        if path == folder:
            return ""
        if path[:len(folder)] == folder and len(path) > len(folder) and path[len(folder)] in members:
            return path[len(folder)]
        return None

    edges = set()
    for path in modules:
        source = member(path)
        if source is None or is_test(modules, path):
            continue
        for at, item in references(modules, path):
            where = origin(modules, at, item) if item else at
            target = member(where)
            if target is not None and target != source:
                edges.add((source, target))
    return edges


def cycle(edges):
    """One cycle of the directed graph `edges` (pairs) as a list of nodes, or None."""
    graph = {}
    for a, b in edges:
        graph.setdefault(a, []).append(b)
    return find_cycle(graph)


def cycles(modules):
    """'folder: a -> b -> a' for every folder whose modules import one another in a cycle."""
    found = []
    for folder in folders(modules):
        if is_test(modules, folder):
            continue
        ring = cycle(folder_graph(modules, folder))
        if ring:
            found.append(f"{'::'.join(folder)}: " + " -> ".join(n or "(parent)" for n in ring))
    return found


@pytest.mark.parametrize("crate", [pytest.param("sdcrack-core", id="core"),
                                   pytest.param("sdcrack-io", id="io")])
def test_no_child_module_imports_its_parent(crate):
    assert back_references(read_crate(CRATES[crate])) == []


@pytest.mark.parametrize("crate", [pytest.param("sdcrack-core", id="core"),
                                   pytest.param("sdcrack-io", id="io")])
def test_the_modules_of_each_folder_import_one_another_without_a_cycle(crate):
    assert cycles(read_crate(CRATES[crate])) == []


def test_the_checker_reads_the_folders_and_their_imports():
    """Not vacuous: both crates' folders are found, and imports among their modules are seen."""
    modules = read_crate(CRATES["sdcrack-core"])
    assert {("expr",), ("linalg",), ("mesh",), ("mesh", "gmsh"), ("geometry",)} <= set(folders(modules))
    assert ("parser", "lexer") in folder_graph(modules, ("expr",))
    assert is_test(modules, ("mesh", "tests")) and not is_test(modules, ("mesh", "bisect"))
    io = read_crate(CRATES["sdcrack-io"])
    assert {("output",), ("output", "xdmf"), ("scene_file",)} <= set(folders(io))
    assert ("xml", "data") in folder_graph(io, ("output", "xdmf"))


def write(folder, files):
    for name, text in files.items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_text(text)
    return read_crate(folder)


LIB = "pub mod shape;\n"


def test_a_child_importing_its_parents_struct_fails(tmp_path):
    modules = write(tmp_path, {
        "lib.rs": LIB,
        "shape.rs": "mod area;\n#[cfg(test)]\nmod tests;\npub use area::area;\n"
                    "/// A `super::Square` in a comment is not an import.\npub struct Square(f64);\n",
        "shape/area.rs": "use super::Square;\npub fn area(s: &Square) -> f64 { s.0 * s.0 }\n",
        "shape/tests.rs": "use super::*;\nuse crate::shape::Square;\n",
    })
    assert back_references(modules) == ["shape::area -> shape::Square"]


def test_a_call_back_into_the_parent_by_its_path_fails(tmp_path):
    modules = write(tmp_path, {
        "lib.rs": LIB,
        "shape.rs": "mod cut;\npub(crate) fn diameter() -> f64 { 1.0 }\n",
        "shape/cut.rs": "pub fn cut() -> f64 { crate::shape::diameter() / 2.0 }\n"
                        "#[cfg(test)]\nmod tests {\n    use super::super::diameter;\n}\n",
    })
    assert back_references(modules) == ["shape::cut -> shape::diameter"]


def test_a_ground_file_passes(tmp_path):
    modules = write(tmp_path, {
        "lib.rs": LIB,
        "shape.rs": "mod area;\nmod square;\npub use area::area;\npub use square::Square;\n",
        "shape/square.rs": "pub struct Square(pub f64);\n",
        "shape/area.rs": "use super::square::Square;\npub fn area(s: &Square) -> f64 { s.0 * s.0 }\n",
    })
    assert back_references(modules) == [] and cycles(modules) == []
    assert folder_graph(modules, ("shape",)) == {("", "area"), ("", "square"), ("area", "square")}


def test_a_cycle_among_siblings_fails_even_through_a_re_export(tmp_path):
    modules = write(tmp_path, {
        "lib.rs": LIB,
        "shape.rs": "mod a;\nmod b;\npub use b::B;\n",
        "shape/a.rs": "use super::B;\npub struct A;\n",
        "shape/b.rs": "pub struct B;\nfn make() -> super::a::A { super::a::A }\n",
    })
    assert back_references(modules) == []
    assert cycles(modules) == ["shape: b -> a -> b"]
