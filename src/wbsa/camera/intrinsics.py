"""Pinhole intrinsics (the paper's K, eq. 3): presets, validation, Open3D JSON round trip."""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path

import numpy as np

from wbsa.core.limits import check_image_size
from wbsa.errors import WbsaError



@dataclass(frozen=True)
class Intrinsics:
    """A pinhole camera: image size, focal lengths, principal point and skew, in pixels.

    Pixel centres sit at integer coordinates (OpenCV): pixel ``(u, v)`` sees the ray through
    ``K^-1 [u, v, 1]``; a centred principal point of a 640-wide image is ``cx = 319.5``.

    Attributes
    ----------
    width, height : int
        Image size in pixels.
    fx, fy : float
        Focal lengths in pixels (the paper's f·s_x, f·s_y).
    cx, cy : float
        Principal point in pixels (the paper's o_x, o_y); must lie inside the image.
    skew : float
        K[0, 1] (the paper's f·s_θ); 0 for square-pixel cameras.
    name : str
        Preset name, or ``'custom'``.
    min_range_m, max_range_m : float
        The sensor's nominal working range. The ideal ray caster ignores it; the sensor stage may apply it.
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    skew: float = 0.0
    name: str = "custom"
    min_range_m: float = 0.0
    max_range_m: float = math.inf

    def __post_init__(self) -> None:
        for key in ("width", "height"):
            value = getattr(self, key)
            if isinstance(value, float) and value.is_integer():
                object.__setattr__(self, key, int(value))
                value = int(value)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value <= 0:
                raise WbsaError(f"camera {key} must be a positive whole number of pixels, got {value!r}")
            object.__setattr__(self, key, int(value))
        check_image_size(self.width, self.height, "the camera image")
        for key in ("fx", "fy", "cx", "cy", "skew", "min_range_m", "max_range_m"):
            try:
                value = float(getattr(self, key))
            except (TypeError, ValueError):
                raise WbsaError(f"camera {key} must be a number, got {getattr(self, key)!r}") from None
            object.__setattr__(self, key, value)
        if not (math.isfinite(self.fx) and self.fx > 0 and math.isfinite(self.fy) and self.fy > 0):
            raise WbsaError(f"camera focal lengths must be positive, got fx={self.fx:g}, fy={self.fy:g} pixels; "
                            f"check the camera's intrinsics")
        lo_deg, hi_deg = FIELD_OF_VIEW_RANGE_DEG
        for axis, f, size in (("horizontal", self.fx, self.width), ("vertical", self.fy, self.height)):
            fov = math.degrees(2.0 * math.atan(size / (2.0 * f)))
            if not lo_deg <= fov <= hi_deg:
                raise WbsaError(f"camera focal length {f:g} px gives a {axis} field of view of {fov:.3g}° over "
                                f"{size} pixels, outside {lo_deg:g}–{hi_deg:g}°; check the camera's intrinsics "
                                "(focal lengths in pixels, not millimetres)")
        if not math.isfinite(self.skew):
            raise WbsaError(f"camera skew must be finite, got {self.skew:g}")
        if not (0.0 <= self.cx <= self.width and 0.0 <= self.cy <= self.height):
            raise WbsaError(
                f"principal point ({self.cx:g}, {self.cy:g}) lies outside the {self.width}x{self.height} image; "
                f"use 0 <= cx <= width and 0 <= cy <= height "
                f"(centre: {(self.width - 1) / 2:g}, {(self.height - 1) / 2:g})"
            )
        if not (0.0 <= self.min_range_m < self.max_range_m) or math.isnan(self.max_range_m):
            raise WbsaError(
                f"camera range must satisfy 0 <= min < max, got {self.min_range_m:g}..{self.max_range_m:g} m"
            )

    @property
    def K(self) -> np.ndarray:
        """(3, 3) float64 intrinsic matrix [[fx, skew, cx], [0, fy, cy], [0, 0, 1]]."""
        return np.array([[self.fx, self.skew, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def fov_deg(self) -> tuple[float, float]:
        """(horizontal, vertical) full field of view in degrees, edge to edge of the image."""
        h = math.degrees(math.atan((self.cx + 0.5) / self.fx) + math.atan((self.width - 0.5 - self.cx) / self.fx))
        v = math.degrees(math.atan((self.cy + 0.5) / self.fy) + math.atan((self.height - 0.5 - self.cy) / self.fy))
        return h, v

    def scaled(self, factor: float) -> "Intrinsics":
        """The same camera with ``factor`` times as many pixels per side (same field of view).

        Pixel centres stay at integer coordinates, so ``cx' = (cx + 0.5)·k − 0.5``.

        Parameters
        ----------
        factor : float
            Pixels per side, relative to this camera's.
        """
        if not (factor > 0 and math.isfinite(factor)):
            raise WbsaError(f"resolution scale must be positive, got {factor!r}")
        w, h = round(self.width * factor), round(self.height * factor)
        if w < 1 or h < 1:
            raise WbsaError(f"resolution scale {factor:g} leaves no pixels; use a larger scale")
        return replace(
            self, width=w, height=h, fx=self.fx * factor, fy=self.fy * factor,
            cx=(self.cx + 0.5) * factor - 0.5, cy=(self.cy + 0.5) * factor - 0.5, skew=self.skew * factor,
            name=self.name if factor == 1 else f"{self.name}@{factor:g}x",
        )

    def to_dict(self) -> dict:
        """Plain fields for tables and reports (``max_range_m`` inf becomes None)."""
        return {
            "name": self.name, "width": self.width, "height": self.height, "fx": self.fx, "fy": self.fy,
            "cx": self.cx, "cy": self.cy, "skew": self.skew, "min_range_m": self.min_range_m,
            "max_range_m": None if math.isinf(self.max_range_m) else self.max_range_m,
        }

    def to_open3d_json(self) -> dict:
        """Open3D's ``PinholeCameraIntrinsic`` JSON (column-major ``intrinsic_matrix``) plus wbsa's extra keys.

        ``open3d.io.read_pinhole_camera_intrinsic`` reads it (it ignores the extra keys).
        """
        return {
            "width": self.width,
            "height": self.height,
            "intrinsic_matrix": [float(x) for x in self.K.T.ravel()],
            "name": self.name,
            "min_range_m": self.min_range_m,
            "max_range_m": None if math.isinf(self.max_range_m) else self.max_range_m,
        }

    @classmethod
    def from_open3d_json(cls, source: dict | str | os.PathLike) -> "Intrinsics":
        """Read Open3D ``PinholeCameraIntrinsic`` JSON: a dict, or the path of a ``.json`` file.

        Parameters
        ----------
        source : dict, str or path
            The JSON's content, or its file.

        Raises
        ------
        WbsaError
            If the file is missing or not valid JSON, or the matrix is not an upper-triangular pinhole K.
        """
        where = "camera JSON"
        if not isinstance(source, dict):
            path = Path(source)
            where = str(path)
            if not path.is_file():
                raise WbsaError(f"camera file {path} does not exist; give a camera preset name (wbsa estimate "
                                f"--help lists them) or an Open3D intrinsics JSON file", field="camera",
                                page=f"camera file {path} does not exist; choose a camera under Camera or add its "
                                     "intrinsics file")
            try:
                source = json.loads(path.read_text())
            except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
                raise WbsaError(f"{path} is not readable camera JSON ({type(exc).__name__}); "
                                f"write it like open3d.io.write_pinhole_camera_intrinsic") from None
        if not isinstance(source, dict):
            raise WbsaError(f"{where} must be a JSON object with width, height and intrinsic_matrix")
        try:
            m = np.asarray(source["intrinsic_matrix"], dtype=np.float64)
            width, height = source["width"], source["height"]
        except KeyError as exc:
            raise WbsaError(f"{where} lacks {exc.args[0]!r}; "
                            f"it needs width, height and intrinsic_matrix (9 numbers)") from None
        except (TypeError, ValueError):
            raise WbsaError(f"{where}: intrinsic_matrix must be 9 numbers (column-major 3x3)") from None
        if m.size != 9 or not np.all(np.isfinite(m)):
            raise WbsaError(f"{where}: intrinsic_matrix must be 9 finite numbers (column-major 3x3), got {m.size}")
        K = m.reshape(3, 3).T  # Open3D stores the matrix column-major
        if not _is_pinhole(K):
            order = ("Open3D lists it column by column, [fx, 0, 0, s, fy, 0, cx, cy, 1], and this one is written row "
                     "by row: write it column by column (open3d.io.write_pinhole_camera_intrinsic does)"
                     if _is_pinhole(K.T) else "Open3D lists it column by column, [fx, 0, 0, s, fy, 0, cx, cy, 1]")
            raise WbsaError(f"{where}: intrinsic_matrix is not a pinhole camera matrix ([[fx, s, cx], [0, fy, cy], "
                            f"[0, 0, 1]]); {order}", code="camera_matrix", field="camera")
        for key in ("width", "height", "min_range_m", "max_range_m"):
            value = source.get(key)
            if key in source and not (value is None and key.endswith("_m")) and (isinstance(value, bool) or not isinstance(value, (int, float))
                                  or (key.endswith("_m") and value is not None and not math.isfinite(value))):
                what = "a finite number of metres" if key.endswith("_m") else "a whole number of pixels"
                raise WbsaError(f"{where}: {key} must be {what}, got {value!r}")
        max_range = source.get("max_range_m")
        return cls(
            width=width, height=height, fx=K[0, 0], fy=K[1, 1], cx=K[0, 2], cy=K[1, 2], skew=K[0, 1],
            name=str(source.get("name", "custom")), min_range_m=float(source.get("min_range_m") or 0.0),
            max_range_m=math.inf if max_range is None else float(max_range),
        )


def _is_pinhole(K: np.ndarray) -> bool:
    """Whether a 3×3 matrix has a pinhole camera matrix's zeros and one: ``[[fx, s, cx], [0, fy, cy], [0, 0, 1]]``."""
    return bool(abs(K[1, 0]) <= 1e-12 and abs(K[2, 0]) <= 1e-12 and abs(K[2, 1]) <= 1e-12 and abs(K[2, 2] - 1.0) <= 1e-12)


