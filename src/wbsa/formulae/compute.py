"""Checked, vectorised BSA: one formula, all formulae, or a table of them.

All entry points take stature in centimetres and mass in kilograms (scalars, numpy arrays or
pandas Series that broadcast together) and an optional sex, and return m².
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from wbsa.errors import WbsaError
from wbsa.formulae.catalogue import FORMULAE, SCHLICH_BY_SEX
from wbsa.formulae.names import formula_key
from wbsa.formulae.validate import as_float_arrays, validate_inputs

if TYPE_CHECKING:
    import pandas as pd

_SEXES = {"male": False, "female": True}


def parse_sex(sex) -> np.ndarray | None:
    """Sex labels as a boolean array, True = female.

    Parameters
    ----------
    sex : None, str or array_like of str
        ``'male'`` / ``'female'`` (case and surrounding spaces ignored).

    Returns
    -------
    None or (...) bool
        ``None`` when ``sex`` is ``None``; otherwise an array of the shape of ``sex``.

    Raises
    ------
    WbsaError
        On any other label (including missing values in an array).
    """
    if sex is None:
        return None
    import pandas as pd

    labels = np.asarray(sex, dtype=object)
    codes, uniques = pd.factorize(labels.ravel(), use_na_sentinel=False)  # hashing: fast on long columns
    female = np.empty(len(uniques), dtype=bool)
    for i, label in enumerate(uniques):
        key = label.strip().lower() if isinstance(label, str) else None
        if key is None and pd.isna(label):
            raise WbsaError("sex is missing for some subjects; give 'male' or 'female' for every one")
        if key not in _SEXES:
            raise WbsaError(f"sex {label!r} is not understood; use 'male' or 'female'")
        female[i] = _SEXES[key]
    return female[codes].reshape(labels.shape)


def bsa(key: str, height_cm, weight_kg, sex=None, *, check: bool = True) -> np.ndarray | float:
    """BSA in m² from one formula.

    Parameters
    ----------
    key : str
        A key of :data:`~wbsa.formulae.FORMULAE`, or ``'schlich_male'`` / ``'schlich_female'``
        (Schlich with a fixed sex, as returned by :func:`bsa_all` without sex), or any name
        :func:`~wbsa.formulae.formula_key` accepts (``'Mosteller'``, ``'DuBois-DuBois'``, ...).
    height_cm : float or (...) array_like
        Stature in centimetres.
    weight_kg : float or (...) array_like
        Body mass in kilograms; broadcasts with ``height_cm``.
    sex : None, str or (...) array_like of str, optional
        ``'male'`` / ``'female'``; required by ``'schlich'``, ignored by formulae without sex.
    check : bool, default True
        Validate units and ranges with :func:`~wbsa.formulae.validate_inputs` and raise on the
        first bad value. With ``check=False`` nothing is raised for the values: pairs with a
        non-finite or non-positive height or weight give NaN, all others are computed as given
        (use this for population tables with missing entries).

    Returns
    -------
    float or (...) float64
        A float when every input is a scalar, otherwise an array of the broadcast shape.

    Raises
    ------
    WbsaError
        Unknown key, bad sex label, Schlich without sex, or (with ``check``) implausible inputs.
    """
    function = _function(key)
    h, w, female = _prepare(height_cm, weight_kg, sex, check)
    with np.errstate(invalid="ignore", divide="ignore"):
        result = function(h, w, female)
    return _finish(result, h, w)


def bsa_all(height_cm, weight_kg, sex=None, *, check: bool = True) -> dict[str, np.ndarray]:
    """BSA in m² from every formula.

    Parameters
    ----------
    height_cm, weight_kg, sex, check
        As for :func:`bsa`.

    Returns
    -------
    dict[str, (...) float64]
        One entry per key of :data:`~wbsa.formulae.FORMULAE`, in that order. Without ``sex``,
        ``'schlich'`` is replaced by ``'schlich_male'`` and ``'schlich_female'`` at its place.
        Values are 0-d arrays for scalar inputs.
    """
    h, w, female = _prepare(height_cm, weight_kg, sex, check)
    out: dict[str, np.ndarray] = {}
    with np.errstate(invalid="ignore", divide="ignore"):
        for key, formula in FORMULAE.items():
            if formula.sex_specific and female is None:
                for fixed_key, function in SCHLICH_BY_SEX.items():
                    out[fixed_key] = _finish_array(function(h, w, None), h, w)
            else:
                out[key] = _finish_array(formula.function(h, w, female), h, w)
    return out


def bsa_table(height_cm, weight_kg, sex=None, *, check: bool = True) -> "pd.DataFrame":
    """Every formula's BSA as a table, one row per subject.

    Parameters
    ----------
    height_cm, weight_kg : float or (n,) array_like
        Stature (cm) and mass (kg); scalars give one row.
    sex, check
        As for :func:`bsa`.

    Returns
    -------
    pandas.DataFrame
        Columns ``bsa_<key>_m2`` in the order of :func:`bsa_all` (float64). The index is taken
        from the first pandas Series among the inputs, otherwise 0..n-1.
    """
    import pandas as pd

    values = bsa_all(height_cm, weight_kg, sex, check=check)
    shape = next(iter(values.values())).shape
    if len(shape) > 1:
        raise WbsaError(f"bsa_table takes one value per subject (1-D), got shape {shape}; use bsa_all for arrays")
    n = int(np.prod(shape))
    index = None
    for arg in (height_cm, weight_kg, sex):
        if isinstance(arg, pd.Series) and len(arg) == n:
            index = arg.index
            break
    return pd.DataFrame({f"bsa_{k}_m2": np.reshape(v, n) for k, v in values.items()}, index=index)


def _function(name: str):
    key = formula_key(name)
    return FORMULAE[key].function if key in FORMULAE else SCHLICH_BY_SEX[key]


def _prepare(height_cm, weight_kg, sex, check: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Float arrays (and a female mask) of one broadcast shape, validated when ``check``."""
    if check:
        validate_inputs(height_cm, weight_kg)
    h, w = as_float_arrays(height_cm, weight_kg)
    female = parse_sex(sex)
    if female is not None:
        try:
            h, w, female = np.broadcast_arrays(h, w, female)
        except ValueError:
            raise WbsaError(
                f"sex has shape {female.shape} but height/weight have shape {h.shape}; give one sex per subject"
            ) from None
    return h, w, female


def _finish_array(result: np.ndarray, h: np.ndarray, w: np.ndarray) -> np.ndarray:
    """float64 array of the inputs' shape, NaN wherever an input is non-finite or non-positive."""
    result = np.array(np.broadcast_to(result, h.shape), dtype=np.float64)
    invalid = ~(np.isfinite(h) & np.isfinite(w) & (h > 0) & (w > 0))
    if np.any(invalid):
        result[invalid] = np.nan
    return result


def _finish(result: np.ndarray, h: np.ndarray, w: np.ndarray) -> np.ndarray | float:
    out = _finish_array(result, h, w)
    return float(out) if out.ndim == 0 else out
