"""What a population scan does, as one frozen, hashable record.

The settings hash identifies a scan folder: a scan resumes into a folder only when the
hash stored in ``DIR/settings.json`` equals the hash of the new run's settings and
population (see :mod:`wbsa.scan.layout`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from wbsa.errors import WbsaError

if TYPE_CHECKING:  # pragma: no cover - imported for type hints only
    import pandas as pd

    from wbsa.camera import Intrinsics, View
    from wbsa.sensor import SensorModel
    from wbsa.surface import ReconstructionSettings

#: Default number of subjects per chunk (one Parquet part, one dask task).
DEFAULT_CHUNK_SIZE = 50


@dataclass(frozen=True)
class ScanSettings:
    """Everything that decides the rows of a scan table.

    Attributes
    ----------
    camera : wbsa.camera.Intrinsics
        Pinhole intrinsics of the virtual depth camera (its ``name`` goes into the ``camera`` column).
    views : tuple of wbsa.camera.View
        Camera placements, each scanned for every subject.
    sensor : wbsa.sensor.SensorModel or None
        Depth-sensor simulation applied to every rendered frame before reconstruction;
        ``None`` keeps the ideal ray-cast frame.
    reconstruct : tuple of str
        Surface reconstruction methods (``'grid'``, ``'ball-pivoting'``, ``'poisson'``); each adds a
        ``vbsa_recon_<method>_m2`` column. Empty: no reconstruction.
    reconstruction : wbsa.surface.ReconstructionSettings or None
        How to reconstruct (denoising, boundary, ...); None: the defaults.
    seed : int
        Root seed; subject ``s`` draws its sensor noise from ``numpy.random.SeedSequence([seed, s])``
        (one child stream per view, keyed by the view's angles and distance), so results do not
        depend on chunking, on the view list or on the number of workers.
    chunk_size : int
        Subjects per chunk: one Parquet part and one unit of parallel work.
    backend : {'open3d', 'warp', 'auto'}
        Ray-casting back end (:mod:`wbsa.camera.backends`); ``auto`` is resolved on construction. Only a
        back end other than ``open3d`` enters :meth:`to_dict` (and the hash).
    """

    camera: Intrinsics
    views: tuple[View, ...]
    sensor: SensorModel | None = None
    reconstruct: tuple[str, ...] = ()
    reconstruction: ReconstructionSettings | None = None
    seed: int = 0
    chunk_size: int = DEFAULT_CHUNK_SIZE
    backend: Literal["auto", "open3d", "warp"] = "open3d"

    def __post_init__(self) -> None:
        from wbsa.camera.backends import resolve_backend

        object.__setattr__(self, "backend", resolve_backend(self.backend))
        object.__setattr__(self, "views", tuple(self.views))
        object.__setattr__(self, "reconstruct", tuple(self.reconstruct))
        if not self.views:
            raise WbsaError("no views to scan; give at least one view with --views")
        if int(self.chunk_size) < 1:
            raise WbsaError(f"chunk size must be at least 1, got {self.chunk_size}; use --chunk-size 50")
        if int(self.seed) < 0:
            raise WbsaError(f"seed must be a non-negative integer, got {self.seed}; use e.g. --seed 0")
        if len(set(self.reconstruct)) != len(self.reconstruct):
            raise WbsaError(f"reconstruction method listed twice in {','.join(self.reconstruct)}; list each once")
        if self.reconstruct and self.reconstruction is None:
            from wbsa.surface.settings import ReconstructionSettings

            object.__setattr__(self, "reconstruction", ReconstructionSettings())

    @property
    def camera_name(self) -> str:
        """Name of the camera (preset name, or ``'custom'``) written to the ``camera`` column."""
        return str(getattr(self.camera, "name", "custom"))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready description of the settings (written to ``DIR/settings.json``)."""
        sensor = None
        if self.sensor is not None:
            sensor = self.sensor.to_dict() if hasattr(self.sensor, "to_dict") else _plain(self.sensor)
        return _json_safe({
            "camera": _plain(self.camera),
            "views": [[float(v.azimuth_deg), float(v.elevation_deg), float(v.distance_m)] for v in self.views],
            "sensor": sensor,
            "reconstruct": list(self.reconstruct),
            "reconstruction": (_plain(self.reconstruction) if self.reconstruction is not None else None)
            if self.reconstruct else None,
            "seed": int(self.seed),
            "chunk_size": int(self.chunk_size),
            **({} if self.backend == "open3d" else {"backend": self.backend}),
        })


def settings_hash(settings: ScanSettings, population_fingerprint: str) -> str:
    """SHA-256 (hex, 16 characters) of the settings and the population that a scan folder holds.

    Parameters
    ----------
    settings : ScanSettings
    population_fingerprint : str
        From :func:`population_fingerprint`.
    """
    payload = json.dumps({"settings": settings.to_dict(), "population": population_fingerprint},
                         sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(payload.encode()).hexdigest()[:16]


def population_fingerprint(population: pd.DataFrame) -> str:
    """SHA-256 (hex) of a population table's subject ids and numeric columns, in subject order.

    Two tables with the same subjects and the same numbers give the same fingerprint,
    whatever their file name, row order or Parquet encoding.
    """
    import pandas as pd

    df = population.sort_values("subject_id", kind="mergesort")
    h = hashlib.sha256()
    for name in sorted(df.columns):
        col = df[name]
        h.update(name.encode() + b"\0")
        if pd.api.types.is_bool_dtype(col) or pd.api.types.is_numeric_dtype(col):
            h.update(np.ascontiguousarray(col.to_numpy(dtype=np.float64)).tobytes())
        else:
            h.update("\0".join(map(str, col.tolist())).encode())
    return h.hexdigest()


def _plain(obj: Any) -> Any:
    """A dataclass (or anything with ``to_dict``) as plain JSON-ready data."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: _plain(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, (list, tuple)):
        return [_plain(o) for o in obj]
    if isinstance(obj, dict):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    return obj


def _json_safe(obj: Any) -> Any:
    """Replace non-finite floats by the strings ``'inf'``, ``'-inf'``, ``'nan'`` (strict JSON)."""
    if isinstance(obj, float) and not math.isfinite(obj):
        return str(obj)
    if isinstance(obj, dict):
        return {k: _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_json_safe(v) for v in obj]
    return obj
