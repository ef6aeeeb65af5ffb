"""What a population scan does: the settings a user writes, and the resolved job the engine runs.

:class:`ScanSettings` is the ``[scan]`` table of a study and the camera/view flags of ``wbsa scan``:
a camera named by preset or JSON path, a view set, camera distances, a seed. :meth:`ScanSettings.job`
resolves it, for one distance and with the sensor and reconstruction settings, into a
:class:`ScanJob` (intrinsics, views), the frozen record the engine and its workers run.

The job's hash identifies a scan folder: a scan resumes into a folder only when the hash stored in
``DIR/settings.json`` equals the hash of the new run's job and population (see :mod:`wbsa.scan.layout`).
How the work is split and run (workers, chunk size, scheduler: :class:`wbsa.parallel.RunSettings`)
is not part of it.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from wbsa.camera.views import PAPER_DISTANCE_M, VIEW_SPECS
from wbsa.errors import SettingsError, WbsaError, check_field
from wbsa.settings_io import check_types
from wbsa.typing import RaycastBackend

if TYPE_CHECKING:  # pragma: no cover - imported for type hints only
    import pandas as pd

    from wbsa.camera import Intrinsics, View
    from wbsa.sensor import SensorSettings
    from wbsa.surface import ReconstructionSettings


@dataclass(frozen=True)
class ScanSettings:
    """The virtual depth camera and where it stands (``[scan]`` of a study, the flags of ``wbsa scan``).

    Attributes
    ----------
    camera : str
        Preset (``kinect-v1``, ``kinect-v2``, ``tum``) or the path of an Open3D intrinsics JSON file
        (a relative path is read from ``base_dir`` of :meth:`intrinsics`: a study file's folder).
    views : str
        View set: ``paper`` (the 65 views), ``front``, ``sphere:N``, ``grid:STEP``. Ignored when
        ``azimuths_deg`` or ``elevations_deg`` is given.
    azimuths_deg, elevations_deg : tuple of float
        Instead of ``views``: the product of these angle lists (empty = use ``views``; one list given
        alone is crossed with 0°).
    distances_m : tuple of float
        Camera distances; each is scanned as its own job (the paper: 4.3 m, with 3.5–5 m in its S1 file).
    seed : int
        Root seed of the per-subject sensor noise.
    backend : {'open3d', 'warp', 'auto'}
        Ray-casting back end (:mod:`wbsa.camera.backends`); only a back end other than ``open3d`` enters the
        scan's key (its rows agree with Open3D's within float32 rounding, see docs/scan.md).
    """

    camera: str = "kinect-v1"
    views: str = "paper"
    azimuths_deg: tuple[float, ...] = ()
    elevations_deg: tuple[float, ...] = ()
    distances_m: tuple[float, ...] = (PAPER_DISTANCE_M,)
    seed: int = 0
    backend: RaycastBackend = "open3d"

    def __post_init__(self) -> None:
        check_types(self)
        for name in ("azimuths_deg", "elevations_deg", "distances_m"):
            object.__setattr__(self, name, tuple(float(x) for x in getattr(self, name)))
        check_field(bool(str(self.camera).strip()), "camera", "must name a preset or an intrinsics JSON file")
        check_field(len(self.distances_m) >= 1, "distances_m", "needs at least one distance, e.g. [4.3]")
        for d in self.distances_m:
            check_field(math.isfinite(d) and d > 0, "distances_m", f"must be positive distances in metres, got {d:g}")
        check_field(len(set(self.distances_m)) == len(self.distances_m), "distances_m", "lists a distance twice")
        check_field(self.seed >= 0, "seed", f"must be 0 or more, got {self.seed}")
        from wbsa.camera.views import check_angle

        for name, kind in (("azimuths_deg", "azimuth"), ("elevations_deg", "elevation")):
            for a in getattr(self, name):
                check_angle(a, kind, name)
        if not (self.azimuths_deg or self.elevations_deg):
            try:
                self.view_list(self.distances_m[0])
            except WbsaError:
                raise SettingsError("views", f"must be one of {', '.join(VIEW_SPECS)} (or give azimuths_deg and "
                                             f"elevations_deg instead), got {self.views!r}") from None

    def view_list(self, distance_m: float) -> tuple[View, ...]:
        """The views at one camera distance (``views``, or ``azimuths_deg`` × ``elevations_deg``)."""
        from wbsa.camera.views import parse_views

        if self.azimuths_deg or self.elevations_deg:
            return tuple(parse_views(None, azimuths=list(self.azimuths_deg) or None,
                                     elevations=list(self.elevations_deg) or None, distance_m=distance_m))
        return tuple(parse_views(self.views, distance_m=distance_m))

    def camera_spec(self, base_dir: str | os.PathLike = ".") -> str:
        """``camera`` with a relative JSON path made absolute from ``base_dir`` (a preset name as it is)."""
        from wbsa.camera.presets import PRESETS

        cam = str(self.camera)
        if cam in PRESETS or not (cam.lower().endswith(".json") or "/" in cam or os.sep in cam):
            return cam  # a preset (an unknown name gets the "unknown preset" message)
        path = Path(cam)
        return str(path if path.is_absolute() else Path(base_dir) / path)

    def intrinsics(self, base_dir: str | os.PathLike = ".") -> Intrinsics:
        """The camera's intrinsics; a relative JSON path is read from ``base_dir``."""
        from wbsa.camera.presets import resolve_camera

        return resolve_camera(self.camera_spec(base_dir))

    def job(self, distance_m: float, *, sensor: SensorSettings | None = None,
            reconstruction: ReconstructionSettings | None = None, base_dir: str | os.PathLike = ".") -> ScanJob:
        """The resolved :class:`ScanJob` of one camera distance.

        Parameters
        ----------
        distance_m : float
            One of ``distances_m`` (any positive distance is accepted).
        sensor : SensorSettings, optional
            None or an ideal sensor: no sensor step.
        reconstruction : ReconstructionSettings, optional
            None or no ``methods``: no reconstruction.
        base_dir : path
            Folder of a relative camera JSON path.
        """
        if sensor is not None and sensor.is_ideal:
            sensor = None
        return ScanJob(camera=self.intrinsics(base_dir), views=self.view_list(distance_m), sensor=sensor,
                       reconstruction=reconstruction, seed=self.seed, backend=self.backend)


