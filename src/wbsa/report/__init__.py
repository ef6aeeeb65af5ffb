"""report stage: the paper's figures and the study's tables in one self-contained HTML file.

Names are imported lazily, so ``wbsa --help`` does not import matplotlib.
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    "build_report": "wbsa.report.build",
    "ReportResult": "wbsa.report.build",
    "FIGURES": "wbsa.report.build",
    "load_report_data": "wbsa.report.data",
    "ReportData": "wbsa.report.data",
    "resolve_sources": "wbsa.report.sources",
    "study_sources": "wbsa.report.sources",
    "fit_dir_sources": "wbsa.report.sources",
    "ReportSources": "wbsa.report.sources",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'wbsa.report' has no attribute {name!r}")


def __dir__() -> list[str]:
    return __all__
