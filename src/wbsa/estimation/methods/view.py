"""The view of a subject every method shares: the mirror-equivalent azimuth, the estimate with its spreads, the view
a prediction uses and the check of a stated view against the estimated one.

Bodies are left/right symmetric, so θ and −θ are one view: azimuths are folded to ψ = |θ| in [0, 180]. How the
view is estimated is each method's own (the regression's :class:`~wbsa.estimation.methods.regression.view_model.ViewModel`,
the body fit's fitted placement).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wbsa.errors import Worded

#: A stated view further than this (degrees) from the estimated one is flagged.
VIEW_TOLERANCE_DEG = 30.0


def fold_azimuth(azimuth_deg) -> np.ndarray:
    """Mirror-equivalent azimuth ψ = |θ| in [0, 180] (θ and −θ are the same view of a symmetric body).

    Parameters
    ----------
    azimuth_deg : float or (n,) float64
        Azimuths θ in degrees, any range.

    Returns
    -------
    float64 array of the input's shape
    """
    return np.abs((np.asarray(azimuth_deg, dtype=np.float64) + 180.0) % 360.0 - 180.0)


def azimuth_error_deg(estimate_deg, truth_deg) -> np.ndarray:
    """Mirror-equivalent azimuth error |ψ̂ − ψ| in degrees (0–180).

    Parameters
    ----------
    estimate_deg, truth_deg : float or (n,) float64
        Azimuths in degrees, any range (folded by :func:`fold_azimuth`).

    Returns
    -------
    float64 array of the inputs' broadcast shape
    """
    return np.abs(fold_azimuth(estimate_deg) - fold_azimuth(truth_deg))


@dataclass(frozen=True)
class ViewEstimate:
    """Estimated view, paper convention, with standard deviations (degrees)."""

    azimuth_deg: float
    azimuth_sd_deg: float
    elevation_deg: float
    elevation_sd_deg: float
    p_front: float

    def to_dict(self) -> dict:
        """JSON-ready fields; a value not estimated (a fitted body's spreads) is None."""
        values = {k: float(getattr(self, k)) for k in ("azimuth_deg", "azimuth_sd_deg", "elevation_deg",
                                                        "elevation_sd_deg", "p_front")}
        return {k: round(v, 3) if np.isfinite(v) else None for k, v in values.items()}


#: An estimated azimuth spread (degrees) above which the estimate is flagged ``uncertain_view``.
UNCERTAIN_AZIMUTH_SD_DEG = 30.0


def view_used(view: ViewEstimate, azimuth_deg: float | None,
              elevation_deg: float | None) -> tuple[tuple[float, float], dict[str, str]]:
    """The view a prediction uses: the stated azimuth (folded, :func:`fold_azimuth`) and elevation where given,
    else the estimated ones; flags ``uncertain_view`` when the azimuth is estimated and unsure.

    Parameters
    ----------
    view : ViewEstimate
        The view estimated from the image.
    azimuth_deg, elevation_deg : float or None
        The stated view (degrees); None: use the estimated one.

    Returns
    -------
    ((float, float), dict of str to str)
        The azimuth and elevation used (degrees) and the flags.
    """
    az = view.azimuth_deg if azimuth_deg is None else float(fold_azimuth(azimuth_deg))
    el = view.elevation_deg if elevation_deg is None else float(elevation_deg)
    flags: dict[str, str] = {}
    if azimuth_deg is None and not view.azimuth_sd_deg <= UNCERTAIN_AZIMUTH_SD_DEG:
        said = (f"azimuth {view.azimuth_deg:.0f}° ± {view.azimuth_sd_deg:.0f}° (camera in front with probability "
                f"{view.p_front:.2f})")
        flags["uncertain_view"] = Worded(f"{said}; give azimuth_deg if you know it",
                                         f"{said}; type the azimuth if you know it",
                                         command=f"{said}; give --azimuth if you know it")
    return (az, el), flags


def view_flags(stated: tuple[float | None, float | None], estimated, tolerance_deg: float = VIEW_TOLERANCE_DEG
               ) -> dict[str, str]:
    """``{"view_disagrees": ...}`` if a stated azimuth or elevation is more than ``tolerance_deg`` off.

    Parameters
    ----------
    stated : (float or None, float or None)
        The stated azimuth and elevation (degrees; None: not stated).
    estimated : ViewEstimate
    tolerance_deg : float
        Largest difference not flagged (degrees; the azimuth's mirror-equivalent).
    """
    az, el = stated
    parts = []
    if az is not None and math.isfinite(estimated.azimuth_deg):
        err = float(azimuth_error_deg(az, estimated.azimuth_deg))
        if err > tolerance_deg:
            spread = f" ± {estimated.azimuth_sd_deg:.0f}°" if math.isfinite(estimated.azimuth_sd_deg) else ""
            parts.append(f"azimuth stated {az:g}°, estimated {estimated.azimuth_deg:.0f}°{spread} (mirror-equivalent)")
    if el is not None and abs(el - estimated.elevation_deg) > tolerance_deg:
        parts.append(f"elevation stated {el:g}°, estimated {estimated.elevation_deg:.0f}°")
    return {"view_disagrees": "; ".join(parts)} if parts else {}
