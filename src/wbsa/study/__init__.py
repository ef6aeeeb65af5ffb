"""study stage: the end-to-end study (``wbsa run``) from one TOML file, with content-addressed stages.

Names are imported lazily, so ``wbsa --help`` stays fast.
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    "run_study": "wbsa.study.pipeline",
    "StudyResult": "wbsa.study.pipeline",
    "load_settings": "wbsa.study.settings",
    "settings_from_dict": "wbsa.study.settings",
    "StudySettings": "wbsa.study.settings",
    "Stage": "wbsa.study.stages",
    "stage_key": "wbsa.study.stages",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'wbsa.study' has no attribute {name!r}")


def __dir__() -> list[str]:
    return __all__
