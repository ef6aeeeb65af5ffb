"""Depth images as a real sensor stores them: 16-bit single-channel PNG, millimetres, 0 = no return."""

from __future__ import annotations

import contextlib
import errno
import os
import stat
import struct
import warnings
from pathlib import Path
from typing import Iterator

import numpy as np

from wbsa.core.limits import MAX_IMAGE_PIXELS, check_image_size
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
    """Decode 16-bit depth units into metres: (h, w) uint16 -> (h, w) float32, 0 = no return.

    Parameters
    ----------
    units : (h, w) uint16
        Depth in units, 0 = no return.
    depth_scale : float
        Units per metre (1000: millimetres).
    """
    return metres_from_units(units, depth_scale)


def write_depth_png(path: str | os.PathLike, depth_m: np.ndarray, *, depth_scale: float = MM_PER_M) -> Path:
    """Write a depth image atomically as a 16-bit grayscale PNG (see :func:`depth_to_png_mm`).

    Parameters
    ----------
    path : str or path
    depth_m : (h, w) float
        Depth in metres, 0 or NaN = no return.
    depth_scale : float
        Units per metre stored (1000: millimetres).
    """
    from PIL import Image

    units = depth_to_png_mm(depth_m, depth_scale=depth_scale)
    path = Path(path)
    with atomic_path(path, verify=png_verifier(units.shape)) as tmp:
        Image.fromarray(units).save(tmp, format="PNG")
    return path


def mask_image(mask: np.ndarray):
    """A subject's mask as an 8-bit image (255 = subject), the format of ``wbsa estimate --mask-out``.

    Parameters
    ----------
    mask : (h, w) bool

    Returns
    -------
    PIL.Image.Image
    """
    from PIL import Image

    return Image.fromarray(np.where(mask, 255, 0).astype(np.uint8))


def write_mask(path: str | os.PathLike, mask: np.ndarray) -> None:
    """Write :func:`mask_image` of ``mask`` to ``path`` as PNG, atomically (verified).

    Parameters
    ----------
    path : str or path
    mask : (h, w) bool
    """
    with atomic_path(path) as tmp:
        mask_image(mask).save(tmp, format="PNG")


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
    from PIL import UnidentifiedImageError

    path = Path(path)
    check_depth_path(path)
    try:
        with _open_image(path) as img:
            mode = img.mode
            units = np.asarray(img)
    except (UnidentifiedImageError, OSError) as exc:
        raise WbsaError(f"{path} is not a readable image ({type(exc).__name__}); give a 16-bit depth PNG") from None
    if mode not in ("I;16", "I;16B", "I;16L", "I") or units.ndim != 2:
        raise WbsaError(f"{path} is {_picture_words(mode)}, not a 16-bit depth image; export the depth frame from "
                        "the camera's software as a 16-bit PNG in millimetres", code="not_depth", field="depth")
    if units.min(initial=0) < 0 or units.max(initial=0) > _UINT16_MAX:
        raise WbsaError(f"{path} holds values outside the 16-bit range; it is not a depth PNG")
    return png_mm_to_depth(units.astype(np.uint16), depth_scale=depth_scale)


#: Depth file types :func:`read_depth` reads.
DEPTH_SUFFIXES = (".png", ".npy", ".tif", ".tiff", ".exr")


#: What an image of each Pillow mode is, in plain words (the messages never name a mode).
_PICTURE_MODES = {
    "1": "a black-and-white (1-bit) picture", "L": "an 8-bit grey-scale picture",
    "LA": "an 8-bit grey-scale picture with transparency", "P": "an 8-bit colour picture with a palette",
    "PA": "an 8-bit colour picture with a palette", "RGB": "a colour picture", "RGBA": "a colour picture with "
    "transparency", "RGBX": "a colour picture", "CMYK": "a colour picture for print (CMYK)", "YCbCr": "a colour picture",
    "HSV": "a colour picture", "LAB": "a colour picture", "F": "a 32-bit floating-point image",
}


def _picture_words(mode: str) -> str:
    """What an image of Pillow mode ``mode`` is, in plain words (``an 8-bit grey-scale picture``)."""
    return _PICTURE_MODES.get(mode, "an image of several channels or an unusual kind")


