"""The paper's eq. 9: how far the camera must stand for a subject of a given stature to fit the frame.

Eq. 9 reads ``max stature = 2 · tan(ψ) · D`` with ψ "the vertical field of view". For a camera aimed at
the subject's centre the pinhole model (paper eq. 2) gives a half-height of ``tan(ψ/2) · D`` above and
below the optical axis, so the formula holds with ψ the *half* angle of the vertical field of view;
taking ψ as the full angle would double-count it (with the Kinect v1's 45.6° it would claim 8.8 m
statures fit at 4.3 m). See docs/camera.md for the numbers.
"""

from __future__ import annotations

import math

from wbsa.camera.intrinsics import Intrinsics
from wbsa.errors import WbsaError


def vertical_half_fov_deg(intrinsics: Intrinsics) -> float:
    """The smaller of the angles from the optical axis to the top and to the bottom image edge, degrees.

    With an off-centre principal point the two halves differ; the smaller one decides whether a
    subject centred on the optical axis fits.

    Parameters
    ----------
    intrinsics : Intrinsics
    """
    k = intrinsics
    up = (k.cy + 0.5) / k.fy
    down = (k.height - 0.5 - k.cy) / k.fy
    return math.degrees(math.atan(min(up, down)))


def distance_to_fit(stature_m: float, intrinsics: Intrinsics, margin: float = 0.05) -> float:
    """Smallest camera distance D at which a standing subject fits the vertical field of view (eq. 9).

    ``D = (1 + margin) · stature / (2 · tan ψ)`` with ψ the vertical half field of view
    (:func:`vertical_half_fov_deg`), for a camera at elevation 0 aimed at the subject's centre.

    Parameters
    ----------
    stature_m : float
        Height of the subject (m), > 0.
    intrinsics : Intrinsics
    margin : float
        Extra fraction of the stature kept free (0.05 = 5 %), for the body's depth and the floor.

    Returns
    -------
    float
        Distance in metres.
    """
    if not (math.isfinite(stature_m) and stature_m > 0):
        raise WbsaError(f"stature must be a positive number of metres, got {stature_m!r}")
    if not (math.isfinite(margin) and margin > -1):
        raise WbsaError(f"margin must be a fraction greater than -1, got {margin!r}")
    tan_psi = math.tan(math.radians(vertical_half_fov_deg(intrinsics)))
    return (1.0 + margin) * stature_m / (2.0 * tan_psi)


def max_stature_m(distance_m: float, intrinsics: Intrinsics, margin: float = 0.0) -> float:
    """Inverse of :func:`distance_to_fit`: the tallest subject that fits at ``distance_m``.

    Parameters
    ----------
    distance_m : float
        Camera distance to the subject's centre (m).
    intrinsics : Intrinsics
    margin : float
        Extra fraction of the stature kept free, as :func:`distance_to_fit`.
    """
    if not (math.isfinite(distance_m) and distance_m > 0):
        raise WbsaError(f"distance must be a positive number of metres, got {distance_m!r}")
    tan_psi = math.tan(math.radians(vertical_half_fov_deg(intrinsics)))
    return 2.0 * tan_psi * distance_m / (1.0 + margin)
