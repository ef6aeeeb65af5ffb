"""scan stage: every subject of a population at every view, in parallel (dask), resumable.

:func:`scan_population` splits the population into chunks of subjects, scans each chunk
(:func:`wbsa.scan.worker.scan_chunk`: batched anny bodies, one ray-casting scene per body,
``measure_view`` per view, optional sensor and reconstruction) in this process or on a dask
cluster, and writes every finished chunk as its own Parquet part, so a killed run resumes.
See docs/scan.md.

Names are imported lazily, so ``wbsa --help`` does not import pandas through this package.
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    "ScanResult": "wbsa.scan.engine",
    "scan_population": "wbsa.scan.engine",
    "run_chunk": "wbsa.scan.engine",
    "ScanSettings": "wbsa.scan.settings",
    "ScanJob": "wbsa.scan.settings",
    "settings_hash": "wbsa.scan.settings",
    "population_fingerprint": "wbsa.scan.settings",
    "scan_chunk": "wbsa.scan.worker",
    "scan_subject": "wbsa.scan.worker",
    "body_model": "wbsa.scan.worker",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'wbsa.scan' has no attribute {name!r}")


def __dir__() -> list[str]:
    return __all__