def check_depth_path(path: Path) -> None:
    """Refuse a depth path that is not a regular file, saying what it is (missing, a folder, a FIFO or device,
    a symbolic-link loop) rather than "does not exist" for all of them, or an empty file (0 bytes).

    Parameters
    ----------
    path : Path

    Raises
    ------
    WbsaError
    """
    try:
        mode = os.stat(path).st_mode
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise WbsaError(f"depth image {path} is a loop of symbolic links; give the file itself") from None
        if exc.errno in (errno.ENOENT, errno.ENOTDIR):
            raise WbsaError(f"depth image {path} does not exist; check the path") from None
        raise WbsaError(f"cannot read depth image {path} ({os.strerror(exc.errno or 0) or type(exc).__name__}); "
                        "check the path and its permissions") from None
    if stat.S_ISDIR(mode):
        raise WbsaError(f"depth image {path} is a folder; give a {', '.join(DEPTH_SUFFIXES)} file")
    if not stat.S_ISREG(mode):
        kind = "a FIFO (named pipe)" if stat.S_ISFIFO(mode) else "a device" if (
            stat.S_ISCHR(mode) or stat.S_ISBLK(mode)) else "a socket" if stat.S_ISSOCK(mode) else "not a regular file"
        raise WbsaError(f"depth image {path} is {kind}, not a file; save the depth image to a file first")
    if os.stat(path).st_size == 0:
        raise WbsaError(f"{path} is empty (0 bytes); export the depth frame again")


@contextlib.contextmanager
def _open_image(path: Path) -> Iterator:
    """Pillow's image of ``path`` (header read, pixels not yet decoded), refused above the pixel budget."""
    from PIL import Image

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)  # wbsa's own, lower limit follows
            img = Image.open(path)
    except Image.DecompressionBombError:  # Pillow's limit: far above wbsa's; its size said as any other's
        check_image_size(*_announced_size(path), f"depth image {path}")
        raise  # pragma: no cover (the size is above Pillow's limit, so above wbsa's)
    with img:
        check_image_size(img.width, img.height, f"depth image {path}")
        yield img


def _announced_size(path: Path) -> tuple[int, int]:
    """(width, height) in an image file's header, read by Pillow's reader of its type without Pillow's own size
    limit (nothing is decoded); raises :class:`WbsaError` where the header cannot be read."""
    from PIL import Image

    try:  # the reader is loaded: Pillow has just read the header with it
        kind = Image.EXTENSION[path.suffix.lower()]
        with Image.OPEN[kind][0](str(path)) as img:
            return img.size
    except Exception as exc:  # a header Pillow reads only to refuse it: whatever its reader raises
        raise WbsaError(f"depth image {path} announces more than {2 * Image.MAX_IMAGE_PIXELS / 1e6:.0f} million "
                        f"pixels, above wbsa's limit of 4096 x 4096 ({MAX_IMAGE_PIXELS / 1e6:.1f} million); use a "
                        f"smaller image or camera resolution ({type(exc).__name__})") from None


def _npy_shape(path: Path) -> tuple[int, ...]:
    """The shape in a ``.npy`` header (nothing else is read), refused above the pixel budget."""
    try:
        with open(path, "rb") as fh:
            version = np.lib.format.read_magic(fh)
            read = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
            shape, _, _ = read(fh)
    except (OSError, ValueError, SyntaxError) as exc:
        raise WbsaError(f"{path} is not a readable .npy array ({type(exc).__name__}); save it with numpy.save") from None
    dims = [int(d) for d in shape if int(d) != 1]
    if len(dims) == 2:
        check_image_size(dims[1], dims[0], f"depth image {path}")
    elif int(np.prod(dims, dtype=np.float64)) > MAX_IMAGE_PIXELS:
        raise WbsaError(f"{path} holds an array of shape {tuple(shape)}, not a single-channel depth image")
    return tuple(shape)


