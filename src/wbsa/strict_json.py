"""Strict JSON: every machine-readable output of wbsa parses with a strict parser (Node, ``jq``, FHIR tooling).

JSON has no NaN or Infinity; Python's :mod:`json` writes them anyway (``NaN``), which strict parsers refuse.
:func:`json_text` writes a non-finite number as ``null``; the code that produces the number says why, in the
output's flags or notes (e.g. the body fit's ``no_interval``). No pandas import: the CLI's
printers use it.
"""

from __future__ import annotations

import json
import math
from pathlib import Path


def finite_or_none(obj: object) -> object:
    """``obj`` with every non-finite float (NaN, ±inf; Python or NumPy) replaced by None, recursively.

    Dicts, lists and tuples are walked (tuples become lists); NumPy scalars and arrays become Python numbers
    and lists; everything else is returned as it is.

    Examples
    --------
    >>> import numpy as np
    >>> finite_or_none({"a": float("nan"), "b": [1.0, np.float32("inf"), 2], "c": np.array([0.5, np.nan])})
    {'a': None, 'b': [1.0, None, 2], 'c': [0.5, None]}
    """
    import numpy as np

    if isinstance(obj, np.ndarray):
        obj = obj.tolist()
    elif isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: finite_or_none(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [finite_or_none(v) for v in obj]
    return obj


def json_default(o: object) -> object:
    """``json.dumps(default=)`` for NumPy scalars and arrays and paths."""
    import numpy as np

    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def json_text(obj: object, indent: int | None = 2) -> str:
    """``obj`` as strict JSON text: non-finite numbers as ``null`` (:func:`finite_or_none`), never ``NaN``.

    Examples
    --------
    >>> json_text({"azimuth_deg": float("nan"), "wbsa_m2": 1.8}, indent=None)
    '{"azimuth_deg": null, "wbsa_m2": 1.8}'
    """
    return json.dumps(finite_or_none(obj), indent=indent, allow_nan=False, default=json_default)
