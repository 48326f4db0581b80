"""sdshared: the modules the reference solvers (references/<tool>/solve.py) share with each other
and with the compare tool (the package sdcompare_lib, which imports them; they import nothing of
it): sdexpr (the scenes' expression grammar), sdexport (the mesh export's files and the crack-jump
error), sdquad (the load quadrature), sdfields (the field files) and sdresults (summary.json,
provenance, the atomic writes). compare/tests/test_import_graph.py holds the layering.

It lies in compare/ beside sdcompare_lib, the checkout's one folder of Python packages; see
sdcompare_lib/__init__.py for where the two are found.
"""
