"""The one table of the limits of what a user states and of what the estimator measures (SI units).

The command line's help and its argument types, the page's inputs (``GET /api/info``) and the library's
checks all read :data:`LIMITS`; a limit changed here changes them all.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Limit:
    """A closed range of one quantity (SI units) and what it is, in words.

    Attributes
    ----------
    low, high : float
    unit : str
        The unit of ``low`` and ``high`` (``m``).
    what : str
        What a value must be, e.g. ``a human height``.
    """

    low: float
    high: float
    unit: str
    what: str

    def contains(self, value: float) -> bool:
        """Whether ``low <= value <= high`` (False for NaN).

        Parameters
        ----------
        value : float
        """
        return self.low <= value <= self.high

    def scaled(self, factor: float) -> tuple[float, float]:
        """``(low, high)`` times ``factor`` (100: in cm), rounded to 10 decimals.

        Parameters
        ----------
        factor : float
        """
        return round(self.low * factor, 10), round(self.high * factor, 10)


#: Every limit, by name: ``stature`` a human height (a stated stature, and the height measured on the point
#: cloud: outside it the depth scale or units are wrong), ``clothing`` the layer of clothes that can be stated
#: (the default model is trained on 0–1.5 cm, flagged beyond), ``depth`` the returns kept by default.
LIMITS: dict[str, Limit] = {
    "stature": Limit(0.5, 2.5, "m", "a human height"),
    "clothing": Limit(0.0, 0.05, "m", "a thickness of clothes"),
    "depth": Limit(0.3, 8.0, "m", "a depth in the camera's range"),
}
#: The limits as tuples, for the code that reads them as numbers.
HUMAN_HEIGHT_M: tuple[float, float] = (LIMITS["stature"].low, LIMITS["stature"].high)
MAX_CLOTHING_M: float = LIMITS["clothing"].high
DEPTH_RANGE_M: tuple[float, float] = (LIMITS["depth"].low, LIMITS["depth"].high)


def limits_json() -> dict[str, list[float]]:
    """The page's limits: ``{"height_cm": [lo, hi], "clothing_cm": [lo, hi], "depth_m": [lo, hi]}``."""
    return {"height_cm": list(LIMITS["stature"].scaled(100)), "clothing_cm": list(LIMITS["clothing"].scaled(100)),
            "depth_m": list(DEPTH_RANGE_M)}


__all__ = ["DEPTH_RANGE_M", "HUMAN_HEIGHT_M", "LIMITS", "Limit", "MAX_CLOTHING_M", "limits_json"]
