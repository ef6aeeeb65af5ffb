"""Documented limits checked before memory is allocated: image sizes and seeds.

A full-image depth frame holds about 40 bytes per pixel (depth, triangle ids, points, normals) plus
the cached pixel rays (12 bytes); the preview and a 16-bit PNG need more transiently. Images are
therefore limited to :data:`MAX_IMAGE_PIXELS` (16.8 megapixels, e.g. 4096 × 4096, about 1 GB per
frame), more than any depth camera in use (the Kinect v2 has 0.2 megapixels, an Azure Kinect 1 MP).
"""

from __future__ import annotations

from wbsa.errors import WbsaError

#: Largest image (width × height pixels) wbsa renders or reads: 4096 × 4096.
MAX_IMAGE_PIXELS = 4096 * 4096


def check_image_size(width: int, height: int, what: str = "image") -> None:
    """Refuse an image larger than :data:`MAX_IMAGE_PIXELS` before anything is allocated.

    Parameters
    ----------
    width, height : int
        The image's size in pixels.
    what : str
        What the image is, in the message.

    Raises
    ------
    WbsaError
        Naming the size, the limit and the fix.
    """
    if int(width) * int(height) > MAX_IMAGE_PIXELS:
        raise WbsaError(f"{what} of {width} x {height} pixels ({int(width) * int(height) / 1e6:.1f} megapixels) is "
                        f"above wbsa's limit of {MAX_IMAGE_PIXELS / 1e6:.1f} megapixels (4096 x 4096, about 1 GB "
                        "per frame); use a smaller image or camera resolution")


def check_seed(seed: object, what: str = "seed") -> int:
    """A seed as a non-negative integer (what :class:`numpy.random.SeedSequence` takes).

    Parameters
    ----------
    seed : object
        The seed given.
    what : str
        Its name in the message.

    Raises
    ------
    WbsaError
        If ``seed`` is negative or not a whole number.
    """
    if isinstance(seed, bool) or not isinstance(seed, int):
        try:
            import numpy as np

            if isinstance(seed, np.integer):
                seed = int(seed)
        except ImportError:  # pragma: no cover
            pass
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise WbsaError(f"{what} must be a whole number 0 or more, got {seed!r}; use e.g. 0")
    return seed
