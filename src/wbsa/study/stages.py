"""Content-addressed stage folders: a stage whose settings and inputs did not change is reused.

Every stage of a study writes into ``DIR/stages/<name>-<key>/``, where ``key`` is the SHA-256
(16 hex characters) of the stage's name, its settings and the keys of the stages it reads
(:func:`stage_key`). The stage is *finished* once ``stage.json`` exists in its folder; it is written
last and atomically, so a crash leaves an unfinished folder that the next run completes (the scan
stage resumes its finished chunks) or redoes. ``stage.json`` records the size of every output, and a
stage whose outputs are missing or have another size is not reused. Because every stage's output is a
deterministic function of its settings and inputs, the key identifies the content; ``stage.json`` is
the stage's run log (its run time, when it finished).
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from wbsa.core.versions import WBSA_VERSION as __version__
from wbsa.io import write_json

#: Marker file of a finished stage.
STAGE_FILE = "stage.json"
#: Folder of the stage folders inside a study folder.
STAGES_DIR = "stages"
#: Bump when a stage's output format changes, so old folders are not reused.
STAGE_FORMAT = 1


def stage_key(name: str, settings: Any, inputs: dict[str, Any] | None = None) -> str:
    """Content address of a stage: SHA-256 (16 hex) of its name, settings and input keys.

    Parameters
    ----------
    name : str
        Stage name (``population``, ``scan``, ``fit``, ``report``).
    settings : JSON-ready object
        Everything that decides the stage's output (never worker counts or paths).
    inputs : dict
        Keys of the stages it reads, e.g. ``{'population': '3f2a...'}``.
    """
    payload = json.dumps({"stage": name, "format": STAGE_FORMAT, "settings": settings, "inputs": inputs or {}},
                         sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(payload.encode()).hexdigest()[:16]


@dataclass(frozen=True)
class Stage:
    """One stage folder of a study.

    Attributes
    ----------
    name : str
        Stage name.
    key : str
        :func:`stage_key` of its settings and inputs.
    path : Path
        ``DIR/stages/<name>-<key>``.
    settings : Any
        The settings that were hashed (recorded in ``stage.json``).
    inputs : dict
        The input keys that were hashed.
    """

    name: str
    key: str
    path: Path
    settings: Any
    inputs: dict

    @classmethod
    def create(cls, study_dir: str | Path, name: str, settings: Any, inputs: dict[str, Any] | None = None) -> "Stage":
        """The stage of ``name`` with these settings and inputs in ``study_dir`` (nothing is written)."""
        key = stage_key(name, settings, inputs)
        return cls(name, key, Path(study_dir) / STAGES_DIR / f"{name}-{key}", settings, dict(inputs or {}))

    @property
    def marker(self) -> Path:
        """``stage.json`` of the stage."""
        return self.path / STAGE_FILE

    @property
    def done(self) -> bool:
        """Whether the stage finished in an earlier run and its recorded outputs are all still there, whole."""
        if not self.marker.is_file():
            return False
        rec = self.record()
        outputs = rec.get("outputs")
        if not isinstance(outputs, dict) or rec.get("key") != self.key:
            return False
        sizes = rec.get("sizes") if isinstance(rec.get("sizes"), dict) else {}
        for rel in outputs.values():
            path = self.path / str(rel)
            if not path.is_file():
                return False
            if rel in sizes and path.stat().st_size != sizes[rel]:
                return False
        return True

    def record(self) -> dict:
        """The content of ``stage.json`` (empty if the stage has not finished)."""
        try:
            doc = json.loads(self.marker.read_text())
        except (OSError, ValueError):
            return {}
        return doc if isinstance(doc, dict) else {}

    def finish(self, seconds: float, outputs: dict[str, str], info: dict | None = None) -> dict:
        """Mark the stage finished: write ``stage.json`` (settings, inputs, outputs, run time).

        Parameters
        ----------
        seconds : float
            Wall-clock time the stage took.
        outputs : dict
            Output name -> path relative to the stage folder.
        info : dict, optional
            Anything else worth keeping (counts, rates).
        """
        sizes = {rel: (self.path / rel).stat().st_size for rel in outputs.values() if (self.path / rel).is_file()}
        doc = {"stage": self.name, "key": self.key, "format": STAGE_FORMAT, "settings": self.settings,
               "inputs": self.inputs, "outputs": outputs, "sizes": sizes, "seconds": float(seconds),
               "info": info or {},
               "finished": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "wbsa_version": __version__}
        write_json(doc, self.marker)
        return doc
