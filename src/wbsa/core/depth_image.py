"""Depth images as a real sensor stores them: 16-bit single-channel PNG, millimetres, 0 = no return."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from wbsa.core.limits import check_image_size
from wbsa.errors import WbsaError
from wbsa.atomic import atomic_path, png_verifier

#: Units per metre of the usual depth PNG (OpenNI / Kinect SDK / Open3D); TUM RGB-D uses 5000.
MM_PER_M = 1000.0
_UINT16_MAX = np.iinfo(np.uint16).max


def depth_to_png_mm(depth_m: np.ndarray, *, depth_scale: float = MM_PER_M) -> np.ndarray:
    """Encode a depth image as 16-bit integers (millimetres by default).

    Parameters
    ----------
    depth_m : (h, w) float
        z-depth in metres; 0, negative or non-finite = no return.
    depth_scale : float
        Integer units per metre (1000 = millimetres).

    Returns
    -------
    (h, w) uint16
        Rounded depth in units, 0 where there is no return.

    Raises
    ------
    WbsaError
        If a depth exceeds the 16-bit range (65.535 m in millimetres).
    """
    d = np.asarray(depth_m, dtype=np.float64)
    if d.ndim != 2:
        raise WbsaError(f"a depth image must be 2-D (h, w), got shape {d.shape}")
    ok = np.isfinite(d) & (d > 0)
    units = np.where(ok, np.rint(d * depth_scale), 0.0)
    if units.max(initial=0.0) > _UINT16_MAX:
        raise WbsaError(f"depth {d[ok].max():.3f} m does not fit a 16-bit PNG at {depth_scale:g} units per metre; "
                        "use a smaller depth_scale")
    return units.astype(np.uint16)


def png_mm_to_depth(units: np.ndarray, *, depth_scale: float = MM_PER_M) -> np.ndarray:
    """Decode 16-bit depth units into metres: (h, w) uint16 -> (h, w) float32, 0 = no return."""
    return (np.asarray(units, dtype=np.float64) / depth_scale).astype(np.float32)


def write_depth_png(path: str | os.PathLike, depth_m: np.ndarray, *, depth_scale: float = MM_PER_M) -> Path:
    """Write a depth image atomically as a 16-bit grayscale PNG (see :func:`depth_to_png_mm`)."""
    from PIL import Image

    units = depth_to_png_mm(depth_m, depth_scale=depth_scale)
    path = Path(path)
    with atomic_path(path, verify=png_verifier(units.shape)) as tmp:
        Image.fromarray(units).save(tmp, format="PNG")
    return path


def read_depth_png(path: str | os.PathLike, *, depth_scale: float = MM_PER_M) -> np.ndarray:
    """Read a 16-bit depth PNG (a real sensor's or :func:`write_depth_png`'s) into metres.

    Parameters
    ----------
    path : path-like
    depth_scale : float
        Integer units per metre in the file (1000 for millimetres; 5000 for TUM RGB-D).

    Returns
    -------
    (h, w) float32
        Depth in metres, 0 = no return.

    Raises
    ------
    WbsaError
        If the file is missing, not an image, not a single-channel 16-bit image, or larger than
        :data:`wbsa.core.limits.MAX_IMAGE_PIXELS` (checked from the header, before decoding).
    """
    from PIL import Image, UnidentifiedImageError

    path = Path(path)
    if not path.is_file():
        raise WbsaError(f"depth image {path} does not exist; check the path")
    try:
        with Image.open(path) as img:
            check_image_size(img.width, img.height, f"depth image {path}")
            mode = img.mode
            units = np.asarray(img)
    except (UnidentifiedImageError, OSError, Image.DecompressionBombError) as exc:
        raise WbsaError(f"{path} is not a readable image ({type(exc).__name__}); give a 16-bit depth PNG") from None
    if mode not in ("I;16", "I;16B", "I;16L", "I") or units.ndim != 2:
        raise WbsaError(f"{path} is a {mode} image, not a single-channel 16-bit depth image; "
                        "save depth as 16-bit PNG in millimetres")
    if units.min(initial=0) < 0 or units.max(initial=0) > _UINT16_MAX:
        raise WbsaError(f"{path} holds values outside the 16-bit range; it is not a depth PNG")
    return png_mm_to_depth(units.astype(np.uint16), depth_scale=depth_scale)
