"""report stage: the paper's figures and the study's tables in one self-contained HTML file.

Names are imported lazily, so ``wbsa --help`` does not import matplotlib.
"""

from __future__ import annotations

from wbsa.lazy import lazy_exports

_EXPORTS = {
    "build_report": "wbsa.report.build",
    "ReportResult": "wbsa.report.build",
    "load_report_data": "wbsa.report.data",
    "ReportData": "wbsa.report.data",
    "resolve_sources": "wbsa.report.sources",
    "study_sources": "wbsa.report.sources",
    "fit_dir_sources": "wbsa.report.sources",
    "ReportSources": "wbsa.report.sources",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
