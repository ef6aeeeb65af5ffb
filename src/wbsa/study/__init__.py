"""study stage: the end-to-end study (``wbsa run``) from one TOML file, with content-addressed stages.

Names are imported lazily, so ``wbsa --help`` stays fast.
"""

from __future__ import annotations

from wbsa.lazy import lazy_exports

_EXPORTS = {
    "Study": "wbsa.study.study",
    "run_study": "wbsa.study.pipeline",
    "StudyResult": "wbsa.study.pipeline",
    "load_settings": "wbsa.study.settings",
    "settings_from_dict": "wbsa.study.settings",
    "StudySettings": "wbsa.study.settings",
    "StudyInfo": "wbsa.study.settings",
    "Stage": "wbsa.study.stages",
    "stage_key": "wbsa.study.stages",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
