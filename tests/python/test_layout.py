"""The data flows one way: the maths modules (mesh, finite elements, assembly, contact, linear
algebra, ordering, norms, expressions, the problem's vocabulary) never import the scene parser
`crate::scene`; they take the vocabulary from `crate::problem` and expressions from `crate::expr`.
Unit tests (after `#[cfg(test)]`) may load scenes."""

import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[2]
MATHS = ["mesh.rs", "assembly.rs", "contact.rs", "linalg.rs", "ordering.rs", "norms.rs",
         "problem.rs", "expr.rs", "expr/*.rs", "fe/*.rs"]


def scene_imports(text):
    """Lines of the non-test part of a Rust file that reach into the scene module."""
    code = text.split("#[cfg(test)]")[0]
    return [line for line in code.splitlines()
            if re.search(r"\bcrate::scene\b|\bsuper::scene\b", line) and not line.lstrip().startswith("//")]


def test_the_checker_sees_an_import():
    assert scene_imports("use crate::scene::Scene;\nfn f() {}\n") == ["use crate::scene::Scene;"]
    assert scene_imports("//! see [`crate::scene`]\nuse crate::problem::USpace;\n") == []
    assert scene_imports("fn f() {}\n#[cfg(test)]\nmod tests { use crate::scene::Scene; }\n") == []


def test_maths_modules_do_not_import_the_scene_parser():
    files = sorted({p for pattern in MATHS for p in (ROOT / "src").glob(pattern)})
    assert len(files) >= 12, files
    offending = {str(p.relative_to(ROOT)): scene_imports(p.read_text()) for p in files}
    assert {k: v for k, v in offending.items() if v} == {}
