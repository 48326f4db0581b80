"""sdcompare_lib: the compare tool (compare/sdcompare, compare/sdcompare-rerun: read, verdict,
render, sections, ...). The modules the reference solvers (references/<tool>/solve.py) share with it
are the package sdshared (sdexpr, sdexport, sdquad, sdfields, sdresults), which it imports and
which imports nothing of it.

Both packages lie in compare/. Where they are found, with nothing edited in sys.path:
- the checkout's Python, .venv/bin/python (Debian's Python and packages): ci/setup installs them
  there once, editable (sdcrack-checkout.pth names compare/); tools/campaign (prepare.py,
  campaign_index.py), tools/cases, tools/mutants and ci/nightly run their Python with it;
- the Snakefile, run by Snakemake's own venv (.venv-workflow/, whose pinned numpy must not meet
  Debian's dolfinx): compare/ first on its sys.path, as it puts its own folder there for prepare.py;
- installed (`pip install .`, pyproject.toml): site-packages/sdcompare_lib/ and sdshared/;
- compare/sdcompare and compare/sdcompare-rerun: beside them (a script's folder is on sys.path);
- the tests in a checkout: pyproject.toml's [tool.pytest.ini_options] `pythonpath` names compare/;
- the reference solvers, which sdcrack starts with Debian's /usr/bin/python3: compare/ on
  PYTHONPATH, set by src/references.rs (and by the tests' conftest.py run_env for the programs
  they start), e.g. `PYTHONPATH=compare /usr/bin/python3 references/dolfinx/solve.py MESH --out DIR`
  (or `.venv/bin/python references/dolfinx/solve.py MESH --out DIR`);
- the GitHub nightly's index job (no ci/setup there): PYTHONPATH=compare. The index runs without
  numpy: it imports only modules that import no numpy at load (page, cases, choices, baseline,
  sdresults).
"""
