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


#: Depth file types :func:`read_depth` reads.
DEPTH_SUFFIXES = (".png", ".npy", ".tif", ".tiff", ".exr")


def read_depth(path: str | os.PathLike, *, depth_scale: float | None = None) -> np.ndarray:
    """Read a depth image of any supported type into metres (0 = no return).

    ``.png``
        16-bit single channel, integer units (``depth_scale`` per metre, default 1000 = millimetres).
    ``.npy``
        A 2-D array: floating point in metres (``depth_scale`` default 1), or integers in units
        (default 1000 per metre).
    ``.tif`` / ``.tiff``
        32-bit float (metres, default scale 1) or 16-bit integer (units, default 1000 per metre), via Pillow.
    ``.exr``
        Single-channel float depth in metres, if the ``OpenEXR`` package is installed.

    NaN, infinite, zero and negative values are "no return".

    Raises
    ------
    WbsaError
        A missing file, an unknown type, more than one channel, or an unreadable file.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in DEPTH_SUFFIXES:
        raise WbsaError(f"cannot read depth from {path.name}: use a {', '.join(DEPTH_SUFFIXES)} file")
    if not path.is_file():
        raise WbsaError(f"depth image {path} does not exist; check the path")
    if depth_scale is not None and not (np.isfinite(depth_scale) and depth_scale > 0):
        raise WbsaError(f"depth scale {depth_scale} must be a positive number of units per metre, e.g. 1000")
    if suffix == ".png":
        return read_depth_png(path, depth_scale=depth_scale or MM_PER_M)
    if suffix == ".npy":
        try:
            arr = np.load(path, allow_pickle=False)
        except (OSError, ValueError) as exc:
            raise WbsaError(f"{path} is not a readable .npy array ({type(exc).__name__}); "
                            "save it with numpy.save") from None
    elif suffix == ".exr":
        arr = _read_exr(path)
    else:
        arr = _read_tiff(path)
    arr = np.squeeze(arr)
    if arr.ndim != 2 or not (np.issubdtype(arr.dtype, np.floating) or np.issubdtype(arr.dtype, np.integer)):
        raise WbsaError(f"{path} holds a {arr.dtype} array of shape {arr.shape}, not a single-channel depth image")
    scale = depth_scale or (1.0 if np.issubdtype(arr.dtype, np.floating) else MM_PER_M)
    depth = arr.astype(np.float64) / scale
    return np.where(np.isfinite(depth) & (depth > 0), depth, 0.0).astype(np.float32)


def _read_tiff(path: Path) -> np.ndarray:
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as img:
            if img.mode not in ("F", "I", "I;16", "I;16B", "I;16L"):
                raise WbsaError(f"{path} is a {img.mode} TIFF, not single-channel depth; save 32-bit float metres "
                                "or 16-bit millimetres")
            return np.asarray(img)
    except (UnidentifiedImageError, OSError) as exc:
        raise WbsaError(f"{path} is not a readable TIFF ({type(exc).__name__}); save depth as 32-bit float "
                        "metres or 16-bit millimetres") from None


def _read_exr(path: Path) -> np.ndarray:
    try:
        import OpenEXR
    except ImportError:
        raise WbsaError(f"reading {path.name} needs the OpenEXR package (pip install openexr); or save the depth "
                        "as .npy (float metres) or 32-bit float .tiff") from None
    try:
        with OpenEXR.File(str(path)) as f:
            channels = f.channels()
            if len(channels) != 1:
                names = ", ".join(channels)
                raise WbsaError(f"{path} has channels {names}; depth needs exactly one (e.g. Z or Y)")
            return np.asarray(next(iter(channels.values())).pixels)
    except (OSError, RuntimeError) as exc:
        raise WbsaError(f"{path} is not a readable EXR ({type(exc).__name__})") from None
