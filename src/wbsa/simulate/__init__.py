"""simulate: one virtual depth view of one body — camera → sensor → surface — and the ``wbsa view`` command.

``view``     :func:`simulate_view` (shared by ``wbsa view``, the scan worker and the report) and :func:`render`
``export``   the files of one view (depth PNG, point cloud, visible triangles, camera JSON, preview)
``target``   what ``wbsa view`` looks at (a mesh file or a population subject)
``command``  the ``wbsa view`` subcommand and its camera/view flags

It sits above ``camera``, ``sensor`` and ``surface`` and below ``scan`` and ``report``.
"""

from __future__ import annotations

from wbsa.lazy import lazy_exports

_EXPORTS = {
    "SimulatedView": "wbsa.simulate.view",
    "points_world": "wbsa.simulate.view",
    "render": "wbsa.simulate.view",
    "simulate_view": "wbsa.simulate.view",
    "simulate_views": "wbsa.simulate.view",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
