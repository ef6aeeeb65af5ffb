"""The report's figures, one function each, drawn from the measured tables (matplotlib, no pyplot state).

Every function takes tables with the documented columns (population, scan, fit outputs; areas in m²)
and returns a :class:`matplotlib.figure.Figure`; areas are shown in dm² (the paper's unit,
1 m² = 100 dm²). A function raises :class:`~wbsa.report.figures.style.FigureUnavailable` when its data
are not in the tables (e.g. no reconstruction columns), and the report then says why instead of showing
the figure.

Modules, one figure family each:

- :mod:`~wbsa.report.figures.style`: the dm² unit, group labels, the figure factory, axis styling.
- :mod:`~wbsa.report.figures.calibration`: mesh / Du Bois and density against BMI beside the published
  real-body relations (the calibration section).
- :mod:`~wbsa.report.figures.population`: WBSA distribution (Fig 5).
- :mod:`~wbsa.report.figures.one_view`: VBSA against WBSA at one view (Fig 10, S1 Fig) and the
  non-linear view (Fig 16).
- :mod:`~wbsa.report.figures.by_view`: CV RMSE and c1 against the azimuth per group (Figs 11–14) and per
  model kind.
- :mod:`~wbsa.report.figures.residuals`: residual diagnostics (S2 Fig).
- :mod:`~wbsa.report.figures.formulae`: the formulae grid.
- :mod:`~wbsa.report.figures.reconstruction`: reconstruction by view (Figs 15, 17).
- :mod:`~wbsa.report.figures.distance`: the camera-distance sweep (section 3.4).
- :mod:`~wbsa.report.figures.point_cloud`: point-cloud snapshots (Fig 8).
- :mod:`~wbsa.report.figures.agreement`: the depth-image estimate against the truth, Bland–Altman and by group
  (``benchmarks/bench_estimate.py --figure``).

This package imports none of them (nor matplotlib) itself. Which paper figure each reproduces is said in
the module's docstring and in the report itself (a ``FIGURES`` id list here was not read by anything and is gone).
"""

from __future__ import annotations
