"""No import cycle among the modules of the compare tool's package (sdcompare_lib) or of the
references' shared package (sdshared), counting the imports inside functions too: a module that
needs another's piece imports it, and a piece two modules share lives below both (refyard.py under
yardsticks.py and ratios.py). And the layers: sdshared imports nothing of sdcompare_lib, the
reference solvers import sdshared and not the compare tool. Read from the sources (ast), so a
cycle fails here whether or not Python would trip on it at import time."""
import ast
import pathlib

import sdcompare_lib
import sdshared
from graphs import find_cycle

PACKAGES = {"sdcompare_lib": pathlib.Path(sdcompare_lib.__file__).parent,
            "sdshared": pathlib.Path(sdshared.__file__).parent}
ROOT = pathlib.Path(__file__).resolve().parents[2]


def imported_modules(path, package, modules):
    """The modules of `package` (names in `modules`) that the source file `path` imports, at any
    depth of its syntax tree: `from . import x`, `from .x import y`, `from package.x import y`,
    `from package import x`, `import package.x`."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            if node.level == 1 or node.module == package:
                names = [node.module] if node.level == 1 and node.module else \
                    [a.name for a in node.names]
            elif node.level == 0 and node.module and node.module.startswith(package + "."):
                names = [node.module.split(".")[1]]
            else:
                continue
            out |= {n.split(".")[0] for n in names}
        elif isinstance(node, ast.Import):
            out |= {a.name.split(".")[1] for a in node.names
                    if a.name.startswith(package + ".")}
    return out & modules


def import_graph(folder, package):
    """{module: the package's modules it imports} of the package in `folder`."""
    files = {p.stem: p for p in folder.glob("*.py")}
    return {m: imported_modules(p, package, set(files)) - {m} for m, p in files.items()}


def test_the_packages_have_no_import_cycle():
    for package, folder in PACKAGES.items():
        graph = import_graph(folder, package)
        assert len(graph) > 5, f"{package}: found no modules in {folder}"
        assert find_cycle(graph) is None, f"{package}: import cycle {find_cycle(graph)}"


def packages_imported(path):
    """The top-level names of every package or module the source file `path` imports (any depth
    of its syntax tree; relative imports excluded)."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            out.add(node.module.split(".")[0])
        elif isinstance(node, ast.Import):
            out |= {a.name.split(".")[0] for a in node.names}
    return out


def test_the_shared_package_and_the_references_import_no_compare_tool():
    shared = sorted(PACKAGES["sdshared"].glob("*.py"))
    solvers = sorted((ROOT / "references").glob("*/solve.py"))
    assert len(shared) == 6 and len(solvers) == 2, (shared, solvers)
    for path in shared + solvers:
        assert "sdcompare_lib" not in packages_imported(path), path
    for path in solvers:
        assert "sdshared" in packages_imported(path), path


def test_an_import_of_the_compare_tool_is_seen_at_any_depth(tmp_path):
    """The layering check's FAIL: an import of sdcompare_lib inside a function."""
    f = tmp_path / "solve.py"
    f.write_text("from sdshared import sdexpr\n\ndef f():\n    from sdcompare_lib.read import x\n")
    assert packages_imported(f) == {"sdshared", "sdcompare_lib"}


def test_a_cycle_through_a_function_level_import_is_found(tmp_path):
    """The check's FAIL: b imports c at the top, c imports a inside a function, a imports b."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from .b import f\n")
    (pkg / "b.py").write_text("from pkg import c\n\ndef f():\n    return c.g()\n")
    (pkg / "c.py").write_text("def g():\n    from . import a\n    return a\n")
    (pkg / "d.py").write_text("import pkg.a\n")
    graph = import_graph(pkg, "pkg")
    assert graph == {"__init__": set(), "a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert find_cycle(graph) == ["a", "b", "c", "a"]
    (pkg / "c.py").write_text("def g():\n    return 1\n")
    assert find_cycle(import_graph(pkg, "pkg")) is None