def _exr_size(path: Path) -> tuple[int, int]:
    """(width, height) of an OpenEXR file's ``dataWindow``, read from its header alone (no OpenEXR needed)."""
    with open(path, "rb") as fh:
        head = fh.read(1 << 16)
    if head[:4] != b"\x76\x2f\x31\x01":
        raise WbsaError(f"{path} is not an OpenEXR file (wrong magic number)")
    pos = 8
    while pos < len(head) and head[pos] != 0:
        try:
            name_end = head.index(b"\0", pos)
            type_end = head.index(b"\0", name_end + 1)
            (size,) = struct.unpack_from("<i", head, type_end + 1)
        except (ValueError, struct.error):
            break
        value = type_end + 5
        if head[pos:name_end] == b"dataWindow" and size == 16 and value + 16 <= len(head):
            x0, y0, x1, y1 = struct.unpack_from("<4i", head, value)
            return x1 - x0 + 1, y1 - y0 + 1
        pos = value + max(size, 0)
    raise WbsaError(f"{path} has no readable dataWindow in its OpenEXR header; check the file")


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

    Parameters
    ----------
    path : str or path
    depth_scale : float or None
        Units per metre of the stored values; None: the type's default above.

    Raises
    ------
    WbsaError
        A missing file, an unknown type, more than one channel, or an unreadable file.
    """
    path = Path(path)
    if os.path.lexists(path):  # a folder, FIFO, device or link loop is named as such, whatever its suffix
        check_depth_path(path)
    suffix = path.suffix.lower()
    if suffix not in DEPTH_SUFFIXES:
        raise WbsaError(f"cannot read depth from {path.name}: use a {', '.join(DEPTH_SUFFIXES)} file, or a .pcd or "
                        ".ply point cloud with wbsa estimate")
    check_depth_path(path)
    if isinstance(depth_scale, bool) or not (depth_scale is None or isinstance(depth_scale, (int, float, np.number))):
        raise WbsaError(f"depth scale must be a number of units per metre, e.g. 1000, got {depth_scale!r}")
    if depth_scale is not None and not (np.isfinite(depth_scale) and depth_scale > 0):
        raise WbsaError(f"depth scale {depth_scale} must be a positive number of units per metre, e.g. 1000")
    if suffix == ".png":
        return read_depth_png(path, depth_scale=depth_scale or MM_PER_M)
    if suffix == ".npy":
        _npy_shape(path)  # the pixel budget, from the header
        try:
            arr = np.load(path, allow_pickle=False)
        except (OSError, ValueError, EOFError) as exc:
            raise WbsaError(f"{path} is not a readable .npy array ({type(exc).__name__}); "
                            "save it with numpy.save") from None
    elif suffix == ".exr":
        check_image_size(*_exr_size(path), f"depth image {path}")
        arr = _read_exr(path)
    else:
        arr = _read_tiff(path)
    arr = np.squeeze(arr)
    if arr.ndim != 2 or not (np.issubdtype(arr.dtype, np.floating) or np.issubdtype(arr.dtype, np.integer)):
        raise WbsaError(f"{path} holds a {arr.dtype} array of shape {arr.shape}, not a single-channel depth image")
    scale = depth_scale or (1.0 if np.issubdtype(arr.dtype, np.floating) else MM_PER_M)
    return metres_from_units(arr, scale)


def metres_from_units(arr: np.ndarray, units_per_m: float) -> np.ndarray:
    """Depth values in units → float32 metres, 0 = no return (NaN, infinite, zero, negative, or beyond float32).

    Parameters
    ----------
    arr : (h, w) int or float
    units_per_m : float
        Units per metre, positive.

    Returns
    -------
    (h, w) float32
        No NumPy warning is raised for values that overflow (an absurd scale such as 1e-300 gives huge
        depths, which are "no return" here and refused later as an implausible height or an empty image).
    """
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        depth = np.asarray(arr, dtype=np.float64) / units_per_m
        ok = np.isfinite(depth) & (depth > 0) & (depth < np.finfo(np.float32).max)
        return np.where(ok, depth, 0.0).astype(np.float32)


def _read_tiff(path: Path) -> np.ndarray:
    from PIL import UnidentifiedImageError

    try:
        with _open_image(path) as img:
            if img.mode not in ("F", "I", "I;16", "I;16B", "I;16L"):
                raise WbsaError(f"{path} is {_picture_words(img.mode)} (TIFF), not a single-channel depth image; "
                                "save the depth as 32-bit float metres or 16-bit millimetres", code="not_depth",
                                field="depth")
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
