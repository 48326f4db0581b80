"""sdcompare_lib: the Python side of sdcrack's verification, one package.

It holds the compare tool (compare/sdcompare, compare/sdcompare-rerun: read, verdict, render, ...)
and the modules the reference solvers (references/<tool>/solve.py) share with it: sdexpr (the
scenes' expression grammar), sdexport (the mesh export's files), sdquad (the load quadrature),
sdfields (the field files) and sdresults (summary.json, provenance, the atomic writes).

Where it is found, with nothing edited in sys.path:
- installed (`pip install .`, pyproject.toml): site-packages/sdcompare_lib/;
- compare/sdcompare and compare/sdcompare-rerun: beside them (a script's folder is on sys.path);
- the tests in a checkout: pyproject.toml's [tool.pytest.ini_options] `pythonpath` names compare/;
- the reference solvers (references/<tool>/solve.py): the folder compare/ on PYTHONPATH, set by
  whoever launches them (sdcrack: src/references.rs; the tests: conftest.py's run_env), e.g.
  `PYTHONPATH=compare /usr/bin/python3 references/dolfinx/solve.py MESH --out DIR`;
- the tools (tools/campaign_index.py, tools/mutants.py, tools/workflow/prepare.py and the
  Snakefile, the script of tools/cases): the same PYTHONPATH, set by their launchers
  (tools/campaign, tools/mutants, tools/cases, ci/nightly, the GitHub nightly). The index runs
  without numpy: it imports only modules that import no numpy at load (baseline, sdresults).
"""
