"""``wbsa serve``: a local web page that estimates WBSA from one depth image (or a batch), for a clinic.

``app``       the Starlette application and its routes (:func:`create_app`)
``uploads``   upload checks: size, type and image size from the bytes, fields without paths
``jobs``      one estimate off the event loop (:func:`measure`, :class:`Runner`), results kept in memory
``progress``  an estimate's progress as JSON lines, its answer last (``Accept: application/x-ndjson``)
``answer``    an Estimate as the page shows it: number (each route's with ``both``), flags, view, meshes,
              formulae, downloads, depth picture
``advice``    the page's rows of an estimate's flags (from :data:`wbsa.estimation.flags.FLAG_RECORDS`)
``batch``     several files: rows, progress, CSV
``command``   the ``wbsa serve`` subcommand (uvicorn on 127.0.0.1 and a free port by default)
``static/``   the page: HTML, CSS and JavaScript (the page, the view sketch, a small canvas 3-D viewer), no
              build step, nothing fetched from elsewhere

The page is a thin layer over :func:`wbsa.estimate`: every check and number comes from it. Names are
imported lazily.
"""

from __future__ import annotations

from wbsa.lazy import lazy_exports

_EXPORTS = {
    "create_app": "wbsa.server.app",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
