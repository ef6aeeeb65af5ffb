"""wbsa: whole body surface area from a single depth view.

The package is laid out like the pipeline:

``population``  virtual bodies (anny), anthropometry, random and survey populations
``formulae``    classical BSA formulae (Du Bois, Mosteller, ...)
``camera``      pinhole intrinsics/extrinsics, view grids, ray casting, visible area
``sensor``      depth noise, quantisation, holes
``surface``     surface reconstruction from one depth view
``scan``        scanning a population at many views, in parallel, resumable
``analysis``    per-view regression, cross-validation, diagnostics, formula comparison
``report``      figures and the HTML report
``study``       the end-to-end study (``wbsa run``)
``cli``         the ``wbsa`` command, a thin layer over the API
"""

__version__ = "0.1.0"