@dataclass(frozen=True)
class ScanJob:
    """Everything that decides the rows of a scan table: one camera distance, resolved.

    Attributes
    ----------
    camera : wbsa.camera.Intrinsics
        Pinhole intrinsics of the virtual depth camera (its ``name`` goes into the ``camera`` column).
    views : tuple of wbsa.camera.View
        Camera placements, each scanned for every subject.
    sensor : wbsa.sensor.SensorSettings or None
        Depth-sensor simulation applied to every rendered frame before reconstruction;
        ``None`` keeps the ideal ray-cast frame.
    reconstruction : wbsa.surface.ReconstructionSettings or None
        Surface reconstruction: its ``methods`` each add a ``vbsa_recon_<method>_m2`` column. None (also
        what settings without methods become): no reconstruction.
    seed : int
        Root seed; subject ``s`` draws its sensor noise from ``numpy.random.SeedSequence([seed, s])``
        (one child stream per view, keyed by the view's angles and distance), so results do not
        depend on chunking, on the view list or on the number of workers.
    backend : {'auto', 'open3d', 'warp'}
        Ray-casting back end (:mod:`wbsa.camera.backends`); ``auto`` is resolved on construction. Only a
        back end other than ``open3d`` enters :meth:`to_dict` (and the hash).
    """

    camera: Intrinsics
    views: tuple[View, ...]
    sensor: SensorSettings | None = None
    reconstruction: ReconstructionSettings | None = None
    seed: int = 0
    backend: RaycastBackend = "open3d"

    def __post_init__(self) -> None:
        from wbsa.camera.backends import resolve_backend

        object.__setattr__(self, "backend", resolve_backend(self.backend))
        object.__setattr__(self, "views", tuple(self.views))
        if self.reconstruction is not None and not self.reconstruction.methods:
            object.__setattr__(self, "reconstruction", None)
        check_field(len(self.views) >= 1, "views", "must hold at least one view")
        check_field(int(self.seed) >= 0, "seed", f"must be 0 or more, got {self.seed}")
        if self.sensor is not None:
            self.sensor.check_camera(self.camera)

    @property
    def reconstruct(self) -> tuple[str, ...]:
        """The reconstruction methods (empty: none)."""
        return self.reconstruction.methods if self.reconstruction is not None else ()

    @property
    def camera_name(self) -> str:
        """Name of the camera (preset name, or ``'custom'``) written to the ``camera`` column."""
        return str(getattr(self.camera, "name", "custom"))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready description of the job (written to ``DIR/settings.json``, hashed into the folder's key)."""
        sensor = None
        if self.sensor is not None:
            sensor = self.sensor.to_dict() if hasattr(self.sensor, "to_dict") else _plain(self.sensor)
        return _json_safe({
            "camera": _plain(self.camera),
            "views": [[float(v.azimuth_deg), float(v.elevation_deg), float(v.distance_m)] for v in self.views],
            "sensor": sensor,
            "reconstruct": list(self.reconstruct),
            "reconstruction": _plain(self.reconstruction) if self.reconstruction is not None else None,
            "seed": int(self.seed),
            **({} if self.backend == "open3d" else {"backend": self.backend}),
        })


def settings_hash(settings: ScanJob, population_fingerprint: str) -> str:
    """SHA-256 (hex, 16 characters) of the job and the population that a scan folder holds.

    Parameters
    ----------
    settings : ScanJob
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
