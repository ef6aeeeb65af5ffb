"""The legs a frame does not show: a subject seen only above some height, completed to its stated stature.

When the feet are not seen (the frame cuts the person off, or something hides the legs) and the stature is
stated, the part of the body below the lowest seen returns is missing from every measure of area. Its
share of the whole body's area is read from the population's profile
(:func:`wbsa.bodies.area_profile.area_below_share`) at the height where the seen body ends; the area
measures are completed by it (:func:`completed`) and every route's interval widens by its spread over
people (:func:`widened`), so the answer accounts for the legs it did not see.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from statistics import NormalDist

import numpy as np

#: The measures of area that the unseen legs are missing from (:meth:`SubjectMeasures.features`).
AREA_MEASURES = ("seen_area_m2", "silhouette_m2")
#: The regression's log error on cut frames, completed, per unit of unseen area share: its mean (the estimate
#: is divided by exp(mean · share)) and its standard deviation (added to the interval in quadrature).
#: Measured on seed 2000's cut captures, never the held-out seed 1000
#: (``python benchmarks/bench_cut_off.py --seed 2000 --subjects 30 --calibrate``).
CUT_LOG_ERROR_PER_SHARE = (-0.219, 0.635)


@dataclass(frozen=True)
class UnseenLegs:
    """The body below the lowest seen returns.

    Attributes
    ----------
    seen_from_m : float
        Height over the floor where the seen body ends (metres).
    stature_m : float
        The stated stature.
    area_share, area_share_sd : float
        Mean and spread over people of the share of the whole body's area below ``seen_from_m``.
    """

    seen_from_m: float
    stature_m: float
    area_share: float
    area_share_sd: float

    def describe(self) -> str:
        """``the body below 0.45 m (about 24 % of its area) is not seen``."""
        return (f"the body below {self.seen_from_m:.2f} m (about {100 * self.area_share:.0f} % of its area) is not "
                "seen; its area is completed from the population's proportions and the interval widened")


def unseen_legs(stature_m: float, seen_from_m: float) -> UnseenLegs | None:
    """The :class:`UnseenLegs` of a body of stated ``stature_m`` seen from ``seen_from_m`` up, or None when
    nothing of area is missing (seen from under 1 cm).

    Parameters
    ----------
    stature_m : float
        The stated stature (metres).
    seen_from_m : float
        Height over the floor of the lowest seen returns (metres): from the floor where one is seen, else
        the stated stature less the seen body's height.
    """
    from wbsa.bodies.area_profile import area_below_share

    seen_from_m = float(np.clip(seen_from_m, 0.0, stature_m))
    if seen_from_m < 0.01:
        return None
    share, sd = area_below_share(seen_from_m / stature_m)
    return UnseenLegs(seen_from_m, float(stature_m), float(share), float(sd))


def completed(features: dict[str, np.ndarray], unseen: UnseenLegs | None) -> dict[str, np.ndarray]:
    """The measures with the area measures (:data:`AREA_MEASURES`) completed by the unseen share.

    Parameters
    ----------
    features : dict of str to (n,) float64
        The subject's measures (:meth:`SubjectMeasures.features`).
    unseen : UnseenLegs or None
        None: the measures unchanged.

    Returns
    -------
    dict of str to (n,) float64
    """
    if unseen is None:
        return features
    scale = 1.0 / (1.0 - unseen.area_share)
    return {**features, **{k: np.asarray(features[k], dtype=np.float64) * scale for k in AREA_MEASURES}}


def corrected(wbsa_m2, unseen: UnseenLegs | None):
    """The regression's estimate of a completed subject less its mean error on cut frames
    (:data:`CUT_LOG_ERROR_PER_SHARE`); unchanged when the whole body is seen.

    Parameters
    ----------
    wbsa_m2 : float or (n,) float64
        The estimate (or a bound of its interval).
    unseen : UnseenLegs or None
    """
    return wbsa_m2 if unseen is None else wbsa_m2 * math.exp(-CUT_LOG_ERROR_PER_SHARE[0] * unseen.area_share)


def widened(lo_m2: float, hi_m2: float, wbsa_m2: float, unseen: UnseenLegs | None,
            level: float) -> tuple[float, float]:
    """An interval widened by the unseen legs: each side's log half-width and z times the log spread they
    add, in quadrature (z the normal quantile of ``level``): the share's spread over people,
    sd / (1 − share), and the regression's spread on cut frames, :data:`CUT_LOG_ERROR_PER_SHARE` · share.

    Parameters
    ----------
    lo_m2, hi_m2, wbsa_m2 : float
        The route's interval and estimate.
    unseen : UnseenLegs or None
        None: the interval unchanged.
    level : float
        The interval's coverage.

    Returns
    -------
    (float, float)
    """
    if unseen is None or not (0 < lo_m2 <= wbsa_m2 <= hi_m2):
        return lo_m2, hi_m2
    extra = NormalDist().inv_cdf(0.5 + level / 2.0) * math.hypot(unseen.area_share_sd / (1.0 - unseen.area_share),
                                                                 CUT_LOG_ERROR_PER_SHARE[1] * unseen.area_share)
    below = math.hypot(math.log(wbsa_m2 / lo_m2), extra)
    above = math.hypot(math.log(hi_m2 / wbsa_m2), extra)
    return wbsa_m2 * math.exp(-below), wbsa_m2 * math.exp(above)
