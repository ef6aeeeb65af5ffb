"""Unit and range checks for stature and mass before any BSA formula is applied.

Bounds (inclusive) are the extremes of recorded humans, so that every real person passes and
a wrong unit does not:

- height 30–272 cm: a very preterm newborn is about 30 cm long; Robert Wadlow, the tallest
  person on record, measured 272 cm.
- weight 0.5–650 kg: very preterm newborns weigh about 0.5 kg; the heaviest person on record
  weighed about 635 kg.

The commonest mistakes get their own message: height below 3 (metres instead of centimetres),
height above the range but within 300–2720 (millimetres), weight above the range but within
500–650000 (grams).
"""

from __future__ import annotations

import numpy as np

from wbsa.errors import WbsaError

#: Inclusive physiological range of stature, centimetres.
HEIGHT_RANGE_CM: tuple[float, float] = (30.0, 272.0)
#: Inclusive physiological range of body mass, kilograms.
WEIGHT_RANGE_KG: tuple[float, float] = (0.5, 650.0)
#: A positive height below this is taken for metres.
METRES_BELOW: float = 3.0


def as_float_arrays(height_cm, weight_kg) -> tuple[np.ndarray, np.ndarray]:
    """Height and weight as float64 arrays of one broadcast shape.

    Parameters
    ----------
    height_cm, weight_kg : float or array_like
        Scalars, lists, numpy arrays or pandas Series of numbers.

    Returns
    -------
    height_cm, weight_kg : (...) float64
        Broadcast against each other (read-only views when broadcasting repeats values).

    Raises
    ------
    WbsaError
        When a value is not a number or the shapes do not broadcast.
    """
    h = _to_float(height_cm, "height")
    w = _to_float(weight_kg, "weight")
    try:
        return tuple(np.broadcast_arrays(h, w))  # type: ignore[return-value]
    except ValueError:
        raise WbsaError(
            f"height has shape {h.shape} and weight has shape {w.shape}; give one value per subject for both"
        ) from None


def validate_inputs(height_cm, weight_kg) -> None:
    """Raise :class:`WbsaError` unless every height/weight pair is a plausible human in cm and kg.

    Parameters
    ----------
    height_cm, weight_kg : float or array_like
        Stature in centimetres and body mass in kilograms; arrays must broadcast together.

    Raises
    ------
    WbsaError
        One line naming the first problem found, in this order: not a finite number, height ≤ 0,
        weight ≤ 0, height < 3 (metres), height 300–2720 (millimetres), height outside
        :data:`HEIGHT_RANGE_CM`, weight above the range but plausible in grams, weight outside
        :data:`WEIGHT_RANGE_KG`. For arrays the message gives the position of the first offending
        value and how many values fail the same check.
    """
    h, w = as_float_arrays(height_cm, weight_kg)
    h_lo, h_hi = HEIGHT_RANGE_CM
    w_lo, w_hi = WEIGHT_RANGE_KG
    scalar = h.ndim == 0
    cm_hint = "give the height in centimetres, e.g. 170" if scalar else "give heights in centimetres, e.g. 170"
    kg_hint = "give the weight in kilograms, e.g. 70" if scalar else "give weights in kilograms, e.g. 70"
    nan_hint = (
        "give a number" if scalar else "drop the missing rows first, or pass check=False to get NaN for them"
    )
    checks = (
        (h, ~np.isfinite(h), "height {v} is not a finite number; " + nan_hint),
        (w, ~np.isfinite(w), "weight {v} is not a finite number; " + nan_hint),
        (h, h <= 0, "height {v} must be positive; " + cm_hint),
        (w, w <= 0, "weight {v} must be positive; " + kg_hint),
        (h, h < METRES_BELOW, "height {v} looks like metres; " + cm_hint),
        (h, (h > h_hi) & (h >= 10 * h_lo) & (h <= 10 * h_hi),
         f"height {{v}} is above {h_hi:g} cm and looks like millimetres; " + cm_hint),
        (h, (h < h_lo) | (h > h_hi),
         f"height {{v}} cm is outside the physiological range {h_lo:g}–{h_hi:g} cm; check the value and the unit"),
        (w, (w > w_hi) & (w >= 1000 * w_lo) & (w <= 1000 * w_hi),
         f"weight {{v}} is above {w_hi:g} kg and looks like grams; " + kg_hint),
        (w, (w < w_lo) | (w > w_hi),
         f"weight {{v}} kg is outside the physiological range {w_lo:g}–{w_hi:g} kg; check the value and the unit"),
    )
    for values, bad, template in checks:
        if np.any(bad):
            raise WbsaError(_message(values, bad, template))


def _to_float(values, what: str) -> np.ndarray:
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise WbsaError(f"{what} must be a number or an array of numbers, got {values!r:.40}") from None
    return arr


def _message(values: np.ndarray, bad: np.ndarray, template: str) -> str:
    """Fill ``template`` with the first offending value (and, for arrays, its position and count)."""
    bad = np.broadcast_to(bad, values.shape)
    if values.ndim == 0:
        return template.format(v=f"{float(values):g}")
    flat = int(np.flatnonzero(bad)[0])
    pos = np.unravel_index(flat, values.shape)
    where = str(pos[0]) if len(pos) == 1 else str(tuple(int(i) for i in pos))
    n_bad, n = int(np.count_nonzero(bad)), bad.size
    first = f"{float(values.flat[flat]):g} (at position {where}; {n_bad} of {n} values)"
    return template.format(v=first)
