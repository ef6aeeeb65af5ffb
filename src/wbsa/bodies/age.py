"""Conversion between anny's ``age`` parameter and age in years.

anny maps its normalised age to a "morphological age" in years by piecewise-linear
interpolation between anchors stored with the model
(``anny/data/shape_calibration/boys.pth``: 0 → 0 y, 0.05 → 1 y, 0.215 → 4 y, 0.415 → 11 y,
0.67 → 16 y, 0.77 → 18 y, 0.83 → 64 y, 1 → 110 y). We read the same anchors so the two
never disagree.
"""

from __future__ import annotations

import functools

import numpy as np


@functools.lru_cache(maxsize=1)
def age_anchors() -> tuple[np.ndarray, np.ndarray]:
    """anny's ``(param, years)`` anchors, each ``(k,) float64``, increasing."""
    from pathlib import Path

    import anny
    import torch

    path = Path(anny.__path__[0]) / "data" / "shape_calibration" / "boys.pth"
    mapping = torch.load(path, weights_only=True, map_location="cpu")["morphological_age_mapping"]
    return (mapping["anny_age_anchors"].double().numpy(), mapping["morphological_age_anchors"].double().numpy())


def years_to_param(age_years: np.ndarray | float) -> np.ndarray:
    """anny ``age`` parameter for an age in years (array-like → ``float64`` array)."""
    param, years = age_anchors()
    return np.interp(np.asarray(age_years, dtype=np.float64), years, param)


def param_to_years(age_param: np.ndarray | float) -> np.ndarray:
    """Age in years for an anny ``age`` parameter in [0, 1]."""
    param, years = age_anchors()
    return np.interp(np.asarray(age_param, dtype=np.float64), param, years)