#: Fields of view (degrees, either axis) a depth camera can have; focal lengths beyond them are typing errors.
FIELD_OF_VIEW_RANGE_DEG = (1.0, 170.0)


@lru_cache(maxsize=16)
def pixel_rays(intrinsics: Intrinsics) -> tuple[np.ndarray, np.ndarray]:
    """Un-normalised ray directions of every pixel and their cosines with the optical axis (cached).

    Parameters
    ----------
    intrinsics : Intrinsics

    Returns
    -------
    dirs : (h, w, 3) float32
        ``K^-1 [u, v, 1]`` in the camera frame (z component 1, so the hit distance along it is the z-depth).
    cos_axis : (h, w) float32
        ``1 / |dirs|``, the cosine of the off-axis angle α of each pixel's ray.
    """
    k = intrinsics
    v, u = np.mgrid[0:k.height, 0:k.width].astype(np.float64)
    y = (v - k.cy) / k.fy
    x = (u - k.cx - k.skew * y) / k.fx
    dirs = np.stack([x, y, np.ones_like(x)], axis=-1).astype(np.float32)
    cos_axis = (1.0 / np.sqrt(x * x + y * y + 1.0)).astype(np.float32)
    dirs.setflags(write=False)
    cos_axis.setflags(write=False)
    return dirs, cos_axis


@lru_cache(maxsize=16)
def pixel_axes(intrinsics: Intrinsics) -> tuple[np.ndarray, np.ndarray, float]:
    """Separable form of the pixel rays: ``x = xu[u] + shear · yv[v]``, ``y = yv[v]`` (cached).

    Parameters
    ----------
    intrinsics : Intrinsics

    Returns
    -------
    xu : (w,) float64
        ``(u − cx) / fx``.
    yv : (h,) float64
        ``(v − cy) / fy``.
    shear : float
        ``−skew / fx``.
    """
    k = intrinsics
    xu = (np.arange(k.width, dtype=np.float64) - k.cx) / k.fx
    yv = (np.arange(k.height, dtype=np.float64) - k.cy) / k.fy
    xu.setflags(write=False)
    yv.setflags(write=False)
    return xu, yv, -k.skew / k.fx
