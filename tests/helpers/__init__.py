"""Test-only generators, kept out of the installed package.

``synthetic``: population and scan tables with a known WBSA–VBSA law (no body model);
``shapes``: meshes with known areas (sphere, box, a body-like figure).

Tests import them as ``helpers.*`` (pytest puts ``tests/`` on ``sys.path`` because of
``tests/conftest.py``); scripts in ``benchmarks/`` and ``docs/`` add ``tests/`` to ``sys.path`` first.
"""
